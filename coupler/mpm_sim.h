/* A simulation: the resolved case, the shared grid, the modules, the integrator and the
 * outputs, and the step loop that ties them together.
 *
 * The loop, per accepted step: integrate one step (not past the next output or checkpoint
 * time) -> migrate particles to their owners -> sort by cell every run.sort_every steps ->
 * diagnostics row -> snapshot / checkpoint when due. After a checkpoint the integrator is
 * restarted from the checkpointed state exactly as `mpmfsi restart` would do, so a restarted
 * run repeats the original bit for bit. */
#ifndef MPM_SIM_H
#define MPM_SIM_H

#include "mpm_config.h"

typedef struct mpm_sim mpm_sim;

/* Add every key of every module to cfg's schema. */
int mpm_sim_add_schema(mpm_config *cfg);

/* Build a new run from a validated configuration: grid, modules, seeded particles,
 * integrator; nothing is written until mpm_sim_run (collective). */
int mpm_sim_create(mpm_sim **sim, mpm_config *cfg);
/* Build a run from a checkpoint; cfg holds the checkpoint's configuration plus overrides. */
int mpm_sim_restart(mpm_sim **sim, mpm_config *cfg, const char *checkpoint);
int mpm_sim_run(mpm_sim *sim);
/* Which code makes the results ("mpmfsi 0.1.0 (git 17dee4f)"), for summary.json; the text
 * is not copied and must outlive the run. Unset, summary.json says "unknown". */
void mpm_sim_set_version(mpm_sim *sim, const char *version);
void mpm_sim_destroy(mpm_sim **sim);

#endif

/* Probes: the history of one material point, written every accepted step to probes.csv
 * (t, then per probe its displacement and velocity components: NAME_ux, NAME_uy, ...,
 * NAME_vx, ...). A case asks for one with
 *   [probe.tip]
 *   point = 0.053 0.03     ; the particle nearest to this point at t = 0
 *   phase = solid          ; solid (default) or fluid
 * The particle is chosen once, at the start (the nearest, ties: the lowest id), and followed
 * by id; its id and starting position go into every checkpoint, so that a restart continues
 * the same history. A probe whose particle has left the domain reads NaN. */
#ifndef MPM_PROBE_H
#define MPM_PROBE_H

#include "mpm_config.h"
#include "mpm_module.h"
#include "mpm_output.h"

#define MPM_PROBE_MAX 8

typedef struct mpm_probes {
  int n, dim;
  char name[MPM_PROBE_MAX][64];
  int module[MPM_PROBE_MAX]; /* index into the sim's modules */
  double id[MPM_PROBE_MAX];  /* the particle followed */
  double x0[MPM_PROBE_MAX][MPM_MAX_DIM];
  char col[MPM_PROBE_MAX * 2 * MPM_MAX_DIM + 1][80]; /* probes.csv column names */
  char attr[MPM_PROBE_MAX * (1 + MPM_MAX_DIM)][96];  /* checkpoint attribute names */
} mpm_probes;

extern const mpm_key_spec mpm_probe_keys[];
extern const int mpm_probe_nkeys;

/* Read the [probe.NAME] sections and pick their particles now (a fresh run). Collective. */
int mpm_probes_new(mpm_probes *pr, const mpm_config *cfg, mpm_module **mod, int nmod);
/* The checkpoint attributes that carry the probes: names[k] (storage in pr) and values. */
int mpm_probes_attrs(mpm_probes *pr, const char **names, double *values, int max);
/* After mpm_probes_new on a restart: follow the particles the checkpoint names (a checkpoint
 * of a run without probes names none: they start here). */
void mpm_probes_restore(mpm_probes *pr, const mpm_checkpoint *ck);
/* Column names of probes.csv (t first); returns their count. */
int mpm_probes_columns(mpm_probes *pr, const char **cols);
/* The row for the current state: t, then displacement and velocity per probe. Collective. */
int mpm_probes_row(const mpm_probes *pr, mpm_module **mod, double t, double *row);

#endif

/* The machinery the partitioned time schemes share (timescheme_staggered.c,
 * timescheme_multirate.c): one ARKODE integrator per module, the interface data between them
 * (mpm_interface.h), and the advances a coupling step is made of.
 *
 * The gas advances against the solid held at its last deposit (a held cycle), or with shared
 * nodes (mpm_interface.h) after the solid, taking the velocity its substeps left on them (a
 * follow cycle); the solid advances under the momentum the gas gave up (a loaded cycle), so the
 * interface balances over every exchange to roundoff. A scheme decides the order, the coupling
 * step and the substeps; these functions do the rest. The classic update only (usl, musl): the
 * captured load is the interface force of each step's one RHS, where an adaptive pair's stages
 * would each give another.
 *
 * A coupling step: partitioned_begin, then hold / advance_gas / advance_solid in the scheme's
 * order, then partitioned_end, which forms the step's interface record: the rates of each side
 * over the step, weighted by the substeps' sizes, and the momentum still owed to the solid. */
#ifndef MPM_PARTITIONED_H
#define MPM_PARTITIONED_H

#include "mpm_integrator.h"
#include "mpm_timescheme.h"

typedef struct mpm_partitioned {
  mpm_module *solid, *gas;
  mpm_integrator *it_solid, *it_gas;
  mpm_interface *ifc;
  mpm_cycle deposit;     /* the solid alone, for its deposit before the gas advances */
  mpm_cycle gas_deposit; /* the gas alone, for its deposit before shared nodes advance */
  int shared;            /* multirate: coupling.exchange = shared (mpm_interface.h) */
  double dt_max;         /* time.dt_max (HUGE_VAL: none) */
  double h_last;         /* the last coupling step */
  /* The scheme's own settings, read by its create. */
  int order;    /* staggered: the order of the advances */
  int substeps; /* multirate: substeps of the fast module per coupling step (0: from the ratio) */
  int slow_substeps;         /* multirate: of the slow module (0: as many as the fast module) */
  int interpolate;           /* multirate: the solid's substeps see a linear trend of the load */
  struct mpm_strong *strong; /* staggered: sub-iterations (NULL: none) */
  int iterations;            /* staggered: the most sub-iterations in a coupling step */
  long steps;
  mpm_coupling_record sum; /* the coupling step under way: sums of h times the rates */
  mpm_coupling_record rec; /* the last coupling step's record */
} mpm_partitioned;

/* Build it for ts (ts->content): a coupled gas and solid and the classic update are required,
 * else an input error naming the key (scheme: the coupling.time name, for the message). */
int mpm_partitioned_new(mpm_timescheme *ts, const mpm_config *cfg, const char *scheme);

/* Use shared nodes (coupling.exchange = shared, mpm_interface.h): the gas then advances in
 * follow cycles. */
int mpm_partitioned_want_shared(mpm_timescheme *ts, const mpm_config *cfg);
/* Deposit the gas as it is now, at t, for the shared nodes. Collective. */
int mpm_partitioned_share(mpm_timescheme *ts, double t);

/* The CFL steps of the solid and of the gas (0: no limit). Collective. */
int mpm_partitioned_cfl_steps(mpm_timescheme *ts, double *h_solid, double *h_gas);

/* Deposit the solid as it is now, at t, and hold it for the gas. Collective. */
int mpm_partitioned_hold(mpm_timescheme *ts, double t);
/* Advance the gas from t0 to t1 in n equal substeps against the held solid, adding what it gives
 * the solid to the owed momentum. Collective. */
int mpm_partitioned_advance_gas(mpm_timescheme *ts, double t0, double t1, int n);
/* Advance the solid from t0 to t1 in n equal substeps under the owed momentum (spread evenly
 * over t1 - t0, or with the trend since the last load when interpolating), then move what stays
 * owed where the solid left (mpm_interface_rehome; with shared nodes the scheme does that after
 * the gas's step, which pays what the solid received). Collective. */
int mpm_partitioned_advance_solid(mpm_timescheme *ts, double t0, double t1, int n);
/* The same with the load rate q (N per node, dim arrays over the box nodes) added to that of the
 * owed momentum: the solid receives H q more than it is owed, which the gas's advance is then
 * expected to pay (strong coupling, mpm_strong.h). Collective. */
int mpm_partitioned_advance_solid_under(mpm_timescheme *ts, double t0, double t1, int n,
                                        const double *const *q);
/* Close the coupling step t0 -> t1: its record, the owed momentum. Collective. */
int mpm_partitioned_end(mpm_timescheme *ts, double t0, double t1);

/* The shared ops: the scheme files put these in their tables. */
void mpm_partitioned_destroy(mpm_timescheme *ts);
int mpm_partitioned_start(mpm_timescheme *ts, double t, double h0);
int mpm_partitioned_resize(mpm_timescheme *ts, double t);
int mpm_partitioned_cfl_step(mpm_timescheme *ts, double *h);
double mpm_partitioned_next_step(const mpm_timescheme *ts);
void mpm_partitioned_counts(const mpm_timescheme *ts, long *steps, long *rhs, long *fails,
                            long *retries);
int mpm_partitioned_record(mpm_timescheme *ts, double t, mpm_coupling_record *out);
int mpm_partitioned_save(mpm_timescheme *ts, mpm_particles **p, const char **name);
int mpm_partitioned_restore(mpm_timescheme *ts, mpm_checkpoint *ck);

#endif

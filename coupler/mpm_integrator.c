/* ERKStep driver of the coupled MPM system (see mpm_integrator.h). */
#include "mpm_integrator.h"

#include "mpm_cycle.h"
#include "mpm_error.h"
#include "mpm_nvector.h"
#include "mpm_sundials.h"
#include "mpm_timer.h"

#include <arkode/arkode_erkstep.h>
#include <arkode/arkode_mristep.h>
#include <math.h>
#include <nvector/nvector_mpimanyvector.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct mpm_integrator {
  MPI_Comm comm;
  SUNContext ctx;
  void *ark;
  N_Vector y, sub[MPM_MAX_MODULES];
  mpm_grid *grid;
  mpm_module *mod[MPM_MAX_MODULES];
  int nmod;
  mpm_cycle cycle; /* the RHS over mod[] */
  mpm_method method;
  int fixed;  /* fixed CFL steps without error control (direct, time.adaptive = false) */
  int direct; /* fixed step (classic, euler, ssprk2): taken here, without ERKStep */
  double rtol, atol, cfl, dt_max;
  int max_retries;
  double h_limit;   /* fixed steps: the stability-limited step of the current state (0: none) */
  double h_cfl;     /* direct steps: the CFL step of the same state (mpm_integrator_cfl_step) */
  int h_limit_set;  /* h_limit and h_cfl belong to the current state (direct steps) */
  double h_last;    /* direct steps: the last step taken (or the first step asked for) */
  double tstop;     /* stop time of the current step */
  double scale;     /* step reduction of the current retry (1 when not retrying) */
  double checked_t; /* direct steps: time of the last step end whose state was checked */
  double *work;     /* direct steps: f and the stage state, each module's block in turn */
  size_t work_cap;  /* doubles allocated in work */
  mpm_fault fault;  /* last unphysical state seen by the RHS (same on every rank) */
  int rhs_error;    /* a non-recoverable failure inside the RHS */
  long steps, rhs_evals, fails, retries;
  long fails_seen;     /* ERKStep's cumulative error-test failures already counted */
  double t_last;       /* time of the last accepted state */
  N_Vector ewt_filled; /* the error-weight vector unit_weights last filled (fixed steps) */
  /* Multirate (MRIStep, mpm_integrator_new_multirate): module fast_k is the fast partition. */
  int mri;
  int fast_k;
  mpm_cycle fast; /* module fast_k alone: its own forces, no coupling */
  int mri_table;  /* ARKODE_MRITableID */
  int substeps;   /* fast substeps per slow step (0: from the ratio of the stable steps) */
  MRIStepInnerStepper stepper; /* the fast partition's integrator (inner_evolve) */
  ARKodeButcherTable table;    /* its Butcher table, the time method's */
  double h_fast;               /* its substep */
  double *fast_rate;           /* module fast_k's rates alone, then the inner stages' work */
  size_t fast_cap;             /* doubles allocated in fast_rate */
};

const mpm_key_spec mpm_integrator_keys[] = {
    {"time.t_end", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL, "end time of the run, s", 0, "s"},
    {"time.method", MPM_KEY_ENUM, "bs32", 0, 0, 0, 0,
     "usl|musl|euler|ralston21|bs32|zonneveld43|dp54|ssprk2",
     "time method: usl or musl (classic MPM, fixed CFL step), an adaptive embedded ERK pair, or "
     "ssprk2 (two-stage second-order SSP Runge-Kutta, fixed CFL step)",
     0, NULL},
    {"time.rtol", MPM_KEY_REAL, "1e-6", 0, 1, 1, 0, NULL, "relative tolerance (adaptive)", 0, "-"},
    {"time.atol", MPM_KEY_REAL, "1e-9", 0, HUGE_VAL, 1, 0, NULL,
     "absolute tolerance (adaptive), in state units (m, m/s, 1)", 0, "m, m/s, -"},
    {"time.cfl", MPM_KEY_REAL, "0.4", 0, 0.999, 1, 0, NULL,
     "fraction of the stable step dx / (c + |v|) allowed, below 1", 0, "-"},
    {"time.dt_max", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL, "largest step, s (0: no limit)", 0,
     "s"},
    {"time.adaptive", MPM_KEY_BOOL, "true", 0, 0, 0, 0, NULL,
     "false: the ERK pairs take a fixed step, time.cfl of the stability limit, without error "
     "control (the shock tubes: bs32 at time.cfl = 0.8; usl, musl, euler and ssprk2 always do)",
     0, NULL},
    {"time.max_retries", MPM_KEY_INT, "8", 0, 100, 0, 0, NULL,
     "restarts with a 4x smaller step after an unphysical stage before the run stops", 0, "-"},
};
const int mpm_integrator_nkeys = (int)(sizeof mpm_integrator_keys / sizeof mpm_integrator_keys[0]);

static const char *const g_method_names[MPM_METHOD_COUNT] = {
    "usl", "musl", "euler", "ralston21", "bs32", "zonneveld43", "dp54", "ssprk2"};
const char *mpm_method_name(mpm_method m) {
  return g_method_names[m];
}

/* ---- the right-hand side ---------------------------------------------------------------- */

static double *module_data(N_Vector y, int k) {
  return N_VGetArrayPointer(N_VGetSubvector_MPIManyVector(y, k));
}

static void vector_blocks(const mpm_integrator *it, N_Vector y, double **yk) {
  for (int k = 0; k < it->nmod; ++k) yk[k] = module_data(y, k);
}

/* The accepted state: every module's state block in its particle data. */
static void particle_blocks(const mpm_integrator *it, double **yk) {
  for (int k = 0; k < it->nmod; ++k) yk[k] = it->mod[k]->particles->data;
}

static size_t block_length(const mpm_integrator *it, int k) {
  const mpm_particles *p = it->mod[k]->particles;
  return (size_t)p->nstate * (size_t)p->n;
}

/* Agree on a fault across ranks: the lowest rank that has one broadcasts it. */
static int share_fault(mpm_integrator *it, mpm_fault *local) {
  int rank, size, who;
  MPI_Comm_rank(it->comm, &rank);
  MPI_Comm_size(it->comm, &size);
  int mine = local->set ? rank : size;
  MPM_CALL_MPI(MPI_Allreduce(&mine, &who, 1, MPI_INT, MPI_MIN, it->comm));
  if (who == size) return 0;
  if (rank == who) it->fault = *local;
  MPM_CALL_MPI(MPI_Bcast(&it->fault, (int)sizeof it->fault, MPI_BYTE, who, it->comm));
  return 1;
}

/* Check every module's block of y (stopping at the first fault) and agree across ranks:
 * 1 if some rank found an unphysical state (now in it->fault), 0 if none. Collective. */
static int check_modules(mpm_integrator *it, double *const *yk, int k0, int k1) {
  mpm_fault local = {0};
  mpm_timer_start(MPM_T_CHECK);
  for (int k = k0; k < k1 && !local.set; ++k) it->mod[k]->ops->check(it->mod[k], yk[k], &local);
  const int faulty = share_fault(it, &local);
  mpm_timer_stop(MPM_T_CHECK);
  return faulty;
}

static int check_state(mpm_integrator *it, double *const *yk) {
  return check_modules(it, yk, 0, it->nmod);
}

/* The rate of the coupling's relaxation of the phases' own velocities at the shared nodes
 * (mpm_coupling.h, relax_rate): coupling.mol_rate times the slowest module's signal rate, its
 * fastest signal at this state over the grid's spacing (the smallest over the modules). No
 * step is longer than time.cfl times that module's stable step (under multirate the slow step
 * is the slow module's), so h k stays below coupling.mol_rate time.cfl, and monolithic and
 * multirate solve the same equations (with the step-setting modules' rate instead, MRIStep's
 * energy on test_multirate_face_mri no longer converged to monolithic's). The signal is read
 * from y alone (mpm_module.h, signal_speed): a rate from the stable step, which reads what the
 * modules commit between steps, differed between an integrator restarted after a migration and
 * one reusing its last stage (2 ranks against 1: 1e-8 of the piston's velocities). Collective. */
static int set_relax_rate(mpm_integrator *it, double *const *yk) {
  mpm_coupling *c = it->cycle.coupling;
  if (!c || !(c->type->needs & (MPM_COUPLING_RELAXES | MPM_COUPLING_RATE)) || !(c->relax_share > 0))
    return 0;
  double s[MPM_MAX_MODULES], slowest = HUGE_VAL;
  for (int k = 0; k < it->nmod; ++k)
    s[k] = it->mod[k]->ops->signal_speed ? it->mod[k]->ops->signal_speed(it->mod[k], yk[k]) : 0.0;
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, s, it->nmod, MPI_DOUBLE, MPI_MAX, it->comm));
  for (int k = 0; k < it->nmod; ++k)
    if (s[k] > 0) slowest = fmin(slowest, s[k]);
  c->relax_rate = isfinite(slowest) ? c->relax_share * slowest / it->grid->dx : 0.0;
  return 0;
}

/* ERKStep's RHS (the ERK pairs): the MPM cycle with h = 0 (the method of lines) on a state
 * that passes the modules' checks; an unphysical one is a recoverable failure. */
static int rhs(mpm_sunreal t, N_Vector y, N_Vector ydot, void *user) {
  mpm_integrator *it = user;
  double *yk[MPM_MAX_MODULES], *ydk[MPM_MAX_MODULES];
  vector_blocks(it, y, yk);
  vector_blocks(it, ydot, ydk);
  if (check_state(it, yk)) return 1;
  it->rhs_evals++;
  if (set_relax_rate(it, yk) != 0) {
    it->rhs_error = 1;
    return -1;
  }
  if (mpm_cycle_rhs(&it->cycle, t, yk, ydk, 0.0) != 0) {
    it->rhs_error = 1;
    return -1;
  }
  return 0;
}

/* Multirate: the slow RHS is the joint cycle less the fast module's rates alone, so that the
 * two partitions sum to the monolithic RHS exactly: the fast partition is the module's own
 * dynamics, the slow one the other module and everything the coupling adds to both. */
static int rhs_slow(mpm_sunreal t, N_Vector y, N_Vector ydot, void *user) {
  mpm_integrator *it = user;
  const int rc = rhs(t, y, ydot, user);
  if (rc != 0) return rc;
  double *yf = module_data(y, it->fast_k), *fd = module_data(ydot, it->fast_k);
  const size_t len = block_length(it, it->fast_k);
  if (mpm_cycle_rhs(&it->fast, t, &yf, &it->fast_rate, 0.0) != 0) {
    it->rhs_error = 1;
    return -1;
  }
  for (size_t i = 0; i < len; ++i) fd[i] -= it->fast_rate[i];
  return 0;
}

/* The fast partition: the fast module alone; the other modules' rates are zero. */
static int rhs_fast(mpm_sunreal t, N_Vector y, N_Vector ydot, void *user) {
  mpm_integrator *it = user;
  double *yk[MPM_MAX_MODULES], *ydk[MPM_MAX_MODULES];
  vector_blocks(it, y, yk);
  vector_blocks(it, ydot, ydk);
  const int k = it->fast_k;
  if (check_modules(it, yk, k, k + 1)) return 1;
  for (int j = 0; j < it->nmod; ++j)
    if (j != k) memset(ydk[j], 0, block_length(it, j) * sizeof(double));
  if (mpm_cycle_rhs(&it->fast, t, &yk[k], &ydk[k], 0.0) != 0) {
    it->rhs_error = 1;
    return -1;
  }
  return 0;
}

/* Stability limit: min over modules (all, or all but module `skip`) and ranks of
 * dx / (c + |v|), before the CFL fraction; each of those modules learns its own limit as its
 * h_limit (mpm_module.h). */
static int stable_step_of(mpm_integrator *it, double *const *yk, int skip, double *hstab) {
  double h[MPM_MAX_MODULES];
  for (int k = 0; k < it->nmod; ++k)
    h[k] = k != skip ? it->mod[k]->ops->stable_dt(it->mod[k], yk[k]) : HUGE_VAL;
  /* Every module's own limit over the ranks (one reduction), for its h_limit. */
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, h, it->nmod, MPI_DOUBLE, MPI_MIN, it->comm));
  *hstab = HUGE_VAL;
  for (int k = 0; k < it->nmod; ++k) {
    *hstab = fmin(*hstab, h[k]);
    if (k != skip) it->mod[k]->h_limit = isfinite(h[k]) ? h[k] : 0.0;
  }
  return 0;
}

/* The step's limit: every module's, or under multirate the slow modules' only. */
static int stable_step(mpm_integrator *it, double *const *yk, double *hstab) {
  return stable_step_of(it, yk, it->mri ? it->fast_k : -1, hstab);
}

/* For the adaptive pairs; ARKODE applies time.cfl as its CFL fraction. */
static int estab(N_Vector y, mpm_sunreal t, mpm_sunreal *hstab, void *user) {
  (void)t;
  double h, *yk[MPM_MAX_MODULES];
  vector_blocks(user, y, yk);
  mpm_timer_start(MPM_T_STABLE);
  const int rc = stable_step(user, yk, &h);
  mpm_timer_stop(MPM_T_STABLE);
  if (rc != 0) return -1;
  *hstab = isfinite(h) ? h : 0.0; /* 0: no limit */
  return 0;
}

/* The stability-limited fixed step (direct methods, non-adaptive pairs) at y: the CFL
 * fraction of the limit, capped by dt_max; 0 when nothing limits it. Also the CFL step
 * without the cap (mpm_integrator_cfl_step). */
static int fixed_limit(mpm_integrator *it, double *const *yk, double *h, double *h_cfl) {
  double hs;
  MPM_CALL(stable_step(it, yk, &hs));
  *h_cfl = isfinite(hs) ? it->cfl * hs : 0.0;
  hs = fmin(it->cfl * hs, it->dt_max);
  *h = hs > 0 && isfinite(hs) ? hs : 0.0;
  return 0;
}

/* h_limit and h_cfl of the current state, unless they are known. Direct steps keep them for
 * the state's step: a partitioned scheme asks for the CFL step at the start of its coupling step,
 * and its module's first step then takes the limit without a second pass over the particles.
 * (ERKStep's fixed steps recompute them: the state may have changed since.) */
static int current_limits(mpm_integrator *it) {
  if (it->h_limit_set) return 0;
  double *yk[MPM_MAX_MODULES];
  particle_blocks(it, yk);
  mpm_timer_start(MPM_T_STABLE);
  const int rc = fixed_limit(it, yk, &it->h_limit, &it->h_cfl);
  mpm_timer_stop(MPM_T_STABLE);
  MPM_CALL(rc);
  it->h_limit_set = it->direct;
  return 0;
}

/* The fixed step from the last accepted state: its stability limit (or, without one, the
 * rest of the way to the stop time) times the retry scale, capped by the stop time so that a
 * step lands on it (and stretched to it when the limit falls short by roundoff only). */
static int fixed_step(mpm_integrator *it, double *h) {
  MPM_CALL(current_limits(it));
  const double t = it->t_last, rest = it->tstop - t;
  const double hs = it->scale * (it->h_limit > 0 ? it->h_limit : rest);
  /* A limit a few ulps short of the rest (a staggered scheme's coupling step, t + H - t) would
   * leave a step of roundoff size. */
  *h = hs >= rest * (1 - 1e-12) ? rest : hs;
  /* A step that does not move the time would end where it starts. From a stability limit that
   * small, the run has blown up; from a stop time that close, a caller asked for a
   * roundoff-sized step. */
  if (t + *h > t) return 0;
  if (*h < rest)
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the run blew up at t = %.6g: the stable step of the state fell to %.3g s, too "
             "small to advance the time (speeds or wave speeds without bound); reduce "
             "time.cfl, refine the grid, or check the scene near the fastest particles",
             t, *h);
  MPM_FAIL(MPM_ERR_INTERNAL,
           "a fixed step of %.3g s from t = %.17g to the stop time %.17g does not advance the "
           "time (roundoff): the time scheme asked for it",
           *h, t, it->tstop);
}

#if SUNDIALS_VERSION_MAJOR < 7
/* ARKODE's own messages become debug lines; the driver reports failures itself. (SUNDIALS 7
 * routes them through the context's logger instead.) */
static void ark_errors(int code, const char *module, const char *func, char *msg, void *user) {
  (void)user;
  mpm_log(MPM_LOG_DEBUG, "ARKODE %s %s (%d): %s", module, func, code, msg);
}
#endif

/* ---- state vector ------------------------------------------------------------------------ */

static void free_state(mpm_integrator *it) {
  if (it->y) N_VDestroy(it->y);
  for (int k = 0; k < it->nmod; ++k)
    if (it->sub[k]) N_VDestroy(it->sub[k]);
  it->y = NULL;
  memset(it->sub, 0, sizeof it->sub);
}

/* ERKStep's fixed steps (the ERK pairs with time.adaptive = false) never use an error norm;
 * ARKODE 6.4 still computes one per step (a "too much accuracy" check read only for adaptive
 * steps), a full pass over the state with a global reduction. For them the state vector
 * reports a zero norm instead: an ops-table specialisation, inherited by ARKODE's clones. */
static mpm_sunreal no_wrmsnorm(N_Vector x, N_Vector w) {
  (void)x, (void)w;
  return 0.0;
}

static int wrap_state(mpm_integrator *it) {
  free_state(it);
  for (int k = 0; k < it->nmod; ++k) {
    mpm_particles *p = it->mod[k]->particles;
    it->sub[k] = N_VMake_Serial((sunindextype)p->nstate * p->n, p->data, it->ctx);
    if (!it->sub[k]) MPM_FAIL(MPM_ERR_SUNDIALS, "cannot wrap the %s state", it->mod[k]->name);
    mpm_nvector_fast_ops(it->sub[k]);
  }
  it->y = N_VMake_MPIManyVector(it->comm, it->nmod, it->sub, it->ctx);
  if (!it->y) MPM_FAIL(MPM_ERR_SUNDIALS, "cannot build the MPIManyVector state");
  /* One pass per subvector for ARKODE's stage and solution combinations. */
  MPM_CALL_SUN(N_VEnableLinearCombination_MPIManyVector(it->y, SUNTRUE));
  MPM_CALL_SUN(N_VEnableScaleAddMulti_MPIManyVector(it->y, SUNTRUE));
  if (it->fixed) it->y->ops->nvwrmsnorm = no_wrmsnorm;
  it->ewt_filled = NULL;
  return 0;
}

/* ---- fixed steps taken here: one stage, and SSP-RK2 ---------------------------------------- */

/* The classic update (usl, musl) and forward Euler are one stage with a fixed step,
 * y_{n+1} = y_n + h f(t_n, y_n), where the classic update's f also depends on h (the grid
 * velocity is advanced by h before G2P). Through ERKStep such a step cost a reset (the driver
 * changes the particles between nearly all steps, and f depends on the step), an interpolant,
 * an end-of-step RHS and some seven copies of the state, and every vector was reallocated
 * whenever a particle entered, left, or changed rank. Here a step is one RHS, one combination
 * h f + y (ERKStep's arithmetic, so results are bit for bit the same) and one copy.
 *
 * SSP-RK2 (Shu and Osher 1988; Heun's method, c = (0, 1), b = (1/2, 1/2)) is two forward
 * Euler stages of the method-of-lines RHS, y1 = y + h f(t, y), then
 * y_{n+1} = (y + y1 + h f(t + h, y1)) / 2: second order, and it keeps any convex bound
 * (positive density and J, no new extrema) that a forward Euler step of h keeps. Taken
 * here rather than through ERKStep: ARKODE before 6.7 treats a table whose last node is c = 1
 * as first-same-as-last and reuses the second stage's RHS as the next step's first
 * (llnl/sundials#311), and every stage is checked as a one-stage step's end is. */

#define MPM_RETRY (-1)

/* Room for f and the stage state of every module's block; grows by a quarter beyond the need. */
static int ensure_work(mpm_integrator *it) {
  size_t need = 0;
  for (int k = 0; k < it->nmod; ++k) need += 2 * block_length(it, k);
  if (need <= it->work_cap) return 0;
  free(it->work);
  it->work = NULL, it->work_cap = 0;
  const size_t cap = need + need / 4;
  MPM_ALLOC(it->work, cap);
  it->work_cap = cap;
  return 0;
}

/* One step of h from the accepted state (the particle data), which the previous step's end
 * checked unless the particles changed since: the new state is checked before it replaces
 * the old one, so a fault leaves the accepted state as it was. */
static int direct_step(mpm_integrator *it, double h, double *t, double *h_taken) {
  double *y[MPM_MAX_MODULES], *f[MPM_MAX_MODULES], *y1[MPM_MAX_MODULES];
  size_t len[MPM_MAX_MODULES];
  particle_blocks(it, y);
  double *w = it->work;
  for (int k = 0; k < it->nmod; ++k) {
    len[k] = block_length(it, k);
    f[k] = w, y1[k] = w + len[k];
    w += 2 * len[k];
  }
  if (it->checked_t != it->t_last && check_state(it, y)) return MPM_RETRY;
  it->rhs_evals++;
  MPM_CALL(mpm_cycle_rhs(&it->cycle, it->t_last, y, f, mpm_method_is_classic(it->method) ? h : 0));
  for (int k = 0; k < it->nmod; ++k) {
    const double *fk = f[k], *yk = y[k];
    double *zk = y1[k];
    for (size_t i = 0; i < len[k]; ++i) zk[i] = h * fk[i] + yk[i];
  }
  if (check_state(it, y1)) return MPM_RETRY;
  if (it->method == MPM_METHOD_SSPRK2) {
    /* The second stage: f(t + h, y1) into f, then the average in place of y1. */
    it->rhs_evals++;
    MPM_CALL(mpm_cycle_rhs(&it->cycle, it->t_last + h, y1, f, 0));
    for (int k = 0; k < it->nmod; ++k) {
      const double *fk = f[k], *yk = y[k];
      double *zk = y1[k];
      for (size_t i = 0; i < len[k]; ++i) zk[i] = 0.5 * (yk[i] + (h * fk[i] + zk[i]));
    }
    if (check_state(it, y1)) return MPM_RETRY;
  }
  for (int k = 0; k < it->nmod; ++k)
    if (len[k] > 0) memcpy(y[k], y1[k], len[k] * sizeof(double));
  it->t_last = it->checked_t = it->t_last + h;
  it->h_limit_set = 0, it->h_last = h;
  *t = it->t_last, *h_taken = h;
  return 0;
}

/* ---- life cycle --------------------------------------------------------------------------- */

static int read_settings(mpm_integrator *it, const mpm_config *cfg) {
  const char *method;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  for (int m = 0; m < MPM_METHOD_COUNT; ++m)
    if (strcmp(method, g_method_names[m]) == 0) it->method = (mpm_method)m;
  MPM_CALL(mpm_config_get_real(cfg, "time.rtol", &it->rtol));
  MPM_CALL(mpm_config_get_real(cfg, "time.atol", &it->atol));
  MPM_CALL(mpm_config_get_real(cfg, "time.cfl", &it->cfl));
  MPM_CALL(mpm_config_get_real(cfg, "time.dt_max", &it->dt_max));
  MPM_CALL(mpm_config_get_int(cfg, "time.max_retries", &it->max_retries));
  int adaptive;
  MPM_CALL(mpm_config_get_bool(cfg, "time.adaptive", &adaptive));
  it->direct = mpm_method_is_direct(it->method);
  it->fixed = !adaptive || it->direct;
  if (it->dt_max <= 0) it->dt_max = HUGE_VAL;
  return 0;
}

int mpm_integrator_new(mpm_integrator **itp, const mpm_config *cfg, const mpm_cycle *cycle) {
  if (cycle->nmod < 1 || cycle->nmod > MPM_MAX_MODULES)
    MPM_FAIL(MPM_ERR_INPUT, "a run needs 1 to %d modules, got %d", MPM_MAX_MODULES, cycle->nmod);
  mpm_integrator *it;
  MPM_ALLOC(it, 1);
  *itp = it;
  it->comm = cycle->grid->comm;
  it->grid = cycle->grid;
  it->nmod = cycle->nmod;
  for (int k = 0; k < cycle->nmod; ++k) it->mod[k] = cycle->mod[k];
  MPM_CALL(read_settings(it, cfg));
  it->cycle = *cycle;
  it->cycle.mod = it->mod;
  it->cycle.musl = it->method == MPM_METHOD_MUSL;
  if (it->direct) return ensure_work(it);
  if (mpm_sun_context_create(&it->comm, &it->ctx) != 0)
    MPM_FAIL(MPM_ERR_SUNDIALS, "SUNContext_Create failed");
  return wrap_state(it);
}

static void free_ark(mpm_integrator *it) {
  if (it->mri) {
    if (it->ark) MRIStepFree(&it->ark);
    if (it->stepper) MRIStepInnerStepper_Free(&it->stepper);
  } else if (it->ark) {
    ERKStepFree(&it->ark);
  }
}

int mpm_integrator_new_multirate(mpm_integrator **itp, const mpm_config *cfg,
                                 const mpm_cycle *cycle, int fast_k, int substeps, int table) {
  MPM_CALL(mpm_integrator_new(itp, cfg, cycle));
  mpm_integrator *it = *itp;
  if (it->direct || fast_k < 0 || fast_k >= it->nmod)
    MPM_FAIL(MPM_ERR_INTERNAL, "MRIStep needs an ERK pair and a fast module among the cycle's");
  it->mri = 1, it->fixed = 1;
  it->fast_k = fast_k, it->substeps = substeps, it->mri_table = table;
  it->fast = (mpm_cycle){.grid = it->grid, .mod = &it->mod[fast_k], .nmod = 1};
  return wrap_state(it); /* the fixed steps' zero norm */
}

void mpm_integrator_destroy(mpm_integrator **it) {
  if (!it || !*it) return;
  free_ark(*it);
  free_state(*it);
  free((*it)->work);
  free((*it)->fast_rate);
  if ((*it)->table) ARKodeButcherTable_Free((*it)->table);
  if ((*it)->ctx) SUNContext_Free(&(*it)->ctx);
  free(*it);
  *it = NULL;
}

/* The Butcher table of an ERK pair (the caller frees it). Ralston's second-order method with
 * an embedded Euler step is built here: SUNDIALS before 6.7 treats every table whose last
 * node is c = 1 as first-same-as-last, which breaks Heun-Euler (llnl/sundials#311); Ralston's
 * nodes are 0 and 2/3. */
static ARKodeButcherTable erk_table(mpm_method m) {
  static const ARKODE_ERKTableID ids[MPM_METHOD_COUNT] = {
      [MPM_METHOD_BS32] = ARKODE_BOGACKI_SHAMPINE_4_2_3,
      [MPM_METHOD_ZONNEVELD43] = ARKODE_ZONNEVELD_5_3_4,
      [MPM_METHOD_DP54] = ARKODE_DORMAND_PRINCE_7_4_5};
  if (m != MPM_METHOD_RALSTON21) return ARKodeButcherTable_LoadERK(ids[m]);
  ARKodeButcherTable B = ARKodeButcherTable_Alloc(2, SUNTRUE);
  if (!B) return NULL;
  B->A[1][0] = 2.0 / 3.0;
  B->c[0] = 0.0, B->c[1] = 2.0 / 3.0;
  B->b[0] = 0.25, B->b[1] = 0.75;
  B->d[0] = 1.0, B->d[1] = 0.0;
  B->q = 2, B->p = 1;
  return B;
}

/* Error weights for ERKStep's fixed steps. These never use them, but ARKODE 6.4 recomputes them
 * every step (four passes over the state with the default function); one constant fill of each
 * weight vector ARKODE allocates is all a fixed step needs. */
static int unit_weights(N_Vector y, N_Vector ewt, void *user) {
  mpm_integrator *it = user;
  (void)y;
  if (ewt != it->ewt_filled) N_VConst(1.0, ewt);
  it->ewt_filled = ewt;
  return 0;
}

/* Error weights of the adaptive pairs: ARKODE's scalar-tolerance weights 1 / (rtol |y| +
 * atol), bit for bit, in one pass (time.atol > 0 keeps them finite, so ARKODE's positivity
 * check has nothing to find). */
static int tolerance_weights(N_Vector y, N_Vector ewt, void *user) {
  const mpm_integrator *it = user;
  mpm_nvector_weights(y, ewt, it->rtol, it->atol);
  return 0;
}

static int configure(mpm_integrator *it, double h0) {
  MPM_CALL_SUN(ERKStepSetUserData(it->ark, it));
#if SUNDIALS_VERSION_MAJOR < 7
  MPM_CALL_SUN(ERKStepSetErrHandlerFn(it->ark, ark_errors, NULL));
#endif
  MPM_CALL_SUN(ERKStepSetMaxNumSteps(it->ark, -1));
  ARKodeButcherTable B = erk_table(it->method);
  if (!B) MPM_FAIL(MPM_ERR_MEMORY, "cannot build the %s table", mpm_method_name(it->method));
  const int flag = ERKStepSetTable(it->ark, B);
  ARKodeButcherTable_Free(B);
  MPM_CALL_SUN(flag);
  if (it->fixed) {
    /* Fixed steps never read ARKODE's dense output (no stop time, see attempt), but the
     * default Hermite interpolant still copies the state and f at every step; a degree-0
     * Lagrange one copies the state only. */
    MPM_CALL_SUN(ERKStepSetInterpolantType(it->ark, ARK_INTERP_LAGRANGE));
    MPM_CALL_SUN(ERKStepSetInterpolantDegree(it->ark, 0));
    MPM_CALL_SUN(ERKStepWFtolerances(it->ark, unit_weights));
    it->ewt_filled = NULL;
    MPM_CALL_SUN(ERKStepSetFixedStep(it->ark, h0 > 0 ? h0 : 1.0));
    return 0;
  }
  MPM_CALL_SUN(ERKStepWFtolerances(it->ark, tolerance_weights));
  MPM_CALL_SUN(ERKStepSetStabilityFn(it->ark, estab, it));
  MPM_CALL_SUN(ERKStepSetCFLFraction(it->ark, it->cfl));
  if (isfinite(it->dt_max)) MPM_CALL_SUN(ERKStepSetMaxStep(it->ark, it->dt_max));
  if (h0 > 0) MPM_CALL_SUN(ERKStepSetInitStep(it->ark, h0));
  return 0;
}

/* ---- multirate: MRIStep's inner stepper ---------------------------------------------------- */

/* MRIStep asks its inner stepper to solve v' = f_fast(t, v) + r(t) over [t0, tout], with the
 * forcing r(t) = sum_j F_j ((t - tshift) / tscale)^j built from the slow stages. ARKStep as the
 * inner stepper would carry the whole state (the gas too, where f_fast is zero) through every
 * fast stage. Here the other modules' blocks take the forcing's exact integral, a polynomial,
 * and the fast module's block alone takes n equal steps of the time method's table (an ERK of
 * order p integrates the gas's forcing of degree p - 1 exactly, so the gas's blocks get what
 * ARKStep would give them), without ARKStep's passes over the gas. */

/* Add w_j F_j[block k] to y for j < nF (w: the forcing's weights). */
static void add_forcing(const mpm_integrator *it, int k, const N_Vector *F, int nF, const double *w,
                        double *y) {
  const size_t len = block_length(it, k);
  for (int j = 0; j < nF; ++j) {
    const double *f = module_data(F[j], k);
    for (size_t i = 0; i < len; ++i) y[i] += w[j] * f[i];
  }
}

#define MPM_MAX_FORCING 8

static int inner_evolve(MRIStepInnerStepper st, mpm_sunreal t0, mpm_sunreal tout, N_Vector v) {
  mpm_integrator *it = NULL;
  mpm_sunreal tshift, tscale;
  N_Vector *F = NULL;
  int nF = 0;
  MRIStepInnerStepper_GetContent(st, (void **)&it);
  MRIStepInnerStepper_GetForcingData(st, &tshift, &tscale, &F, &nF);
  if (nF > MPM_MAX_FORCING) return -1;
  double w[MPM_MAX_FORCING];
  const double a0 = (t0 - tshift) / tscale, a1 = (tout - tshift) / tscale;
  for (int j = 0; j < nF; ++j) w[j] = tscale * (pow(a1, j + 1) - pow(a0, j + 1)) / (j + 1);
  for (int k = 0; k < it->nmod; ++k)
    if (k != it->fast_k) add_forcing(it, k, F, nF, w, module_data(v, k));
  /* The fast block: n equal steps of the Butcher table. */
  const ARKodeButcherTable B = it->table;
  const int fk = it->fast_k, ns = B->stages;
  const size_t len = block_length(it, fk);
  double *y = module_data(v, fk), *Y = it->fast_rate, *K = Y + len;
  double *yk[MPM_MAX_MODULES] = {NULL};
  const double span = tout - t0;
  const int n = (int)fmax(1.0, ceil(span / it->h_fast * (1 - 1e-12)));
  const double h = span / n;
  for (int step = 0; step < n; ++step) {
    const double t = t0 + step * h;
    for (int i = 0; i < ns; ++i) {
      memcpy(Y, y, len * sizeof(double));
      for (int j = 0; j < i; ++j) {
        const double a = h * B->A[i][j];
        if (a != 0.0)
          for (size_t q = 0; q < len; ++q) Y[q] += a * K[(size_t)j * len + q];
      }
      const double ti = t + B->c[i] * h;
      yk[fk] = Y;
      if (check_modules(it, yk, fk, fk + 1)) return 1;
      double *Ki = K + (size_t)i * len;
      if (mpm_cycle_rhs(&it->fast, ti, &Y, &Ki, 0.0) != 0) {
        it->rhs_error = 1;
        return -1;
      }
      const double ai = (ti - tshift) / tscale;
      for (int j = 0; j < nF; ++j) w[j] = pow(ai, j);
      add_forcing(it, fk, F, nF, w, Ki);
    }
    for (int i = 0; i < ns; ++i) {
      const double b = h * B->b[i];
      for (size_t q = 0; q < len; ++q) y[q] += b * K[(size_t)i * len + q];
    }
  }
  return 0;
}

/* The fast partition's RHS without forcing, for MRIStep's dense output. */
static int inner_full_rhs(MRIStepInnerStepper st, mpm_sunreal t, N_Vector v, N_Vector f, int mode) {
  (void)mode;
  void *it = NULL;
  MRIStepInnerStepper_GetContent(st, &it);
  return rhs_fast(t, v, f, it);
}

/* Nothing to reset: the inner stepper keeps no state between calls. */
static int inner_reset(MRIStepInnerStepper st, mpm_sunreal tR, N_Vector vR) {
  (void)st, (void)tR, (void)vR;
  return 0;
}

/* A fresh MRIStep over the joint state with the inner stepper above; fixed steps, set before
 * each step (attempt_multirate). */
static int start_multirate(mpm_integrator *it, double t) {
  if (!it->table && !(it->table = erk_table(it->method)))
    MPM_FAIL(MPM_ERR_MEMORY, "cannot build the %s table", mpm_method_name(it->method));
  const size_t len = block_length(it, it->fast_k) * (size_t)(it->table->stages + 1);
  if (len > it->fast_cap) {
    free(it->fast_rate);
    it->fast_rate = NULL, it->fast_cap = 0;
    MPM_ALLOC(it->fast_rate, len + len / 4);
    it->fast_cap = len + len / 4;
  }
  MPM_CALL_SUN(MRIStepInnerStepper_Create(it->ctx, &it->stepper));
  MPM_CALL_SUN(MRIStepInnerStepper_SetContent(it->stepper, it));
  MPM_CALL_SUN(MRIStepInnerStepper_SetEvolveFn(it->stepper, inner_evolve));
  MPM_CALL_SUN(MRIStepInnerStepper_SetFullRhsFn(it->stepper, inner_full_rhs));
  MPM_CALL_SUN(MRIStepInnerStepper_SetResetFn(it->stepper, inner_reset));
  it->ark = MRIStepCreate(rhs_slow, NULL, t, it->y, it->stepper, it->ctx);
  if (!it->ark) MPM_FAIL(MPM_ERR_SUNDIALS, "MRIStepCreate failed");
  MPM_CALL_SUN(MRIStepSetUserData(it->ark, it));
#if SUNDIALS_VERSION_MAJOR < 7
  MPM_CALL_SUN(MRIStepSetErrHandlerFn(it->ark, ark_errors, NULL));
#endif
  MPM_CALL_SUN(MRIStepSetMaxNumSteps(it->ark, -1));
  MRIStepCoupling C = MRIStepCoupling_LoadTable((ARKODE_MRITableID)it->mri_table);
  if (!C) MPM_FAIL(MPM_ERR_SUNDIALS, "cannot load MRI coupling table %d", it->mri_table);
  const int cflag = MRIStepSetCoupling(it->ark, C);
  MRIStepCoupling_Free(C);
  MPM_CALL_SUN(cflag);
  MPM_CALL_SUN(MRIStepWFtolerances(it->ark, unit_weights));
  it->ewt_filled = NULL;
  MPM_CALL_SUN(MRIStepSetFixedStep(it->ark, 1.0));
  return 0;
}

int mpm_integrator_start(mpm_integrator *it, double t, double h0) {
  it->t_last = t;
  it->scale = 1.0, it->fails_seen = 0, it->h_limit_set = 0;
  it->checked_t = NAN, it->h_last = h0;
  if (it->direct) return ensure_work(it);
  free_ark(it);
  MPM_CALL(wrap_state(it));
  if (it->mri) return start_multirate(it, t);
  it->ark = ERKStepCreate(rhs, t, it->y, it->ctx);
  if (!it->ark) MPM_FAIL(MPM_ERR_SUNDIALS, "ERKStepCreate failed");
  return configure(it, h0);
}

int mpm_integrator_resize(mpm_integrator *it, double t) {
  it->h_limit_set = 0; /* particles moved between ranks, or were added or removed */
  if (it->direct) return ensure_work(it);
  if (it->mri) return mpm_integrator_start(it, t, 0.0); /* fixed steps: nothing to carry */
  MPM_CALL(wrap_state(it));
  MPM_CALL_SUN(ERKStepResize(it->ark, it->y, 1.0, t, NULL, NULL));
  return 0;
}

int mpm_integrator_substeps(const mpm_integrator *it) {
  return it->mri ? it->substeps : 0;
}

int mpm_integrator_cfl_step(mpm_integrator *it, double *h) {
  MPM_CALL(current_limits(it));
  *h = it->h_cfl;
  return 0;
}

double mpm_integrator_next_step(const mpm_integrator *it) {
  if (it->direct) return it->h_last;
  if (it->mri) return it->h_last; /* fixed steps, set before each */
  mpm_sunreal h = 0;
  ERKStepGetCurrentStep(it->ark, &h);
  return h;
}

void mpm_integrator_counts(const mpm_integrator *it, long *steps, long *rhs_evals, long *fails,
                           long *retries) {
  *steps = it->steps, *rhs_evals = it->rhs_evals, *fails = it->fails, *retries = it->retries;
}

static int report_fault(const mpm_integrator *it, double t, int tries) {
  const mpm_fault *f = &it->fault;
  char where[96];
  if (it->grid->dim == 2)
    snprintf(where, sizeof where, "(%.6g, %.6g)", f->x[0], f->x[1]);
  else
    snprintf(where, sizeof where, "(%.6g, %.6g, %.6g)", f->x[0], f->x[1], f->x[2]);
  mpm_log(MPM_LOG_ERROR,
          "the run stopped at t = %.6g after %d %s with smaller steps: particle %lld at %s: %s. %s",
          t, tries, tries == 1 ? "retry" : "retries", (long long)f->id, where, f->cause,
          f->advice[0] ? f->advice
                       : "Reduce time.cfl or time.rtol, refine the grid, or check the material "
                         "parameters and boundary conditions near that point");
  return MPM_ERR_UNPHYSICAL;
}

/* More fast substeps than this in one slow step means the fast module's stable step has
 * collapsed: the ratio of two stable modules' steps is 10-100. */
#define MPM_MAX_SUBSTEPS 1e4

/* MRIStep and ERKStep with a first-same-as-last pair reuse the last stage of the step before.
 * A module whose RHS reads what it commits between steps (mpm_module.commits_history: the gas
 * with fluid.strain_rate = lagged, a solid with a plastic history) has made that stage stale,
 * and it is reused only where no migration or refill restarted the integrator: 2 ranks then
 * differed from 1 by 4e-4 of the largest gas velocity (MRIStep, the stiff piston at t = 0.5)
 * and 1e-5 (monolithic bs32, fixed steps). Such steps start from a fresh first stage, for one
 * RHS more a step; adaptive pairs keep the reuse (their error control sees the difference). */
static int stale_stage(const mpm_integrator *it) {
  for (int k = 0; k < it->nmod; ++k)
    if (it->mod[k]->commits_history) return 1;
  return 0;
}

/* One multirate step: the slow step H from the slow modules' limit (fixed_step), m fast
 * substeps of H / m (coupling.substeps, or the fewest the fast module's limit allows). */
static int attempt_multirate(mpm_integrator *it, double *t, double *h) {
  double H, hf, *yk[MPM_MAX_MODULES];
  MPM_CALL(fixed_step(it, &H));
  int m = it->substeps;
  if (m == 0) {
    particle_blocks(it, yk);
    double hs = HUGE_VAL,
           hl = it->mod[it->fast_k]->ops->stable_dt(it->mod[it->fast_k], yk[it->fast_k]);
    MPM_CALL_MPI(MPI_Allreduce(&hl, &hs, 1, MPI_DOUBLE, MPI_MIN, it->comm));
    hf = it->scale * it->cfl * hs;
    const double need = isfinite(hf) && hf > 0 ? fmax(1.0, ceil(H / hf * (1 - 1e-12))) : 1.0;
    if (need > MPM_MAX_SUBSTEPS)
      MPM_FAIL(MPM_ERR_UNPHYSICAL,
               "the run blew up at t = %.6g: the %s module's stable step %.3g s is %.3g times "
               "below the slow step %.3g s (its particles have reached speeds no stable scene "
               "has); reduce time.cfl, refine the grid, or check the scene near the interface",
               it->t_last, it->mod[it->fast_k]->name, hf, need, H);
    m = (int)need;
  }
  MPM_CALL_SUN(MRIStepSetFixedStep(it->ark, H));
  it->h_fast = H / m;
  /* A fresh first stage where a module commits history between steps (stale_stage). */
  if (stale_stage(it)) MPM_CALL_SUN(MRIStepReset(it->ark, it->t_last, it->y));
  it->fault.set = 0, it->rhs_error = 0;
  mpm_sunreal tret = it->t_last;
  const int flag = MRIStepEvolve(it->ark, it->t_last + H, it->y, &tret, ARK_ONE_STEP);
  if (flag >= 0) {
    *t = it->t_last = tret, *h = H, it->h_last = H;
    return 0;
  }
  if (it->fault.set) return MPM_RETRY;
  MPM_FAIL(it->rhs_error ? MPM_ERR_INTERNAL : MPM_ERR_SUNDIALS,
           "MRIStep failed at t = %.6g with flag %d", it->t_last, flag);
}

/* One attempt with the step scaled by `scale`: 0 = accepted, MPM_RETRY = an unphysical stage
 * (retry smaller), otherwise an error code. */
static int attempt(mpm_integrator *it, double tstop, double scale, double *t, double *h) {
  mpm_sunreal tret = it->t_last;
  it->tstop = tstop, it->scale = scale;
  if (it->direct) {
    double hf;
    MPM_CALL(fixed_step(it, &hf));
    return direct_step(it, hf, t, h);
  }
  if (it->mri) return attempt_multirate(it, t, h);
  if (it->fixed) {
    double hf;
    MPM_CALL(fixed_step(it, &hf));
    MPM_CALL_SUN(ERKStepSetFixedStep(it->ark, hf));
    /* A fresh first stage where the last one is stale, as in attempt_multirate. */
    if (stale_stage(it)) MPM_CALL_SUN(ERKStepReset(it->ark, it->t_last, it->y));
  }
  /* A fixed step already lands on tstop (see fixed_step); ARKODE's stop time would replace
   * the state it reaches by its interpolant there. */
  if (!it->fixed) MPM_CALL_SUN(ERKStepSetStopTime(it->ark, tstop));
  it->fault.set = 0;
  it->rhs_error = 0;
  int flag = ERKStepEvolve(it->ark, tstop, it->y, &tret, ARK_ONE_STEP);
  if (flag >= 0) {
    mpm_sunreal hl;
    ERKStepGetLastStep(it->ark, &hl);
    *t = it->t_last = tret, *h = hl;
    return 0;
  }
  if (it->fault.set) return MPM_RETRY;
  if (flag == ARK_ERR_FAILURE || flag == ARK_TOO_MUCH_ACC)
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the run blew up at t = %.6g: the adaptive %s step failed its error test "
             "repeatedly (ERKStep flag %d): the state changes faster than time.rtol and "
             "time.atol (in the state's units: m, m/s, J/kg) allow at any step; an impulsive "
             "start or a near vacuum is the usual cause: loosen time.atol, start the flow "
             "gradually, or use time.method = usl",
             it->t_last, mpm_method_name(it->method), flag);
  MPM_FAIL(it->rhs_error ? MPM_ERR_INTERNAL : MPM_ERR_SUNDIALS,
           "ERKStep failed at t = %.6g with flag %d", it->t_last, flag);
}

/* The smallest step a retry may try, relative to the CFL step: a stage that still fails
 * below it meets a barrier (a wall, an inverted element) that no step size removes. */
#define MPM_RETRY_FLOOR 1e-6

int mpm_integrator_step(mpm_integrator *it, double tstop, double *t, double *h) {
  double scale = 1.0, h_cfl, h_tried = 0.0;
  for (int tries = 0;; ++tries) {
    const int rc = attempt(it, tstop, scale, t, h);
    long nfail = 0;
    if (it->ark && !it->mri) ERKStepGetNumErrTestFails(it->ark, &nfail);
    it->fails += nfail - it->fails_seen;
    it->fails_seen = nfail;
    if (rc == 0) {
      it->steps++;
      return 0;
    }
    if (rc != MPM_RETRY) return mpm_trace(__FILE__, __LINE__, __func__, rc);
    /* The step ERKStep tried (it keeps it as the next step after a failure). */
    if (tries == 0) h_tried = fabs(mpm_integrator_next_step(it));
    scale *= 0.25;
    double *yk[MPM_MAX_MODULES];
    particle_blocks(it, yk);
    MPM_CALL(stable_step(it, yk, &h_cfl));
    h_cfl = isfinite(h_cfl) ? it->cfl * h_cfl : h_tried; /* no stability limit: the step tried */
    const double h_next = it->fixed ? scale * h_cfl : scale * h_tried;
    if (tries >= it->max_retries || h_next < MPM_RETRY_FLOOR * h_cfl)
      return report_fault(it, it->t_last, tries);
    it->retries++;
    mpm_log(MPM_LOG_DEBUG, "retrying from t = %.6g with step %.3g: particle %lld: %s", it->t_last,
            h_next, (long long)it->fault.id, it->fault.cause);
    /* ERKStep cannot retry a recoverable explicit RHS failure itself: restart it from the
     * last accepted state (the particle data) with a quarter of the step it tried. */
    MPM_CALL(mpm_integrator_start(it, it->t_last, it->fixed ? 0.0 : h_next));
    /* A fresh ERKStep may grow its first step 10^4-fold, straight back into the failure. */
    if (!it->fixed) MPM_CALL_SUN(ERKStepSetMaxFirstGrowth(it->ark, 2.0));
  }
}

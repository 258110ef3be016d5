/* The simulation object and its step loop (see mpm_sim.h). */
#include "mpm_sim.h"

#include "mpm_bc.h"
#include "mpm_budget.h"
#include "mpm_cells.h"
#include "mpm_coupling.h"
#include "mpm_diag.h"
#include "mpm_error.h"
#include "mpm_geometry.h"
#include "mpm_guard.h"
#include "mpm_h5.h"
#include "mpm_integrator.h"
#include "mpm_iowatch.h"
#include "mpm_timescheme.h"
#include "mpm_output.h"
#include "mpm_probe.h"
#include "mpm_refine.h"
#include "mpm_rundir.h"
#include "mpm_safefile.h"
#include "mpm_scene.h"
#include "mpm_signal.h"
#include "mpm_timer.h"
#include "fluid_module.h"
#include "solid_module.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define SIM_MAX_MODULES 4
/* The estimate of the step count is refined after this many steps (see refine_estimate). */
#define ESTIMATE_AFTER 20
enum { PROGRESS_OFF, PROGRESS_LOG, PROGRESS_LIVE };

struct mpm_sim {
  const char *version; /* the code's version and revision, for summary.json */
  MPI_Comm comm;
  int rank, size;
  mpm_config *cfg;
  char *config_text;
  mpm_grid *grid;
  mpm_module *mod[SIM_MAX_MODULES];
  int nmod;
  mpm_coupling *coupling; /* NULL: one phase, or scheme = none */
  mpm_hier *hier;         /* the refinement hierarchy (mpm_refine.h); NULL: none */
  int dynamic;            /* it regrids (refine.criterion) */
  int diag_levels;        /* per-level particle counts in diagnostics.csv (0: unrefined) */
  mpm_timescheme *it;     /* the temporal coupling scheme */
  mpm_guard guard;
  double energy;      /* total energy at the last diagnostics row */
  double kinetic;     /* kinetic energy at the last diagnostics row */
  mpm_rundir *rundir; /* the claim on the output folder, while the run writes */
  double run_id;      /* the run's id, in its folder's run.id and its checkpoints */
  char *checkpoint;   /* restart: the checkpoint it started from */
  mpm_output *out;
  mpm_diag *diag;
  mpm_diag *coupling_csv; /* coupling.csv, with a coupler only */
  mpm_probes probes;
  mpm_diag *probe_csv;       /* probes.csv, with probes only */
  double coupling_work;      /* cumulative energy the coupling created (J; < 0: destroyed) */
  double coupling_crossed;   /* energy that crossed the interface: int max(|P_s|, |P_f|) dt */
  double solid_peak;         /* the solid's largest total energy so far (J) */
  double coupling_imbalance; /* largest |F_solid + F_fluid + d owed/dt| / max(|F_s|, |F_f|) */
  double owed[MPM_MAX_DIM];  /* interface momentum the solid has yet to receive (staggered) */
  char body_cols[MPM_COUPLING_MAX_BODIES][MPM_MAX_DIM][80]; /* coupling.csv column names */
  double t, t_end, h_next;
  long step;
  double out_interval, ckpt_interval;
  long out_next, ckpt_next; /* index k of the next output / checkpoint at time k * interval */
  long ckpt_number;         /* the number in the next checkpoint_NNNNNN.h5 */
  int sort_every, snapshots, grid_fields, overwrite, truncate;
  int progress; /* PROGRESS_OFF, _LOG or _LIVE (run.progress resolved) */
  const char *dir;
  double particle_steps;
  double progress_interval;        /* s of wall time between progress lines (log; run.log) */
  double progress_last;            /* wall time of the last progress line (log) or redraw (live) */
  double progress_logged;          /* wall time of the last progress line in run.log (live) */
  double estimate;                 /* the expected step count of the run from t (0: none yet) */
  double dt_first[ESTIMATE_AFTER]; /* the first steps' sizes, for the refined estimate */
  long step0;                      /* the step the run (or restart) started at */
  /* RHS evaluations before this command (a restart: the checkpoint's), so that
   * diagnostics.csv's rhs_evals continues the run's count; 0 for a new run. */
  double rhs_before;
};

static const mpm_key_spec sim_keys[] = {
    {"run.name", MPM_KEY_STRING, "mpmfsi", 0, 0, 0, 0, NULL, "name of the run", 0, NULL},
    {"run.log_level", MPM_KEY_ENUM, "info", 0, 0, 0, 0, "error|warn|info|debug|trace",
     "how much to log; debug also prints the traceback of a failure", 0, NULL},
    {"run.log_all_ranks", MPM_KEY_BOOL, "false", 0, 0, 0, 0, NULL, "log on every rank", 0, NULL},
    {"run.progress", MPM_KEY_ENUM, "auto", 0, 0, 0, 0, "auto|live|log|off|true|false",
     "how to show progress: live = a line on the terminal redrawn twice a second (step, t, "
     "%, dt, wall, ETA); log = a progress line every run.progress_interval seconds; auto = "
     "live when the user watches a terminal (stderr is one, or under mpiexec/mpirun started "
     "from one, the launcher's stderr is), else log; off = none. true = auto, false = off",
     0, NULL},
    {"run.progress_interval", MPM_KEY_REAL, "60", 0, HUGE_VAL, 0, 0, NULL,
     "wall-clock seconds between progress lines on a console that is not a terminal, and in "
     "run.log",
     0, "s"},
    {"run.sort_every", MPM_KEY_INT, "20", 0, 1e9, 0, 0, NULL,
     "sort particles by cell every N steps (0: never)", 0, "-"},
    {"domain.dim", MPM_KEY_INT, "2", 2, 3, 0, 0, NULL, "spatial dimension, 2 or 3", 0, "-"},
    {"domain.lo", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL, "lower corner, m", 0, "m"},
    {"domain.hi", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL, "upper corner, m", 0, "m"},
    {"grid.dx", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "cell size, m; the domain must be a whole number of cells", 0, "m"},
    {"grid.shape", MPM_KEY_ENUM, "quadratic", 0, 0, 0, 0, "linear|gimp|quadratic|cubic",
     "shape function", 0, NULL},
    {"grid.ranks", MPM_KEY_REALS, "0 0 0", 0, 65536, 0, 3, NULL,
     "MPI ranks per direction (0: mpmfsi chooses, the layout with the smallest halo)", 0, "-"},
    {"physics.gauge_pressure", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "a uniform pressure taken out of every phase's stress in its nodal forces (the gas's p - "
     "p_g, a solid's sigma + p_g I), not out of its energy: the particles' quadrature then sees "
     "the departures from it only; set it to the ambient pressure beside coupling.scheme = "
     "sharp, whose gas otherwise grows a transverse mode at the solid's face; walls and "
     "periodic faces only (no open faces, obstacles, refinement, grid or hybrid pressure); 0: "
     "none",
     0, "Pa"},
    {"physics.gravity", MPM_KEY_REALS, "0 0 0", -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "body acceleration, m/s^2", 0, "m/s^2"},
    {"transfer.velocity", MPM_KEY_ENUM, "flip", 0, 0, 0, 0, "flip|apic",
     "particle velocity transfer: flip (FLIP/PIC blend, see pic_fraction) or apic (affine "
     "particle-in-cell: PIC with an affine velocity per particle; classic update only)",
     0, NULL},
    {"transfer.pic_fraction", MPM_KEY_REAL, "0", 0, 1, 0, 0, NULL,
     "PIC share of the particle velocity update: 0 = FLIP (no numerical dissipation), 1 = "
     "PIC (smooth, dissipative); classic update only",
     0, "-"},
    {"physics.damping", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "mass-proportional damping rate alpha, 1/s (amplitudes decay as exp(-alpha t / 2)); "
     "for quasi-static problems",
     0, "1/s"},
    {"output.dir", MPM_KEY_STRING, "out", 0, 0, 0, 0, NULL, "output folder", 0, NULL},
    {"output.interval", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "time between snapshots, s (0: t_end / 10)", 0, "s"},
    {"output.snapshots", MPM_KEY_BOOL, "true", 0, 0, 0, 0, NULL, "write HDF5 snapshots", 0, NULL},
    {"output.grid_fields", MPM_KEY_BOOL, "false", 0, 0, 0, 0, NULL,
     "add nodal mass and velocity to the snapshots", 0, NULL},
    {"output.checkpoint_interval", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "time between checkpoints, s (0: only at the end)", 0, "s"},
    {"output.overwrite", MPM_KEY_BOOL, "false", 0, 0, 0, 0, NULL,
     "delete the results of an earlier run found in output.dir before writing (otherwise "
     "such a folder is refused)",
     0, NULL},
    {"output.truncate", MPM_KEY_BOOL, "false", 0, 0, 0, 0, NULL,
     "restart in the checkpoint's own folder although it holds later results: cut the run "
     "back to the checkpoint (its later snapshots and checkpoints are deleted)",
     0, NULL},
};

int mpm_sim_add_schema(mpm_config *cfg) {
  MPM_CALL(mpm_config_add_schema(cfg, sim_keys, (int)(sizeof sim_keys / sizeof sim_keys[0])));
  MPM_CALL(mpm_config_add_schema(cfg, mpm_integrator_keys, mpm_integrator_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, mpm_guard_keys, mpm_guard_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, mpm_budget_keys, mpm_budget_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, mpm_probe_keys, mpm_probe_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, mpm_refine_keys, mpm_refine_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, mpm_geometry_keys, mpm_geometry_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, mpm_bc_keys, mpm_bc_nkeys));
  MPM_CALL(mpm_coupling_add_schema(cfg));
  MPM_CALL(mpm_timescheme_add_schema(cfg));
  MPM_CALL(solid_add_schema(cfg));
  MPM_CALL(fluid_add_schema(cfg));
  return 0;
}

/* ---- set-up ---------------------------------------------------------------------------- */

static int read_domain(const mpm_config *cfg, int *dim, double *lo, double *hi) {
  int nlo, nhi;
  MPM_CALL(mpm_config_get_int(cfg, "domain.dim", dim));
  MPM_CALL(mpm_config_get_reals(cfg, "domain.lo", lo, 3, &nlo));
  MPM_CALL(mpm_config_get_reals(cfg, "domain.hi", hi, 3, &nhi));
  if (nlo != *dim) return mpm_config_fail(cfg, "domain.lo", "needs %d values, got %d", *dim, nlo);
  if (nhi != *dim) return mpm_config_fail(cfg, "domain.hi", "needs %d values, got %d", *dim, nhi);
  for (int d = 0; d < *dim; ++d)
    if (!(hi[d] > lo[d]))
      return mpm_config_fail(cfg, "domain.hi", "component %d (%g) must exceed domain.lo (%g)", d,
                             hi[d], lo[d]);
  return 0;
}

static int build_grid(mpm_sim *s) {
  int dim, nr, nproc[3] = {0, 0, 0}, periodic[MPM_MAX_DIM];
  double lo[3], hi[3], dx, ranks[3] = {0, 0, 0};
  const char *shape;
  mpm_walls walls;
  MPM_CALL(read_domain(s->cfg, &dim, lo, hi));
  MPM_CALL(mpm_walls_from_config(&walls, s->cfg, dim));
  mpm_walls_periodic(&walls, periodic);
  MPM_CALL(mpm_config_get_real(s->cfg, "grid.dx", &dx));
  MPM_CALL(mpm_config_get_string(s->cfg, "grid.shape", &shape));
  MPM_CALL(mpm_config_get_reals(s->cfg, "grid.ranks", ranks, 3, &nr));
  for (int d = 0; d < dim && d < nr; ++d) {
    if (ranks[d] != floor(ranks[d]))
      return mpm_config_fail(s->cfg, "grid.ranks", "expected whole numbers, got %g", ranks[d]);
    nproc[d] = (int)ranks[d];
  }
  for (int d = 0; d < dim; ++d) {
    const double cells = (hi[d] - lo[d]) / dx;
    if (cells > INT_MAX / 4)
      return mpm_config_fail(s->cfg, "grid.dx",
                             "the domain length %g along axis %d holds %.6g cells of %g, more "
                             "than the %d cells per axis a grid can index; coarsen grid.dx",
                             hi[d] - lo[d], d, cells, dx, INT_MAX / 4);
    if (fabs(cells - round(cells)) > 1e-9 * cells)
      return mpm_config_fail(s->cfg, "grid.dx",
                             "the domain length %g along axis %d is not a whole number of cells "
                             "of %g (%.6g cells); adjust grid.dx or the domain",
                             hi[d] - lo[d], d, dx, cells);
    const int ghost = mpm_shape_ghost_width(mpm_shape_parse(shape));
    if (periodic[d] && round(cells) < ghost) {
      char key[32];
      snprintf(key, sizeof key, "boundary.%c_lo", "xyz"[d]);
      return mpm_config_fail(s->cfg, key,
                             "a periodic axis needs at least %d cells for the %s shape, but the "
                             "domain holds %.0f along %c; lengthen the domain, refine grid.dx or "
                             "use a narrower shape",
                             ghost, shape, round(cells), "xyz"[d]);
    }
  }
  MPM_CALL(mpm_grid_new_periodic(&s->grid, s->comm, dim, lo, hi, dx, mpm_shape_parse(shape), nproc,
                                 periodic));
  mpm_log(MPM_LOG_INFO, "grid: %d-D, %d x %d%s cells of %g, %s, %d rank%s (%d x %d%s)", dim,
          s->grid->ncells[0], s->grid->ncells[1], dim == 3 ? " x ..." : "", dx, shape, s->size,
          s->size == 1 ? "" : "s", s->grid->nproc[0], s->grid->nproc[1], dim == 3 ? " x ..." : "");
  return 0;
}

/* run.progress: auto is live when the user watches a terminal (mpm_log_console_is_terminal:
 * stderr, or the MPI launcher's stderr), so that ctest, CI and files never receive \r lines. */
static int read_progress(mpm_sim *s) {
  const char *mode;
  MPM_CALL(mpm_config_get_string(s->cfg, "run.progress", &mode));
  if (strcmp(mode, "off") == 0 || strcmp(mode, "false") == 0)
    s->progress = PROGRESS_OFF;
  else if (strcmp(mode, "log") == 0)
    s->progress = PROGRESS_LOG;
  else if (strcmp(mode, "live") == 0)
    s->progress = PROGRESS_LIVE;
  else /* auto, true */
    s->progress = mpm_log_console_is_terminal() ? PROGRESS_LIVE : PROGRESS_LOG;
  return 0;
}

static int read_run_settings(mpm_sim *s) {
  MPM_CALL(mpm_config_get_real(s->cfg, "time.t_end", &s->t_end));
  MPM_CALL(mpm_config_get_real(s->cfg, "output.interval", &s->out_interval));
  MPM_CALL(mpm_config_get_real(s->cfg, "output.checkpoint_interval", &s->ckpt_interval));
  MPM_CALL(mpm_config_get_int(s->cfg, "run.sort_every", &s->sort_every));
  MPM_CALL(read_progress(s));
  MPM_CALL(mpm_config_get_real(s->cfg, "run.progress_interval", &s->progress_interval));
  MPM_CALL(mpm_config_get_bool(s->cfg, "output.snapshots", &s->snapshots));
  MPM_CALL(mpm_config_get_bool(s->cfg, "output.grid_fields", &s->grid_fields));
  MPM_CALL(mpm_config_get_string(s->cfg, "output.dir", &s->dir));
  if (!s->dir[0])
    return mpm_config_fail(s->cfg, "output.dir", "is empty; name the folder to write into");
  MPM_CALL(mpm_config_get_bool(s->cfg, "output.overwrite", &s->overwrite));
  MPM_CALL(mpm_config_get_bool(s->cfg, "output.truncate", &s->truncate));
  /* Rank 0 looks at the folder (a file system need not look the same everywhere). */
  char why[1024] = "";
  int bad = s->rank == 0 ? mpm_rundir_check_dir(s->dir, s->overwrite, why, sizeof why) : 0;
  MPM_CALL_MPI(MPI_Bcast(&bad, 1, MPI_INT, 0, s->comm));
  if (bad) return mpm_config_fail(s->cfg, "output.dir", "%s", why);
  if (s->out_interval <= 0) s->out_interval = s->t_end / 10;
  if (s->ckpt_interval <= 0) s->ckpt_interval = HUGE_VAL;
  return 0;
}

static int build_modules(mpm_sim *s, int seed) {
  mpm_module *solid = NULL, *fluid = NULL;
  MPM_CALL(solid_module_create(&solid, s->cfg, s->grid, seed));
  if (solid) s->mod[s->nmod++] = solid;
  MPM_CALL(fluid_module_create(&fluid, s->cfg, s->grid, seed));
  if (fluid) s->mod[s->nmod++] = fluid;
  if (solid && fluid && fluid_module_reads_beside(fluid)) fluid->beside = solid->ops->points(solid);
  if (s->nmod == 0)
    return mpm_config_fail(s->cfg, "solid",
                           "the case defines neither bodies nor gas: add a [solid.NAME] or a "
                           "[gas.NAME] section");
  MPM_CALL(mpm_coupling_new(&s->coupling, s->cfg, s->grid, s->mod, s->nmod));
  if (s->coupling && solid && fluid) s->coupling->hand_over = fluid_module_hands_over(fluid);
  if (seed) MPM_CALL(mpm_scene_check_overlaps(s->cfg, s->grid, s->mod, s->nmod));
  /* The walls a coupling scheme offers are attached: a module that needs one and has none says
   * so now (mpm_module.h). */
  for (int k = 0; k < s->nmod; ++k) {
    int taken;
    if (s->mod[k]->ops->attach_wall)
      MPM_CALL(s->mod[k]->ops->attach_wall(s->mod[k], s->cfg, NULL, &taken));
  }
  /* The hierarchy over the built grid and phases; the gas reseeds its finer regions; the
   * coupling acts on every level. */
  MPM_CALL(mpm_refine_build(&s->hier, s->cfg, s->grid, s->mod, s->nmod, seed));
  return mpm_coupling_set_hier(s->coupling, s->cfg, s->hier);
}

static const char *const g_diag_cols[] = {"t",       "step",     "dt",    "particles",
                                          "mass",    "px",       "py",    "pz",
                                          "kinetic", "internal", "total", "rhs_evals"};
enum { NDIAG = (int)(sizeof g_diag_cols / sizeof g_diag_cols[0]) };
/* Appended when refined: the particles on each level (mpm_hier_count_levels). */
static const char *const g_level_cols[MPM_HIER_MAX_LEVELS] = {
    "particles_l0", "particles_l1", "particles_l2", "particles_l3", "particles_l4"};

/* diagnostics.csv's columns: g_diag_cols, then one per level when refined (refine.levels of
 * them when regridding: a regrid may build fewer levels, or none, for a while). */
static int diag_columns(mpm_sim *s, const char **cols, int *ncols) {
  int n = 0, levels = 0;
  for (int k = 0; k < NDIAG; ++k) cols[n++] = g_diag_cols[k];
  if (s->dynamic) MPM_CALL(mpm_config_get_int(s->cfg, "refine.levels", &levels));
  s->diag_levels = s->dynamic ? levels : s->hier ? s->hier->nlevels : 0;
  for (int l = 0; l < s->diag_levels; ++l) cols[n++] = g_level_cols[l];
  *ncols = n;
  return 0;
}

/* coupling.csv: the interface force on each phase (the momentum the other gives it per unit
 * time; they cancel), the power of each, their sum (the energy rate the coupling creates), its
 * time integral, the gas mass on nodes inside the solid, and each phase's total energy. */
static const char *const g_coupling_cols2[] = {
    "t",       "step",    "dt",    "Fx_solid", "Fy_solid",   "Fx_fluid", "Fy_fluid",
    "P_solid", "P_fluid", "P_net", "W_net",    "gas_inside", "E_solid",  "E_fluid"};
static const char *const g_coupling_cols3[] = {
    "t",        "step",    "dt",      "Fx_solid", "Fy_solid", "Fz_solid",   "Fx_fluid", "Fy_fluid",
    "Fz_fluid", "P_solid", "P_fluid", "P_net",    "W_net",    "gas_inside", "E_solid",  "E_fluid"};
#define NCOUPLING(dim) ((dim) == 2 ? 14 : 16)

/* run.log: what rank 0 logged so far (held since the start) and from now on. A restart in
 * place appends after a separator naming the checkpoint and the time. */
static void open_log(mpm_sim *s, int append) {
  char path[4096], sep[4400], when[64] = "?";
  const time_t now = time(NULL);
  struct tm tm;
  if (gmtime_r(&now, &tm)) strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S UTC", &tm);
  snprintf(path, sizeof path, "%s/run.log", s->dir);
  snprintf(sep, sizeof sep, "==== restart from %s (t = %.6g, step %ld), %s ====",
           s->checkpoint ? s->checkpoint : "?", s->t, s->step, when);
  mpm_log_file_open(path, append, sep);
}

/* Claim the output folder (see mpm_rundir.h), then open the outputs in it: continued from the
 * checkpoint's time when the run carries on its folder's record, new otherwise. */
static int open_outputs(mpm_sim *s) {
  char path[4096];
  int append;
  const mpm_rundir_request req = {s->dir,        s->overwrite, s->truncate,
                                  s->checkpoint, s->t,         s->run_id};
  MPM_CALL(mpm_rundir_claim(&s->rundir, s->comm, &req, &append, &s->run_id, &s->ckpt_number));
  open_log(s, append);
  MPM_CALL(mpm_config_resolved_text(s->cfg, &s->config_text));
  MPM_CALL(mpm_output_new(&s->out, s->comm, s->dir, s->config_text, s->grid->dim, append, s->t));
  MPM_CALL(mpm_output_set_hier(s->out, s->hier)); /* NULL: unrefined */
  snprintf(path, sizeof path, "%s/diagnostics.csv", s->dir);
  const char *dcols[NDIAG + MPM_HIER_MAX_LEVELS];
  int nd = 0;
  MPM_CALL(diag_columns(s, dcols, &nd));
  MPM_CALL(mpm_diag_open(&s->diag, s->comm, path, nd, dcols, append, s->t));
  if (s->probes.n > 0) {
    const char *pcols[MPM_PROBE_MAX * 2 * MPM_MAX_DIM + 1];
    const int np = mpm_probes_columns(&s->probes, pcols);
    snprintf(path, sizeof path, "%s/probes.csv", s->dir);
    MPM_CALL(mpm_diag_open(&s->probe_csv, s->comm, path, np, pcols, append, s->t));
  }
  if (!s->coupling) return 0;
  const int dim = s->grid->dim, nb = s->coupling->nbodies;
  const char *cols[NCOUPLING(3) + MPM_MAX_DIM * MPM_COUPLING_MAX_BODIES];
  int n = NCOUPLING(dim);
  memcpy(cols, dim == 2 ? g_coupling_cols2 : g_coupling_cols3, sizeof *cols * (size_t)n);
  for (int b = 0; b < nb; ++b) { /* F<axis>_<body>, the body named without its "solid." */
    const char *name = strrchr(s->coupling->body_name[b], '.');
    name = name ? name + 1 : s->coupling->body_name[b];
    for (int d = 0; d < dim; ++d) {
      snprintf(s->body_cols[b][d], sizeof s->body_cols[b][d], "F%c_%s", "xyz"[d], name);
      cols[n++] = s->body_cols[b][d];
    }
  }
  snprintf(path, sizeof path, "%s/coupling.csv", s->dir);
  return mpm_diag_open(&s->coupling_csv, s->comm, path, n, cols, append, s->t);
}

static int sim_alloc(mpm_sim **sp, mpm_config *cfg) {
  mpm_sim *s;
  MPM_ALLOC(s, 1);
  *sp = s;
  s->cfg = cfg;
  s->dynamic = mpm_refine_dynamic(cfg);
  s->comm = MPI_COMM_WORLD;
  MPI_Comm_rank(s->comm, &s->rank);
  MPI_Comm_size(s->comm, &s->size);
  MPM_CALL(read_run_settings(s));
  return build_grid(s);
}

/* ---- the run's budget ------------------------------------------------------------------ */

/* Bytes of one snapshot or checkpoint: every particle's fields, and the grid fields. */
static int output_bytes(const mpm_sim *s, double *bytes) {
  double local = 0;
  for (int k = 0; k < s->nmod; ++k)
    local += 8.0 * s->mod[k]->particles->ncomp * s->mod[k]->particles->n;
  MPM_CALL_MPI(MPI_Allreduce(&local, bytes, 1, MPI_DOUBLE, MPI_SUM, s->comm));
  if (s->grid_fields) {
    double nodes = 1;
    for (int d = 0; d < s->grid->dim; ++d) nodes *= s->grid->ncells[d] + 1.0;
    *bytes += 8.0 * nodes * (1 + s->grid->dim) * s->nmod;
  }
  return 0;
}

/* Refuse an absurd run before it starts (mpm_budget.h). */
static int check_budget(mpm_sim *s, int restart) {
  mpm_budget b = {.restart = restart,
                  .t = s->t,
                  .t_end = s->t_end,
                  .out_interval = s->out_interval,
                  .ckpt_interval = s->ckpt_interval,
                  .snapshots = s->snapshots};
  MPM_CALL(mpm_timescheme_cfl_step(s->it, &b.h0));
  MPM_CALL(mpm_timescheme_work(s->it, &b.work, &b.need, &b.work_key));
  MPM_CALL(output_bytes(s, &b.bytes));
  return mpm_budget_check(s->cfg, &b, &s->estimate);
}

static int between_substeps(void *ctx, mpm_module *m, double t, double h, int *changed);

/* A checkpoint whose time is so large that a step of its state would not change it (an
 * edited time) could only take steps of zero length: refused like a damaged one. */
static int check_advance(mpm_sim *s, const char *path) {
  double h0;
  MPM_CALL(mpm_timescheme_cfl_step(s->it, &h0));
  if (!(h0 > 0) || s->t + h0 > s->t) return 0;
  mpm_log(MPM_LOG_ERROR,
          "the checkpoint '%s' cannot be continued: at its time t = %.17g a step of %.3g s (the "
          "step its state allows) does not change the time (a double resolves %.3g s there). "
          "Restart from an earlier checkpoint",
          path, s->t, h0, nextafter(s->t, HUGE_VAL) - s->t);
  return MPM_ERR_INPUT;
}

int mpm_sim_create(mpm_sim **sp, mpm_config *cfg) {
  MPM_CALL(sim_alloc(sp, cfg));
  mpm_sim *s = *sp;
  MPM_CALL(build_modules(s, 1));
  MPM_CALL(mpm_probes_new(&s->probes, cfg, s->mod, s->nmod));
  s->out_next = 0;
  s->ckpt_next = 1;
  MPM_CALL(mpm_timescheme_new(&s->it, cfg, s->grid, s->mod, s->nmod, s->coupling));
  s->it->between = between_substeps, s->it->between_ctx = s;
  return check_budget(s, 0);
}

/* The run's RHS evaluations up to the checkpoint. A checkpoint from before they were kept
 * continues from its step count: exact for usl and musl (one evaluation a step), a lower
 * bound for the ERK pairs (at least one a step). */
static int restore_rhs_count(mpm_sim *s, const mpm_checkpoint *ck, const char *path, double step) {
  s->rhs_before = step;
  if (!mpm_checkpoint_attr_optional(ck, "rhs_evals", &s->rhs_before)) return 0;
  if (!(s->rhs_before >= step && s->rhs_before <= 0x1p53 && s->rhs_before == floor(s->rhs_before)))
    MPM_FAIL_ON_ROOT(s->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' is damaged: its RHS evaluation count rhs_evals is %.17g, "
                     "not a whole number at least its step count %.17g. Restart from an earlier "
                     "checkpoint",
                     path, s->rhs_before, step);
  return 0;
}

static int follow_levels(mpm_sim *s, int resize);

int mpm_sim_restart(mpm_sim **sp, mpm_config *cfg, const char *path) {
  MPM_CALL(sim_alloc(sp, cfg));
  mpm_sim *s = *sp;
  MPM_CALL(build_modules(s, 0));
  mpm_checkpoint *ck = NULL;
  MPM_CALL(mpm_checkpoint_open(&ck, s->comm, path));
  double step;
  int rc = mpm_checkpoint_attr(ck, "t", &s->t);
  if (!rc) rc = mpm_checkpoint_attr(ck, "step", &step);
  if (!rc) rc = mpm_checkpoint_attr(ck, "h_next", &s->h_next);
  /* Checkpoints from before the coupler have no coupling work: it was zero. */
  if (!rc && s->coupling) rc = mpm_checkpoint_attr(ck, "coupling_work", &s->coupling_work);
  if (!rc) mpm_checkpoint_attr_optional(ck, "run_id", &s->run_id); /* 0: from before run ids */
  /* The summary's scale of the coupling work (0: a checkpoint from before it was kept). */
  if (!rc) mpm_checkpoint_attr_optional(ck, "coupling_crossed", &s->coupling_crossed);
  if (!rc) mpm_checkpoint_attr_optional(ck, "solid_peak", &s->solid_peak);
  if (!rc) rc = restore_rhs_count(s, ck, path, step);
  if (!rc && !(s->checkpoint = strdup(path))) rc = MPM_ERR_MEMORY;
  for (int k = 0; !rc && k < s->nmod; ++k)
    rc = mpm_checkpoint_read_particles(ck, s->mod[k]->name, s->mod[k]->particles);
  /* The probes follow the particles the run started with (a checkpoint without them, from a
   * run without probes, starts them here). */
  if (!rc) rc = mpm_probes_new(&s->probes, cfg, s->mod, s->nmod);
  if (!rc) mpm_probes_restore(&s->probes, ck);
  if (rc) mpm_checkpoint_close(&ck);
  MPM_CALL(rc);
  if (s->t_end <= s->t * (1 + 1e-14)) {
    mpm_checkpoint_close(&ck);
    return mpm_config_fail(cfg, "time.t_end",
                           "the checkpoint is at t = %.6g, so there is nothing to run until "
                           "t_end = %.6g; restart with time.t_end=<a later time>",
                           s->t, s->t_end);
  }
  s->step = (long)step;
  /* Outputs continue on the (possibly new) intervals: the next ones after t. Written at t
   * already, so strictly after it. */
  s->out_next = (long)floor(s->t / s->out_interval * (1 + 1e-12)) + 1;
  s->ckpt_next =
      isfinite(s->ckpt_interval) ? (long)floor(s->t / s->ckpt_interval * (1 + 1e-12)) + 1 : 1;
  for (int k = 0; !rc && k < s->nmod; ++k)
    rc = mpm_particles_migrate(s->mod[k]->particles, s->grid, NULL);
  /* A dynamic refinement's hierarchy, from the particles as the run regridded before writing. */
  int regridded = 0;
  if (!rc && s->dynamic)
    rc = mpm_refine_regrid(&s->hier, cfg, s->grid, s->mod, s->nmod, s->step, 1, &regridded);
  if (!rc && regridded) rc = mpm_coupling_set_hier(s->coupling, cfg, s->hier);
  /* The particles follow the levels, as the run did after writing the checkpoint (always: the
   * run's regrid may have kept its regions, or dropped them all, where this one builds). */
  if (!rc && s->dynamic) rc = follow_levels(s, 0);
  /* The time scheme's own state (a partitioned scheme's owed momentum) follows the particles. */
  if (!rc) rc = mpm_timescheme_new(&s->it, cfg, s->grid, s->mod, s->nmod, s->coupling);
  if (!rc) rc = mpm_timescheme_restore(s->it, ck);
  mpm_checkpoint_close(&ck);
  MPM_CALL(rc);
  s->it->between = between_substeps, s->it->between_ctx = s;
  MPM_CALL(check_advance(s, path));
  MPM_CALL(check_budget(s, 1));
  mpm_log(MPM_LOG_INFO, "restarted from %s at t = %.6g, step %ld", path, s->t, s->step);
  return 0;
}

void mpm_sim_destroy(mpm_sim **sp) {
  if (!sp || !*sp) return;
  mpm_sim *s = *sp;
  mpm_timescheme_destroy(&s->it);
  mpm_coupling_destroy(&s->coupling);
  for (int k = 0; k < s->nmod; ++k) mpm_module_destroy(&s->mod[k]);
  mpm_hier_destroy(&s->hier);
  mpm_output_destroy(&s->out);
  mpm_diag_close(&s->diag);
  mpm_diag_close(&s->coupling_csv);
  mpm_diag_close(&s->probe_csv);
  mpm_guard_free(&s->guard);
  mpm_grid_destroy(&s->grid);
  mpm_rundir_release(&s->rundir);
  mpm_log_file_close();
  free(s->checkpoint);
  free(s->config_text);
  free(s);
  *sp = NULL;
}

/* ---- the step loop --------------------------------------------------------------------- */

/* Derived output fields are refreshed only when they are written. */
static int prepare_output(mpm_sim *s) {
  for (int k = 0; k < s->nmod; ++k)
    if (s->mod[k]->ops->output) MPM_CALL(s->mod[k]->ops->output(s->mod[k]));
  return 0;
}

static int write_snapshot(mpm_sim *s) {
  const mpm_particles *p[SIM_MAX_MODULES];
  MPM_CALL(prepare_output(s));
  const char *names[SIM_MAX_MODULES];
  for (int k = 0; k < s->nmod; ++k) p[k] = s->mod[k]->particles, names[k] = s->mod[k]->name;
  mpm_timer_start(MPM_T_IO);
  int rc = mpm_output_snapshot(s->out, s->t, s->step, p, names, s->nmod,
                               s->grid_fields ? s->grid : NULL);
  mpm_timer_stop(MPM_T_IO);
  return rc;
}

/* The run's RHS evaluations so far, restarts included. */
static double rhs_evals(const mpm_sim *s) {
  long steps, rhs, fails, retries;
  mpm_timescheme_counts(s->it, &steps, &rhs, &fails, &retries);
  return s->rhs_before + (double)rhs;
}

static int write_checkpoint(mpm_sim *s, const char *path) {
  const mpm_particles *p[SIM_MAX_MODULES + 1];
  MPM_CALL(prepare_output(s));
  const char *names[SIM_MAX_MODULES + 1];
  for (int k = 0; k < s->nmod; ++k) p[k] = s->mod[k]->particles, names[k] = s->mod[k]->name;
  /* The time scheme's own state, as one more particle set. */
  mpm_particles *own = NULL;
  MPM_CALL(mpm_timescheme_save(s->it, &own, &names[s->nmod]));
  p[s->nmod] = own;
  enum { NA = 8, MAXA = NA + MPM_PROBE_MAX * (1 + MPM_MAX_DIM) };
  const char *attr[MAXA] = {
      "t",          "step",     "h_next", "coupling_work", "run_id", "coupling_crossed",
      "solid_peak", "rhs_evals"};
  double val[MAXA] = {s->t,      (double)s->step,     s->h_next,     s->coupling_work,
                      s->run_id, s->coupling_crossed, s->solid_peak, rhs_evals(s)};
  const int na = NA + mpm_probes_attrs(&s->probes, attr + NA, val + NA, MAXA - NA);
  mpm_timer_start(MPM_T_IO);
  int rc = mpm_checkpoint_write(s->comm, path, s->config_text, attr, val, na, p, names,
                                s->nmod + (own != NULL));
  mpm_timer_stop(MPM_T_IO);
  mpm_particles_destroy(&own);
  MPM_CALL(rc);
  mpm_log(MPM_LOG_INFO, "checkpoint %s at t = %.6g", path, s->t);
  return 0;
}

/* One row of coupling.csv for the step of size dt that reached s->t; energy[r] is the total
 * energy of the phase of role r. */
static int coupling_row(mpm_sim *s, double dt, const double *energy) {
  mpm_coupling_record r;
  MPM_CALL(mpm_timescheme_record(s->it, s->t, &r));
  const int dim = s->grid->dim, S = MPM_ROLE_SOLID, F = MPM_ROLE_FLUID;
  const double net = r.power[S] + r.power[F];
  double row[NCOUPLING(3) + MPM_MAX_DIM * MPM_COUPLING_MAX_BODIES], fs = 0, ff = 0, fsum = 0;
  int c = 0;
  if (dt > 0) s->coupling_work += dt * net;
  /* What crossed: the work of the interface force on the side that gave the energy up (the
   * larger in size; the other side received that less what the coupling destroyed). */
  if (dt > 0) s->coupling_crossed += dt * fmax(fabs(r.power[S]), fabs(r.power[F]));
  s->solid_peak = fmax(s->solid_peak, energy[S]);
  row[c++] = s->t, row[c++] = (double)s->step, row[c++] = dt;
  for (int d = 0; d < dim; ++d) row[c++] = r.force[S][d];
  for (int d = 0; d < dim; ++d) row[c++] = r.force[F][d];
  /* The momentum the fluid gives up at the interface reaches the solid, now or (staggered) at
   * its next advance: F_solid + F_fluid + d(owed)/dt = 0. */
  for (int d = 0; d < dim; ++d) {
    const double late = dt > 0 ? (r.owed[d] - s->owed[d]) / dt : 0.0;
    fs += r.force[S][d] * r.force[S][d], ff += r.force[F][d] * r.force[F][d];
    fsum += (r.force[S][d] + r.force[F][d] + late) * (r.force[S][d] + r.force[F][d] + late);
    s->owed[d] = r.owed[d];
  }
  if (fs + ff > 0) s->coupling_imbalance = fmax(s->coupling_imbalance, sqrt(fsum / fmax(fs, ff)));
  row[c++] = r.power[S], row[c++] = r.power[F], row[c++] = net, row[c++] = s->coupling_work;
  row[c++] = r.gas_inside, row[c++] = energy[S], row[c++] = energy[F];
  for (int b = 0; b < s->coupling->nbodies; ++b)
    for (int d = 0; d < dim; ++d) row[c++] = r.body[b][d];
  return mpm_diag_row(s->coupling_csv, row);
}

/* The sums of a diagnostics row: [0] particles, [1] mass, [2..4] momentum, [5] kinetic, [6]
 * internal, [8 + role] each role's total energy, then ROW_LEVELS.. the particles per level. */
enum { ROW_LEVELS = 10, ROW_SUMS = ROW_LEVELS + MPM_HIER_MAX_LEVELS };

static int diagnostics_row(mpm_sim *s, double dt) {
  double local[ROW_SUMS] = {0}, sum[ROW_SUMS];
  for (int k = 0; k < s->nmod; ++k) {
    mpm_module_sums m;
    s->mod[k]->ops->sums(s->mod[k], &m);
    local[0] += s->mod[k]->particles->n;
    local[1] += m.mass;
    for (int d = 0; d < MPM_MAX_DIM; ++d) local[2 + d] += m.momentum[d];
    local[5] += m.kinetic;
    local[6] += m.internal;
    local[8 + s->mod[k]->role] += m.kinetic + m.internal;
    if (s->hier)
      mpm_hier_count_levels(s->hier, s->mod[k]->particles, local + ROW_LEVELS);
    else if (s->diag_levels) /* a regridded run with nothing refined just now */
      local[ROW_LEVELS] += (double)s->mod[k]->particles->n;
  }
  MPM_CALL_MPI(MPI_Allreduce(local, sum, ROW_SUMS, MPI_DOUBLE, MPI_SUM, s->comm));
  s->energy = sum[5] + sum[6], s->kinetic = sum[5];
  if (s->coupling) MPM_CALL(coupling_row(s, dt, sum + 8));
  double row[NDIAG + MPM_HIER_MAX_LEVELS] = {
      s->t,   (double)s->step, dt,     sum[0], sum[1],          sum[2],
      sum[3], sum[4],          sum[5], sum[6], sum[5] + sum[6], rhs_evals(s)};
  for (int l = 0; l < s->diag_levels; ++l) row[NDIAG + l] = sum[ROW_LEVELS + l];
  if (dt > 0) s->particle_steps += sum[0]; /* the row at t = 0 is not a step */
  if (s->probes.n > 0) {
    double prow[MPM_PROBE_MAX * 2 * MPM_MAX_DIM + 1];
    MPM_CALL(mpm_probes_row(&s->probes, s->mod, s->t, prow));
    MPM_CALL(mpm_diag_row(s->probe_csv, prow));
  }
  return mpm_diag_row(s->diag, row);
}

/* Total and kinetic energy of every module, summed over the ranks (as diagnostics_row does). */
static int energies(mpm_sim *s) {
  double local[2] = {0.0, 0.0}, sum[2];
  for (int k = 0; k < s->nmod; ++k) {
    mpm_module_sums m;
    s->mod[k]->ops->sums(s->mod[k], &m);
    local[0] += m.kinetic, local[1] += m.internal;
  }
  MPM_CALL_MPI(MPI_Allreduce(local, sum, 2, MPI_DOUBLE, MPI_SUM, s->comm));
  s->energy = sum[0] + sum[1], s->kinetic = sum[0];
  return 0;
}

static int diagnostics(mpm_sim *s, double dt) {
  mpm_timer_start(MPM_T_DIAG);
  int rc = diagnostics_row(s, dt);
  mpm_timer_stop(MPM_T_DIAG);
  return rc;
}

/* Between two substeps of one module inside a coupling step (mpm_timescheme_between). */
static int between_substeps(void *ctx, mpm_module *m, double t, double h, int *changed) {
  mpm_sim *s = ctx;
  int migrated = 0;
  mpm_timer_start(MPM_T_BOUNDARY);
  int rc = m->ops->boundary ? m->ops->boundary(m, t, h, changed) : 0;
  mpm_timer_stop(MPM_T_BOUNDARY);
  mpm_timer_start(MPM_T_MIGRATE);
  if (!rc) rc = mpm_particles_migrate(m->particles, s->grid, &migrated);
  mpm_timer_stop(MPM_T_MIGRATE);
  *changed |= migrated;
  return rc;
}

/* Between steps: particles enter and leave through the boundary (timer phase `boundary`), move
 * to their owners and are sorted now and then (`migrate`); the cells' occupancy is counted when
 * a module asks for it, the modules do their post-step work and the integrator is told
 * (`post_step`). */
static int after_step(mpm_sim *s, double h) {
  int changed[SIM_MAX_MODULES] = {0}, changed_any = 0, want_cells = 0;
  for (int k = 0; k < s->nmod; ++k) {
    mpm_module *m = s->mod[k];
    int migrated = 0;
    m->step = s->step;
    mpm_timer_start(MPM_T_BOUNDARY);
    if (m->ops->boundary) MPM_CALL(m->ops->boundary(m, s->t, h, &changed[k]));
    mpm_timer_stop(MPM_T_BOUNDARY);
    mpm_timer_start(MPM_T_MIGRATE);
    MPM_CALL(mpm_particles_migrate(m->particles, s->grid, &migrated));
    changed[k] |= migrated;
    if (s->sort_every > 0 && s->step % s->sort_every == 0) {
      MPM_CALL(mpm_particles_sort(m->particles, s->grid));
      changed[k] = 1;
    }
    want_cells |= m->cells_every > 0 && s->step % m->cells_every == 0;
    mpm_timer_stop(MPM_T_MIGRATE);
  }
  mpm_timer_start(MPM_T_POST);
  for (int k = 0; want_cells && k < s->nmod; ++k) {
    MPM_CALL(mpm_cells_count(s->grid, s->mod[k]->phase, s->mod[k]->particles));
    if (s->hier)
      MPM_CALL(mpm_cells_count_levels(s->hier, s->mod[k]->phase, s->mod[k]->particles, NULL));
  }
  for (int k = 0; k < s->nmod; ++k) {
    mpm_module *m = s->mod[k];
    if (m->ops->post_step) MPM_CALL(m->ops->post_step(m, s->t, h, &changed[k]));
    changed_any |= changed[k];
  }
  /* A module's own changes may be local to a rank; the resize is collective. */
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &changed_any, 1, MPI_INT, MPI_LOR, s->comm));
  if (changed_any) MPM_CALL(mpm_timescheme_resize(s->it, s->t));
  mpm_timer_stop(MPM_T_POST);
  return 0;
}

/* After a regrid: the gas's particles split and merge onto the new levels (mpm_refine_follow),
 * and with resize the integrator follows them (without, the caller starts it afresh). */
static int follow_levels(mpm_sim *s, int resize) {
  int changed = 0;
  mpm_timer_start(MPM_T_REGRID);
  int rc = mpm_refine_follow(s->mod, s->nmod, &changed);
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_LOR, s->comm));
  if (!rc && changed && resize) rc = mpm_timescheme_resize(s->it, s->t);
  mpm_timer_stop(MPM_T_REGRID);
  return rc;
}

/* A dynamic refinement's regrid (mpm_refine.h), after the step's own work: every refine.every
 * steps, and before a checkpoint (force), so that a restart, which regrids from the checkpoint's
 * particles, continues on the same hierarchy. The integrator restarts its RHS on the new one, and
 * the particles follow the new levels at once (a particle left a level or more too coarse for a
 * step deposits one point where its new level has 2^dim or more nodes a span, and the sparse
 * nodes between then take the tails of its stencil: on Sod over 4 levels such a step compressed
 * the new level-3 particles threefold in two steps and blew the run up). Before a checkpoint
 * (force) they follow after it is written, whether or not the regions changed, as they do after
 * every restart's regrid, so that the checkpoint holds the particles the restart regrids from
 * and both relevel alike (mpm_sim_run). */
static int regrid(mpm_sim *s, int force) {
  int changed = 0;
  if (!s->dynamic) return 0;
  mpm_timer_start(MPM_T_REGRID);
  int rc = mpm_refine_regrid(&s->hier, s->cfg, s->grid, s->mod, s->nmod, s->step, force, &changed);
  if (!rc && changed) rc = mpm_output_set_hier(s->out, s->hier);
  if (!rc && changed) rc = mpm_coupling_set_hier(s->coupling, s->cfg, s->hier);
  if (!rc && changed) rc = mpm_timescheme_resize(s->it, s->t);
  mpm_timer_stop(MPM_T_REGRID);
  MPM_CALL(rc);
  return changed && !force ? follow_levels(s, 1) : 0;
}

/* The step count, refined once the run has taken ESTIMATE_AFTER steps. The starting state's
 * stable step (the budget's estimate, mpm_budget.h) is often not the step the run settles to:
 * the artificial viscosity that limits the step at a shock needs the velocity divergence,
 * which is zero in a state at rest or in uniform flow and appears with the first step (Sod
 * and the main job settle to 0.3 and 0.5 of it within a few steps); an adaptive pair starts
 * from a tiny step and its error control may keep it below the stability limit. Neither is
 * known before the run. The model: the rest of the run goes at the median step of the latest
 * half of those steps (the median ignores the steps cut short at output times and the
 * adaptive pairs' first steps), plus one step per output time left. */
static void refine_estimate(mpm_sim *s, double dt) {
  const long k = s->step - s->step0;
  if (k >= 1 && k <= ESTIMATE_AFTER) s->dt_first[k - 1] = dt;
  if (k != ESTIMATE_AFTER || s->t >= s->t_end) return;
  double h[ESTIMATE_AFTER / 2];
  const int n = ESTIMATE_AFTER / 2;
  memcpy(h, s->dt_first + ESTIMATE_AFTER - n, sizeof h);
  for (int i = 1; i < n; ++i) /* insertion sort: ten numbers */
    for (int j = i; j > 0 && h[j] < h[j - 1]; --j) {
      const double x = h[j];
      h[j] = h[j - 1], h[j - 1] = x;
    }
  const double med = 0.5 * (h[(n - 1) / 2] + h[n / 2]), span = s->t_end - s->t;
  if (!(med > 0)) return;
  const double nout = floor(span / s->out_interval * (1 + 1e-12));
  const double before = s->estimate;
  s->estimate = (double)k + span / med + nout;
  mpm_log(MPM_LOG_INFO,
          "estimate after %ld steps: about %.3g steps in all (the step has settled to %.3g s; "
          "the estimate before the run was %.3g)",
          k, s->estimate, med, before);
}

/* Progress, rank 0. Live (run.progress, read_progress): a line on the terminal redrawn at most
 * twice a second, ended with a newline at the end (mpm_log clears it before any other line),
 * and a progress line in run.log every progress_interval seconds. Log: that line on the
 * console as well, so that a batch job or a pipe is never silent for long. The ETA is the
 * measured rate: wall time so far over the simulated time reached. */
static void progress(mpm_sim *s, double dt, double wall0, int final) {
  if (s->progress == PROGRESS_OFF || s->rank != 0) return;
  const int live = s->progress == PROGRESS_LIVE;
  const double now = MPI_Wtime(), wall = now - wall0;
  const double frac = s->t / s->t_end, eta = frac > 0 ? wall * (1 - frac) / frac : 0;
  /* Before 1 % of the run the rate is that of the first steps (an adaptive pair's tiny ones,
   * the start-up's I/O): no ETA yet. */
  char eta_s[32] = "ETA ?";
  if (frac >= 0.01) snprintf(eta_s, sizeof eta_s, "ETA %.0f s", eta);
  if (s->progress_last == 0) s->progress_last = s->progress_logged = wall0;
  const int log_due = now - s->progress_logged >= s->progress_interval && !final;
  if (log_due) {
    s->progress_logged = s->progress_last = now;
    char line[256];
    snprintf(line, sizeof line,
             "progress: step %ld, t = %.6g (%.1f%%), dt = %.3g, %.0f s wall, ETA %.0f s", s->step,
             s->t, 100 * frac, dt, wall, eta);
    if (live) /* the console has the live line: the log line goes to run.log only */
      mpm_log_record(MPM_LOG_INFO, "%s", line);
    else
      mpm_log(MPM_LOG_INFO, "%s", line);
  }
  if (!live || (!final && now - s->progress_last < 0.5 && !log_due)) return;
  s->progress_last = now;
  char of[32] = "";
  if (s->estimate > 0) snprintf(of, sizeof of, " of ~%.0f", s->estimate + (double)s->step0);
  mpm_log_status("step %ld%s  t = %.5g (%.1f%%)  dt = %.3g  wall %.0f s  %s", s->step, of, s->t,
                 100 * frac, dt, wall, eta_s);
  if (final) mpm_log_status_end();
}

static int summary_json(const mpm_sim *s, double wall, char *path, size_t n);

static int write_summary(mpm_sim *s, double wall) {
  long steps, rhs, fails, retries;
  mpm_timescheme_counts(s->it, &steps, &rhs, &fails, &retries);
  char path[4096];
  snprintf(path, sizeof path, "%s/timers.csv", s->dir);
  MPM_CALL(mpm_timer_report(s->comm, path));
  mpm_log(MPM_LOG_INFO,
          "done: t = %.6g, %ld steps (%ld rhs evaluations, %ld error-test failures, %ld "
          "retries), %.3f s wall, %.3g particle-steps/s",
          s->t, steps, rhs, fails, retries, wall, s->particle_steps / wall);
  /* The coupling's energy error on the scale of what it moves: the energy that crossed the
   * interface, the solid's peak energy (that of the body it drives) and the total energy. */
  const double rel_crossed = s->coupling_crossed > 0 ? s->coupling_work / s->coupling_crossed : 0;
  const double rel_solid = s->solid_peak > 0 ? s->coupling_work / s->solid_peak : 0;
  const double rel_total = s->energy > 0 ? s->coupling_work / s->energy : 0;
  if (s->coupling)
    mpm_log(
        MPM_LOG_INFO,
        "coupling %s: interface momentum imbalance at most %.2g of the interface force; "
        "energy created by the coupling %.6g J (%.3g %% of the %.3g J that crossed the "
        "interface, %.3g %% of the solid's peak energy %.3g J, %.3g %% of the total energy %.3g "
        "J)",
        s->coupling->type->name, s->coupling_imbalance, s->coupling_work, 100 * rel_crossed,
        s->coupling_crossed, 100 * rel_solid, s->solid_peak, 100 * rel_total, s->energy);
  int status = s->rank == 0 ? summary_json(s, wall, path, sizeof path) : 0;
  /* Rank 0 wrote it: every rank learns whether it could (MPM_ERR_OUTPUT, explained once). */
  MPM_CALL_MPI(MPI_Bcast(&status, 1, MPI_INT, 0, s->comm));
  MPM_CALL(status ? MPM_ERR_OUTPUT : 0);
  return 0;
}

/* Rank 0: summary.json (path is a buffer of size n). */
static int summary_json(const mpm_sim *s, double wall, char *path, size_t n) {
  long steps, rhs, fails, retries;
  mpm_timescheme_counts(s->it, &steps, &rhs, &fails, &retries);
  const double rel_crossed = s->coupling_crossed > 0 ? s->coupling_work / s->coupling_crossed : 0;
  const double rel_solid = s->solid_peak > 0 ? s->coupling_work / s->solid_peak : 0;
  const double rel_total = s->energy > 0 ? s->coupling_work / s->energy : 0;
  snprintf(path, n, "%s/summary.json", s->dir);
  FILE *f = mpm_file_begin(path, "w");
  if (!f) return mpm_file_fail(path, errno, "summary");
  fprintf(f,
          "{\"version\": \"%s\", \"t\": %.17g, \"steps\": %ld, \"rhs_evals\": %ld, "
          "\"error_test_fails\": %ld, "
          "\"retries\": %ld, \"wall_s\": %.6f, \"ranks\": %d, \"particle_steps\": %.17g, "
          "\"particle_steps_per_s\": %.6g, \"coupling\": \"%s\", "
          "\"coupling_imbalance\": %.6g, \"coupling_work\": %.17g, "
          "\"coupling_crossed\": %.17g, \"coupling_work_of_crossed\": %.6g, "
          "\"solid_energy_peak\": %.17g, \"coupling_work_of_solid\": %.6g, "
          "\"coupling_work_of_total\": %.6g, \"steps_estimated\": %.17g}\n",
          s->version ? s->version : "unknown", s->t, steps, rhs, fails, retries, wall, s->size,
          s->particle_steps, s->particle_steps / wall,
          s->coupling ? s->coupling->type->name : "none", s->coupling_imbalance, s->coupling_work,
          s->coupling_crossed, rel_crossed, s->solid_peak, rel_solid, rel_total, s->estimate);
  const int e = mpm_file_commit(f, path);
  if (e) return mpm_file_fail(path, e, "summary");
  return 0;
}

/* A run stopped as unphysical (the blow-up guard, or a step that failed its state checks or
 * its stability limit) leaves its last accepted state as one more snapshot (the series stays
 * valid: it is written like any other), to show where it failed. Only on that verdict, which
 * every rank reaches alike from reduced values: a local failure (no memory) must not enter the
 * collective write on one rank. */
static int stopped(mpm_sim *s, int rc) {
  if (rc == MPM_ERR_UNPHYSICAL && s->snapshots && write_snapshot(s) == 0)
    mpm_log(MPM_LOG_ERROR,
            "the state where the run stopped (t = %.6g, step %ld) is snapshot %ld "
            "of %s/series.xmf",
            s->t, s->step, (long)mpm_output_count(s->out) - 1, s->dir);
  return mpm_trace(__FILE__, __LINE__, __func__, rc);
}

/* The blow-up guard after an accepted step. */
static int guard(mpm_sim *s, double dt, double tstop) {
  const int rc = mpm_guard_check(&s->guard, s->t, s->step, dt, s->t >= tstop * (1 - 1e-14),
                                 s->energy, s->kinetic);
  return rc ? stopped(s, rc) : 0;
}

int mpm_sim_run(mpm_sim *s) {
  char path[4096];
  MPM_CALL(open_outputs(s));
  s->step0 = s->step;
  mpm_timer_reset();
  mpm_timer_start(MPM_T_TOTAL);
  const double wall0 = MPI_Wtime();
  MPM_CALL(mpm_timescheme_start(s->it, s->t, s->h_next));
  if (s->out_next == 0) {
    MPM_CALL(diagnostics(s, 0.0));
    if (s->snapshots) MPM_CALL(write_snapshot(s));
    s->out_next = 1;
  } else {
    MPM_CALL(energies(s));
  }
  if (s->coupling) { /* the interface momentum owed at the start (a restarted staggered run) */
    mpm_coupling_record r;
    MPM_CALL(mpm_timescheme_record(s->it, s->t, &r));
    memcpy(s->owed, r.owed, sizeof s->owed);
  }
  double h0;
  MPM_CALL(mpm_timescheme_cfl_step(s->it, &h0));
  MPM_CALL(mpm_guard_init(&s->guard, s->cfg, h0, s->energy, s->kinetic));
  const double t_stop = s->t_end * (1 - 1e-14);
  double dt = 0.0;
  int sig = 0;
  mpm_signal_catch();
  while (s->t < t_stop) {
    const double t_out = fmin(s->out_next * s->out_interval, s->t_end);
    const double t_ckpt = s->ckpt_next * s->ckpt_interval, tstop = fmin(t_out, t_ckpt);
    const int rc = mpm_timescheme_step(s->it, tstop, &s->t, &dt);
    if (rc) return stopped(s, rc); /* the state is the last accepted step's */
    s->step++;
    refine_estimate(s, dt);
    MPM_CALL(after_step(s, dt));
    const int ckpt_due = s->t >= t_ckpt * (1 - 1e-14) && s->t < t_stop;
    MPM_CALL(regrid(s, ckpt_due));
    MPM_CALL(diagnostics(s, dt));
    MPM_CALL(guard(s, dt, tstop));
    progress(s, dt, wall0, 0);
    if (s->t >= t_out * (1 - 1e-14)) {
      if (s->snapshots) MPM_CALL(write_snapshot(s));
      s->out_next++;
    }
    if (s->t >= t_ckpt * (1 - 1e-14) && s->t < t_stop) {
      s->h_next = mpm_timescheme_next_step(s->it);
      s->ckpt_next++;
      snprintf(path, sizeof path, "%s/checkpoint_%06ld.h5", s->dir, s->ckpt_number++);
      MPM_CALL(write_checkpoint(s, path));
      /* Exactly what a restart from this file does. */
      if (s->dynamic) MPM_CALL(follow_levels(s, 0)); /* after regrid(s, 1), as a restart */
      MPM_CALL(mpm_timescheme_start(s->it, s->t, s->h_next));
    }
    MPM_CALL(mpm_signal_agreed(s->comm, &sig));
    if (sig) break;
  }
  progress(s, dt, wall0, 1);
  s->h_next = mpm_timescheme_next_step(s->it);
  snprintf(path, sizeof path, "%s/checkpoint_final.h5", s->dir);
  MPM_CALL(write_checkpoint(s, path));
  mpm_timer_stop(MPM_T_TOTAL);
  MPM_CALL(write_summary(s, MPI_Wtime() - wall0));
  if (!sig) return 0;
  mpm_log(MPM_LOG_WARN,
          "stopped by %s at t = %.6g (step %ld) before t_end = %.6g; %s holds the state: continue "
          "with `mpmfsi restart %s`",
          mpm_signal_name(sig), s->t, s->step, s->t_end, path, path);
  return MPM_ERR_INTERRUPTED;
}

void mpm_sim_set_version(mpm_sim *s, const char *version) {
  s->version = version;
}

/* The MPM cycle (see mpm_cycle.h). */
#include "mpm_cycle.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_timer.h"

#include <stdlib.h>
#include <string.h>

#define CYCLE_MAX_FIELDS (4 * (2 + 3 * MPM_MAX_DIM))

/* Sum the ghosts into the owners (reverse: m, mv, f and the mass gradient where a scheme asks
 * for it) or copy the owners' v and a into the ghosts (forward), for the modules advanced. */
static int halo(const mpm_cycle *c, int reverse) {
  double *f[CYCLE_MAX_FIELDS];
  int nf = 0;
  const int dim = c->grid->dim;
  for (int k = 0; k < c->nmod; ++k) {
    mpm_grid_phase *ph = &c->grid->phase[c->mod[k]->phase];
    if (reverse) f[nf++] = ph->m_i;
    for (int d = 0; d < dim; ++d) {
      f[nf++] = reverse ? ph->mv_i[d] : ph->v_i[d];
      f[nf++] = reverse ? ph->f_i[d] : ph->a_i[d];
      if (reverse && ph->normals) f[nf++] = ph->normal_i[d];
    }
  }
  mpm_timer_start(MPM_T_HALO);
  int rc = reverse ? mpm_grid_halo_reverse(c->grid, f, nf) : mpm_grid_halo_forward(c->grid, f, nf);
  mpm_timer_stop(MPM_T_HALO);
  return rc;
}

/* The held solid, in a held cycle (NULL otherwise). */
static mpm_module *held(const mpm_cycle *c) {
  return c->mode == MPM_CYCLE_HELD ? c->coupling->module[MPM_ROLE_SOLID] : NULL;
}

/* The coupling between the solve and the constraints: the spatial scheme (joint, held: its
 * exchanges into the held solid are captured) or the load (loaded, first pass only). */
static int interact(const mpm_cycle *c, double t, double hs, mpm_pass pass) {
  if (c->mode == MPM_CYCLE_JOINT || c->mode == MPM_CYCLE_HELD)
    return mpm_coupling_after_solve(c->coupling, t, hs, pass);
  if (pass != MPM_PASS_FIRST) return 0;
  mpm_interface *ifc = c->iface;
  if (c->mode == MPM_CYCLE_FOLLOW) {
    mpm_coupling_follow_shared(c->coupling, t, hs, (const double *const *)ifc->v_gas, ifc->touched);
    return 0;
  }
  MPM_CALL(mpm_coupling_apply_load(c->coupling, t, hs, mpm_interface_load_at(ifc, t, hs),
                                   mpm_interface_mass_start(ifc)));
  if (ifc->m_gas)
    mpm_coupling_apply_shared(c->coupling, hs, ifc->m_gas, (const double *const *)ifc->f_gas,
                              (const double *const *)ifc->v_gas, ifc->v_now, ifc->touched_now);
  return 0;
}

/* ---- a refined module (mpm_module.h, hier): its phase on every level ------------------------- */

/* The nodal solve of a module's phase: on the grid, or on every level of its hierarchy. */
static int solve(mpm_grid *grid, const mpm_module *m, double hs) {
  return m->hier ? mpm_hier_phase_update(m->hier, m->phase, hs)
                 : mpm_grid_phase_update(grid, m->phase, hs);
}

/* Zero a module's phase before its deposit, on every level where it has a hierarchy. */
static void zero(mpm_grid *grid, const mpm_module *m) {
  if (m->hier)
    mpm_hier_phase_zero(m->hier, m->phase);
  else
    mpm_grid_phase_zero(grid, m->phase);
}

/* Move the deposits on the finer levels' inactive nodes onto their parents, for every refined
 * module (rate_only: those whose p2g_rate deposited more; restriction is linear and leaves the
 * inactive nodes at zero, so a second call moves only what was added since). */
static void restrict_deposits(const mpm_cycle *c, int rate_only) {
  for (int k = 0; k < c->nmod; ++k)
    if (c->mod[k]->hier && (!rate_only || c->mod[k]->ops->p2g_rate))
      mpm_hier_restrict(c->mod[k]->hier, c->mod[k]->phase);
}

/* The grid work between the transfers. The solve takes the step only in the first pass. */
static int grid_pass(const mpm_cycle *c, double t, double h, mpm_pass pass) {
  const double hs = pass == MPM_PASS_FIRST ? h : 0.0;
  mpm_module *hm = held(c);
  const int hooks = c->mode == MPM_CYCLE_JOINT || c->mode == MPM_CYCLE_HELD;
  MPM_CALL(halo(c, 1));
  mpm_timer_start(MPM_T_GRID);
  /* A loaded solid (a partitioned scheme's substep) is small beside the grid: its passes visit
   * its own nodes (mpm_grid_phase_narrow; mpm_partitioned.c widens it after its substeps, and
   * every other cycle sees its phases whole). */
  for (int k = 0; k < c->nmod; ++k)
    if (c->mode != MPM_CYCLE_LOADED || c->mod[k]->hier)
      mpm_grid_phase_widen(c->grid, c->mod[k]->phase);
    else
      mpm_grid_phase_narrow(c->grid, c->mod[k]->phase);
  if (hm) mpm_grid_phase_widen(c->grid, hm->phase);
  for (int k = 0; k < c->nmod; ++k) MPM_CALL(c->mod[k]->ops->forces(c->mod[k], t, h, pass));
  if (hm) mpm_interface_restore(c->iface), mpm_interface_predict(c->iface, t);
  /* Held and loaded first passes capture what the solid is given (mpm_interface.h). */
  mpm_interface *cap = c->mode != MPM_CYCLE_JOINT && pass == MPM_PASS_FIRST ? c->iface : NULL;
  if (cap) mpm_interface_capture_begin(cap);
  mpm_coupling_capture(c->coupling, cap);
  if (hooks) MPM_CALL(mpm_coupling_before_solve(c->coupling, t, hs, pass));
  for (int k = 0; k < c->nmod; ++k) MPM_CALL(solve(c->grid, c->mod[k], hs));
  if (hm) MPM_CALL(mpm_grid_phase_update(c->grid, hm->phase, hs));
  MPM_CALL(interact(c, t, hs, pass));
  /* A loaded first pass books its exchanges where the constraints override them at the
   * constrained velocity (mpm_interface.h, constraints). */
  const int loaded = c->mode == MPM_CYCLE_LOADED && pass == MPM_PASS_FIRST;
  if (loaded) mpm_interface_solved(c->iface);
  for (int k = 0; k < c->nmod; ++k) MPM_CALL(c->mod[k]->ops->constrain(c->mod[k], t, h, pass));
  if (loaded) mpm_coupling_book_constrained(c->coupling, c->iface, hs);
  if (hm) MPM_CALL(hm->ops->constrain(hm, t, h, pass));
  if (hooks) MPM_CALL(mpm_coupling_after_constrain(c->coupling, t, hs, pass));
  if (c->mode == MPM_CYCLE_FOLLOW && pass == MPM_PASS_FIRST)
    mpm_coupling_record_inside(c->coupling);
  mpm_coupling_capture(c->coupling, NULL);
  mpm_timer_stop(MPM_T_GRID);
  MPM_CALL(halo(c, 0));
  for (int k = 0; k < c->nmod; ++k)
    if (c->mod[k]->hier) mpm_hier_prolong(c->mod[k]->hier, c->mod[k]->phase);
  return 0;
}

/* ---- the velocity preview (mpm_module.h, p2g_rate) ---------------------------------------- */

enum { DEPOSIT_MAX = 1 + 3 * MPM_MAX_DIM };

/* The arrays a deposit fills in phase ph: m, m v, f and, where it is deposited, the mass
 * gradient. Returns their number. */
static int deposit_arrays(mpm_grid_phase *ph, int dim, double **slot[DEPOSIT_MAX]) {
  int n = 0;
  slot[n++] = &ph->m_i;
  for (int d = 0; d < dim; ++d) slot[n++] = &ph->mv_i[d], slot[n++] = &ph->f_i[d];
  for (int d = 0; ph->normals && d < dim; ++d) slot[n++] = &ph->normal_i[d];
  return n;
}

/* The grids that hold module k's phase: the shared grid, then its hierarchy's finer levels.
 * Returns their number. */
static int phase_grids(const mpm_cycle *c, int k, mpm_grid **g) {
  const mpm_hier *h = c->mod[k]->hier;
  int n = 0;
  g[n++] = c->grid;
  for (int l = 1; h && l < h->nlevels; ++l) g[n++] = h->level[l].grid;
  return n;
}

/* Put copies of phase ph's deposit (on g, dim axes) in its arrays' place, keeping the arrays in
 * own; returns their number. */
static int shadow_in(mpm_grid *g, int phase, double *own[DEPOSIT_MAX]) {
  mpm_grid_phase *ph = &g->phase[phase];
  const size_t nn = (size_t)g->nnodes;
  double **slot[DEPOSIT_MAX];
  const int ns = deposit_arrays(ph, g->dim, slot);
  if (!ph->shadow) MPM_ALLOC(ph->shadow, DEPOSIT_MAX * nn);
  for (int j = 0; j < ns; ++j) {
    own[j] = *slot[j];
    memcpy(ph->shadow + j * nn, own[j], nn * sizeof(double));
    *slot[j] = ph->shadow + j * nn;
  }
  return 0;
}

/* Give phase ph on g its own deposit arrays back. */
static void shadow_out(mpm_grid *g, int phase, double *const own[DEPOSIT_MAX]) {
  double **slot[DEPOSIT_MAX];
  const int ns = deposit_arrays(&g->phase[phase], g->dim, slot);
  for (int j = 0; j < ns; ++j) *slot[j] = own[j];
}

/* Preview the solve of this deposit at h = 0 and let the modules that read it complete their
 * deposits. The grid pass (as MUSL's remap: nothing is recorded) runs on copies of the
 * deposits in the phases' shadows, on every level of a hierarchy (the walls fold the finer
 * levels' deposits in place), so that the deposits themselves are summed and solved once, by
 * the pass that follows; it leaves the velocity of the solve in every phase's v_i. A held
 * partner's phase is restored from the interface by either pass alike. */
static int preview(const mpm_cycle *c, double t, double *const *y) {
  int need = 0;
  for (int k = 0; k < c->nmod; ++k) need |= c->mod[k]->ops->p2g_rate != NULL;
  if (!need) return 0;
  double *own[MPM_MAX_MODULES][MPM_HIER_MAX_LEVELS][DEPOSIT_MAX];
  mpm_grid *g[MPM_MAX_MODULES][MPM_HIER_MAX_LEVELS];
  int ng[MPM_MAX_MODULES];
  for (int k = 0; k < c->nmod; ++k) {
    ng[k] = phase_grids(c, k, g[k]);
    for (int l = 0; l < ng[k]; ++l) MPM_CALL(shadow_in(g[k][l], c->mod[k]->phase, own[k][l]));
  }
  const int rc = grid_pass(c, t, 0.0, MPM_PASS_REMAP);
  for (int k = 0; k < c->nmod; ++k)
    for (int l = 0; l < ng[k]; ++l) shadow_out(g[k][l], c->mod[k]->phase, own[k][l]);
  MPM_CALL(rc);
  for (int k = 0; k < c->nmod; ++k)
    if (c->mod[k]->ops->p2g_rate) MPM_CALL(c->mod[k]->ops->p2g_rate(c->mod[k], t, y[k]));
  return 0;
}

/* Every module's deposit at (t, y), with the velocity preview where a module asks for it. */
static int deposit(const mpm_cycle *c, double t, double *const *y) {
  for (int k = 0; k < c->nmod; ++k) {
    zero(c->grid, c->mod[k]);
    MPM_CALL(c->mod[k]->ops->p2g(c->mod[k], t, y[k]));
  }
  restrict_deposits(c, 0);
  MPM_CALL(preview(c, t, y));
  restrict_deposits(c, 1); /* what p2g_rate added */
  return 0;
}

int mpm_cycle_deposit(const mpm_cycle *c, double t, double *const *y) {
  /* The module deposits alone: its preview sees its own constraints, no coupling. */
  mpm_cycle alone = *c;
  alone.coupling = NULL, alone.mode = MPM_CYCLE_JOINT, alone.musl = 0;
  MPM_CALL(deposit(&alone, t, y));
  MPM_CALL(halo(c, 1));
  for (int k = 0; k < c->nmod; ++k)
    MPM_CALL(c->mod[k]->ops->forces(c->mod[k], t, 0.0, MPM_PASS_FIRST));
  return 0;
}

int mpm_cycle_rhs(const mpm_cycle *c, double t, double *const *y, double *const *ydot, double h) {
  MPM_CALL(deposit(c, t, y));
  MPM_CALL(grid_pass(c, t, h, MPM_PASS_FIRST));
  for (int k = 0; c->coupling && k < c->nmod; ++k)
    if (c->mod[k] == c->coupling->module[MPM_ROLE_SOLID])
      MPM_CALL(mpm_coupling_body_loads(c->coupling, y[k]));
  if (c->musl) {
    mpm_timer_start(MPM_T_P2G);
    for (int k = 0; k < c->nmod; ++k)
      if (c->mod[k]->ops->remap) MPM_CALL(c->mod[k]->ops->remap(c->mod[k], t, y[k], h));
    mpm_timer_stop(MPM_T_P2G);
    restrict_deposits(c, 0); /* a refined module's remap deposited on its levels */
    MPM_CALL(grid_pass(c, t, h, MPM_PASS_REMAP));
  }
  /* The gas first: a wall a coupling scheme gave it (mpm_wall.h) hands what the gas's G2P
   * exchanged there to the solid's nodes before the solid's G2P reads them. */
  mpm_timer_start(MPM_T_G2P);
  for (int pass = 0; pass < 2; ++pass)
    for (int k = 0; k < c->nmod; ++k)
      if ((c->mod[k]->role == MPM_ROLE_FLUID) == (pass == 0))
        MPM_CALL(c->mod[k]->ops->g2p(c->mod[k], t, y[k], ydot[k], h));
  mpm_timer_stop(MPM_T_G2P);
  return 0;
}

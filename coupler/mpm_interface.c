/* The interface data of a staggered time scheme (see mpm_interface.h). */
#include "mpm_interface.h"

#include "mpm_bc.h"
#include "mpm_error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int mpm_interface_new(mpm_interface **ifcp, mpm_grid *grid, int phase) {
  mpm_interface *ifc;
  MPM_ALLOC(ifc, 1);
  *ifcp = ifc;
  ifc->grid = grid, ifc->phase = phase;
  const size_t nn = (size_t)grid->nnodes;
  MPM_ALLOC(ifc->m, nn);
  MPM_ALLOC(ifc->m_start, nn);
  for (int d = 0; d < grid->dim; ++d) {
    MPM_ALLOC(ifc->mv[d], nn);
    MPM_ALLOC(ifc->f[d], nn);
    MPM_ALLOC(ifc->capture[d], nn);
    MPM_ALLOC(ifc->booked[d], nn);
    MPM_ALLOC(ifc->v_solved[d], nn);
    MPM_ALLOC(ifc->a_solved[d], nn);
    MPM_ALLOC(ifc->impulse[d], nn);
    MPM_ALLOC(ifc->load[d], nn);
    if (grid->phase[phase].normals) MPM_ALLOC(ifc->normal[d], nn);
  }
  return 0;
}

void mpm_interface_destroy(mpm_interface **ifcp) {
  if (!ifcp || !*ifcp) return;
  mpm_interface *ifc = *ifcp;
  free(ifc->m), free(ifc->m_start);
  for (int d = 0; d < MPM_MAX_DIM; ++d) {
    free(ifc->mv[d]), free(ifc->f[d]), free(ifc->normal[d]);
    free(ifc->capture[d]), free(ifc->impulse[d]), free(ifc->load[d]);
    free(ifc->booked[d]), free(ifc->v_solved[d]), free(ifc->a_solved[d]);
    free(ifc->trend[d]), free(ifc->prev[d]), free(ifc->now[d]), free(ifc->moved[d]);
    free(ifc->vprev[d]), free(ifc->accel[d]);
    free(ifc->f_gas[d]), free(ifc->v_gas[d]), free(ifc->v_now[d]);
  }
  free(ifc->mprev), free(ifc->m_gas), free(ifc->touched), free(ifc->touched_now);
  free(ifc);
  *ifcp = NULL;
}

/* Copy the held fields between the phase and the store (save: phase -> store). */
static void copy_fields(const mpm_interface *ifc, int save) {
  mpm_grid_phase *ph = &ifc->grid->phase[ifc->phase];
  const size_t bytes = sizeof(double) * (size_t)ifc->grid->nnodes;
#define MPM_IFC_COPY(store, field) memcpy(save ? (store) : (field), save ? (field) : (store), bytes)
  MPM_IFC_COPY(ifc->m, ph->m_i);
  for (int d = 0; d < ifc->grid->dim; ++d) {
    MPM_IFC_COPY(ifc->mv[d], ph->mv_i[d]);
    MPM_IFC_COPY(ifc->f[d], ph->f_i[d]);
    if (ifc->normal[d]) MPM_IFC_COPY(ifc->normal[d], ph->normal_i[d]);
  }
#undef MPM_IFC_COPY
}

void mpm_interface_hold(mpm_interface *ifc) {
  copy_fields(ifc, 1);
}

void mpm_interface_restore(const mpm_interface *ifc) {
  copy_fields(ifc, 0);
}

int mpm_interface_want_predictor(mpm_interface *ifc) {
  const size_t nn = (size_t)ifc->grid->nnodes;
  MPM_ALLOC(ifc->mprev, nn);
  for (int d = 0; d < ifc->grid->dim; ++d) {
    MPM_ALLOC(ifc->vprev[d], nn);
    MPM_ALLOC(ifc->accel[d], nn);
  }
  ifc->t_prev = -1.0;
  return 0;
}

void mpm_interface_predict_hold(mpm_interface *ifc, double t) {
  if (!ifc->mprev) return;
  const int dim = ifc->grid->dim;
  const double span = t - ifc->t_prev, inv = ifc->t_prev >= 0.0 && span > 0.0 ? 1.0 / span : 0.0;
  for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l) {
    const double m = ifc->m[l];
    const int known = inv > 0.0 && m > 0.0 && ifc->mprev[l] > 0.0;
    /* The load over the larger of the two holds' masses, as the solid's advance spreads it
     * (mpm_coupling_apply_load): where the solid left a node since the hold before, its mass
     * now is roundoff (1e-13 of the heaviest node's on the shock panel) and load / m gave the
     * gas a face moving at 1e4 m/s (+150 J booked in one coupling step at 1 mm). */
    const double m_load = m > ifc->mprev[l] ? m : ifc->mprev[l];
    for (int d = 0; d < dim; ++d) {
      const double v = m > 0.0 ? ifc->mv[d][l] / m : 0.0;
      /* (no history: the held force, as without the predictor) */
      ifc->accel[d][l] = known     ? (v - ifc->vprev[d][l]) * inv - ifc->load[d][l] / m_load
                         : m > 0.0 ? ifc->f[d][l] / m
                                   : 0.0;
      ifc->vprev[d][l] = v;
    }
    ifc->mprev[l] = m;
  }
  ifc->t_prev = ifc->t_hold = t;
}

void mpm_interface_predict(const mpm_interface *ifc, double t) {
  if (!ifc->mprev) return;
  mpm_grid_phase *ph = &ifc->grid->phase[ifc->phase];
  const double s = t - ifc->t_hold;
  for (int d = 0; d < ifc->grid->dim; ++d)
    for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l) {
      const double ma = ph->m_i[l] * ifc->accel[d][l];
      ph->mv_i[d][l] += s * ma, ph->f_i[d][l] = ma;
    }
}

int mpm_interface_want_shared(mpm_interface *ifc) {
  const size_t nn = (size_t)ifc->grid->nnodes;
  MPM_ALLOC(ifc->m_gas, nn);
  MPM_ALLOC(ifc->touched, nn);
  MPM_ALLOC(ifc->touched_now, nn);
  for (int d = 0; d < ifc->grid->dim; ++d) {
    MPM_ALLOC(ifc->f_gas[d], nn);
    MPM_ALLOC(ifc->v_gas[d], nn);
    MPM_ALLOC(ifc->v_now[d], nn);
  }
  return 0;
}

void mpm_interface_share(mpm_interface *ifc, int gas_phase) {
  const mpm_grid_phase *ph = &ifc->grid->phase[gas_phase];
  const size_t nn = (size_t)ifc->grid->nnodes;
  for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l)
    ifc->m_gas[l] = ph->m_i[l] > ph->m_empty ? ph->m_i[l] : 0.0;
  memset(ifc->touched, 0, nn);
  for (int d = 0; d < ifc->grid->dim; ++d) {
    memcpy(ifc->f_gas[d], ph->f_i[d], sizeof(double) * nn);
    for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l)
      ifc->v_gas[d][l] = ifc->m_gas[l] > 0.0 ? ph->mv_i[d][l] / ifc->m_gas[l] : 0.0;
  }
}

/* Over the solid's span (mpm_grid_phase_narrow): the captures are made where it has mass. */
void mpm_interface_capture_begin(mpm_interface *ifc) {
  const mpm_grid_phase *ph = &ifc->grid->phase[ifc->phase];
  for (int d = 0; d < ifc->grid->dim; ++d)
    MPM_PHASE_FOR(ifc->grid, ph, l) ifc->capture[d][l] = ifc->booked[d][l] = 0.0;
}

void mpm_interface_solved(mpm_interface *ifc) {
  const mpm_grid_phase *ph = &ifc->grid->phase[ifc->phase];
  for (int d = 0; d < ifc->grid->dim; ++d) MPM_PHASE_FOR(ifc->grid, ph, l) {
      ifc->v_solved[d][l] = ph->v_i[d][l];
      ifc->a_solved[d][l] = ph->a_i[d][l];
    }
}

void mpm_interface_capture_accept(mpm_interface *ifc, double h, int sign) {
  const double w = sign * h;
  if (sign < 0 && ifc->m_gas) { /* a solid substep: the shared nodes move on */
    /* where the solid has mass, as its constraints and the forward halo left them */
    const mpm_grid_phase *ph = &ifc->grid->phase[ifc->phase];
    for (int d = 0; d < ifc->grid->dim; ++d)
      for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l)
        ifc->v_gas[d][l] = ifc->touched_now[l] ? ph->v_i[d][l] : ifc->v_now[d][l];
    for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l) ifc->touched[l] |= ifc->touched_now[l];
  }
  const mpm_grid_phase *ph = &ifc->grid->phase[ifc->phase];
  for (int d = 0; d < ifc->grid->dim; ++d)
    MPM_PHASE_FOR(ifc->grid, ph, l) ifc->impulse[d][l] += w * ifc->capture[d][l];
}

int mpm_interface_want_trend(mpm_interface *ifc) {
  const size_t nn = (size_t)ifc->grid->nnodes;
  for (int d = 0; d < ifc->grid->dim; ++d) {
    MPM_ALLOC(ifc->trend[d], nn);
    MPM_ALLOC(ifc->prev[d], nn);
    MPM_ALLOC(ifc->now[d], nn);
  }
  return 0;
}

void mpm_interface_load(mpm_interface *ifc, double t0, double H, int interpolate) {
  const double inv = H > 0 ? 1.0 / H : 0.0;
  const int trend = interpolate && ifc->trend[0];
  const double gap = 0.5 * (H + ifc->span_prev);
  for (int d = 0; d < ifc->grid->dim; ++d)
    for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l) {
      const double load = ifc->impulse[d][l] * inv;
      ifc->load[d][l] = load;
      if (!trend) continue;
      ifc->trend[d][l] = ifc->span_prev > 0 ? (load - ifc->prev[d][l]) / gap : 0.0;
      ifc->prev[d][l] = load;
    }
  ifc->t_mid = t0 + 0.5 * H;
  ifc->span_prev = trend ? H : 0.0;
  ifc->start_due = 1;
}

const double *const *mpm_interface_load_at(mpm_interface *ifc, double t, double h) {
  if (!ifc->trend[0] || ifc->span_prev <= 0) return (const double *const *)ifc->load;
  const double s = t + 0.5 * h - ifc->t_mid;
  for (int d = 0; d < ifc->grid->dim; ++d)
    for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l)
      ifc->now[d][l] = ifc->load[d][l] + s * ifc->trend[d][l];
  return (const double *const *)ifc->now;
}

const double *mpm_interface_mass_start(mpm_interface *ifc) {
  if (ifc->start_due)
    memcpy(ifc->m_start, ifc->grid->phase[ifc->phase].m_i,
           sizeof(double) * (size_t)ifc->grid->nnodes);
  ifc->start_due = 0;
  return ifc->m_start;
}

/* The node of the 3^dim block around l (within the box) with the most mass m; l itself on a tie. */
static mpm_lidx heaviest_neighbour(const mpm_grid *g, const double *m, mpm_lidx l) {
  const int dim = g->dim;
  int gi[MPM_MAX_DIM], nb = 1;
  mpm_grid_node_global(g, l, gi);
  for (int d = 0; d < dim; ++d) nb *= 3;
  mpm_lidx best = l;
  for (int k = 0; k < nb; ++k) {
    int gj[MPM_MAX_DIM], inside = 1;
    for (int d = 0, q = k; d < dim; ++d, q /= 3) {
      gj[d] = gi[d] + q % 3 - 1;
      inside &= gj[d] >= g->box_lo[d] && gj[d] < g->box_lo[d] + g->box_n[d];
    }
    if (!inside) continue;
    const mpm_lidx j = mpm_grid_local_index(g, gj);
    if (m[j] > m[best]) best = j;
  }
  return best;
}

int mpm_interface_rehome(mpm_interface *ifc, const unsigned char *owned) {
  mpm_grid *g = ifc->grid;
  const int dim = g->dim;
  const mpm_lidx nn = g->nnodes;
  const double *m = g->phase[ifc->phase].m_i;
  for (int d = 0; d < dim; ++d) {
    if (!ifc->moved[d]) MPM_ALLOC(ifc->moved[d], nn);
    memset(ifc->moved[d], 0, sizeof(double) * (size_t)nn);
  }
  for (mpm_lidx l = 0; l < nn; ++l) {
    if (!owned[l] || !(m[l] < ifc->m_start[l] || m[l] == 0.0)) continue;
    int any = 0;
    for (int d = 0; d < dim; ++d) any |= ifc->impulse[d][l] != 0.0;
    if (!any) continue;
    const mpm_lidx j = heaviest_neighbour(g, m, l);
    if (j == l) continue;
    for (int d = 0; d < dim; ++d) ifc->moved[d][j] += ifc->impulse[d][l], ifc->impulse[d][l] = 0.0;
  }
  MPM_CALL(mpm_grid_halo_reverse(g, ifc->moved, dim));
  for (int d = 0; d < dim; ++d)
    for (mpm_lidx l = 0; l < nn; ++l)
      if (owned[l]) ifc->impulse[d][l] += ifc->moved[d][l];
  return 0;
}

void mpm_interface_owed(const mpm_interface *ifc, const unsigned char *owned, double *J) {
  for (int d = 0; d < ifc->grid->dim; ++d) {
    J[d] = 0.0;
    for (mpm_lidx l = 0; l < ifc->grid->nnodes; ++l)
      if (owned[l]) J[d] += ifc->impulse[d][l];
  }
}

/* ---- checkpoints ---------------------------------------------------------------------------- */

enum { IFC_X, IFC_J, IFC_L, IFC_SPAN, IFC_P, IFC_PM, IFC_TP, IFC_Q, IFC_NFIELDS };

int mpm_interface_particles_new(mpm_particles **p, int dim, int predictor) {
  const mpm_field_desc fields[IFC_NFIELDS] = {{"x", dim}, {"v", dim}, {"L", dim}, {"span", 1},
                                              {"P", dim}, {"Pm", 1},  {"tp", 1},  {"Q", dim}};
  return mpm_particles_new(p, dim, fields, predictor ? IFC_NFIELDS : IFC_P, 2);
}

/* Does node l carry state? */
static int carries(const mpm_interface *ifc, mpm_lidx l) {
  int any = 0;
  for (int d = 0; d < ifc->grid->dim; ++d)
    any |= ifc->impulse[d][l] != 0.0 || (ifc->prev[d] && ifc->prev[d][l] != 0.0);
  return any || (ifc->mprev && ifc->mprev[l] > 0.0);
}

int mpm_interface_pack(const mpm_interface *ifc, const unsigned char *owned, mpm_particles *p) {
  const mpm_grid *g = ifc->grid;
  const int dim = g->dim;
  mpm_lidx n = 0;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) n += owned[l] && carries(ifc, l);
  double *add;
  const size_t stride = (size_t)p->ncomp;
  MPM_ALLOC(add, stride * (n ? n : 1));
  /* add is component-major (mpm_particles_edit): component c of particle k at c n + k. The
   * position is a quarter cell inside the node's own cell (the last node's: inside the cell
   * below), so that migration takes it to the rank that owns the node. */
  mpm_lidx k = 0;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    if (!owned[l] || !carries(ifc, l)) continue;
    mpm_lidx r = l;
    for (int d = 0; d < dim; ++d) {
      const int gi = g->box_lo[d] + (int)(r % g->box_n[d]);
      r /= g->box_n[d];
      const double inward = gi < g->ncells[d] ? 0.25 : -0.25;
      add[(size_t)d * n + k] = g->lo[d] + (gi + inward) * g->dx;
      add[(size_t)(dim + d) * n + k] = ifc->impulse[d][l];
      add[(size_t)(2 * dim + d) * n + k] = ifc->prev[d] ? ifc->prev[d][l] : 0.0;
    }
    add[(size_t)(3 * dim) * n + k] = ifc->span_prev;
    if (ifc->mprev) {
      for (int d = 0; d < dim; ++d) add[(size_t)(3 * dim + 1 + d) * n + k] = ifc->vprev[d][l];
      add[(size_t)(4 * dim + 1) * n + k] = ifc->mprev[l];
      add[(size_t)(4 * dim + 2) * n + k] = ifc->t_prev;
      for (int d = 0; d < dim; ++d) add[(size_t)(4 * dim + 3 + d) * n + k] = ifc->load[d][l];
    }
    ++k;
  }
  const int rc = mpm_particles_inject(p, g->comm, n, add);
  free(add);
  return rc;
}

void mpm_interface_unpack(mpm_interface *ifc, const mpm_particles *p) {
  const mpm_grid *g = ifc->grid;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    int gi[MPM_MAX_DIM] = {0};
    for (int d = 0; d < g->dim; ++d)
      gi[d] = (int)lround((mpm_particles_comp(p, IFC_X, d)[i] - g->lo[d]) / g->dx);
    const mpm_lidx l = mpm_grid_local_index(g, gi);
    for (int d = 0; d < g->dim; ++d) {
      ifc->impulse[d][l] = mpm_particles_comp(p, IFC_J, d)[i];
      if (ifc->prev[d]) ifc->prev[d][l] = mpm_particles_comp(p, IFC_L, d)[i];
    }
    ifc->span_prev = ifc->trend[0] ? mpm_particles_comp(p, IFC_SPAN, 0)[i] : 0.0;
    if (!ifc->mprev) continue;
    for (int d = 0; d < g->dim; ++d) ifc->vprev[d][l] = mpm_particles_comp(p, IFC_P, d)[i];
    ifc->mprev[l] = mpm_particles_comp(p, IFC_PM, 0)[i];
    ifc->t_prev = mpm_particles_comp(p, IFC_TP, 0)[i];
    for (int d = 0; d < g->dim; ++d) ifc->load[d][l] = mpm_particles_comp(p, IFC_Q, d)[i];
  }
}

/* Exact integrals over the knot spans of a grid's quadratic B-splines: the pressure's nodal
 * force and the velocity's nodal divergence of a field given by its nodal values.
 *
 * Spans. Span i of a grid is the dual cell of node i, [x_i - dx/2, x_i + dx/2] per axis
 * (mpm_hier.h); on it the quadratic B-splines of nodes i - 1, i, i + 1 per axis are the only
 * nonzero ones, each a polynomial. With p_h = sum_j N_j p_j and v_h = sum_k N_k v_k:
 *
 *   force:       f_i += integral of p_h grad N_i       (the pressure's force, -grad p, in
 *                                                    weak form; adds, per component)
 *   divergence:  D_i += integral of N_i div v_h        (adds)
 *
 * both over the spans of the set. On a span each is a product of exact 1-D integrals of the
 * B-splines (polynomials of degree at most 4 per axis; the same as a three-point Gauss rule per
 * axis gives, to roundoff). The two are adjoint on any span set:
 * sum_i f_i . v_i = sum_j p_j D_j, which is what lets a module book the force's work as the
 * particles' pressure work exactly (fluid/fluid_gridp.c). A constant p gives f_i = 0 at every
 * node whose support lies in the set's interior, and a constant v gives D = 0 everywhere.
 *
 * Cost: by sum factorisation, about 3^dim x 3 x dim^2 products per span and per field (650
 * in 3-D), without a particle (bench/results/span_cost.md). */
#ifndef MPM_SPAN_H
#define MPM_SPAN_H

#include "mpm_grid.h"

/* The spans to integrate over: global span indices lo[d] .. hi[d] (inclusive) of the grid's box,
 * less those with skip[n] != 0 (n the box index of the span's node; skip may be NULL). Where
 * half_lo[d] is set the span lo[d] keeps only its upper half (a domain face through its node),
 * likewise half_hi[d] for hi[d]'s lower half. Every node of every span integrated must lie in
 * the box. */
typedef struct mpm_span_set {
  int lo[MPM_MAX_DIM], hi[MPM_MAX_DIM];
  int half_lo[MPM_MAX_DIM], half_hi[MPM_MAX_DIM];
  const unsigned char *skip;
} mpm_span_set;

/* The spans of the domain that this rank owns (the spans of its owned nodes inside [lo, hi] of
 * the grid), halved at non-periodic faces; skip as given. */
mpm_span_set mpm_span_owned(const mpm_grid *g, const unsigned char *skip);

/* f[d][i] += integral of p_h dN_i/dx_d over the set, for every box node i (p: box array). */
void mpm_span_force(const mpm_grid *g, const mpm_span_set *s, const double *p, double *const *f);

/* D[i] += integral of N_i div v_h over the set (v[d]: box arrays). */
void mpm_span_divergence(const mpm_grid *g, const mpm_span_set *s, const double *const *v,
                         double *D);

/* f[i] += integral of N_i q_h over the node plane x_axis = x of node s->lo[axis] (s->hi[axis]
 * must equal it), within the set's spans along the other axes, for every box node i (q: box
 * array). The boundary term of an open face: with q the face's pressure, the span force less
 * this term (times the outward normal) is -integral of N_i grad p_h, so a uniform p that equals
 * q gives no force at any node (fluid/fluid_boundary.c). */
void mpm_span_plane(const mpm_grid *g, const mpm_span_set *s, int axis, const double *q, double *f);

#endif

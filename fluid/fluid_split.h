/* Split and merge of gas particles for refinement (issue 51), exactly conservative: mass,
 * momentum, total energy (kinetic + internal) and the centre of mass of the set are unchanged
 * to roundoff by every call. The operations act on the particles the caller names and do not
 * decide levels: a regrid chooses who splits (entering a finer level) and who merges (leaving
 * it) and calls them between steps, merges first (fluid_split.c says why).
 *
 * Split: each parent becomes 2^dim children, one at each corner (x +- delta_d per axis) of a
 * box centred on it, with delta = s / 4 for the parent's size s = (J V0)^(1/dim), so the
 * children tile the parent's volume with cubes of side s / 2. Each child has m / 2^dim and
 * V0 / 2^dim and every other field of the parent (v, e, J, C, the lagged strain rate): a
 * split changes no velocity, so momentum, kinetic and internal energy are exact, and the
 * symmetric offsets keep the centre of mass. delta is shortened near a domain wall and
 * around an obstacle (still symmetric: still exact).
 *
 * Merge: each group becomes one particle, in the slot and with the id of its member of lowest
 * id: m = sum m_i, x and v mass-weighted, V0 = sum V0_i, J V0 = sum J_i V0_i,
 * e = (sum m_i e_i + sum 1/2 m_i |v_i - v|^2) / m (the kinetic energy the averaging of v removes
 * becomes heat, so m (e + |v|^2 / 2) is the group's total). C mass-weighted; the lagged strain
 * rate and its limiter volume-weighted (fluid_split.c says why).
 *
 * Both edit the set at once (mpm_particles_edit) and so change the particle count: the caller
 * migrates afterwards (a child or merged particle may lie in another rank's cell) and then
 * re-wraps the state and calls the integrator's Resize, as after the gas's boundary op. The
 * output fields (rho, p, mach, T, s, rho_grid) are left undefined, as by every edit;
 * fluid_output_fields refreshes them before any write. */
#ifndef FLUID_SPLIT_H
#define FLUID_SPLIT_H

#include "mpm_module.h"

/* What one call did on this rank. */
typedef struct fluid_split_report {
  mpm_lidx parents;  /* split: particles split */
  mpm_lidx children; /* split: particles appended (2^dim - 1 per parent) */
  mpm_lidx shrunk;   /* split: parents whose children sit closer than s / 4 (wall, obstacle) */
  mpm_lidx groups;   /* merge: groups of two or more merged */
  mpm_lidx removed;  /* merge: particles removed (members but the one kept) */
  mpm_lidx away;     /* particles now in cells of another rank: a migration is due */
} fluid_split_report;

/* Split the k particles idx[0 .. k) (distinct local indices) of the gas module m. Parent
 * idx[a] stays in its slot as child 0 (the corner -delta on every axis) and keeps its id;
 * child j = 1 .. 2^dim - 1 (bit d of j set: +delta_d) is appended at index
 * n + a (2^dim - 1) + j - 1, n being the count before the call. The new ids do not depend on
 * the rank layout: id_next + ((c S + r) (2^dim - 1) + j - 1), c the global cell of the parent,
 * r its rank by id among the cell's parents and S the most parents any cell splits; every
 * rank then advances id_next by ncells S (2^dim - 1). Every parent must sit on the rank owning
 * its cell (as after a migration). Collective over the grid's communicator (every rank calls,
 * k = 0 too). */
int fluid_split(mpm_module *m, const mpm_lidx *idx, mpm_lidx k, fluid_split_report *r);

/* Merge ngroups groups of the gas module m: group g is the local indices
 * member[start[g] .. start[g + 1]) (disjoint groups; a group of one is left as it is). The
 * members are summed in id order, so the result does not depend on their order in the set.
 * Local. */
int fluid_merge(mpm_module *m, const mpm_lidx *start, const mpm_lidx *member, mpm_lidx ngroups,
                fluid_split_report *r);

/* Groups for fluid_merge from the k candidates idx[0 .. k) (distinct local indices): the
 * candidates sharing a parent slot, the cell of the lattice of spacing H from the domain's
 * lower corner (H: the particle spacing of the coarser level, dx_l / fluid.ppc; seeded gas
 * sits at the slots' centres, and a parent's children in its slot). A slot of c candidates
 * gives ceil(c / 2^dim) groups of as equal sizes as can be, in id order, or with full set
 * floor(c / 2^dim) groups of exactly 2^dim, in id order, the rest left out; slots of one
 * candidate give none. With span > 0 (a multiple of H) the candidates share a cell of the
 * lattice of that spacing from the same corner instead, taken slot by slot in the slots'
 * global order and in id order within a slot. *start (ngroups + 1) and *member (from malloc)
 * are the caller's. Local. */
int fluid_merge_groups(const mpm_module *m, const mpm_lidx *idx, mpm_lidx k, double H, double span,
                       int full, mpm_lidx **start, mpm_lidx **member, mpm_lidx *ngroups);

/* The centre of mass of the c particles mem[] as a merge places it (wrapped into the domain
 * along a periodic axis) into x. */
void fluid_merge_centre(const mpm_module *m, const mpm_lidx *mem, int c, double *x);

#endif

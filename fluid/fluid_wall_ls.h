/* The least-squares wall treatment of the seed paper (fluid.wall_treatment = least_squares):
 * the gas particles next to a static obstacle take their velocity, internal energy and density
 * from a weighted least-squares fit over the interior particles near them, with the wall
 * condition imposed, instead of from the held nodes alone. Private to fluid/.
 *
 * Who is who. A particle closer to an obstacle (or a moving wall, below) than fluid.wall_band cells
 * (phi < band dx) is a wall particle; every other particle near a body is a donor. Particles far
 * from every body are neither and cost one lookup. With fluid.wall_blend = b > 0, a particle
 * between the band and b cells beyond it is both: a donor, and fitted in part, its new values w fit
 * + (1 - w) own with w falling linearly from 1 at the band's edge to 0 at b beyond it.
 *
 * Why blend. With a sharp edge the particle rows just outside the band are the worst of the
 * flow: uniform Mach 2.5 flow along a slip wall at 10 and 30 degrees to the grid (cases/
 * slanted_wall.ini, dx = 0.02) kept its largest pressure deviation, 2.5 and 4.2 %, 1.4-1.7 cells
 * from the wall, just beyond the fitted rows; a wider band did not cure it (which lattice rows a
 * band holds decides: at 2 cells 0.7 and 1.0 %, at 1.5 cells 2.6 and 5.4 %), and emptied the
 * wedge's first layer. A blend of 1 cell gives 0.55 and 0.52 % (velocity 0.16 %) at every
 * snapshot. It costs the wedge (dx = 0.01) 0.44 degrees of shock angle (37.48 against 37.04,
 * theory 36.94) and 0.7 points of pressure ratio (+1.49 % against +0.78 %), so it is not the
 * default.
 *
 * The fit. For a wall particle p, every fitted field f (the new velocity, the velocity that
 * moves the particle, e and rho) minimises sum_q w_pq (f_q - f(x_q))^2 over the donors q, with
 * w_pq = V_q sum_i S_i(x_p) S_i(x_q): the grid's own shape functions make the weight, so the
 * sums are nodal moments of the donors (sum S V, sum S V r, sum S V r r^T, sum S V f,
 * sum S V f r with r = x_q - x_i) that one deposit and one halo exchange give on every rank,
 * whatever the decomposition. The wall condition fixes the normal velocity u_n = u . n (every
 * component for no_slip): u_n(x) ~ c . (x - x_w), zero at the nearest surface point x_w, and
 * the particle takes c . (x_p - x_w). The tangential velocity, e and rho take a constant fit
 * (fluid.wall_fit_order = 0, the donors' weighted mean) or a linear one (1). The constant is
 * the default: on the Mach 2.5 wedge at dx = 0.01 the linear fit extrapolated the wall
 * layer's gradients outwards and fed them back (the first layer 2-4 % fast, its pressure
 * 10-57 % over p2, growing along the ramp), the constant fit gives the post-shock speed within
 * 0.1 % and the pressure within 4 %. A linear fit with too few donors to fix a gradient (a
 * singular system) falls back on the mean, and so does a fitted e or rho that is not positive
 * or is more than a factor 2 from the mean. Gas at rest stays at rest (every velocity moment
 * is zero), and a uniform flow along the wall is reproduced. A wall particle with no donor near
 * (gas expanding away from a face into near vacuum) keeps its own values, less any velocity
 * into the body (without that, gas crept into the back of a square in a Mach 2.5 flow). The
 * normal velocity that moves a fitted particle is bounded so that one step covers at most half
 * its distance to the surface (a linear fit in a steep gradient, such as the wake's reverse flow
 * onto a back face, otherwise overshot it), and a particle already inside never moves deeper.
 *
 * Held nodes. Under this treatment a constrained node that the gas barely covers
 * (fluid_obstacle.h) is not stopped: it keeps the velocity its particles deposited, projected
 * on the surface, and the force the nodal update would have given it goes to the obstacle.
 * Stopped, those nodes drag the donors next to the band (the wall layer compressed along the
 * wedge's ramp); left free, they made the flow unsteady (their small mass takes the large,
 * nearly cancelling gas and ghost forces).
 *
 * Balances. Mass is untouched. The momentum the fit gives the gas is an impulse of the obstacle
 * (booked in its force record: P - P0 + sum h F stays exact). A static wall does no work, so
 * the fit's change of total energy (kinetic and internal, summed over all wall particles and
 * ranks) is given back to the gas as a whole: every particle's internal energy, the wall
 * particles' fitted one included, is scaled by one common factor 1 - dE / sum m e (a change
 * larger than all of it stops the run with a message). (The obstacles' own energy exchange,
 * ghost work and constraint power, is booked as heat by fluid_obstacle.c.)
 * Why the whole gas: the fit resets the wall particles' e from the donors at every step, so
 * whatever part of its energy change lands on the particles that flow along the wall (and
 * stay near it for their whole passage) builds up there step after step. Taken back from the
 * wall particles alone (as this treatment first did), the correction re-imposed on them the
 * very departure from the donors that the fit had just removed: uniform Mach 2.5 flow along a
 * slip wall (cases/slanted_wall.ini, dx = 0.02) kept a wall layer 6.6 % over the free
 * stream's pressure with the wall 0.005 cells off a grid line, and 4.5 % under it at 10
 * degrees; taken back from the wall particles and the donors, the layer was still 0.6 % hot
 * and 1.8 % cold; spread over the whole gas, its pressure is within 0.1 % beside the grid line
 * (at 10 degrees the flow's other errors, a 2 % compression of the first two cells, then
 * dominate). The factor differs from 1 by the fit's energy change over the gas's internal
 * energy, about 2e-6 a step there; where the fit keeps changing the energy one way, the whole
 * flow carries it (the wedge's post-shock pressure rose by 0.3-0.5 %).
 *
 * A moving wall. A coupling scheme may give the gas a moving wall (common/mpm_wall.h): under
 * coupling.scheme = traction, the solid's surface (coupler/mpm_solid_wall.h). Its cells are
 * flagged afresh at every step; a particle near both a static obstacle and the moving wall takes
 * the nearer. The wall condition is then zero normal velocity relative to the wall's, (u - v_w)
 * . n = 0 on the surface: the normal fit is made on u . n - v_w . n, and the motion bound, the
 * keep-out rule and "never deeper" act on the relative normal velocity. It shapes the velocity
 * that moves the particle; the new velocity (the momentum) takes the fit's tangential
 * components and keeps its own normal one, which the traction scheme's held nodes have already
 * set to the wall's. Fitting that one too (as a static wall does) put back, at every step, the
 * donors' normal velocity extrapolated to the wall layer, which the held nodes (a stencil deep
 * into the gas) then took out again inelastically: the interface destroyed 2.1 times the energy
 * of ghost on the main job at 4 mm to 1.5 ms (-1346 J against -641 J), 4.1 times on
 * cases/fsi_box.ini (-4.9e-4 J against -1.2e-4); keeping it, -877 J and -1.5e-4 J, with the
 * piston's first layer as good. The fit's impulses J go to the wall (the solid's nodes) instead
 * of an obstacle's force record, and the wall's work (which the source returns) stays with the
 * gas: only the rest of the fit's energy change is given back as heat. On the 1-D piston
 * (cases/fsi_gas_piston.ini, a slab at 0.5 into gas at rest, dx = 0.01) the gas's first layer
 * next to the slab is within 1 % of the exact post-shock pressure and density; ghost (traction's
 * held nodes alone) leaves it at -36 % and -27 % (tests/verification/test_traction_ls.py).
 *
 * Where it acts. In the classic update (usl, musl), after G2P, on the step's new values: the
 * wall particles' rates are rewritten so that the step ends on the fitted state, and they move
 * with the fitted transport velocity. The method-of-lines pairs would need a projection
 * between steps that their error control does not see; they are refused at input. */
#ifndef FLUID_WALL_LS_H
#define FLUID_WALL_LS_H

#include "mpm_config.h"
#include "mpm_grid.h"
#include "mpm_module.h"

typedef struct fluid_wall_ls {
  int on;
  int order;            /* of the free fits: 0 (weighted mean) or 1 (linear) */
  double band;          /* wall particles: phi < band, m */
  double blend;         /* band <= phi < band + blend: part fitted, part donors, m */
  unsigned char *reach; /* per box node as a cell's lower corner: far, donors only, or may fit */
  int nf;               /* fitted fields: v (dim), vhat (dim), e, rho */
  int nmom;             /* moments per node */
  double *mom;          /* nnodes * nmom: a node's moments together */
  int clear_lo[MPM_MAX_DIM], clear_n[MPM_MAX_DIM]; /* the block of box nodes they reach */
  int obs_lo[MPM_MAX_DIM], obs_n[MPM_MAX_DIM];     /* the obstacles' part of it */
  int exchange;      /* the box has a neighbour: the moments go through the halo exchanges */
  double *need;      /* per box node: a fitted particle reads it (nonzero), this step */
  double *halo;      /* nmom * nnodes: the same, one array per moment, for the exchanges */
  double **halo_ptr; /* nmom pointers into halo */
  mpm_lidx cap;      /* capacity of the per-particle arrays */
  signed char *kind; /* -1 far, 0 donor, 1 wall particle, 2 both (the blend) */
  int *ob;           /* wall particle: the nearest obstacle, or -1 for the moving wall */
  double *geo; /* wall particle: phi, the outward normal and the wall's velocity (1 + 2 dim) */
  const mpm_wall_source *src; /* a moving wall a coupling scheme gave the gas (mpm_wall.h) */
  unsigned char *near_src;    /* per box node as a cell's lower corner: near that wall (1), where it
                                 may    be fitted (2), this step (mpm_wall.h) */
  double *val;                /* new field values (nf per particle) */
} fluid_wall_ls;

extern const mpm_key_spec fluid_wall_keys[];
extern const int fluid_wall_nkeys;

/* Read fluid.wall_treatment and fluid.wall_band and, for least_squares, mark the cells near the
 * obstacles. classic: the module runs the classic update. */
int fluid_wall_ls_init(mpm_module *m, const mpm_config *cfg, int classic);
/* Take the moving wall src (the module's attach_wall op; see mpm_module.h): *taken = 1 under
 * least_squares. src = NULL ends the attaching: least_squares with neither an obstacle nor a
 * wall is an input error. */
int fluid_wall_ls_attach(mpm_module *m, const mpm_config *cfg, const mpm_wall_source *src,
                         int *taken);
/* After the classic step's G2P (rates in ydot over h from the state y): fit the wall
 * particles and rewrite their rates. Collective. */
int fluid_wall_ls_apply(mpm_module *m, const double *y, double *ydot, double h);
void fluid_wall_ls_free(fluid_wall_ls *w);

#endif

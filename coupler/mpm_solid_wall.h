/* The solid's surface as a moving wall for the gas (common/mpm_wall.h): how `traction` gives
 * the gas's least-squares wall treatment (fluid.wall_treatment = least_squares) the interface.
 *
 * Where the wall is. Every solid particle is gathered on every rank at each G2P (positions, and
 * a half-width r_q = V0^(1/dim) / 2), with its images across a periodic face when it lies within
 * reach of one, and bucketed by cell. At a point x the outward normal n is
 * the solid's mass gradient interpolated at x (the grid's shape functions, normalised), the
 * wall's velocity is the solid's nodal velocity interpolated with mass weights (the velocity
 * of the nodal solve just made, which `traction` has set to the common normal velocity at the
 * interface), and the distance is phi = min over the solid particles within range + dx of x of
 * (x - x_q) . n - r_q: on a straight face exactly the distance to the face of the particles'
 * cells, whatever the particles' spacing along it.
 *
 * Momentum. The impulse J the gas's fit gives a gas particle at x is taken from the solid's
 * nodes of x's stencil in proportion to S_i(x) m_i (the solid's nodal masses), summed over the
 * ranks and applied to the solid's nodal velocities and accelerations as an exchange
 * (mpm_coupling.h) before the solid's G2P, which the cycle runs after the gas's: the interface
 * record books -J / h on the solid and J / h on the gas, so the exchange balances to roundoff.
 * A component that the solid's own constraint set (a wall face, a clamp, a rigid body) keeps
 * its value: the constraint takes that share, as it takes the held gas's under
 * MPM_COUPLING_HOLDS (without that, a review measured floor nodes of a panel on a slip floor
 * moving into the floor at 9e-5 against the panel's 3.5e-3).
 * The gas's energy changes by J . v (the wall's work; the fit's remainder goes back to the gas
 * as heat), booked as the gas's interface power; the solid's power is that of its exchange.
 *
 * Limits. The fit happens in the gas's G2P, so the solid must be solved in the same cycle:
 * coupling.time = monolithic only (a staggered or multirate scheme holds or loads the solid in a
 * separate cycle: refused at input), and time.method = usl only (under musl the solid's remap
 * sets its particles' velocities before the gas's G2P: the impulses would not reach them;
 * measured on cases/fsi_gas_piston.ini, the slab's momentum then missed 0.46 % of its recorded
 * interface impulse; refused at input). The per-body split of the interface force (several
 * [solid.NAME] bodies) does not include the fit's share. Every rank holds every solid particle:
 * a solid of millions of particles would want only those near the gas, gathered by
 * neighbourhood. */
#ifndef MPM_SOLID_WALL_H
#define MPM_SOLID_WALL_H

#include "mpm_coupling.h"

typedef struct mpm_solid_wall mpm_solid_wall;

/* Offer the solid's surface to the gas as a wall. *w is NULL if the gas does not take it (its
 * wall treatment is not least_squares). Input errors for a time scheme that cannot carry it. */
int mpm_solid_wall_offer(mpm_coupling *c, const mpm_config *cfg, mpm_solid_wall **w);
void mpm_solid_wall_free(mpm_solid_wall **w);

#endif

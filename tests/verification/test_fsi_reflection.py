"""Shocks reflecting from a near-rigid and a soft elastic slab (cases/fsi_reflect_rigid.ini,
cases/fsi_reflect_soft.ini; their headers give the states; the test sets them from SLABS).

Quasi-1-D strips, 3 cells high, periodic in y, slip walls at the x ends, gamma = 1.4,
linear_elastic slabs with nu = 0 (M = E) from the gas's face to a slip wall, dx = 0.01, ppc 2:
  rigid: Mach 1.21 into (rho, p) = (1, 1); rho_s = 4000, E = 1e5: c_s = 5, Z_s / Z_g = 1.69e4.
  soft:  Mach 2 into (1, 1);             rho_s = 0.1,  E = 160: c_s = 40, Z_s / Z_g = 3.38.
Each slab starts at rest, pre-stressed at the ambient p0 = 1 (solid.slab.initial_pressure), so
gas and slab start in equilibrium. Both slabs run with a bulk viscosity under every time method
(solid.slab.bulk_viscosity_linear = 0.5, _quadratic = 1.5; docs/solid.md: usl and musl lag tr D
by a step, the method of lines takes the stage's current rate), which damps the wave train
behind the transmitted shock. Why 0.5: it is the linear coefficient of the gas's own default
viscosity (fluid.av_form = vnr), and the linear term is the one that acts on a weak shock (strain
2.9 %); the soft slab's RMS bound below is met narrowly with it (2.82 % usl, 2.93 % musl, 2.99 %
bs32, against 3 %), and not with LS-DYNA's 0.06 (5.6 %): see Known failures. Under usl and musl
the gas takes the PIC share of 0.02 a gas beside a solid takes by default (docs/gas.md).

Exact answer: the code's small-strain model puts V0 sigma into the nodal forces, so in uniaxial
strain its nominal stress is P(F) = M (F - 1) / F (the slab's ambient F, 160/161, measured to
1e-5 with the moving-slab start of cases/fsi_transmission.ini): it stiffens in compression, and a
compressive wave is a shock, Lagrangian speed U = sqrt((P1 - P0) / (rho_r (F1 - F0))), velocity
jump U (F0 - F1). The pre-stressed slab is seeded at F0 = M / (M + p0) with reference density
rho_r = rho_s F0. A reflected shock into the incident state (rho1, u1, p1) meets the slab's
transmitted shock at p*, u*:
  u1 - f(p*; rho1, p1) = sqrt((p* - p0) (F0 - F*) / rho_r),  F* = M / (M + p*),
and the gas next to the slab holds rho* (Rankine-Hugoniot of the reflected shock). The soft slab
has c_s = 40 to keep its strain at 2.9 %: at c_s = 20 (strain 5.7 %) the interface state sat on
the linear P = M (F - 1) answer instead (the slab behind its undamped shock rings, and the mean
of a ringing wave train does not obey the jump conditions): force and gas plateau -2.1 %,
transmitted -5.3 % (with the moving-slab start); at 2.9 % and pre-stressed: -0.36 %, -0.30 %,
-1.6 %.

Measured at t_end (the last snapshot):
  first layer   the column of gas particles nearest the slab (ppc x 3 cells = 6 particles),
                their mean p and rho against p*, rho*; also the second column, the layer's
                entropy p / rho^gamma, and its p at every snapshot after the impact (printed);
  plateau       mean gas p and rho from 5 cells behind the reflected shock to 4 cells from the
                slab's face;
  force         mean Fx_solid / H of coupling.csv from DELAY after the impact to t_end (plus the
                gauge p0 with `gauge`, which coupling.csv does not book), against p* (the gas
                pressure on the face);
  transmitted   the median of P = M (F - 1) / F over the slab from 5 cells behind its face to
                DELAY (in slab travel) behind its transmitted front and 0.5 ahead of that
                front's reflection from the wall: the jump -median - p0 against p* - p0; its
                ringing: the cell averages of P (columns of 12 particles) about the median,
                their RMS and largest deviation, over p* - p0 (the particles' scatter about
                their cell's mean is printed: FLIP noise, not a wave).

Tolerances and why:
  first layer   3 % in p and rho (issue 55's acceptance). For scale, the gas alone reflecting
                the near-rigid slab's shock from the domain's slip wall (the exact wall
                condition) holds its first layer at p -4.14 %, rho -3.54 % under usl and
                -1.77 %, -1.99 % under bs32, steady from t = 0.25: the wall heating of a
                reflected shock (entropy 1.0142 and 1.0165 against the exact 1.0061; one run
                each, 2026-12-07). Met by the least-squares wall
                (traction, usl) next to both slabs: rigid p +1.16 %, rho +0.09 %; soft
                +1.85 %, -0.26 % (2026-12-06). Under usl the gas takes the PIC share a gas
                beside a solid takes by default (0.02, docs/gas.md); in pure FLIP the soft
                layer sat at -3.0 %, -3.4 % (the second column alike; -3.9 %, -4.0 % with the
                moving-slab start), and the rigid one at +1.5 %.
                coupling.scheme = sharp (the phases tied at points on the solid's face alone,
                coupler/coupling_sharp.c; run with its gauge, physics.gauge_pressure = p0)
                meets it next to the rigid slab: p +0.34 %, rho -0.66 % (usl), +0.48 %,
                -0.50 % (bs32, long; plateau -0.10 %, force -0.11 %, transmitted -0.15 %,
                ringing 0.36 %, 2.22 %; 2026-12-07; without the gauge -0.37 %, -1.29 % and
                +1.56 %, +0.23 %); next to the soft one it meets it under usl at time.cfl = 0.1
                or with fluid.pic_fraction = 0.02 (long) and fails with the defaults (Known
                failures).
  plateau       2 % in p and in rho: the slip-wall reflection of the same shock in gas alone
                (what the interface should reach) scatters by 1-2 % over such a region under
                usl (FLIP noise behind a shock).
  force         1 %: the interface force carries the state * in momentum; measured (velocity
                usl, bs32) -0.002 %, -0.23 % (rigid) and -0.19 %, -0.11 % (soft; the slab's
                residual nonlinearity, see above); without the viscosity -0.06 % and -0.36 %.
  transmitted   2 % of the jump (issue 55's acceptance), median; measured (velocity usl,
                bs32) -0.10 %, -0.11 % (rigid) and -1.02 %, -0.89 % (soft); without the
                viscosity -0.04 % (bs32 +0.53 %) and -1.6 %.
  ringing       RMS 3 %, largest 10 % of the jump (cell averages): a clean acoustic plateau
                (the rigid slab under usl: 0.28 %, 1.1 % without the viscosity, 0.26 %, 1.27 %
                with it) with room for the smeared start of the wave; the issue's moving-slab
                start measured a median -10 %, beyond both.
                The pre-stressed start brings the issue's -10 % median to -1.6 %.

Known failures, marked EXPECTED-FAIL (printed with the reason; not counted as failures):
- the first layer beside the soft slab under coupling.scheme = sharp (with the gauge): usl
  p +8.06 %, rho +4.01 % (second column +6.58 %, +2.21 %); bs32 (long) p +6.35 %, rho +3.24 %
  (+4.09 %, +0.07 %) (2026-12-07). Everything else there passes: plateau +0.02 % (bs32
  +0.08 %), force -0.11 % (-0.09 %), transmitted -0.89 % (-0.80 %), ringing RMS 1.90 % (1.89 %),
  largest 7.51 % (7.60 %). The layer reaches p* at the impact and is then compressed slowly:
  p / p* 0.99, 1.03, 1.05, 1.07, 1.08 at t = 0.15 to 0.35 under usl (1.04 to 1.06 under bs32);
  under usl at time.cfl = 0.1 it stays within 1 % of p* (1.008 at 0.35), so under usl it is
  the step's error; under bs32 it is not (time.cfl = 0.2, 15,503 steps against 9,069: p
  +6.34 %, as at 0.4). Under both the drift comes from the particles' quadrature of the face's
  pressure above the gauge: with physics.gauge_pressure at p* (5.837) instead of p0 the layer
  stays flat after the impact (usl 0.96 -> 0.98 of p*, ending -2.13 %, -3.12 %; bs32 1.01 ->
  1.00, ending +0.06 %, -1.16 %; gauge 3, usl: +2.50 %, +0.16 %; one run each, 2026-12-07;
  docs/coupling.md, sharp). `long` runs sharp under usl at time.cfl = 0.1 beside both slabs, where the
  first layer is an ordinary check (soft p +0.85 %, rho -0.55 %, largest ringing 7.61 %; rigid
  +0.42 %, -0.57 %; every other check passes; 28,513 and 5,009 steps, four times the default's),
  and with the PIC share the gas takes beside the other schemes (fluid.pic_fraction = 0.02):
  soft +2.26 %, -1.55 % (largest ringing 7.87 %), rigid -0.40 %, -1.30 %, every other check
  passing. Beside sharp with the gauge the gas takes no share by default: with it the
  resonator's f_1 converges at order 1.07 (-0.152, -0.065, -0.031, -0.016 % at 50 to 400
  cells/m, the last halving 0.90) against 1.39 without. History (coupler/coupling_sharp.c): the points first read the slab's
  velocity on its spline-tail node, which held 1e-4 of a particle's mass: the constraint was met
  by that node alone and the gas passed through the face (first layer p +35.9 %, RMS 3.39 %,
  largest 27.6 %; under bs32 the step collapsed after the impact). With the near-empty nodes'
  weights scaled in the rows, the gas's own tail node beyond the face, which no row reads, took
  the gas's outward push alone, and the first column expanded into the face (usl p -47 %, the
  layer at p / p* 0.53 by t_end; bs32 -4.5 %). A near-empty node of either phase now moves
  with the centre of mass along the solid's normal (tie_near_empty).
- the first layer under every scheme but the least-squares wall
  (measured: p -59 %, rho -47 % next to the rigid slab; -63 %, -48 % next to the soft one). The
  solid's particles reach, through the quadratic B-spline, every node within 1.5 cells of them,
  so the node one cell outside the slab's face carries solid mass (weight 1/32 of a face
  particle: 63 times the gas's mass there next to the rigid slab, 0.2 % next to the soft one).
  The spatial schemes treat it as an interface node (velocity: the shared velocity; traction:
  the slip wall; contact: the approach; all three give the same layer to 4 digits in 1-D), so
  the gas sees the solid a cell ahead of its face. Next to the rigid slab the particles between
  are neither moved nor compressed: they keep the ambient density and entropy (p 0.95, rho
  0.97, p / rho^gamma 1.0006, column 0.0025 from the face where the exact gas puts it at
  0.0014), from the impact to t_end. Next to the soft slab the layer is under-compressed at
  the impact and stays so (p / p* 0.36 at t = 0.15, 0.37 at 0.35; entropy 1.06 against 1.15).
  An experiment that leaves that one node out of the velocity exchange brings the first layer
  to -2.0 % (rigid) and -1.7 % (soft), but the gas then overruns the face (columns up to 0.003
  inside it) and the second column is 24-31 % high: the gas needs the wall condition on the
  nodes beyond the face (a mirror of its velocity about the solid's, as the domain's slip wall
  does), not just the tail node left out. A domain slip wall at the face gives the first layer
  -4.3 % (usl) and -0.9 % (bs32) in p: it holds the face node alone and mirrors the node beyond.
  A second experiment (issue 55, not merged) gave the gas that wall in the coupler where a face
  lies on a node along a grid axis: the tail node the gas's alone; the gas's mass, momentum and
  force on the node a cell inside the face folded into it (normal mirrored about the face's
  velocity, the reaction to the solid); that node given the mirrored velocity after the
  constraints; the solid's tail folded into its face node. Next to the rigid slab the first layer
  came to p +0.2 %, rho -0.6 % (usl: velocity, contact, traction alike; bs32 p +1.1 %;
  least-squares p -2.8 %) with the other checks passing; next to the soft slab, whose face moves
  across the nodes (the rule acts only while it lies within a quarter cell of one), p -9.7 %
  (least-squares -29 %). It broke the regression tests: test_fsi_waves (transmission -12 %, the
  free slab's acceleration -3.4 %), test_coupling's momentum (drift 1.8e-3 where 1e-13 is asked;
  probably the G2P reading velocities set on nodes without mass), test_prestress's rest state
  under the partitioned schemes, test_traction_ls's balances. A mirror about a face near a
  mid-cell as well kept the soft layer near p* to t = 0.30 but heated it and emptied the columns
  behind it (-38 %).
  A third experiment, the multi-material MPM literature's position-based contact detection (Nairn;
  Lemiale et al.), was built as an opt-in key (2026-12-03; not merged, as it met no target): a
  shared node takes part in the exchange only where the phases' nodal
  centres of mass, x_k = x_i + sum m_p S_i (x_p - x_i) / m_k,i, lie within a cutoff of each other
  along the solid's normal (a flat face under the quadratic B-spline: 0.81-0.90 dx on the node
  nearest the face, 1.27 dx on the tail nodes a cell either side). Measured (cutoff 1 dx unless
  said; velocity, contact and traction give the same figures to 4 digits in 1-D):
  * the rule as stated, both tail nodes left out: a gas at rest against the pre-stressed slab does
    not stay at rest (test_prestress: particle speed 10.7 c_g). Each tail node carries 1/8 of the
    face's p A as the boundary term of the B-spline pressure force (p N_i(x_face)), in the gas and,
    opposite, in the solid; coupled they cancel, left out each pushes its phase unopposed (the
    gas's tail inside the solid, with 1/32 of a particle's mass, carried the face's particles into
    the slab before the shock arrived). Rigid first layer p -74 % (cutoff 1.0), -83 % (0.9),
    -31 % (1.2).
  * both left out, the solid's force on a left-out node handed to the gas and the gas's to the
    solid (an exchange; each keeps its velocity): the rest state holds again (1e-13), and the
    rigid first layer reaches p* 0.989 at t = 0.20, but then climbs linearly to 1.37 p* at 0.50
    (the gas's tail node inside the slab moves with the face particle's own FLIP velocity, so
    the particle keeps creeping into the wall).
  * the node beyond the face left out alone (the gas's tail inside the solid stays coupled),
    with the hand-off (the form measured in full): rest state and the other checks hold, but rigid
    usl p -17.5 %, rho -13.1 % (second column +4.7 %, the first at 0.0011 from the face against the
    exact 0.0014; steady, 0.84-0.82 p* from t = 0.20 to 0.50); bs32 +14 % and growing (0.93 to
    1.14 p* from 0.20 to 0.50; second column +77 %); least squares -3.2 % (fails, main passes);
    soft usl p -58 % (second column -27 %), least squares -5.4 % (main -3.0 %); the soft slab's
    largest cell deviation fell to 8.9 % (from 17 %). With it on, test_fsi_waves' musl
    transmission is +3.15 % (main +1.20 %, bound 3 %), test_traction_ls's piston fails (shock
    -0.71 cells, least-squares first layer +10.8 %), test_coupling's shared-node identity no
    longer holds beyond the face (by design); test_prestress and test_fsi_resonator pass.
  The detection only decides which nodes the wall holds; the first column's density follows
  sum v_i grad S_i over nodes within 1.5 cells of the face, and no choice of held and free nodes
  gives it the wall's kinematics (held: not compressed; free: its own tail velocity drifts). A
  B-spline wall needs what lies beyond the face (the mirror above) or a boundary-fitted basis.
- the ringing's largest cell average behind the soft slab's shock (the RMS is an ordinary check)
  under velocity, contact and traction; coupling.scheme = sharp meets it (7.51 % usl, 7.60 %
  bs32), an ordinary check there.
  History: without a solid viscosity the soft slab rang at RMS 7.4 %, largest 21 % (usl), 7.85 %,
  18.7 % (bs32: median -1.10 %, force -0.20 %, 10064 steps), and under bs32, which refused the
  viscosity until issue 55's item 3, the rigid one at 3.8 %, 15 %: the slab's own wave train
  (3.6 % RMS a metre behind the face, 8.6 % near the front), as large from the pre-stressed start
  as from the moving-slab start (5.0 %). With the bulk viscosity (c1 = 0.5, c2 = 1.5) under every
  method: rigid RMS 0.26 %, largest 1.27 % (usl), 0.29 %, 0.98 % (musl), 1.95 %, 7.21 % (bs32);
  soft RMS 2.91 % (velocity, traction: usl), 2.94 % (contact:usl), 2.80 % (traction:usl:ls),
  2.99 % (velocity, traction: bs32), met narrowly, and 3.06 % (velocity:musl), not met, in pure
  FLIP. With the PIC share the gas takes beside a solid under usl and musl (2026-12-06): rigid
  RMS 0.28 %, largest 1.69 % (usl), 0.28 %, 1.47 % (musl); soft RMS 2.82 % (velocity, contact,
  traction: usl), 2.73 % (traction:usl:ls), 2.93 % (velocity:musl), 2.99 % (bs32, which takes
  no share), all met, and largest 15.3 % (usl), 12.7 % (traction:usl:ls), 14.8 % (musl),
  15.7 % (bs32). Under bs32 with the hybrid pressure, which the gas takes beside a solid under
  the ERK pairs since 2026-12-06: rigid RMS 1.49 %, largest 4.94 %, median -0.20 %, first
  layer p -57.2 %; soft RMS 2.43 %, largest 14.33 %, median -0.62 %, first layer p -58.7 %.
  With the relaxation of the phases' own velocities at the shared nodes as well (the velocity
  and traction schemes under the ERK pairs, coupling.mol_rate, since 2026-12-06): rigid RMS
  0.27 %, largest 1.02 %, first layer p -57.2 %; soft RMS 2.32 %, largest 14.32 %, median
  -0.62 %, first layer p -59.7 % (velocity:bs32; traction:bs32 the same to these digits).
  The linear coefficient does the work (RMS
  velocity:usl: 0.06 -> 5.62 %, 0.3 -> 3.48 %, 1.0 -> 2.55 %; c2 1.2 or 1.5 alike: the strain jump
  is only 2.9 %), at the price of the stable step (soft usl 4042 steps -> 7141; rigid usl 630 ->
  1259; bs32 takes the current rate: rigid 1537 -> 1673, soft 9700 steps). LS-DYNA's defaults
  (0.06, 1.5) leave the RMS at 5.6 %. The median moves from -1.61 % to -1.02 % (velocity:usl; bs32
  -0.89 %), the force from -0.36 % to -0.19 % (bs32 -0.11 %). The largest deviation stays an
  expected failure next to the soft slab: 17.2 % (velocity:usl), 14.9 % (traction:usl:ls), 15.7 %
  (velocity:bs32); 20.4 % without the viscosity. Diagnosis (velocity:usl, snapshots every 0.005 s,
  P per particle column): within 15 cells of the face the cell averages hold +-20 % of the jump
  from t = 0.2 to t_end, nearly fixed in the material (at t_end +22, +21, -8, -22, +4, +16, -7,
  -18 % in the cells 1-8 behind the face), with a +-5 % part that alternates between snapshots;
  beyond the first 0.5 m the RMS is 1.9-2.2 % (largest 3.8 %) in each 0.5 m. Split into each
  material cell's mean and the half-difference of its two particle columns, the half-difference
  dominates: 50 % of the jump in the face cell at t = 0.080 (the gas's smeared shock arriving),
  159 % at 0.090, 98-171 % to t_end; it reaches the next cell (30-80 %) from 0.105, the 8th
  (13-31 %) from 0.11, the 30th (5-12 %) from 0.19, and stays under 0.5 % at the 100th. A
  particle-scale alternation of F lies in the kernel of the quadratic B-spline's nodal forces at 2
  particles per cell: the grid does not see it, so the elastic response does not carry it off as a
  wave and the bulk viscosity, which reads the grid's rate, does not damp it; it spreads only as
  the slab crosses the grid, and the +-20 % is its residue in the cell averages. Its source is the
  first layer's node: the face column's rate reads the node a cell outside the face, which holds
  the solid's spline tail and, under the shared velocity, the gas's velocity (the gas's mass there
  is 500 times the tail's). While the incoming gas leads the slab (u1 = 1.48 against a slab at
  rest) that node adds up to |S'(1.25 dx)| (v_gas - v_solid) = 0.25 x 1.48 / dx = 37 /s to the
  first column's rate and nothing to the second's; over a few ms of the smeared shock's rise
  (DELAY = 4.2 ms) that is a strain difference of order 10 %, the size measured (a half-difference
  of 159 % of the jump is a difference of 9 % in strain, three times the 2.9 % jump). Next to the
  rigid slab the tail node's velocity is mostly the solid's (its mass there is 63 times the
  gas's), but the jump is tiny (strain 1.3e-5): the same alternation holds half-differences of
  545, 89, 30 and 3 % of the jump in the first, second, third and fifth cells from t = 0.2 to
  t_end, and none by the 9th; it stays there because that slab does not move across the grid (u* =
  7e-5), and the measured region starts 5 cells behind the face. The soft slab moves 32 cells
  across the grid by t_end, and its alternation has spread over some 30. A bar driven into a slip
  wall (test_solid_bulkq's scene) leaves 1-2 % there: the coupling face makes it, not the slab's
  own impact. It is therefore a defect, the solid side of the first layer's; its cure is the wall
  condition at the face that the first layer needs (above). An experiment that left the solid out
  of the velocity exchange at nodes holding little of its mass (not kept) broke the coupling: a
  momentum imbalance up to 1.2 times the interface force with one threshold, a failed run
  (t = 0.105) with another.
  The projected dilatation (solid.slab.dilatation = projected, the `fbar` variants under long;
  solid/solid_dilatation.c) stops the face's rate from building the volumetric half of the
  alternation; at nu = 0 the deviatoric half carries the other half of the slab's stress, and it
  stays. Soft slab, 2026-12-07: velocity:usl RMS 2.25 %, largest 9.80 % (an ordinary check:
  met), velocity:bs32 1.68 %, 10.62 % (expected to fail), and, run by hand, velocity:musl 2.31 %,
  10.03 %, traction:usl:ls 2.20 %, 9.97 %; the first layer p -61.9 % (usl; -63.7 % without).

Arguments: [long] [slab:scheme:method[:ls][:fbar][:gauge] ...] (fbar: the projected dilatation;
gauge: physics.gauge_pressure at the ambient pressure).
Default (~80 s idle before the rigid slab took
the viscosity, whose usl runs now take twice the steps, a few seconds more; 149-209 s measured
with the machine's load at 10-12): the rigid slab under
velocity:usl, contact:usl, traction:usl, traction:usl:ls (fluid.wall_treatment =
least_squares) and velocity:bs32 (the default time method); the soft slab under velocity:usl
and traction:usl:ls. `long` runs the rest: rigid traction:bs32, velocity:musl,
traction:musl; soft contact:usl, traction:usl, velocity:bs32 (3-4 minutes alone),
traction:bs32, velocity:musl, velocity:usl:fbar, velocity:bs32:fbar (about 12 minutes in all; measured 467 s with another run
sharing the core, before the viscosity under bs32). Rigid under musl: ringing RMS 0.29 %,
largest 0.98 % (1.4 %, 6.0 % without the viscosity).
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
from gaswaves import (bisect, shock_density, shock_pressure, shock_state,  # noqa: E402
                      sound, wave_du)

check = mt.Checks("test_fsi_reflection")
ARGS = sys.argv[1:]
LONG = bool(ARGS) and ARGS[0] == "long"
if LONG:
    ARGS = ARGS[1:]
DX, PPC = 0.01, 2
H = 3 * DX
RHO0, P0 = 1.0, 1.0
DELAY = 5 * DX / sound(RHO0, P0)  # the rise of the smeared shock at the interface
TOL_LAYER, TOL_PLATEAU, TOL_FORCE, TOL_T, TOL_RMS, TOL_MAX = 0.03, 0.02, 0.01, 0.02, 0.03, 0.10
LAYER_REASON = ("the node a cell outside the solid's face carries its spline tail and the schemes "
                "treat it as interface, so the column between is not compressed; see the "
                "docstring")

PEAK_REASON = ("within 15 cells of the soft slab's face the cell averages hold +-20 % of the jump "
               "(the largest 5-8 cells behind it): the residue of a particle-scale strain "
               "alternation the impact leaves in the face cells (the solid's spline-tail node "
               "carries the gas's velocity into the first column's rate), which the grid does not "
               "see, so neither elasticity nor the bulk viscosity removes it; see the docstring")

FBAR_REASON = ("the projected dilatation (solid.slab.dilatation = projected) smooths the volumetric "
               "half of the face's strain alternation; with nu = 0 the deviatoric half carries "
               "the other half of the slab's stress, and under this method its residue stays "
               "just above the bound; see the docstring")

SHARP_SOFT_REASON = ("coupling.scheme = sharp beside the soft slab: the first layer reaches p* at the "
                     "impact and is then compressed slowly, by the particles' quadrature of "
                     "the face's pressure above the gauge (with the gauge at p* it stays flat); "
                     "see the docstring")

SLABS = {
    "rigid": dict(case="fsi_reflect_rigid.ini", mach=1.21, rho_s=4000.0, E=1e5, x_s=1.5,
                  x_i=1.7, L=3.0, t_end=0.5),
    "soft": dict(case="fsi_reflect_soft.ini", mach=2.0, rho_s=0.1, E=160.0, x_s=2.0, x_i=2.2,
                 L=9.0, t_end=0.35),
}


def exact(sl):
    """The exact reflected state of the docstring, as a dict."""
    M, rho_s = sl["E"], sl["rho_s"]
    p1 = shock_pressure(sl["mach"], P0)
    rho1, u1, S = shock_state(RHO0, P0, p1)
    F0 = M / (M + P0)

    rho_ref = rho_s * F0  # mass per reference volume (the slab is seeded at F0)

    def u_solid(p):
        return math.sqrt((p - P0) * (F0 - M / (M + p)) / rho_ref)

    ps = bisect(lambda p: u1 - wave_du(p, rho1, p1) - u_solid(p), p1, 20 * p1)
    rs, us = shock_density(rho1, p1, ps), u_solid(ps)
    Fs = M / (M + ps)
    return dict(p1=p1, rho1=rho1, u1=u1, S=S, ps=ps, rs=rs, us=us, Fs=Fs, F0=F0,
                W=(rs * us - rho1 * u1) / (rs - rho1),  # reflected shock velocity (lab)
                U=math.sqrt((ps - P0) / (rho_ref * (F0 - Fs))),  # transmitted, Lagrangian
                t_hit=(sl["x_i"] - sl["x_s"]) / S)


# The slabs' bulk viscosity (c1, c2), under every time method (docstring).
Q = (0.5, 1.5)


def run(name, sl, ex, scheme, method, ls, fbar, gauge=False, keys=()):
    tag = (f"{name} {scheme} {method}" + (" least_squares" if ls else "")
           + (" projected" if fbar else "") + (" gauge" if gauge else "")
           + "".join(" " + k for k in keys))
    out = mt.outdir(tag.replace(" ", "_"))
    extra = [f"domain.hi={sl['x_i'] + sl['L']} {H}", f"geometry.shocked.hi={sl['x_s']} {H}",
             f"geometry.ambient.hi={sl['x_i']} {H}", f"geometry.slab.hi={sl['x_i'] + sl['L']} {H}",
             f"gas.shocked.density={ex['rho1']!r}", f"gas.shocked.pressure={ex['p1']!r}",
             f"gas.shocked.velocity={ex['u1']!r} 0", f"solid.slab.density={sl['rho_s']!r}",
             f"solid.slab.E={sl['E']!r}", f"solid.slab.initial_pressure={P0!r}",
             f"time.t_end={sl['t_end']}"]
    if ls:
        extra.append("fluid.wall_treatment=least_squares")
    if fbar:
        extra.append("solid.slab.dilatation=projected")
    if gauge:  # the ambient pressure out of both phases' forces (fluid/fluid_gauge.c)
        extra.append(f"physics.gauge_pressure={P0!r}")
    extra += list(keys)
    extra += [f"solid.slab.bulk_viscosity_linear={Q[0]!r}",
              f"solid.slab.bulk_viscosity_quadratic={Q[1]!r}"]
    mt.run(["run", mt.case(sl["case"]), f"output.dir={out}", f"grid.dx={DX}",
            f"coupling.scheme={scheme}", f"time.method={method}", "run.progress=false"] + extra)
    print(f"cost {tag}: {mt.cost(out)}")
    return tag, out


def face_and_layers(path, ex):
    """The slab's face, and the gas columns nearest it (each ppc x 3 particles)."""
    g, s = mt.particles(path, "fluid"), mt.particles(path, "solid")
    face = float(s["x"][:, 0].min()) - 0.5 * DX / PPC * ex["Fs"]
    order = np.argsort(g["x"][:, 0])[::-1]
    n = 3 * PPC
    cols = [order[k * n:(k + 1) * n] for k in range(2)]
    return g, s, face, cols


def verdict(cond, reason, msg):
    """An ordinary check, or one known to fail on this code (reason given)."""
    if reason:
        check.expect_fail(cond, msg, reason)
    else:
        check(cond, msg)


def measure(name, sl, ex, scheme, method, ls, fbar, gauge=False, keys=()):
    tag, out = run(name, sl, ex, scheme, method, ls, fbar, gauge, keys)
    snaps = mt.snapshots(out)
    # The first layer in time (diagnosis: does it approach p* or stay?).
    hist = []
    for t, path in snaps:
        if t > ex["t_hit"] + DELAY:
            g, _, _, cols = face_and_layers(path, ex)
            hist.append(f"{t:.2f}: {float(g['p'][cols[0], 0].mean()) / ex['ps']:.3f}")
    print(f"info {tag}: first layer p / p* in time: " + ", ".join(hist))
    tf, path = snaps[-1]
    g, s, face, cols = face_and_layers(path, ex)
    xg, pg, rg = g["x"][:, 0], g["p"][:, 0], g["rho"][:, 0]
    lay = [(float(pg[c].mean()), float(rg[c].mean()), float(face - xg[c].mean())) for c in cols]
    # Entropy of the first layer against the plateau's (p / rho^gamma).
    ent = lay[0][0] / lay[0][1] ** 1.4
    # Reflected plateau.
    x_refl = sl["x_i"] + ex["W"] * (tf - ex["t_hit"])
    sel = (xg >= x_refl + 5 * DX) & (xg <= face - 4 * DX)
    if sel.sum() < 3 * PPC * 4:
        raise SystemExit(f"{tag}: the reflected plateau holds only {int(sel.sum())} particles")
    p_pl, r_pl = float(pg[sel].mean()), float(rg[sel].mean())
    ent_pl = p_pl / r_pl ** 1.4
    # Interface force.
    c = np.genfromtxt(os.path.join(out, "coupling.csv"), delimiter=",", names=True)
    win = (c["t"] >= ex["t_hit"] + DELAY) & (c["t"] <= tf)
    # With the gauge the interface carries p - p_g only (its p_g is the walls'): add it back.
    p_if = float(np.mean(c["Fx_solid"][win])) / H + (P0 if gauge else 0.0)
    # Transmitted plateau in the slab (current positions; the front moves at U F0 there).
    xs, Fs = s["x"][:, 0], s["F"][:, 0]
    P = sl["E"] * (Fs - 1) / Fs
    x_front = sl["x_i"] + ex["U"] * ex["F0"] * (tf - ex["t_hit"])
    # ... and ahead of its reflection from the wall behind the slab.
    x_back = sl["x_i"] + 2 * sl["L"] - ex["U"] * ex["F0"] * (tf - ex["t_hit"])
    lo, hi = face + 5 * DX, min(x_front - ex["U"] * DELAY, x_back - 0.5)
    reg = (xs >= lo) & (xs <= hi)
    med = float(np.median(P[reg]))
    jump = ex["ps"] - P0
    T = (-med - P0) / jump
    # Ringing: cell averages (a column of 3 x ppc^2 particles) about the median; the particles'
    # own scatter about their cell's mean is printed.
    edges = np.arange(lo, hi, DX)
    k = np.digitize(xs[reg], edges)
    cells = np.array([P[reg][k == j].mean() for j in np.unique(k)])
    rms = float(np.sqrt(np.mean((cells - med) ** 2))) / jump
    dev = float(np.max(np.abs(cells - med))) / jump
    scat = float(np.sqrt(np.mean((P[reg] - cells[np.searchsorted(np.unique(k), k)]) ** 2))) / jump
    face_ex = sl["x_i"] + ex["us"] * (tf - ex["t_hit"])
    print(f"info {tag}: face at {face:.4f} (exact {face_ex:.4f}); "
          f"columns at {lay[0][2]:.4f}, {lay[1][2]:.4f} from it: p {lay[0][0]:.4f}, "
          f"{lay[1][0]:.4f}, rho {lay[0][1]:.4f}, {lay[1][1]:.4f}; entropy p/rho^g first layer "
          f"{ent:.4f}, plateau {ent_pl:.4f} (exact {ex['ps'] / ex['rs'] ** 1.4:.4f}, ambient 1)")
    print(f"info {tag}: transmitted region [{lo:.3f}, {hi:.3f}] ({int(reg.sum())} particles); "
          f"interface force / H {p_if:.5f}; particles' RMS scatter about their cell's mean "
          f"{100 * scat:.2f} % of the jump")
    e_p, e_r = lay[0][0] / ex["ps"] - 1, lay[0][1] / ex["rs"] - 1
    layer_ok = abs(e_p) <= TOL_LAYER and abs(e_r) <= TOL_LAYER
    verdict(layer_ok,
            None if ls or scheme == "sharp" and name == "rigid"
            else None if scheme == "sharp" and keys
            else SHARP_SOFT_REASON if scheme == "sharp" else LAYER_REASON,
            f"{tag}: first gas layer p {lay[0][0]:.4f} ({100 * e_p:+.2f} %), rho "
            f"{lay[0][1]:.4f} ({100 * e_r:+.2f} %) against p* {ex['ps']:.5f}, rho* {ex['rs']:.5f} "
            f"(<= {100 * TOL_LAYER:g} %); second column {100 * (lay[1][0] / ex['ps'] - 1):+.2f} %, "
            f"{100 * (lay[1][1] / ex['rs'] - 1):+.2f} %")
    e_pp, e_rp = p_pl / ex["ps"] - 1, r_pl / ex["rs"] - 1
    check(abs(e_pp) <= TOL_PLATEAU and abs(e_rp) <= TOL_PLATEAU,
          f"{tag}: reflected plateau [{x_refl + 5 * DX:.3f}, {face - 4 * DX:.3f}] p {p_pl:.4f} "
          f"({100 * e_pp:+.2f} %), rho {r_pl:.4f} ({100 * e_rp:+.2f} %) "
          f"(<= {100 * TOL_PLATEAU:g} %)")
    e_f = p_if / ex["ps"] - 1
    check(abs(e_f) <= TOL_FORCE, f"{tag}: interface force / H {p_if:.5f} against p* "
          f"{ex['ps']:.5f}: {100 * e_f:+.3f} % (<= {100 * TOL_FORCE:g} %)")
    check(abs(T - 1) <= TOL_T, f"{tag}: transmitted stress jump (median) {-med - P0:.5f} against "
          f"p* - p0 = {jump:.5f}: {100 * (T - 1):+.2f} % (<= {100 * TOL_T:g} %)")
    ring = (f"{tag}: ringing of the transmitted stress (cell averages): RMS {100 * rms:.2f} %, "
            f"largest {100 * dev:.2f} % of the jump (<= {100 * TOL_RMS:g} %, {100 * TOL_MAX:g} %)")
    soft = name == "soft"
    check(rms <= TOL_RMS, ring + " [RMS]")
    reason = (None if scheme == "sharp" else PEAK_REASON if soft and not fbar
              else FBAR_REASON if soft and method != "usl" else None)
    verdict(dev <= TOL_MAX, reason, ring + " [largest]")


def variants():
    if ARGS:
        for a in ARGS:
            f = a.split(":")
            yield (f[0], f[1], f[2], "ls" in f[3:], "fbar" in f[3:], "gauge" in f[3:],
                   tuple(e for e in f[3:] if "=" in e))
        return
    rigid = [("velocity", "usl", False, False), ("contact", "usl", False, False),
             ("traction", "usl", False, False), ("traction", "usl", True, False),
             ("velocity", "bs32", False, False), ("sharp", "usl", False, False)]
    soft = [("velocity", "usl", False, False), ("traction", "usl", True, False),
            ("sharp", "usl", False, False)]
    if LONG:  # the rest: soft under bs32 alone takes about 6 minutes (then: keys to add)
        rigid = [("traction", "bs32", False, False), ("velocity", "musl", False, False),
                 ("traction", "musl", False, False), ("sharp", "bs32", False, False),
                 ("sharp", "usl", False, False, "time.cfl=0.1"),
                 ("sharp", "usl", False, False, "fluid.pic_fraction=0.02")]
        soft = [("contact", "usl", False, False), ("traction", "usl", False, False),
                ("velocity", "bs32", False, False), ("traction", "bs32", False, False),
                ("velocity", "musl", False, False), ("velocity", "usl", False, True),
                ("velocity", "bs32", False, True), ("sharp", "bs32", False, False),
                ("sharp", "usl", False, False, "time.cfl=0.1"),
                ("sharp", "usl", False, False, "fluid.pic_fraction=0.02")]
    for v in rigid:  # sharp with its gauge (docs/coupling.md)
        yield ("rigid",) + v[:4] + (v[0] == "sharp", v[4:])
    for v in soft:
        yield ("soft",) + v[:4] + (v[0] == "sharp", v[4:])


for name, sl in SLABS.items():
    ex = exact(sl)
    print(f"info {name}: p1 {ex['p1']:.5f}, rho1 {ex['rho1']:.5f}, u1 {ex['u1']:.5f}; exact p* "
          f"{ex['ps']:.6f}, rho* {ex['rs']:.6f}, u* {ex['us']:.6g}; reflected shock "
          f"{ex['W']:+.4f}; "
          f"transmitted U {ex['U']:.4f}, strain {1 - ex['Fs'] / ex['F0']:.4f}; impact at "
          f"{ex['t_hit']:.4f}; Z_s / Z_g {math.sqrt(sl['rho_s'] * sl['E']) / sound(RHO0, P0):.4g}")
for name, scheme, method, ls, fbar, gauge, keys in variants():
    measure(name, SLABS[name], exact(SLABS[name]), scheme, method, ls, fbar, gauge, keys)

sys.exit(check.finish())

"""Coupled runs are independent of the decomposition and restart bit for bit, for every
spatial coupling scheme (cases/fsi_pulse.ini: a gas pulse hits an elastic block that straddles
the rank boundary).

- 2 ranks vs 1, classic update (usl and musl), by particle id in every field of both phases.
  Tolerance 1e-12 relative to each field's scale: only the order of the P2G and halo additions
  differs, and the coupling acts on the summed nodal values, so the difference is roundoff.
- Two solid bodies: coupling.csv splits the solid's interface force over them (Fx_NAME, ...);
  the parts sum to the resultant to 1e-12 of its largest value (roundoff: the split interpolates
  the nodal force to the particles, whose weights sum to one), on 1 and 2 ranks alike.
- Restart: a run to T with a checkpoint at T/2, restarted from it to T, gives the same state in
  both phases (tolerance 0: bitwise) and the same coupling.csv rows after the restart time
  (the cumulative coupling work is checkpointed).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_coupling_ranks")
CASE = mt.case("fsi_pulse.ini")
SCHEMES = ["velocity", "contact", "traction"]
PHASES = ("solid", "fluid")


def final_state(out):
    path = mt.snapshots(out)[-1][1]
    return {phase: mt.particles(path, phase) for phase in PHASES}


def coupling_rows(out, t_from):
    c = np.genfromtxt(os.path.join(out, "coupling.csv"), delimiter=",", names=True)
    return c[c["t"] > t_from * (1 + 1e-12)]


for scheme in SCHEMES:
    for method in ("usl", "musl"):
        args = [f"coupling.scheme={scheme}", f"time.method={method}", "time.t_end=0.2",
                "run.progress=false"]
        states = []
        for ranks in (1, 2):
            out = mt.outdir(f"{scheme}_{method}_np{ranks}")
            mt.run(["run", CASE, f"output.dir={out}"] + args, ranks)
            states.append(final_state(out))
        for phase in PHASES:
            a, b = states[0][phase], states[1][phase]
            same = np.array_equal(a["id"], b["id"])
            worst = mt.worst_difference(a, b)[0] if same else float("inf")
            check(same and worst <= 1e-12,
                  f"{scheme} {method} {phase}: the same {len(a['id'])} ids on 2 ranks as on 1, "
                  f"fields agree to {worst:.1e} relative (tolerance 1e-12)")

    T = 0.2
    full, rest = mt.outdir(f"{scheme}_full"), mt.outdir(f"{scheme}_restarted")
    common = [f"coupling.scheme={scheme}", f"time.t_end={T}", "run.progress=false"]
    mt.run(["run", CASE, f"output.dir={full}", f"output.checkpoint_interval={T / 2}"] + common)
    mt.run(["restart", os.path.join(full, "checkpoint_000001.h5"), f"output.dir={rest}"] + common)
    a, b = final_state(full), final_state(rest)
    for phase in PHASES:
        same = np.array_equal(a[phase]["id"], b[phase]["id"])
        worst = mt.worst_difference(a[phase], b[phase])[0] if same else float("inf")
        check(same and worst == 0.0, f"{scheme} restart ({phase}): identical ids, largest "
              f"difference {worst:.1e} (tolerance 0: bitwise)")
    ra, rb = coupling_rows(full, T / 2), coupling_rows(rest, T / 2)
    same_rows = len(ra) == len(rb) and len(ra) > 0 and all(
        np.array_equal(ra[k], rb[k]) for k in ra.dtype.names)
    check(same_rows, f"{scheme} restart: the {len(rb)} coupling.csv rows after the checkpoint "
          f"are identical to the uninterrupted run's {len(ra)} (W_net included)")

# Two bodies: the block split in two (upper "block", lower "lower").
text = open(CASE).read().replace("lo = 0.45 0.25", "lo = 0.45 0.55").replace(
    "of = box block", "of = box block lower_region")
text += ("\n[geometry.lower_region]\ntype = box\nlo = 0.45 0.1\nhi = 0.6 0.45\n\n"
         "[solid.lower]\ngeometry = lower_region\nmaterial = neo_hookean\ndensity = 5\nE = 50\n"
         "nu = 0.3\n")
path = os.path.join(mt.outdir("two_bodies_case"), "case.ini")
with open(path, "w") as f:
    f.write(text)
for scheme in SCHEMES:
    rows = []
    for ranks in (1, 2):
        out = mt.outdir(f"two_bodies_{scheme}_np{ranks}")
        mt.run(["run", path, f"output.dir={out}", f"coupling.scheme={scheme}", "time.t_end=0.2",
                "run.progress=false"], ranks)
        c = np.genfromtxt(os.path.join(out, "coupling.csv"), delimiter=",", names=True)
        rows.append(c)
        scale = max(float(np.abs(c["Fx_solid"]).max()), float(np.abs(c["Fy_solid"]).max()))
        gap = max(float(np.abs(c[f"F{a}_block"] + c[f"F{a}_lower"] - c[f"F{a}_solid"]).max())
                  for a in "xy") / scale
        check(gap <= 1e-12 and float(np.abs(c["Fy_block"]).max()) > 1e-3 * scale,
              f"{scheme} on {ranks} rank(s): the two bodies' forces sum to the solid's to "
              f"{gap:.1e} of its largest (tolerance 1e-12); each body loaded")
    a, b = rows
    diff = max(float(np.abs(a[k] - b[k]).max()) for k in ("Fx_block", "Fy_block", "Fx_lower",
                                                          "Fy_lower")) / scale
    check(len(a) == len(b) and diff <= 1e-12, f"{scheme}: per-body forces on 2 ranks as on 1 to "
          f"{diff:.1e} of the largest force (tolerance 1e-12: roundoff, as the state)")
    gi = float(np.abs(a["gas_inside"] - b["gas_inside"]).max()) / max(
        float(np.abs(a["gas_inside"]).max()), 1e-300)
    check(gi <= 1e-12, f"{scheme}: the interpenetration measure on 2 ranks as on 1 to {gi:.1e} "
          f"relative (tolerance 1e-12)")

sys.exit(check.finish())

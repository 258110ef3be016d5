#!/usr/bin/python3
"""Post-processing of a supersonic_bar run (cases/supersonic_bar.ini): the paper's Fig. 5 as a
grid of density panels, and the histories a user of the main job looks at. Run with Debian's
/usr/bin/python3 (h5py, matplotlib):

    /usr/bin/python3 tools/supersonic_bar.py out/supersonic_bar

writes into the run folder (the domain, cell size and bar are read from the case stored in
the snapshots, so refined runs and the gas-only twin with an `[obstacle.bar]` work too)
  density_strip.png  gas density (the snapshot's rho_grid, the grid's density mapped back to
                     the particles, mass-weighted over each cell; --density particle: the
                     particles' own rho, which shows the particle noise cell by cell;
                     white: a cell without gas) at every snapshot after t = 0, one panel each
                     (3 across), axes in mm, one colour bar from 0 to 1.5 x the density behind
                     a normal shock at the free stream's Mach number, so that neither the
                     densest particle nor the run sets it; the bar as the outline of its
                     particles at that time (it bends);
  tip.csv, tip.png   the tip's displacement (probes.csv, every step), mm, beside the same
                     scheme's committed runs at the next finer and coarser cell size (--runs),
                     with the RMS differences;
  force.csv, force.png  the gas force on the bar (coupling.csv, or a gas-only twin's
                     obstacles.csv; every step), kN per m of span: the first 0.1 ms whole on
                     the left, the run on the right on an axis that shows the plateau (the
                     start-up peak clipped and its value written), beside the rigid bar's
                     drag from the finite-volume Euler reference (--euler);
  standoff.csv       per snapshot: the bow shock's stand-off ahead of the bar (the distance
                     from the bar's upstream face to the first x, coming from upstream, where
                     the density averaged over the bar's height rises past 1.5 x the free
                     stream, by linear interpolation), and the empty cells inside the gas
                     (cells without gas whose four face neighbours hold gas).
and prints the figures it wrote. A folder that is not such a run is a one-line error, exit 2;
--help lists the options.
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
# mpmtest moves a test driver started inside the checkout to out/tests/ (and says so): run as a
# command, this tool stays where the user stands, so that a relative run folder means what it
# says, and keeps quiet about a move it undoes.
_CWD = os.getcwd()
if __name__ == "__main__":
    _stderr, sys.stderr = sys.stderr, open(os.devnull, "w")
try:
    import mpmtest as mt  # noqa: E402
finally:
    if __name__ == "__main__":
        sys.stderr.close()
        sys.stderr = _stderr
        os.chdir(_CWD)

RHO_INF = 1.2
# The committed refinement study of the main job (bench/bench_supersonic_bar.py: every run's
# tip history on a 10 us grid) and the rigid bar's finite-volume Euler reference
# (bench/euler_reference.py, 1 mm cells): the comparisons the tip and force figures draw.
RUNS = os.path.join(ROOT, "bench", "results", "supersonic_bar_runs.json")
EULER = os.path.join(ROOT, "bench", "results", "euler_reference_main_dx1.csv")
CASE = os.path.join(ROOT, "cases", "supersonic_bar.ini")


class RunError(Exception):
    """A folder that is not a finished supersonic_bar run: the message says what to give."""


def scene(path):
    """The scene of a run, from the resolved case stored in its snapshot `path`: domain lo and
    hi, cell size, the bar's box (the solid's geometry.bar, or a gas-only twin's
    obstacle.bar), the free stream and the coupling scheme, time method and time.cfl, as a
    dict."""
    import h5py
    with h5py.File(path, "r") as f:
        config = f.attrs["config"]
    config = config.decode() if isinstance(config, bytes) else str(config)
    return scene_of(parse_case(config), path)


def parse_case(text):
    """{"section.key": value} of a case's text."""
    section, kv = "", {}
    for line in text.splitlines():
        line = line.split("#")[0].strip()
        if line.startswith("["):
            section = line.strip("[]")
        elif "=" in line:
            k, v = line.split("=", 1)
            kv[f"{section}.{k.strip()}"] = v.strip()
    return kv


def scene_of(kv, path):
    vec = lambda key: np.array([float(v) for v in kv[key].split()])  # noqa: E731
    # A gas-only twin keeps the case's [geometry.bar] beside its [obstacle.bar] (the same box).
    if "obstacle.bar.lo" in kv:
        bar = "obstacle.bar"
    elif "geometry.bar.lo" in kv:
        bar = "geometry.bar"
    else:
        raise RunError(f"{path}: the case has no [geometry.bar] or [obstacle.bar]: not a run of "
                       "cases/supersonic_bar.ini")
    return {"lo": vec("domain.lo"), "hi": vec("domain.hi"), "dx": float(kv["grid.dx"]),
            "bar_lo": vec(f"{bar}.lo"), "bar_hi": vec(f"{bar}.hi"), "rigid": bar == "obstacle.bar",
            "rho_inf": float(kv.get("freestream.density", RHO_INF)),
            "p_inf": float(kv.get("freestream.pressure", 1.0e5)),
            "u_inf": float(kv.get("freestream.velocity", "854 0").split()[0]),
            "gamma": float(kv.get("fluid.gamma", 1.4)),
            "scheme": kv.get("coupling.scheme", "velocity"),
            "method": kv.get("time.method", "usl"), "cfl": float(kv.get("time.cfl", 0.4)),
            "bar": {k: v for k, v in kv.items() if k.startswith("solid.bar.")}}


def density(P, lo, hi, dx):
    nx, ny = int(round((hi[0] - lo[0]) / dx)), int(round((hi[1] - lo[1]) / dx))
    H, _, _ = np.histogram2d(P["x"][:, 0], P["x"][:, 1], bins=(nx, ny),
                             range=((lo[0], hi[0]), (lo[1], hi[1])), weights=P["m"][:, 0])
    return H / (dx * dx)


def density_field(P, lo, hi, dx, key="rho"):
    """The gas's own density (the particles' `key`, rho or rho_grid, mass-weighted over each
    cell; 0 in a cell without gas), for the picture: it does not flicker with the number of
    particles a cell happens to hold, as the mass per cell (density) does."""
    nx, ny = int(round((hi[0] - lo[0]) / dx)), int(round((hi[1] - lo[1]) / dx))
    rng = ((lo[0], hi[0]), (lo[1], hi[1]))
    m = P["m"][:, 0]
    M = np.histogram2d(P["x"][:, 0], P["x"][:, 1], bins=(nx, ny), range=rng, weights=m)[0]
    R = np.histogram2d(P["x"][:, 0], P["x"][:, 1], bins=(nx, ny), range=rng,
                       weights=m * P[key][:, 0])[0]
    return np.divide(R, M, out=np.zeros_like(R), where=M > 0)


def standoff(rho, sc):
    """Stand-off (m) of the bow shock from the bar's upstream face, or NaN: coming from the
    inflow, the first x where the density averaged over the bar's height passes 1.5 x the free
    stream (linear interpolation between cell centres). rho holds cells of sc["dx"] from
    sc["lo"]. The distance to the inflow when the shock is there (an unstarted channel)."""
    dx, lo, face = sc["dx"], sc["lo"], sc["bar_lo"][0]
    band = rho[:, : int(round((sc["bar_hi"][1] - lo[1]) / dx))].mean(axis=1)
    x = lo[0] + (np.arange(len(band)) + 0.5) * dx
    i_face = int(round((face - lo[0]) / dx))
    # The first two columns hold the inflow's injection layer, denser than the free stream
    # while its particles settle: a shock there counts as at the inflow.
    skip = 2
    above = np.where(band[skip:i_face] > 1.5 * RHO_INF)[0] + skip
    if len(above) == 0:
        return float("nan")
    k = above[0]
    if k == skip:
        return face - lo[0]
    xs = x[k - 1] + dx * (1.5 * RHO_INF - band[k - 1]) / (band[k] - band[k - 1])
    return face - xs


def empty_inside(rho, solid_cells):
    gas = rho > 0
    inner = gas[1:-1, 1:-1] == 0
    nb = gas[:-2, 1:-1] & gas[2:, 1:-1] & gas[1:-1, :-2] & gas[1:-1, 2:]
    return int(np.sum(inner & nb & ~solid_cells[1:-1, 1:-1]))


def forces(out):
    """The gas force on the bar per step (N per m of span): coupling.csv's force on the solid,
    or a gas-only twin's obstacles.csv (the force on the obstacle)."""
    path = os.path.join(out, "coupling.csv")
    if os.path.exists(path):
        cp = np.genfromtxt(path, delimiter=",", names=True)
        return cp["t"], cp["Fx_solid"], cp["Fy_solid"]
    path = os.path.join(out, "obstacles.csv")
    if not os.path.exists(path):
        raise RunError(f"{out} has neither coupling.csv nor obstacles.csv: was the run stopped "
                       "before its first step?")
    ob = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding=None)
    return ob["t"], ob["Fx"], ob["Fy"]


def solid_particles(path):
    """The solid's particles, or None in a gas-only scene."""
    import h5py
    with h5py.File(path, "r") as f:
        if "solid" not in f:
            return None
    return mt.particles(path, "solid")


def bar_cells(S, sc, shape):
    """The cells of the bar: its particles' cells (S, solid_particles of a snapshot), or a
    gas-only twin's obstacle box (S None)."""
    lo, hi, dx = sc["lo"], sc["hi"], sc["dx"]
    if S is not None:
        return np.histogram2d(S["x"][:, 0], S["x"][:, 1], bins=shape,
                              range=((lo[0], hi[0]), (lo[1], hi[1])))[0] > 0
    xc = lo[0] + (np.arange(shape[0]) + 0.5) * dx
    yc = lo[1] + (np.arange(shape[1]) + 0.5) * dx
    return ((xc[:, None] > sc["bar_lo"][0]) & (xc[:, None] < sc["bar_hi"][0])
            & (yc[None, :] > sc["bar_lo"][1]) & (yc[None, :] < sc["bar_hi"][1]))


def normal_shock_density(sc):
    """The density behind a normal shock at the free stream's Mach number (Rankine-Hugoniot):
    the scale of the colour bar, so that it does not follow the densest particle."""
    g = sc["gamma"]
    m2 = sc["u_inf"]**2 / (g * sc["p_inf"] / sc["rho_inf"])
    return sc["rho_inf"] * (g + 1) * m2 / ((g - 1) * m2 + 2)


def bar_mask(X, spacing):
    """The bar as a 0/1 image: (x edges, y edges, mask) on pixels of a third of the particle
    spacing, a pixel set when a particle lies within 0.6 spacing of it in x and in y. Each
    particle stands for a square of one spacing, so the set's outline is the bar's (a tenth of
    a spacing out), and it follows the bar as it bends: the small overlap closes the
    pinholes a rotated lattice leaves between axis-aligned squares."""
    h = spacing / 3
    k = int(np.ceil(0.6 * spacing / h))
    lo, hi = X.min(axis=0) - (k + 2) * h, X.max(axis=0) + (k + 2) * h
    n = np.ceil((hi - lo) / h).astype(int)
    H, xe, ye = np.histogram2d(X[:, 0], X[:, 1], bins=n, range=((lo[0], lo[0] + n[0] * h),
                                                                 (lo[1], lo[1] + n[1] * h)))
    # A (2k+1) x (2k+1) box sum through cumulative sums: nonzero where a particle is near.
    c = np.pad(H, k + 1).cumsum(0).cumsum(1)
    w = 2 * k + 1
    box = c[w:, w:] - c[:-w, w:] - c[w:, :-w] + c[:-w, :-w]
    return xe, ye, (box[:n[0], :n[1]] > 0).astype(float)


def draw_bar(ax, S, sc, spacing, scale):
    """The bar on the axes (lengths times scale): its particles' outline, filled light grey,
    or a gas-only twin's obstacle box."""
    import matplotlib.pyplot as plt
    if S is None:
        ax.add_patch(plt.Rectangle(scale * sc["bar_lo"], *(scale * (sc["bar_hi"] - sc["bar_lo"])),
                                   facecolor="0.85", edgecolor="k", lw=0.8))
        return
    xe, ye, m = bar_mask(S["x"][:, :2], spacing)
    xc, yc = scale * 0.5 * (xe[1:] + xe[:-1]), scale * 0.5 * (ye[1:] + ye[:-1])
    ax.contourf(xc, yc, m.T, levels=[0.5, 1.5], colors=["0.85"])
    ax.contour(xc, yc, m.T, levels=[0.5], colors="k", linewidths=0.8)


def density_figure(out, shown, sc, path, which="grid"):
    """density_strip.png: one panel per snapshot in `shown`, the particles' rho_grid (which =
    grid; their rho where a snapshot has none) or rho (particle); returns the standoff.csv
    rows."""
    import matplotlib.pyplot as plt
    lo, hi, dx = sc["lo"], sc["hi"], sc["dx"]
    mm = 1e3
    ext = (mm * lo[0], mm * hi[0], mm * lo[1], mm * hi[1])
    S0 = solid_particles(shown[0][1])
    # The particle spacing (the lattice the case seeds: a particle's initial volume), for the
    # outline.
    spacing = float(np.sqrt(np.median(S0["V0"]))) if S0 is not None else dx
    vmax = 1.5 * normal_shock_density(sc)
    ncol = min(3, len(shown))
    nrow = int(np.ceil(len(shown) / ncol))
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.9 * ncol + 1.0, 3.9 * aspect * nrow + 0.9),
                             squeeze=False, sharex=True, sharey=True, constrained_layout=True)
    cmap = plt.get_cmap("viridis").copy()
    cmap.set_bad("white")
    rows = []
    for k, ax in enumerate(axes.flat):
        if k >= len(shown):
            ax.set_visible(False)
            continue
        t, snap = shown[k]
        G, S = mt.particles(snap, "fluid"), solid_particles(snap)
        rho = density(G, lo, hi, dx)
        so, ne = standoff(rho, sc), empty_inside(rho, bar_cells(S, sc, rho.shape))
        rows.append((t, so, ne))
        key = "rho_grid" if which == "grid" and "rho_grid" in G else "rho"
        shown_rho = density_field(G, lo, hi, dx, key) if key in G else rho
        im = ax.imshow(np.ma.masked_equal(shown_rho.T, 0), origin="lower", extent=ext, cmap=cmap,
                       vmin=0, vmax=vmax, interpolation="nearest")
        draw_bar(ax, S, sc, spacing, mm)
        ax.set_xlim(ext[0], ext[1]), ax.set_ylim(ext[2], ext[3])
        ax.set_aspect("equal")
        so_text = f", stand-off {mm * so:.0f} mm" if np.isfinite(so) else ""
        ax.set_title(f"t = {t * 1e3:.2f} ms{so_text}", fontsize=10)
        if k // ncol == nrow - 1 or k + ncol >= len(shown):
            ax.set_xlabel("x (mm)")
        if k % ncol == 0:
            ax.set_ylabel("y (mm)")
    rigid = sc["rigid"] or sc["bar"].get("solid.bar.material") == "rigid"
    kind = "gas only" if sc["rigid"] else f"{sc['scheme']} coupling, {sc['method']}"
    fig.suptitle(f"Mach {sc['u_inf'] / np.sqrt(sc['gamma'] * sc['p_inf'] / sc['rho_inf']):.1f} "
                 f"air over a {'rigid' if rigid else 'clamped elastic'} bar: gas "
                 f"{'particle ' if which == 'particle' else ''}density ({kind}, "
                 f"dx = {mm * dx:g} mm, CFL {sc['cfl']:g})", fontsize=11)
    fig.colorbar(im, ax=axes.ravel().tolist(), label="density (kg/m^3)", shrink=0.8,
                 extend="max")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return rows


def committed_tips(sc, runs_path):
    """The committed refinement study's runs of this run's scheme, time method and time.cfl
    (bench/results/supersonic_bar_runs.json): {dx: (t, ux in m)}; empty when there is none, or
    for a gas-only twin."""
    if sc["rigid"] or not runs_path or not os.path.exists(runs_path):
        return {}
    # The study ran the case's own bar: another material (the rigid twin) has no comparison.
    with open(CASE) as f:
        case_bar = {k: v for k, v in parse_case(f.read()).items() if k.startswith("solid.bar.")}
    if any(sc["bar"].get(k) != v for k, v in case_bar.items() if k != "solid.bar.geometry"):
        return {}
    with open(runs_path) as f:
        rows = json.load(f)
    t = np.linspace(0.0, 0.003, 301)  # bench_supersonic_bar.T_HIST
    return {float(r["dx"]): (t, np.array(r["tip_hist"])) for r in rows
            if r.get("ok") and "tip_hist" in r and r.get("scheme") == sc["scheme"]
            and r.get("method") == sc["method"] and abs(r.get("cfl", 0.4) - sc["cfl"]) < 1e-9}


def tip_figure(out, pr, sc, runs_path, path):
    """tip.png: this run's tip ux, uy (mm) against the committed runs at the next finer and
    the next coarser cell size; prints the RMS differences."""
    import matplotlib.pyplot as plt
    ms, mm, dx = 1e3, 1e3, sc["dx"]
    t, ux, uy = pr["t"], pr["tip_ux"], pr["tip_uy"]
    ref = committed_tips(sc, runs_path)
    finer = [d for d in ref if d < dx - 1e-12]
    coarser = [d for d in ref if d > dx + 1e-12]
    fig, ax = plt.subplots(figsize=(8.0, 4.2))
    ax.plot(ms * t, mm * ux, color="C0", lw=1.6,
            label=f"this run, dx = {mm * dx:g} mm: ux (downstream)")
    ax.plot(ms * t, mm * uy, color="C0", lw=1.0, ls=":",
            label=f"this run, dx = {mm * dx:g} mm: uy (vertical)")
    notes = []
    for d, style in ((max(finer), dict(color="C3", lw=1.3, ls="--")) if finer else (None, None),
                     (min(coarser), dict(color="0.55", lw=1.0, ls="-.")) if coarser else
                     (None, None)):
        if d is None:
            continue
        tr, ur = ref[d]
        ax.plot(ms * tr, mm * ur, label=f"committed refinement run, dx = {mm * d:g} mm: ux",
                **style)
        inside = tr <= t[-1] + 1e-12
        diff = np.interp(tr[inside], t, ux) - ur[inside]
        notes.append(f"{mm * np.sqrt(np.mean(diff**2)):.2f} mm against dx = {mm * d:g} mm")
        print(f"tip ux against the committed run at dx = {mm * d:g} mm: RMS difference "
              f"{mm * np.sqrt(np.mean(diff**2)):.3f} mm over 0-{ms * tr[inside][-1]:g} ms")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("t (ms)")
    ax.set_ylabel("tip displacement (mm)")
    ax.set_xlim(0, ms * t[-1])
    title = (f"Bar tip (probe at its top centre): {sc['scheme']} coupling, {sc['method']}, "
             f"CFL {sc['cfl']:g}")
    if notes:
        title += f"\nRMS difference of ux over 0-{ms * t[-1]:g} ms: " + ", ".join(notes)
    ax.set_title(title, fontsize=9.5)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def euler_drag(sc, euler_path):
    """(t, Fx in N/m) of the rigid bar in the finite-volume Euler reference, when its scene is
    this run's (domain and bar position); else None."""
    meta = os.path.splitext(euler_path or "")[0] + ".json"
    if not euler_path or not os.path.exists(euler_path) or not os.path.exists(meta):
        return None
    with open(meta) as f:
        m = json.load(f)
    size = sc["hi"] - sc["lo"]
    if (abs(m.get("length", 0) - size[0]) > 1e-9 or abs(m.get("height", 0) - size[1]) > 1e-9
            or abs(m.get("bar_x", 0) - sc["bar_lo"][0]) > 1e-9):
        return None
    d = np.genfromtxt(euler_path, delimiter=",", names=True)
    return d["t"], d["Fx"], m.get("dx")


def force_figure(t, Fx, Fy, sc, euler_path, path):
    """force.png: on the right the force history in kN/m on an axis that shows the plateau,
    the start-up transient clipped and its peak annotated; on the left the first 0.1 ms
    whole."""
    import matplotlib.pyplot as plt
    ms, k, t0 = 1e3, 1e-3, 0.1e-3
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(9.5, 4.2),
                                 gridspec_kw=dict(width_ratios=[1, 3.2]))
    ref = euler_drag(sc, euler_path)
    series = [(Fx, "Fx (drag)", "C0"), (Fy, "Fy", "C1")]
    early = t <= t0
    for F, label, colour in series:
        a0.plot(1e6 * t[early], k * F[early], color=colour, lw=0.9)
        a1.plot(ms * t, k * F, color=colour, lw=0.9, label=label)
    if ref is not None:
        a1.plot(ms * ref[0], k * ref[1], color="k", lw=1.2, ls="--",
                label="Fx of a rigid bar: finite-volume Euler reference "
                      f"(dx = {1e3 * ref[2]:g} mm)")
    a0.set_xlim(0, 1e6 * t0)
    a0.set_xlabel("t (us)")
    a0.set_ylabel("force on the bar (kN per m of span)")
    a0.set_title("start-up, 0-0.1 ms, whole", fontsize=9.5)
    # The right axis: what the force does once the bow shock has stood off (after 5 % of the
    # run), with a margin.
    late = t > 0.05 * t[-1]
    lo_, hi_ = np.percentile(np.r_[Fx[late], Fy[late]], [0.2, 99.8])
    pad = 0.15 * (hi_ - lo_)
    ylo, yhi = k * min(lo_ - pad, 0), k * (hi_ + pad)
    a1.set_ylim(ylo, yhi)
    a1.axvspan(0, ms * t0, color="0.92", zorder=0)
    clipped = []
    for F, label, colour in series:
        i = int(np.argmax(np.abs(F)))
        if not ylo <= k * F[i] <= yhi:
            clipped.append(f"{label.split()[0]} peaks at {k * F[i]:.0f} kN/m at "
                           f"t = {1e6 * t[i]:.1f} us")
    if clipped:
        a1.text(0.02 * ms * t[-1] + ms * t0, yhi - 0.04 * (yhi - ylo),
                "start-up clipped (left): " + "; ".join(clipped), fontsize=8, va="top")
    a1.set_xlim(0, ms * t[-1])
    a1.set_xlabel("t (ms)")
    a1.set_ylabel("kN per m of span")
    a1.set_title("gas force on the bar, every step", fontsize=9.5)
    for a in (a0, a1):
        a.grid(alpha=0.3)
    fig.legend(loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(out, runs=RUNS, euler=EULER, which="grid"):
    """Draw the figures and write the tables of run folder `out`; raises RunError for a folder
    that is not a run of the case."""
    import matplotlib
    matplotlib.use("Agg")
    if not os.path.isdir(out):
        raise RunError(f"no folder {out}: give the output.dir of a run of "
                       "cases/supersonic_bar.ini (bash tools/run_main.sh writes "
                       "out/supersonic_bar)")
    if not os.path.exists(os.path.join(out, "series.xmf")):
        raise RunError(f"{out} has no series.xmf: not an mpmfsi run folder (give the output.dir "
                       "of a run of cases/supersonic_bar.ini)")
    snaps = mt.snapshots(out)
    shown = [s for s in snaps if s[0] > 0]
    if not shown:
        raise RunError(f"{out} holds no snapshot after t = 0: the run stopped before its first "
                       "output.interval")
    sc = scene(snaps[0][1])
    rows = density_figure(out, shown, sc, os.path.join(out, "density_strip.png"), which)
    with open(os.path.join(out, "standoff.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "standoff_m", "empty_cells_inside_gas"])
        w.writerows(rows)

    written = ["density_strip.png"]
    if os.path.exists(os.path.join(out, "probes.csv")):
        pr = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
        np.savetxt(os.path.join(out, "tip.csv"),
                   np.c_[pr["t"], 1e3 * pr["tip_ux"], 1e3 * pr["tip_uy"]], delimiter=",",
                   header="t,ux_mm,uy_mm", comments="")
        tip_figure(out, pr, sc, runs, os.path.join(out, "tip.png"))
        written.append("tip.csv/png")
        print(f"tip ux at the end {1e3 * pr['tip_ux'][-1]:.2f} mm, "
              f"largest {1e3 * np.nanmax(pr['tip_ux']):.2f} mm")
    t, Fx, Fy = forces(out)
    np.savetxt(os.path.join(out, "force.csv"), np.c_[t, Fx, Fy], delimiter=",",
               header="t,Fx_N_per_m,Fy_N_per_m", comments="")
    force_figure(t, Fx, Fy, sc, euler, os.path.join(out, "force.png"))
    written.append("force.csv/png")
    for t, so, ne in rows:
        print(f"t = {t * 1e3:.2f} ms: stand-off {so * 1e3:.2f} mm, empty cells inside the gas {ne}")
    print(f"wrote {', '.join(written)}, standoff.csv in {out}")


def cli(argv=None):
    ap = argparse.ArgumentParser(
        prog="supersonic_bar.py",
        description="Figures and tables of a run of cases/supersonic_bar.ini (the main job): "
                    "density_strip.png, tip.png/csv, force.png/csv, standoff.csv, written into "
                    "the run folder.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("out", nargs="?", default="out/supersonic_bar",
                    help="the run's output.dir")
    ap.add_argument("--runs", default=RUNS,
                    help="the refinement study whose tip histories tip.png compares with "
                         "(bench/bench_supersonic_bar.py's store; 'none' for none)")
    ap.add_argument("--euler", default=EULER,
                    help="the rigid bar's finite-volume Euler reference force.png compares "
                         "with (bench/euler_reference.py's csv; 'none' for none)")
    ap.add_argument("--density", choices=("grid", "particle"), default="grid",
                    help="the strip's density: the snapshots' rho_grid (the grid's density "
                         "mapped back to the particles) or the particles' own rho")
    a = ap.parse_args(argv)
    try:
        main(a.out, None if a.runs == "none" else a.runs, None if a.euler == "none" else a.euler,
             a.density)
    except RunError as e:
        print(f"supersonic_bar.py: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    try:
        sys.exit(cli())
    except BrokenPipeError:  # the reader went away (| head): nothing left to say
        sys.stderr.close()
        sys.exit(0)

"""Post-processing of a supersonic_bar run (cases/supersonic_bar.ini): the paper's Fig. 5 as
one strip, and the histories a user of the main job looks at. Run with Debian's
/usr/bin/python3 (h5py, matplotlib):

    /usr/bin/python3 tools/supersonic_bar.py out/supersonic_bar

writes into the run folder (the domain, cell size and bar are read from the case stored in
the snapshots, so refined runs and the gas-only twin with an `[obstacle.bar]` work too)
  density_strip.png  gas density (mass per cell over the cell area: an empty cell shows as
                     white) at every snapshot after t = 0, with the bar in black;
  tip.csv, tip.png   the tip's displacement (probes.csv, every step), mm;
  force.csv, force.png  the gas force on the bar (coupling.csv, or a gas-only twin's
                     obstacles.csv; every step), N per m of span;
  standoff.csv       per snapshot: the bow shock's stand-off ahead of the bar (the distance
                     from the bar's upstream face to the first x, coming from upstream, where
                     the density averaged over the bar's height rises past 1.5 x the free
                     stream, by linear interpolation), and the empty cells inside the gas
                     (cells without gas whose four face neighbours hold gas).
and prints the figures it wrote.
"""
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "tools"))
import mpmtest as mt  # noqa: E402

RHO_INF = 1.2


def scene(path):
    """The scene of a run, from the resolved case stored in its snapshot `path`: domain lo and
    hi, cell size, and the bar's box (the solid's geometry.bar, or a gas-only twin's
    obstacle.bar), as a dict."""
    import h5py
    with h5py.File(path, "r") as f:
        config = f.attrs["config"]
    config = config.decode() if isinstance(config, bytes) else str(config)
    section, kv = "", {}
    for line in config.splitlines():
        line = line.split("#")[0].strip()
        if line.startswith("["):
            section = line.strip("[]")
        elif "=" in line:
            k, v = line.split("=", 1)
            kv[f"{section}.{k.strip()}"] = v.strip()
    vec = lambda key: np.array([float(v) for v in kv[key].split()])  # noqa: E731
    bar = "geometry.bar" if "geometry.bar.lo" in kv else "obstacle.bar"
    return {"lo": vec("domain.lo"), "hi": vec("domain.hi"), "dx": float(kv["grid.dx"]),
            "bar_lo": vec(f"{bar}.lo"), "bar_hi": vec(f"{bar}.hi")}


def density(P, lo, hi, dx):
    nx, ny = int(round((hi[0] - lo[0]) / dx)), int(round((hi[1] - lo[1]) / dx))
    H, _, _ = np.histogram2d(P["x"][:, 0], P["x"][:, 1], bins=(nx, ny),
                             range=((lo[0], hi[0]), (lo[1], hi[1])), weights=P["m"][:, 0])
    return H / (dx * dx)


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
    ob = np.genfromtxt(os.path.join(out, "obstacles.csv"), delimiter=",", names=True, dtype=None,
                       encoding=None)
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


def main(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import h5py
    snaps = mt.snapshots(out)
    sc = scene(snaps[0][1])
    lo, hi, dx = sc["lo"], sc["hi"], sc["dx"]
    ext = (lo[0], hi[0], lo[1], hi[1])
    shown = [s for s in snaps if s[0] > 0]
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])
    fig, axes = plt.subplots(len(shown), 1, figsize=(7, 0.3 + 5.2 * aspect * len(shown)),
                             squeeze=False, constrained_layout=True)
    rows = []
    for ax, (t, path) in zip(axes[:, 0], shown):
        rho, S = density(mt.particles(path, "fluid"), lo, hi, dx), solid_particles(path)
        so, ne = standoff(rho, sc), empty_inside(rho, bar_cells(S, sc, rho.shape))
        rows.append((t, so, ne))
        im = ax.imshow(np.ma.masked_equal(rho.T, 0), origin="lower", extent=ext,
                       cmap="viridis", vmin=0, vmax=6)
        if S is not None:
            ax.plot(S["x"][:, 0], S["x"][:, 1], "k.", ms=0.6)
        else:
            ax.add_patch(plt.Rectangle(sc["bar_lo"], *(sc["bar_hi"] - sc["bar_lo"]), color="k"))
        ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1])
        ax.set_title(f"t = {t * 1e3:.2f} ms   stand-off {so * 1e3:.1f} mm", fontsize=9)
        ax.set_aspect("equal")
    fig.colorbar(im, ax=axes[:, 0].tolist(), label="density, kg/m³", shrink=0.6)
    fig.savefig(os.path.join(out, "density_strip.png"), dpi=110, bbox_inches="tight")
    plt.close(fig)
    with open(os.path.join(out, "standoff.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "standoff_m", "empty_cells_inside_gas"])
        w.writerows(rows)

    histories = []  # (file, t, series, labels, unit)
    if os.path.exists(os.path.join(out, "probes.csv")):
        pr = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
        np.savetxt(os.path.join(out, "tip.csv"),
                   np.c_[pr["t"], 1e3 * pr["tip_ux"], 1e3 * pr["tip_uy"]], delimiter=",",
                   header="t,ux_mm,uy_mm", comments="")
        histories.append(("tip.png", pr["t"], (1e3 * pr["tip_ux"], 1e3 * pr["tip_uy"]),
                          ("ux", "uy"), "mm"))
        print(f"tip ux at the end {1e3 * pr['tip_ux'][-1]:.2f} mm, "
              f"largest {1e3 * np.nanmax(pr['tip_ux']):.2f} mm")
    t, Fx, Fy = forces(out)
    np.savetxt(os.path.join(out, "force.csv"), np.c_[t, Fx, Fy], delimiter=",",
               header="t,Fx_N_per_m,Fy_N_per_m", comments="")
    histories.append(("force.png", t, (Fx, Fy), ("Fx", "Fy"), "N/m"))
    for name, x, ys, labels, unit in histories:
        fig, ax = plt.subplots(figsize=(6, 3.2))
        for y, lab in zip(ys, labels):
            ax.plot(1e3 * x, y, label=lab)
        ax.set_xlabel("t, ms"), ax.set_ylabel(unit), ax.legend(), ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(os.path.join(out, name), dpi=110)
        plt.close(fig)
    for t, so, ne in rows:
        print(f"t = {t * 1e3:.2f} ms: stand-off {so * 1e3:.2f} mm, empty cells inside the gas {ne}")
    print(f"wrote density_strip.png, tip.csv/png, force.csv/png, standoff.csv in {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out/supersonic_bar")

"""Post-processing of a supersonic_bar run (cases/supersonic_bar.ini): the paper's Fig. 5 as
one strip, and the histories a user of the main job looks at. Run with Debian's
/usr/bin/python3 (h5py, matplotlib):

    /usr/bin/python3 tools/supersonic_bar.py out/supersonic_bar

writes into the run folder
  density_strip.png  gas density (mass per cell over the cell area: an empty cell shows as
                     white) at every snapshot after t = 0, with the bar's particles in black;
  tip.csv, tip.png   the tip's displacement (probes.csv, every step), mm;
  force.csv, force.png  the gas force on the bar (coupling.csv, every step), N per m of span;
  standoff.csv       per snapshot: the bow shock's stand-off ahead of the bar (the distance
                     from the bar's upstream face to the first x, coming from upstream, where
                     the density averaged over y in [0, 0.03] rises past 1.5 x the free
                     stream, to 0.1 mm by linear interpolation), and the empty cells inside
                     the gas (cells without gas whose four face neighbours hold gas).
and prints the figures it wrote.
"""
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "tools"))
import mpmtest as mt  # noqa: E402

RHO_INF, FACE = 1.2, 0.05


def density(P, lo, hi, dx):
    nx, ny = int(round((hi[0] - lo[0]) / dx)), int(round((hi[1] - lo[1]) / dx))
    H, _, _ = np.histogram2d(P["x"][:, 0], P["x"][:, 1], bins=(nx, ny),
                             range=((lo[0], hi[0]), (lo[1], hi[1])), weights=P["m"][:, 0])
    return H / (dx * dx)


def standoff(rho, dx):
    """Stand-off (m) of the bow shock from the upstream face, or NaN."""
    band = rho[:, : int(round(0.03 / dx))].mean(axis=1)
    x = (np.arange(len(band)) + 0.5) * dx
    i_face = int(FACE / dx)
    above = np.where(band[:i_face] > 1.5 * RHO_INF)[0]
    if len(above) == 0:
        return float("nan")
    k = above[0]
    if k == 0:
        return FACE
    xs = x[k - 1] + dx * (1.5 * RHO_INF - band[k - 1]) / (band[k] - band[k - 1])
    return FACE - xs


def empty_inside(rho, solid_cells):
    gas = rho > 0
    inner = gas[1:-1, 1:-1] == 0
    nb = gas[:-2, 1:-1] & gas[2:, 1:-1] & gas[1:-1, :-2] & gas[1:-1, 2:]
    return int(np.sum(inner & nb & ~solid_cells[1:-1, 1:-1]))


def main(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import h5py
    snaps = mt.snapshots(out)
    lo, hi = np.array([0.0, 0.0]), np.array([0.3, 0.18])
    with h5py.File(snaps[0][1], "r") as f:  # the cell size, from the resolved case
        config = f.attrs["config"]
    config = config.decode() if isinstance(config, bytes) else str(config)
    section, dx = "", None
    for line in config.splitlines():
        line = line.split("#")[0].strip()
        if line.startswith("["):
            section = line.strip("[]")
        elif section == "grid" and line.split("=")[0].strip() == "dx":
            dx = float(line.split("=")[1])
    shown = [s for s in snaps if s[0] > 0]
    fig, axes = plt.subplots(len(shown), 1, figsize=(7, 2.6 * len(shown)), squeeze=False)
    rows = []
    for ax, (t, path) in zip(axes[:, 0], shown):
        G, S = mt.particles(path, "fluid"), mt.particles(path, "solid")
        rho = density(G, lo, hi, dx)
        sc = np.histogram2d(S["x"][:, 0], S["x"][:, 1], bins=rho.shape,
                            range=((lo[0], hi[0]), (lo[1], hi[1])))[0] > 0
        so, ne = standoff(rho, dx), empty_inside(rho, sc)
        rows.append((t, so, ne))
        im = ax.imshow(np.ma.masked_equal(rho.T, 0), origin="lower", extent=(0, 0.3, 0, 0.18),
                       cmap="viridis", vmin=0, vmax=6)
        ax.plot(S["x"][:, 0], S["x"][:, 1], "k.", ms=0.6)
        ax.set_xlim(0, 0.3), ax.set_ylim(0, 0.18)
        ax.set_title(f"t = {t * 1e3:.2f} ms   stand-off {so * 1e3:.1f} mm", fontsize=9)
        ax.set_aspect("equal")
    fig.colorbar(im, ax=axes[:, 0].tolist(), label="density, kg/m³", shrink=0.6)
    fig.savefig(os.path.join(out, "density_strip.png"), dpi=110)
    plt.close(fig)
    with open(os.path.join(out, "standoff.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "standoff_m", "empty_cells_inside_gas"])
        w.writerows(rows)

    pr = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
    np.savetxt(os.path.join(out, "tip.csv"), np.c_[pr["t"], 1e3 * pr["tip_ux"], 1e3 * pr["tip_uy"]],
               delimiter=",", header="t,ux_mm,uy_mm", comments="")
    cp = np.genfromtxt(os.path.join(out, "coupling.csv"), delimiter=",", names=True)
    np.savetxt(os.path.join(out, "force.csv"), np.c_[cp["t"], cp["Fx_solid"], cp["Fy_solid"]],
               delimiter=",", header="t,Fx_N_per_m,Fy_N_per_m", comments="")
    for name, x, ys, labels, unit in (
            ("tip.png", pr["t"], (1e3 * pr["tip_ux"], 1e3 * pr["tip_uy"]), ("ux", "uy"), "mm"),
            ("force.png", cp["t"], (cp["Fx_solid"], cp["Fy_solid"]), ("Fx", "Fy"), "N/m")):
        fig, ax = plt.subplots(figsize=(6, 3.2))
        for y, lab in zip(ys, labels):
            ax.plot(1e3 * x, y, label=lab)
        ax.set_xlabel("t, ms"), ax.set_ylabel(unit), ax.legend(), ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(os.path.join(out, name), dpi=110)
        plt.close(fig)
    print(f"tip ux at the end {1e3 * pr['tip_ux'][-1]:.2f} mm, largest {1e3 * np.nanmax(pr['tip_ux']):.2f} mm")
    for t, so, ne in rows:
        print(f"t = {t * 1e3:.2f} ms: stand-off {so * 1e3:.2f} mm, empty cells inside the gas {ne}")
    print(f"wrote density_strip.png, tip.csv/png, force.csv/png, standoff.csv in {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out/supersonic_bar")

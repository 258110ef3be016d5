#!/usr/bin/python3
"""PNG field images of an mpmfsi snapshot: the particles binned onto a pixel image.

Usage: /usr/bin/python3 tools/plot_fields.py SNAPSHOT.h5 | OUTDIR [INDEX]
           [--field rho,p,mach,T,s,speed,sigma] [--out DIR | FILE.png] [--log]
           [--mode mass|nearest] [--pixel SIZE] [--slice Z] [--width PX] [--phase NAME]
e.g.   tools/plot_fields.py out/sod --field rho,p          (last snapshot of out/sod)
       tools/plot_fields.py out/box 3 --field mach --out mach.png
       tools/plot_fields.py out/box/snap_000002.h5 --field rho --log --slice 0.5

Fields: gas (phase `fluid`) rho, p, mach, T, s, as the snapshot stores them; speed |v| (every
phase in the snapshot); J, the volume ratio (a solid's det F); sigma, the von Mises stress
of a solid whose model stores its stress (the rate-form models; the hyperelastic models
store F only); any other one-column particle field by its name. INDEX is
the snapshot number NNNNNN of snap_NNNNNN.h5 (negative: counted from the last; default the
last). One PNG per field, named <snapshot>_<field>.png in --out (default: the snapshot's
folder), or exactly --out when it ends in .png and one field is asked for.

Binning (bin_particles): mode `mass` (default) gives each pixel the mass-weighted mean of the
field over the particles whose positions fall inside it, on pixels of one grid cell
(`grid.dx`); mode `nearest` gives each pixel the value of the particle nearest its centre, on
pixels of a quarter cell, and leaves empty the pixels with no particle within one cell.
Empty pixels are masked (white), so fixed obstacles and regions the gas has left show empty.
In 3-D the image is the x-y plane at z = --slice (default: the middle of the domain), from
the particles within half a pixel of it. Axes in metres, the colour bar in the field's
units, the title with the time. Run with Debian's /usr/bin/python3, which has h5py.
"""
import argparse
import glob
import os
import re
import sys

import h5py
import numpy as np

GAS_FIELDS = ("rho", "p", "mach", "T", "s")
LABELS = {"rho": "density ρ [kg/m³]", "p": "pressure p [Pa]", "mach": "Mach number",
          "T": "temperature T [K]", "s": "entropy s [J/(kg K)]", "speed": "|v| [m/s]",
          "sigma": "von Mises stress [Pa]", "J": "volume ratio J"}


_REQUIRED = object()


def config_value(text, section, key, default=_REQUIRED):
    """Value of `key` in `[section]` of the resolved case text a snapshot carries (the
    `config` attribute: one `key = value   # origin` line per key); `default` if it has none
    (KeyError without one)."""
    current = None
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        m = re.fullmatch(r"\[(.+)\]", line)
        if m:
            current = m.group(1).strip()
        elif current == section and "=" in line:
            k, v = (s.strip() for s in line.split("=", 1))
            if k == key:
                return v
    if default is not _REQUIRED:
        return default
    raise KeyError(f"no {section}.{key} in the snapshot's configuration")


def load(path):
    """The snapshot as a dict: time, dim, lo, hi (domain corners), dx, and per phase a dict
    of its particle datasets (arrays with one row per particle)."""
    with h5py.File(path, "r") as f:
        cfg = f.attrs["config"]
        cfg = cfg.decode() if isinstance(cfg, bytes) else str(cfg)
        dim = int(f.attrs["dim"])
        snap = {"path": path, "time": float(f.attrs["time"]), "dim": dim, "phases": {},
                "lo": np.array(config_value(cfg, "domain", "lo").split(), float)[:dim],
                "hi": np.array(config_value(cfg, "domain", "hi").split(), float)[:dim],
                "dx": float(config_value(cfg, "grid", "dx"))}
        for name, g in f.items():
            if isinstance(g, h5py.Group) and "x" in g and "m" in g:
                snap["phases"][name] = {k: g[k][()] for k in g if isinstance(g[k], h5py.Dataset)}
    return snap


def von_mises(sig, dim):
    """Von Mises equivalent of Cauchy stresses stored row-major (n x dim*dim); in 2-D the
    out-of-plane stress is taken as zero."""
    s = sig.reshape(-1, dim, dim)
    full = np.zeros((len(s), 3, 3))
    full[:, :dim, :dim] = s
    dev = full - np.trace(full, axis1=1, axis2=2)[:, None, None] * np.eye(3) / 3
    return np.sqrt(1.5 * np.einsum("nij,nij->n", dev, dev))


def field_values(snap, field, phase=None):
    """(positions, masses, values) of `field` over the particles that carry it: gas fields
    from the `fluid` phase, speed and J from every phase, sigma from the solid phase, any
    other name from the phases holding a one-column dataset of that name (or only `phase`)."""
    xs, ms, qs = [], [], []
    for name, P in snap["phases"].items():
        if phase is not None and name != phase:
            continue
        if field == "speed":
            q = np.linalg.norm(P["v"], axis=1)
        elif field == "J" and "J" not in P and "F" in P:
            q = np.linalg.det(P["F"].reshape(-1, snap["dim"], snap["dim"]))
        elif field == "sigma":
            if "sigma" not in P:
                continue
            q = von_mises(P["sigma"], snap["dim"])
        elif field in P and P[field].ndim == 2 and P[field].shape[1] == 1:
            if field in GAS_FIELDS and name != "fluid":
                continue
            q = P[field][:, 0]
        else:
            continue
        xs.append(P["x"]), ms.append(P["m"][:, 0]), qs.append(q)
    if not qs:
        have = {n: sorted(P) for n, P in snap["phases"].items()}
        raise SystemExit(f"error: {snap['path']}: no particles carry the field '{field}' "
                         f"(phases and their fields: {have}; sigma needs a solid model that "
                         "stores its stress)")
    return np.concatenate(xs), np.concatenate(ms), np.concatenate(qs)


def image_shape(lo, hi, pixel):
    """(ny, nx) pixels of size `pixel` covering the rectangle [lo, hi] (rounded up)."""
    n = np.maximum(np.ceil((np.asarray(hi) - np.asarray(lo)) / pixel - 1e-9).astype(int), 1)
    return int(n[1]), int(n[0])


def bin_particles(x, q, w, lo, hi, pixel, mode="mass", reach=None):
    """Bin particle values q (positions x: n x 2, weights w: the masses) onto the pixel image
    of [lo, hi] with square pixels of side `pixel`; returns a masked array of shape
    image_shape(...), row 0 at y = lo[1]. mode "mass": per pixel sum(w q) / sum(w) over the
    particles inside it; "nearest": the value of the particle nearest the pixel centre, masked
    where that particle is farther than `reach` (default: 4 pixels). Pixels with no value
    are masked."""
    lo, hi = np.asarray(lo, float)[:2], np.asarray(hi, float)[:2]
    ny, nx = image_shape(lo, hi, pixel)
    x = np.asarray(x, float)[:, :2]
    if mode == "mass":
        ij = np.floor((x - lo) / pixel).astype(int)
        ok = (ij[:, 0] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] >= 0) & (ij[:, 1] < ny)
        flat = ij[ok, 1] * nx + ij[ok, 0]
        wsum = np.bincount(flat, weights=w[ok], minlength=nx * ny)
        qsum = np.bincount(flat, weights=w[ok] * q[ok], minlength=nx * ny)
        empty = wsum <= 0
        img = np.divide(qsum, wsum, out=np.zeros_like(qsum), where=~empty)
        return np.ma.masked_array(img.reshape(ny, nx), empty.reshape(ny, nx))
    if mode == "nearest":
        from scipy.spatial import cKDTree
        cy, cx = np.meshgrid(lo[1] + (np.arange(ny) + 0.5) * pixel,
                             lo[0] + (np.arange(nx) + 0.5) * pixel, indexing="ij")
        if len(x) == 0:
            return np.ma.masked_all((ny, nx))
        dist, k = cKDTree(x).query(np.column_stack([cx.ravel(), cy.ravel()]))
        far = dist > (4 * pixel if reach is None else reach)
        return np.ma.masked_array(np.asarray(q)[k].reshape(ny, nx), far.reshape(ny, nx))
    raise ValueError(f"unknown binning mode '{mode}' (mass or nearest)")


def slice_3d(x, m, q, z, thickness):
    """The particles within thickness/2 of the plane z (3-D positions), positions in x-y."""
    keep = np.abs(x[:, 2] - z) <= 0.5 * thickness
    return x[keep, :2], m[keep], q[keep]


def render(img, lo, hi, title, label, out, log=False, width=800):
    """Write the image as a PNG of `width` pixels and a height that follows the domain's
    aspect ratio (at least 240 px for the colour bar and title); returns (width, height)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    dpi = 100
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])
    height = int(max(240, min(3 * width, round(0.85 * width * aspect + 110))))
    fig = plt.figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    ax = fig.add_axes([0.1, 0.12, 0.72, 0.78])
    cax = fig.add_axes([0.86, 0.12, 0.03, 0.78])
    norm = None
    if log:
        if img.count() and img.min() <= 0:
            raise SystemExit(f"error: --log: the field has values <= 0 (min {img.min():g})")
        norm = LogNorm()
    cmap = matplotlib.colormaps["viridis"].copy()
    cmap.set_bad("white")
    im = ax.imshow(img, origin="lower", extent=(lo[0], hi[0], lo[1], hi[1]), cmap=cmap,
                   norm=norm, interpolation="nearest", aspect="equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    fig.colorbar(im, cax=cax, label=label)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return width, height


def snapshot_path(target, index):
    """The snapshot file: `target` itself, or snap_<index>.h5 in the folder `target`."""
    if os.path.isfile(target):
        return target
    snaps = sorted(glob.glob(os.path.join(target, "snap_*.h5")))
    if not snaps:
        raise SystemExit(f"error: {target}: no snap_*.h5 snapshots")
    if index < 0:
        if -index > len(snaps):
            raise SystemExit(f"error: {target}: {len(snaps)} snapshots, index {index}")
        return snaps[index]
    path = os.path.join(target, f"snap_{index:06d}.h5")
    if not os.path.isfile(path):
        raise SystemExit(f"error: {path} does not exist")
    return path


def plot_field(snap, field, out, mode="mass", pixel=None, log=False, z=None, width=800,
               phase=None):
    """Bin one field of a loaded snapshot and write its PNG; returns (image, (width, height))."""
    x, m, q = field_values(snap, field, phase)
    lo, hi, dx = snap["lo"], snap["hi"], snap["dx"]
    if pixel is None:
        pixel = dx if mode == "mass" else dx / 4
    where = ""
    if snap["dim"] == 3:
        z = 0.5 * (lo[2] + hi[2]) if z is None else z
        x, m, q = slice_3d(x, m, q, z, max(pixel, dx / 2))
        where = f", z = {z:g} m"
    img = bin_particles(x, q, m, lo, hi, pixel, mode, reach=dx if mode == "nearest" else None)
    title = f"{field} at t = {snap['time']:.6g} s{where}"
    size = render(img, lo, hi, title, LABELS.get(field, field), out, log, width)
    return img, size


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("target", help="snapshot file or output folder")
    ap.add_argument("index", nargs="?", type=int, default=-1, help="snapshot number (folder)")
    ap.add_argument("--field", default="rho", help="comma-separated fields")
    ap.add_argument("--out", default=None, help="folder, or FILE.png for one field")
    ap.add_argument("--log", action="store_true", help="logarithmic colour scale")
    ap.add_argument("--mode", default="mass", choices=("mass", "nearest"))
    ap.add_argument("--pixel", type=float, default=None, help="pixel size in metres")
    ap.add_argument("--slice", type=float, default=None, dest="z", help="z of the 3-D slice")
    ap.add_argument("--width", type=int, default=800, help="PNG width in pixels")
    ap.add_argument("--phase", default=None, help="only this phase (e.g. fluid, solid)")
    a = ap.parse_args(argv[1:])
    path = snapshot_path(a.target, a.index)
    snap = load(path)
    fields = [f for f in a.field.split(",") if f]
    stem = os.path.splitext(os.path.basename(path))[0]
    for field in fields:
        if a.out and a.out.endswith(".png"):
            if len(fields) > 1:
                raise SystemExit("error: --out FILE.png takes one field; give a folder")
            out = a.out
        else:
            folder = a.out or os.path.dirname(os.path.abspath(path))
            os.makedirs(folder, exist_ok=True)
            out = os.path.join(folder, f"{stem}_{field}.png")
        img, (w, h) = plot_field(snap, field, out, a.mode, a.pixel, a.log, a.z, a.width, a.phase)
        print(f"wrote {out} ({w} x {h} px; {img.count()} of {img.size} pixels filled, "
              f"{field} {img.min():.6g} ... {img.max():.6g})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

"""Field images (tools/plot_fields.py) of gas snapshots.

1. bin_particles on made-up particles: two particles of mass 1 and 3 with values 0 and 4 in
   one pixel give the mass-weighted mean 3 exactly; a pixel without particles is masked; a
   particle on the far edge of the domain is left out rather than wrapped; "nearest" gives
   the nearest particle's value and masks pixels farther than the reach.
2. A short Sod run (cases/sod.ini at 100 x 3 cells to t = 0.02, a few steps): the CLI writes one
   PNG per field (rho, p, mach, T, s) for the last snapshot, each a valid PNG of the asked
   width (640) and the height the layout gives a 1 x 0.03 strip (its minimum, 240 px). The
   binned density and pressure (mass mode on pixels of one cell, nearest mode on pixels of a
   quarter cell) fill every pixel (gas fills the strip) and hold the known states to 1e-12
   relative: at t = 0 exactly (1, 1) left of x = 0.5 and (0.125, 0.1) right of it, pixel by
   pixel (the diaphragm is a pixel edge, so a shifted or transposed image fails); at t = 0.02
   left of x = 0.3 and right of 0.75, where the gas is still undisturbed to below 1e-12
   (measured: the discrete kernels spread the jump as a tail that falls by about 1e-3 per 3
   cells, from 4e-6 at 0.1 to 2e-15 at 0.22 from the diaphragm; the physical waves are at
   0.476 and 0.535).
3. A 3-D periodic box at t = 0 (8^3 cells, uniform density 1, a pressure pulse at the centre):
   the CLI writes a nearest-particle PNG of the slice z = 0.5 (400 x 450 px); in mass mode that slice is full
   and its density is 1 to 1e-12; its pressure (nearest mode, pixels on the particle lattice)
   peaks within one pixel of (0.5, 0.5), and the pixel at (0.7, 0.5) holds the seeded pulse
   1 + 0.5 exp(-r^2 / 0.01) at its particle to 1e-12 (the case's expression evaluated there).
"""
import os
import struct
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

sys.path.insert(0, os.path.join(mt.SOURCE, "tools"))
import plot_fields as pf  # noqa: E402

check = mt.Checks("test_plot_fields")
SCRIPT = os.path.join(mt.SOURCE, "tools", "plot_fields.py")


def png_size(path):
    """(width, height) from a PNG's IHDR chunk, or None if the file is not a PNG."""
    with open(path, "rb") as f:
        head = f.read(24)
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", head[16:24])


# 1. The binning itself.
x = np.array([[0.1, 0.1], [0.2, 0.3], [1.5, 0.5], [2.0, 0.5]])
img = pf.bin_particles(x, np.array([0.0, 4.0, 7.0, 9.0]), np.array([1.0, 3.0, 2.0, 1.0]),
                       [0, 0], [2, 1], 0.5)
check(img.shape == (2, 4), f"a 2 x 1 domain in pixels of 0.5: image shape {img.shape} (2, 4)")
check(img[0, 0] == 3.0 and img[1, 3] == 7.0,
      f"mass-weighted means: pixel (0, 0) {img[0, 0]} (3), pixel (1, 3) {img[1, 3]} (7; the "
      "particle at x = 2, on the far edge, left out)")
check(int(img.count()) == 2, f"{img.count()} pixels filled of 8 (2; the rest masked)")
# nearest: pixel centres (0.25, 0.25), ..., (1.75, 0.75); reach 0.3.
xn = np.array([[0.2, 0.2], [0.45, 0.45], [1.7, 0.8], [1.2, 0.6]])
near = pf.bin_particles(xn, np.array([1.0, 2.0, 3.0, 4.0]), np.ones(4), [0, 0], [2, 1], 0.5,
                        "nearest", reach=0.3)
# Nearest particles and distances: pixel (0, 0) the one at (0.2, 0.2), 0.07; (1, 2) the one at
# (1.2, 0.6), 0.16; (1, 3) the one at (1.7, 0.8), 0.07; every other pixel 0.35 or more.
want = np.ma.masked_array([[1, 0, 0, 0], [0, 0, 4, 3]], [[0, 1, 1, 1], [1, 1, 0, 0]])
same = np.array_equal(near.mask, want.mask) and np.array_equal(near.compressed(), want.compressed())
check(same, f"nearest with reach 0.3: {near.tolist()} (expected {want.tolist()})")

# 2. A short Sod run through the CLI.
out = mt.outdir("plot_sod")
H = 0.03
mt.run(["run", mt.case("sod.ini"), f"output.dir={out}", "grid.dx=0.01", f"domain.hi=1 {H}",
        f"geometry.left.hi=0.5 {H}", f"geometry.right.hi=1 {H}", "time.t_end=0.02",
        "output.interval=0.02", "run.progress=false"])
imgdir = os.path.join(out, "img")
fields = ["rho", "p", "mach", "T", "s"]
p = subprocess.run([sys.executable, SCRIPT, out, "--field", ",".join(fields), "--out", imgdir,
                    "--width", "640"], capture_output=True, text=True)
check(p.returncode == 0, f"plot_fields.py exit status {p.returncode} {p.stderr[-300:]}")
for f in fields:
    path = os.path.join(imgdir, f"snap_000001_{f}.png")
    size = png_size(path) if os.path.exists(path) else None
    check(size == (640, 240), f"{os.path.basename(path)}: PNG of {size} px (640 x 240)")

snaps = mt.snapshots(out)
for (t, path), (xl, xr) in zip(snaps, ((0.5, 0.5), (0.3, 0.75))):
    snap = pf.load(path)
    check(abs(snap["time"] - t) < 1e-12, f"{os.path.basename(path)}: time {snap['time']} ({t})")
    for mode in ("mass", "nearest"):
        for field, (left, right) in (("rho", (1.0, 0.125)), ("p", (1.0, 0.1))):
            xs, m, q = pf.field_values(snap, field)
            pixel = 0.01 if mode == "mass" else 0.0025
            img = pf.bin_particles(xs, q, m, snap["lo"], snap["hi"], pixel, mode,
                                   reach=0.01 if mode == "nearest" else None)
            xc = (np.arange(img.shape[1]) + 0.5) * pixel
            el = float(np.abs(img[:, xc < xl] - left).max()) / left
            er = float(np.abs(img[:, xc > xr] - right).max()) / right
            check(img.count() == img.size and el <= 1e-12 and er <= 1e-12,
                  f"t = {t:g}, {mode} {field}: {img.shape[1]} x {img.shape[0]} pixels, "
                  f"{img.size - img.count()} empty (0); x < {xl}: {left:g} to {el:.1e}, "
                  f"x > {xr}: {right:g} to {er:.1e} (<= 1e-12)")

# 3. A 3-D box, the slice z = 0.5 of the first snapshot (t = 0).
out3 = mt.outdir("plot_box3d")
mt.run(["run", os.path.join(mt.SOURCE, "bench", "bench_fluid.ini"), f"output.dir={out3}",
        "domain.dim=3", "grid.dx=0.125", "domain.lo=0 0 0", "domain.hi=1 1 1",
        "geometry.box.lo=0 0 0", "geometry.box.hi=1 1 1", "boundary.z_lo=periodic",
        "boundary.z_hi=periodic", "output.snapshots=true", "output.interval=0.01",
        "time.t_end=0.01", "gas.air.pressure_field=1 + 0.5*exp(-((x-0.5)^2 + (y-0.5)^2 + "
        "(z-0.5)^2)/0.01)", "run.progress=false"])
png3 = os.path.join(out3, "p3.png")
p = subprocess.run([sys.executable, SCRIPT, out3, "0", "--field", "p", "--slice", "0.5",
                    "--mode", "nearest", "--width", "400", "--out", png3], capture_output=True,
                   text=True)
size = png_size(png3) if os.path.exists(png3) else None
check(p.returncode == 0 and size == (400, 450),
      f"3-D: plot_fields.py exit {p.returncode}, PNG of {size} px (400 x 450: a square domain "
      "at 400 px wide)")
snap3 = pf.load(os.path.join(out3, "snap_000000.h5"))
img_rho, _ = pf.plot_field(snap3, "rho", os.path.join(out3, "rho3.png"), z=0.5)
check(img_rho.count() == img_rho.size == 64 and float(np.abs(img_rho - 1).max()) <= 1e-12,
      f"3-D slice z = 0.5, density: {img_rho.count()} of {img_rho.size} pixels filled (64), "
      f"largest |rho - 1| {float(np.abs(img_rho - 1).max()):.1e} (<= 1e-12)")
xs, m, q = pf.slice_3d(*pf.field_values(snap3, "p"), 0.5, 0.0625)
img_p = pf.bin_particles(xs, q, m, [0, 0], [1, 1], 0.0625, "nearest", reach=0.125)
j, i = np.unravel_index(np.argmax(img_p), img_p.shape)
peak = ((i + 0.5) * 0.0625, (j + 0.5) * 0.0625)
# Particles sit on a lattice of spacing 0.0625 from 0.03125, so each pixel centre holds a
# particle at z = 0.46875 and one at 0.53125 (the same pressure by symmetry): the pixel of
# (0.7, 0.5) must hold the seeded pulse at its centre, z 0.03125 off the centre plane.
ii, jj = int(0.7 / 0.0625), int(0.5 / 0.0625)
cx, cy = (ii + 0.5) * 0.0625, (jj + 0.5) * 0.0625
exact = 1 + 0.5 * np.exp(-((cx - 0.5) ** 2 + (cy - 0.5) ** 2 + 0.03125 ** 2) / 0.01)
check(abs(peak[0] - 0.5) <= 0.0625 and abs(peak[1] - 0.5) <= 0.0625
      and abs(img_p[jj, ii] - exact) <= 1e-12 * exact,
      f"3-D slice, pressure: peak at ({peak[0]:.4f}, {peak[1]:.4f}) (within a pixel of the "
      f"centre); pixel at ({cx}, {cy}): {float(img_p[jj, ii]):.6f} vs the seeded pulse "
      f"{exact:.6f} (to 1e-12)")

sys.exit(check.finish())

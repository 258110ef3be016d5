"""The main job's output as a ParaView 5.11 user meets it, checked on rendered pictures.

A short version of the main job (cases/supersonic_bar.ini at dx = 4 mm to t = 1.5 ms on 2 ranks:
the bow shock stands in front of the bar) is opened in pvpython under xvfb-run:

1. Default: OpenDataFile(series.xmf) (ParaView picks Xdmf3ReaderS), Show, Render, nothing else.
   The picture is not uniform: more than one colour in the domain (before the fix everything
   was white: the reader's one merged dataset kept only the fields every phase has, and the
   gas's colour field rho was not one of them; now the solid has rho too).
2. The shipped script: the run folder's view.py (mpmfsi writes it; tools/paraview_view.py)
   renders the last snapshot to paraview_short.png in the build tree, with the default reader.
   (a) The bar is visible: pixels of the bar's colour fill at least 85 % of the lower bar's box
       (from the case file) and there are none away from the bar. The check guards against a
       bar hidden under the gas or not drawn (about 0 %); the rest of the box is the gas's
       splats over its edges, 8 % in pure FLIP and 10 % since the case took a 2 % PIC share
       (2026-12-02), so the bound is 85 %, not the 90 % it was.
   (b) The bow shock is visible: along the bar's mid-height line upstream of it, the density
       read back from the colours steps from the free stream (1.2) to post-shock (above 3.2;
       4.0 behind a normal shock at Mach 2.5) within a short distance (12 mm: 3 cells), at a
       stand-off from the bar's face in a sensible band (30-75 mm; 52 mm in the steady
       reference solution, docs/main-job.md).
If pvpython or xvfb-run is missing the test fails and names the Debian package.
"""
import json
import os
import shutil
import subprocess
import sys
import time


def default_render(series, png):
    """Under pvpython: what a user gets from the reader alone. (Returns normally: sys.exit
    from pvpython tears the render window down in a way that Xvfb's GLX reports as an error.)"""
    from paraview import simple as pv
    reader = pv.OpenDataFile(series)
    view = pv.GetActiveViewOrCreate("RenderView")
    view.ViewSize = [1000, 800]
    view.OrientationAxesVisibility = 0  # its red and green axes are not data
    pv.Show(reader, view)
    pv.Render(view)
    pv.SaveScreenshot(png, view, ImageResolution=[1000, 800])
    print("reader", reader.GetXMLName())


import numpy as np  # noqa: E402
from matplotlib import colormaps  # noqa: E402
from matplotlib import image as mimage  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

def main():
    check = mt.Checks("test_paraview")
    SHORT = ["grid.dx=0.004", "time.t_end=0.0015", "output.interval=0.0005", "run.progress=false"]
    BAR = (0.1, 0.106, 0.0, 0.03)  # [geometry.bar] of the case file
    RHO_INF, RHO_SHOCK = 1.2, 4.0  # free stream; behind a normal shock at Mach 2.5 (gamma 1.4)

    missing = [f"{tool} (Debian package {pkg})" for tool, pkg in
               (("pvpython", "paraview"), ("xvfb-run", "xvfb")) if not shutil.which(tool)]
    if missing:
        print("FAIL test_paraview needs " + " and ".join(missing) +
              ": apt-get install paraview xvfb (tools/setup.sh)")
        sys.exit(1)

    def pvpython(args):
        """Run pvpython under a virtual X server. One retry: xvfb-run -a can lose the race for a
        display number to another X client starting at the same moment."""
        for attempt in range(2):
            p = subprocess.run(["xvfb-run", "-a", "pvpython"] + args, capture_output=True, text=True,
                               timeout=300)
            x_lost = any(w in p.stderr for w in ("X server", "DISPLAY", "X Error", "GLX"))
            if p.returncode == 0 or not x_lost:
                break
        if p.returncode != 0:
            sys.stderr.write(p.stdout[-3000:] + p.stderr[-3000:])
        return p

    def rgb(path):
        return mimage.imread(path)[..., :3].astype(float)

    # ---- the run ---------------------------------------------------------------------------------
    t0 = time.time()
    out = os.path.abspath(mt.outdir("paraview_bar"))
    mt.run(["run", mt.case("supersonic_bar.ini"), f"output.dir={out}"] + SHORT, ranks=2)
    print(f"info: run {time.time() - t0:.1f} s ({mt.cost(out)})")
    series, script = os.path.join(out, "series.xmf"), os.path.join(out, "view.py")
    shipped = os.path.join(mt.SOURCE, "tools", "paraview_view.py")
    check(os.path.exists(script) and open(script, "rb").read() == open(shipped, "rb").read(),
          "the run folder holds view.py, a copy of tools/paraview_view.py")

    # ---- 1. the reader alone -----------------------------------------------------------------------
    t1 = time.time()
    default_png = os.path.abspath("paraview_default.png")
    p = pvpython([os.path.abspath(__file__), "--default-render", series, default_png])
    print(f"info: default render {time.time() - t1:.1f} s")
    if p.returncode == 0 and os.path.exists(default_png):
        img = rgb(default_png)
        background = img[2, 2]
        data = img[np.abs(img - background).max(axis=2) > 0.02]
        # Colours (1/16 steps) of at least 0.05 % of the data pixels (the bar at t = 0 is 0.2 %)
        # with some saturation: white, its blends with the grey-blue background at the points'
        # edges and the midpoint of the default map are all grey, so "all white" has none,
        # while a mapped field has blue and red.
        q = np.round(data * 16).astype(int)
        colours, counts = np.unique(q, axis=0, return_counts=True)
        major = colours[(counts > 0.0005 * len(q)) & (np.ptp(colours, axis=1) >= 4)]
        distinct = len(major) >= 2 and np.abs(major[:, None] - major[None]).max() >= 5
        check(len(q) > 0.02 * img.shape[0] * img.shape[1] and distinct,
              f"default view ({p.stdout.split()[-1] if p.stdout.split() else '?'}, no script): "
              f"coloured {[tuple(c) for c in major[:4]]} (in 1/16) over {len(q)} data pixels: "
              f"not uniform, the all-white bug is gone; {default_png}")
    else:
        check(False, f"pvpython rendered the default view ({p.returncode})")

    # ---- 2. the shipped script ---------------------------------------------------------------------
    t2 = time.time()
    png = os.path.abspath("paraview_short.png")
    p = pvpython([script, "--png", png])
    print(f"info: view.py {time.time() - t2:.1f} s: {p.stdout.strip()}")
    if p.returncode != 0 or not os.path.exists(png + ".json"):
        check(False, f"view.py rendered the last snapshot ({p.returncode})")
        return check.finish()
    img = rgb(png)
    meta = json.load(open(png + ".json"))
    H, W = img.shape[:2]
    x0, x1, y0, y1 = meta["world_box"]

    def pixel(x, y):
        """(row, column) of world point (x, y)."""
        return (int((y1 - y) / (y1 - y0) * H), int((x - x0) / (x1 - x0) * W))

    def box_mask(xa, xb, ya, yb):
        m = np.zeros((H, W), bool)
        (r1, c0), (r0, c1) = pixel(xa, ya), pixel(xb, yb)
        m[max(r0, 0):max(r1, 0) + 1, max(c0, 0):max(c1, 0) + 1] = True
        return m

    # (a) the bar
    is_bar = np.abs(img - np.array(meta["bar_colour"])).max(axis=2) < 0.1
    r = meta["gaussian_radius"]
    core = box_mask(BAR[0] + 0.001, BAR[1] - 0.001, BAR[2] + 0.002, BAR[2] + 0.012)
    near = box_mask(BAR[0] - r - 0.002, BAR[1] + r + 0.01, BAR[2] - r - 0.002, BAR[3] + r + 0.004)
    fill = is_bar[core].mean() if core.any() else 0.0
    stray = int((is_bar & ~near).sum())
    check(fill >= 0.85 and stray <= 0.01 * is_bar.sum() and is_bar.sum() > 0,
          f"bar visible: {fill:.0%} of the lower bar's box in the bar's colour, {is_bar.sum()} bar "
          f"pixels, {stray} away from the bar")

    # (b) the bow shock: density read back from the colours along the bar's mid-height
    lo, hi = meta["range"]
    lut = colormaps["viridis"](np.linspace(0, 1, 256))[:, :3]
    ymid = 0.5 * (BAR[2] + BAR[3])
    xs = np.linspace(0.004, BAR[0] - 0.004, 400)
    rho = []
    for x in xs:
        rows = [pixel(x, ymid + dy)[0] for dy in (-0.002, 0.0, 0.002)]
        col = pixel(x, ymid)[1]
        px = img[rows, col]
        k = np.argmin(((px[:, None, :] - lut[None, :, :]) ** 2).sum(axis=2), axis=1)
        rho.append(np.median(lo + (hi - lo) * k / 255))
    rho = np.array(rho)
    mid = 0.5 * (RHO_INF + RHO_SHOCK)
    above = np.nonzero(rho > mid)[0]
    if len(above):
        xs_shock = xs[above[0]]
        up = rho[xs < xs_shock - 0.012]
        down = rho[(xs > xs_shock + 0.004) & (xs < xs_shock + 0.02)]
        a = xs[np.nonzero(rho > RHO_INF + 0.25 * (RHO_SHOCK - RHO_INF))[0][0]]
        b = xs[np.nonzero(rho > RHO_INF + 0.75 * (RHO_SHOCK - RHO_INF))[0][0]] if (
            rho > RHO_INF + 0.75 * (RHO_SHOCK - RHO_INF)).any() else np.inf
        standoff = BAR[0] - xs_shock
        ok = (len(up) > 10 and np.all(np.abs(up - RHO_INF) < 0.3) and len(down) > 0
              and np.median(down) > 3.2 and b - a <= 0.012 and 0.03 <= standoff <= 0.075)
        check(ok, f"bow shock visible on y = {ymid * 1e3:.0f} mm: free stream "
              f"{np.median(up) if len(up) else float('nan'):.2f} (max dev "
              f"{np.abs(up - RHO_INF).max() if len(up) else float('nan'):.2f}) up to x = "
              f"{(xs_shock - 0.012) * 1e3:.0f} mm, post-shock {np.median(down) if len(down) else 0:.2f} "
              f"behind it; the jump (25 % to 75 %) over {(b - a) * 1e3:.1f} mm, stand-off "
              f"{standoff * 1e3:.1f} mm from the face; {png}")
    else:
        check(False, f"bow shock: no density above {mid} upstream of the bar (max {rho.max():.2f})")
    print(f"info: test_paraview took {time.time() - t0:.1f} s")
    return check.finish()


if len(sys.argv) == 4 and sys.argv[1] == "--default-render":
    default_render(sys.argv[2], sys.argv[3])
else:
    sys.exit(main())

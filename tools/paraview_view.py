"""Show an mpmfsi run in ParaView (5.11): the gas coloured by density over a range that shows
its shocks, the solid on top in one contrasting colour, at the last snapshot.

mpmfsi writes this file as view.py into every output folder, beside series.xmf.
  pvpython view.py [--png FILE] [--size W H] [--time T] [--range LO HI] [SERIES.xmf]
      headless: xvfb-run -a pvpython view.py --png picture.png
  ParaView GUI: View > Python Shell > Run Script, choose view.py. It shows the XDMF source
      selected in the Pipeline Browser, or opens the series.xmf beside the script (or in the
      current directory); the time slider still steps through the snapshots.

Why a script: XDMF carries the data but no colour range or map. ParaView takes the range at
t = 0, where the gas is uniform (rho = 1.2), and "rescale to data range" later picks up the few
dozen particles of the wake and the bar's corners above rho = 10, so the gas looks flat. The range
here is robust: the 0.5 and 99.5 percentiles of the gas's density at the time shown. The gas is
drawn as discs one particle spacing across (Point Gaussian), so that the field looks continuous.

The gas is what has a pressure p; the solid what has a body index (mpmfsi's fields). Both are
picked out with Threshold filters, which work with every XDMF reader (Xdmf3ReaderS, the one
OpenDataFile picks, gives the phases as pieces of one dataset, without names).

With --png it also writes FILE.json: the world box the picture shows, its size in pixels, the
colours and the range, so that a test can find the bar and the shock in the picture.
"""
import json
import math
import os
import sys

from paraview import servermanager as sm
from paraview import simple as pv

BAR_COLOUR = [0.9, 0.05, 0.05]  # red: not in the gas's colour map (Viridis)
BACKGROUND = [1.0, 1.0, 1.0]
RADIUS = 0.8  # disc radius / mean particle spacing: discs overlap, the field looks continuous
COLOUR_MAP = "Viridis (matplotlib)"


def options(argv):
    import argparse
    ap = argparse.ArgumentParser(prog="view.py", description=__doc__.split("\n")[0])
    ap.add_argument("series", nargs="?", help="series.xmf (default: beside this script)")
    ap.add_argument("--png", help="save the picture to this file and exit")
    ap.add_argument("--size", nargs=2, type=int, default=[1440, 1000], metavar=("W", "H"))
    ap.add_argument("--time", type=float, help="time to show (default: the last snapshot)")
    ap.add_argument("--range", nargs=2, type=float, metavar=("LO", "HI"),
                    help="density range (default: percentiles 0.5 and 99.5 of the gas)")
    return ap.parse_args(argv)


def find_source(series):
    """The reader to show: SERIES, the selected XDMF source (GUI), or series.xmf nearby."""
    if not series:
        active = pv.GetActiveSource()
        names = []
        for prop in ("FileName", "FileNames"):
            if active is not None and active.ListProperties().count(prop):
                value = active.GetPropertyValue(prop)
                names = [value] if isinstance(value, str) else [str(v) for v in value]
        if names and str(names[0]).endswith(".xmf"):
            return active
        here = os.path.dirname(os.path.abspath(globals().get("__file__", "view.py")))
        for d in (here, os.getcwd()):
            if os.path.exists(os.path.join(d, "series.xmf")):
                series = os.path.join(d, "series.xmf")
                break
    if not series or not os.path.exists(series):
        raise SystemExit("view.py: no series.xmf found; give its path: pvpython view.py PATH")
    # Xdmf3 finds the .h5 files relative to the index's directory only when the path has one.
    return pv.OpenDataFile(os.path.abspath(series))


def phase(source, field):
    """The particles that have `field` (Threshold over its whole range keeps them all)."""
    t = pv.Threshold(Input=source, Scalars=["POINTS", field])
    t.LowerThreshold, t.UpperThreshold = -1e300, 1e300
    t.ThresholdMethod = "Between"
    return t


def values(source, name, t):
    """All values of point array `name` of source at time t, as a list of floats."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    import numpy as np
    source.UpdatePipeline(t)
    data = sm.Fetch(source)
    out = []
    it = data.NewIterator() if data.IsA("vtkCompositeDataSet") else None
    blocks = []
    if it is None:
        blocks = [data]
    else:
        it.InitTraversal()
        while not it.IsDoneWithTraversal():
            blocks.append(it.GetCurrentDataObject())
            it.GoToNextItem()
    for b in blocks:
        a = b.GetPointData().GetArray(name) if b is not None else None
        if a is not None and a.GetNumberOfTuples() > 0:
            out.append(vtk_to_numpy(a).ravel())
    return np.concatenate(out) if out else np.zeros(0)


def show(opt):
    source = find_source(opt.series)
    times = list(getattr(source, "TimestepValues", []) or [])
    times = times if isinstance(times, list) else [times]
    t = opt.time if opt.time is not None else (times[-1] if times else 0.0)
    scene = pv.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = t

    view = pv.GetActiveViewOrCreate("RenderView")
    if opt.png:
        view.ViewSize = list(opt.size)
    view.ViewTime = t
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = BACKGROUND
    pv.Hide(source, view)

    gas, solid = phase(source, "p"), phase(source, "body")
    rho = values(gas, "rho", t)
    if opt.range:
        lo, hi = opt.range
    elif rho.size:
        import numpy as np
        lo, hi = (float(v) for v in np.percentile(rho, [0.5, 99.5]))
    else:
        lo, hi = 0.0, 1.0
    hi = max(hi, lo * (1 + 1e-6) + 1e-12)

    # The world box: the particles' bounds (2-D runs lie in z = 0).
    source.UpdatePipeline(t)
    b = source.GetDataInformation().GetBounds()
    flat = b[5] - b[4] <= 1e-12 * max(b[1] - b[0], b[3] - b[2], 1e-300)
    n_gas = max(rho.size, 1)
    spacing = math.sqrt((b[1] - b[0]) * (b[3] - b[2]) / n_gas) if flat else 0.0

    lut = pv.GetColorTransferFunction("rho")
    lut.AutomaticRescaleRangeMode = "Never"  # before ColorBy, which would rescale it
    lut.ApplyPreset(COLOUR_MAP, True)
    g = pv.Show(gas, view)
    pv.ColorBy(g, ("POINTS", "rho"))
    g.LookupTable = lut
    lut.RescaleTransferFunction(lo, hi)
    pv.GetOpacityTransferFunction("rho").RescaleTransferFunction(lo, hi)
    s = pv.Show(solid, view)
    s.ColorArrayName = ["POINTS", ""]
    s.AmbientColor = s.DiffuseColor = BAR_COLOUR
    for rep in (g, s):
        if flat:
            rep.SetRepresentationType("Point Gaussian")
            rep.ShaderPreset = "Plain circle"
            rep.GaussianRadius = RADIUS * spacing
        rep.Ambient, rep.Diffuse = 1.0, 0.0  # flat colours: the picture shows values only
    if flat:
        s.Position = [0.0, 0.0, 0.01 * max(b[1] - b[0], b[3] - b[2])]  # the solid on top
    bar = pv.GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle = "gas density rho", "[kg/m^3]"
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    bar.Visibility = 1

    box = None
    pv.Render(view)  # the first render resets the camera: set it afterwards
    if flat:
        # Parallel projection onto the world box, a margin around it and room on the right
        # for the colour bar; the picture's aspect ratio is the box's.
        lx, ly = b[1] - b[0], b[3] - b[2]
        m = 0.03 * max(lx, ly)
        w, h = view.ViewSize
        x0, y0, y1 = b[0] - m, b[2] - m, b[3] + m
        x1 = x0 + (y1 - y0) * w / h
        if x1 < b[1] + m + 0.15 * lx:  # too narrow for the bar: widen the box, not the picture
            x1 = b[1] + m + 0.15 * lx
            half = (x1 - x0) * h / w / 2
            yc = (b[2] + b[3]) / 2
            y0, y1 = yc - half, yc + half
        bar.WindowLocation = "Any Location"
        bar.Orientation = "Vertical"
        bar.Position = [min(0.98, (b[1] + 0.02 * lx - x0) / (x1 - x0)), 0.15]
        bar.ScalarBarLength = 0.7
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        view.CameraParallelProjection = 1
        view.CameraPosition = [cx, cy, 10 * max(lx, ly)]
        view.CameraFocalPoint = [cx, cy, 0.0]
        view.CameraViewUp = [0.0, 1.0, 0.0]
        view.CameraParallelScale = (y1 - y0) / 2
        box = [x0, x1, y0, y1]
    else:
        view.ResetCamera()
    pv.SetActiveSource(gas)
    pv.Render(view)
    if opt.png:
        w, h = view.ViewSize
        pv.SaveScreenshot(opt.png, view, ImageResolution=[w, h])
        with open(opt.png + ".json", "w") as f:
            json.dump({"time": t, "range": [lo, hi], "world_box": box, "size": [w, h],
                       "bar_colour": BAR_COLOUR, "background": BACKGROUND,
                       "colour_map": COLOUR_MAP, "gas_points": int(rho.size),
                       "gaussian_radius": RADIUS * spacing,
                       "bounds": list(b)}, f, indent=1)
        print(f"view.py: t = {t:g} s, rho range {lo:.4g} .. {hi:.4g}; wrote {opt.png}")


# Run as a script (pvpython) or from the GUI's Python Shell, where sys.argv may be empty.
show(options([a for a in getattr(sys, "argv", [])[1:] if a]))

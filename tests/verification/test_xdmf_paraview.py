"""The XDMF indexes open in ParaView as a new user expects (common/mpm_xdmf.h gives the why).

A small run of the main job (cases/supersonic_bar.ini at dx = 6 mm to t = 0.1 ms, 2 ranks,
grid fields on, 3 snapshots) and a 3-D solid (cases/cantilever3d.ini, 2 snapshots) are
checked without ParaView, on the structure ParaView 5.11's readers need:

1. Stable blocks: each snapshot of series.xmf is a spatial collection with one
   `<Time Value=` (mpm_rundir.c scans for it) whose children are one-grid temporal
   collections named after the phases, with the same names in the same order at every step
   (XDMFReader names blocks after them; the grids inside are renamed per step by the
   readers); each holds one Uniform grid of that name at the snapshot's time.
2. The grid fields are in grid.xmf, built the same way (solid_grid, fluid_grid) over the
   same snapshots, and nowhere in series.xmf (their lattice would cover the particles).
3. Particles as points: a Polyvertex topology of N one-point cells, N equal to the rows of
   the phase's datasets, with a connectivity dataset holding 0 .. N-1 (without it Xdmf3
   makes no cells and draws nothing).
4. Every HDF DataItem names a dataset of the snapshot with its Dimensions (axes of length 1
   aside).
5. Colouring: every phase lists rho first and it is the only Scalar attribute of the index
   (Xdmf3ReaderS draws the phases as one dataset with only the fields all have: without the
   solid's rho, written by the output layer, it drew everything white); id is a one-column
   Matrix, last. Tensor components have names of their own (F_xx ...), HyperSlabs of F.
6. Tensors, row-major: the 2-D bar's F is a Matrix [N 4] equal to /solid/F; the 3-D
   cantilever's F a Tensor [N 9], the identity at t = 0.
7. A later run into the folder without grid fields leaves no grid.xmf behind.
If pvpython is on the PATH it also opens series.xmf with XDMFReader, Xdmf3ReaderS and
Xdmf3ReaderT: points and cells of every block at two times, the block paths the same at both
times, the active scalars (rho) of every block.
"""
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

READERS = ("XDMFReader", "Xdmf3ReaderS", "Xdmf3ReaderT")


def paraview_check(index):
    """Under pvpython: one line per reader, time and leaf block (path points cells scalars)."""
    from paraview import servermanager as sm
    from paraview import simple
    from vtkmodules.vtkCommonDataModel import vtkDataAssembly, vtkDataAssemblyUtilities

    def leaves(ds):
        tree = vtkDataAssembly()
        vtkDataAssemblyUtilities.GenerateHierarchy(ds, tree)
        it = ds.NewIterator()
        it.UnRegister(None)
        it.SetVisitOnlyLeaves(False)
        it.InitTraversal()
        blocks = {}
        while not it.IsDoneWithTraversal():
            blocks[it.GetCurrentFlatIndex()] = it.GetCurrentDataObject()
            it.GoToNextItem()
        out = []

        def walk(node, path):
            path += "/" + tree.GetNodeName(node)
            kids = [tree.GetChild(node, i) for i in range(tree.GetNumberOfChildren(node))]
            ids = tree.GetDataSetIndices(node, False)
            if ids and not kids:
                d = blocks.get(ids[0])
                if d is not None and d.IsA("vtkMultiPieceDataSet"):
                    for k in range(d.GetNumberOfPieces()):
                        out.append((f"{path}#{k}", d.GetPiece(k)))
                else:
                    out.append((path, d))
            for k in kids:
                walk(k, path)

        walk(0, "")
        return out

    for name in READERS:
        if name == "XDMFReader":
            reader = simple.XDMFReader(FileNames=[index])
        else:
            reader = getattr(simple, name)(FileName=[index])
        for t in list(reader.TimestepValues)[:2]:
            reader.UpdatePipeline(t)
            for path, d in leaves(sm.Fetch(reader)):
                if d is None:
                    print(f"PV {name} {t!r} {path} none")
                    continue
                s = d.GetPointData().GetScalars()
                print(f"PV {name} {t!r} {path} {d.GetNumberOfPoints()} {d.GetNumberOfCells()} "
                      f"{s.GetName() if s else '-'}")
        simple.Delete(reader)


if len(sys.argv) == 3 and sys.argv[1] == "--in-paraview":
    paraview_check(sys.argv[2])
    sys.exit(0)

import h5py  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_xdmf_paraview")
BAR = ["grid.dx=0.006", "time.t_end=0.0001", "output.interval=0.00005", "run.progress=false"]


def blocks(index):
    """[(time, [(block name, uniform grid)])] of an index; the name is None where the nesting
    of item 1 is wrong (the grid is then the block itself if it is a uniform grid)."""
    root = ET.parse(index).getroot()
    series = root.find("Domain/Grid")
    assert series is not None and series.get("CollectionType") == "Temporal", index
    out = []
    for snap in series.findall("Grid"):
        times = snap.findall("Time")
        t = float(times[0].get("Value")) if len(times) == 1 else float("nan")
        entry = []
        for block in snap.findall("Grid"):
            grids = block.findall("Grid")
            ok = (snap.get("CollectionType") == "Spatial"
                  and block.get("CollectionType") == "Temporal" and len(grids) == 1
                  and grids[0].get("GridType") == "Uniform"
                  and grids[0].get("Name") == block.get("Name")
                  and grids[0].find("Time") is not None
                  and float(grids[0].find("Time").get("Value")) == t)
            uniform = grids[0] if grids else block if block.get("GridType") == "Uniform" else None
            entry.append((block.get("Name") if ok else None, uniform))
        out.append((t, entry))
    return out


def h5_item(outdir, item):
    """(file, dataset path, Dimensions) of an HDF DataItem."""
    fname, _, dset = item.text.strip().partition(":")
    return os.path.join(outdir, fname), dset, tuple(int(d) for d in item.get("Dimensions").split())


def squeeze(shape):
    return tuple(d for d in shape if d != 1)


def check_items(outdir, index):
    """Item 4: (items checked, list of mismatches)."""
    bad, n = [], 0
    for item in ET.parse(index).getroot().iter("DataItem"):
        if item.get("Format") != "HDF":
            continue
        path, dset, dims = h5_item(outdir, item)
        with h5py.File(path, "r") as f:
            shape = f[dset].shape if dset in f else None
        n += 1
        if shape is None or squeeze(shape) != squeeze(dims) or np.prod(shape) != np.prod(dims):
            bad.append(f"{os.path.basename(path)}:{dset} {shape} vs {dims}")
    return n, bad


def check_phase(outdir, grid):
    """Items 3 and 5 for one particle grid: (N, attribute names, types, problems)."""
    problems = []
    if grid is None:
        return 0, [], [], ["not a uniform grid"]
    name = grid.get("Name")
    topo = grid.find("Topology")
    n = int(topo.get("NumberOfElements", "0"))
    if topo.get("TopologyType") != "Polyvertex" or topo.get("NodesPerElement") != "1":
        problems.append(f"topology {topo.attrib}")
    conn = topo.find("DataItem")
    if conn is None or topo.get("TopologyType") != "Polyvertex":
        problems.append("no connectivity")
    else:
        path, dset, dims = h5_item(outdir, conn)
        with h5py.File(path, "r") as f:
            if dims != (n,) or not np.array_equal(f[dset][()], np.arange(n)):
                problems.append(f"connectivity {dset} {dims} is not 0 .. {n - 1}")
            rows = f[name]["id"].shape[0]
            if rows != n or f[name]["x"].shape[0] != n:
                problems.append(f"{n} cells for {rows} particles")
    attrs = grid.findall("Attribute")
    return n, [a.get("Name") for a in attrs], [a.get("AttributeType") for a in attrs], problems


def run_paraview(index):
    """pvpython's report on index: {reader: {time: {path: (points, cells, scalars)}}}."""
    cmd = ["pvpython", os.path.abspath(__file__), "--in-paraview", index]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=90)
    seen = {r: {} for r in READERS}
    for line in p.stdout.splitlines():
        f = line.split()
        if len(f) == 7 and f[0] == "PV":
            seen[f[1]].setdefault(float(f[2]), {})[f[3]] = (int(f[4]), int(f[5]), f[6])
        elif len(f) == 5 and f[0] == "PV":
            seen[f[1]].setdefault(float(f[2]), {})[f[3]] = None
    if p.returncode != 0:
        sys.stderr.write(p.stdout[-2000:] + p.stderr[-2000:])
    return p.returncode, seen


# ---- the main job, with grid fields ------------------------------------------------------
out = mt.outdir("xdmf_bar")
mt.run(["run", mt.case("supersonic_bar.ini"), f"output.dir={out}", "output.grid_fields=true"]
       + BAR, ranks=2)
series, grids = os.path.join(out, "series.xmf"), os.path.join(out, "grid.xmf")
entries = blocks(series)
names = [[b for b, _ in e] for _, e in entries]
check(len(entries) == 3 and all(n == ["solid", "fluid"] for n in names),
      f"series.xmf: {len(entries)} snapshots, blocks {names[0] if names else []} at every step, "
      f"each a temporal collection around one grid of its name at the snapshot's time: {names}")
text = open(series).read()
check(len(re.findall(r'<Time Value="', text)) == len(entries) and "CoRectMesh" not in text,
      "series.xmf: one `<Time Value=` per snapshot; no grid lattice")
gentries = blocks(grids) if os.path.exists(grids) else []
gnames = [[b for b, _ in e] for _, e in gentries]
check([t for t, _ in gentries] == [t for t, _ in entries]
      and all(n == ["solid_grid", "fluid_grid"] for n in gnames)
      and all(g.find("Topology").get("TopologyType") == "3DCoRectMesh"
              for _, e in gentries for _, g in e),
      f"grid.xmf: the same {len(gentries)} snapshots, blocks {gnames[0] if gnames else []} "
      f"(3DCoRectMesh) at every step")
for index in (series, grids):
    n_items, bad = check_items(out, index) if os.path.exists(index) else (0, ["missing"])
    check(n_items > 0 and not bad, f"{os.path.basename(index)}: {n_items} HDF DataItems name "
          f"datasets of their Dimensions {bad[:3]}")
counts, problems, orders, scalars = [], [], {}, set()
for t, entry in entries:
    for _, grid in entry:
        n, attrs, types, p = check_phase(out, grid)
        name = grid.get("Name") if grid is not None else None
        counts.append(n)
        problems += [f"t = {t:g} {name}: {q}" for q in p]
        orders.setdefault(name, []).append((attrs, types))
        scalars |= {a for a, ty in zip(attrs, types) if ty == "Scalar"}
check(not problems and all(n > 0 for n in counts),
      f"particles: Polyvertex, one vertex per cell, connectivity 0 .. N-1, N = the rows "
      f"({counts}) {problems[:3]}")
fluid_attrs, fluid_types = orders.get("fluid", [([], [])])[0]
solid_attrs, solid_types = orders.get("solid", [([], [])])[0]
check(fluid_attrs[:2] == ["rho", "v"] and fluid_types[:2] == ["Scalar", "Vector"]
      and solid_attrs[:2] == ["rho", "v"] and scalars == {"rho"}
      and [a for a in solid_attrs if a.startswith("F_")] == ["F_xx", "F_xy", "F_yx", "F_yy"]
      and all(a[-1] == "id" and ty[-1] == "Matrix" for o in orders.values() for a, ty in o),
      f"colouring: gas attributes {fluid_attrs[:3]}..., solid {solid_attrs[:3]}...; Scalar "
      f"attributes {sorted(scalars)}; id last, a Matrix")
F = [(a, ty) for a, ty in zip(solid_attrs, solid_types) if a == "F"]
grid0 = entries[0][1][0][1]
item = [a for a in grid0.findall("Attribute") if a.get("Name") == "F"][0].find("DataItem")
check(F == [("F", "Matrix")] and item.get("Dimensions").split()[1:] == ["4"]
      and item.text.strip().endswith(":/solid/F"),
      f"2-D tensors: F is a Matrix [N 4] of /solid/F (row-major, as docs/output.md gives) {F}")
listed = [os.path.basename(p) for _, p in mt.snapshots(out)]
check(listed == [f"snap_{k:06d}.h5" for k in range(3)], f"mpmtest.snapshots(): {listed}")

# ---- ParaView itself, when installed -------------------------------------------------------
if shutil.which("pvpython"):
    rc, seen = run_paraview(series)
    want = [{"solid": n_s, "fluid": n_f} for n_s, n_f in zip(counts[0::2], counts[1::2])][:2]
    for reader in READERS:
        times = sorted(seen[reader])
        per_t = [seen[reader][t] for t in times]
        paths = [sorted(b) for b in per_t]
        points = [sorted(v[0] for v in b.values() if v) for b in per_t]
        cells_ok = all(v and v[0] == v[1] for b in per_t for v in b.values())
        act = sorted({v[2] for b in per_t for v in b.values() if v})
        ok = (rc == 0 and len(times) == 2 and paths[0] == paths[1] and len(paths[0]) == 2
              and cells_ok and points == [sorted(w.values()) for w in want]
              and act == ["rho"])
        check(ok, f"ParaView {reader}: blocks {paths[0] if paths else []} at both times, points "
              f"{points}, one cell per point, active scalars {act}")
else:
    print("info: pvpython not found; the ParaView check is skipped (apt install paraview)")

# ---- a later run without grid fields: no stale grid.xmf ------------------------------------
mt.run(["run", mt.case("supersonic_bar.ini"), f"output.dir={out}", "output.overwrite=true"]
       + BAR)
check(not os.path.exists(grids) and len(blocks(series)) == 3,
      "a later run into the folder without grid fields leaves no grid.xmf")

# ---- 3-D: the deformation gradient as a Tensor ---------------------------------------------
out3 = mt.outdir("xdmf_3d")
mt.run(["run", mt.case("cantilever3d.ini"), f"output.dir={out3}", "time.t_end=0.001",
        "output.interval=0.0005", "run.progress=false"])
e3 = blocks(os.path.join(out3, "series.xmf"))
g3 = e3[0][1][0][1]
attr = {a.get("Name"): a for a in g3.findall("Attribute")}
path, dset, dims = h5_item(out3, attr["F"].find("DataItem"))
with h5py.File(path, "r") as f:
    identity = np.allclose(f[dset][()], np.eye(3).ravel())
check(attr["F"].get("AttributeType") == "Tensor" and dims[1:] == (9,) and identity
      and [b for b, _ in e3[0][1]] == ["solid"] and len(e3) == 3,
      f"3-D: F is a Tensor [N 9], row-major (the identity at t = 0), in {len(e3)} snapshots")
sys.exit(check.finish())

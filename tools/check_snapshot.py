#!/usr/bin/python3
"""Check an mpmfsi output directory against its XDMF index.

Usage: check_snapshot.py OUTDIR [OUTDIR ...]

For every snapshot listed in OUTDIR/series.xmf (and OUTDIR/grid.xmf, the grid fields, if
present) this opens the HDF5 file with h5py and
checks that
  - the file exists, and its root attributes time, step, dim, config and version are there,
    with time equal to the <Time> of its entry;
  - every dataset a DataItem names exists, with the element count of its Dimensions and the
    same extents once axes of length 1 are dropped (a 2-D lattice is listed as one node
    thick in z, while the file stores it as [Ny][Nx]);
  - a Polyvertex grid has as many points as its Topology says, its connectivity dataset
    holds 0 .. N-1, and every particle dataset of the phase group (not only those listed)
    has one row per particle;
  - times increase from one entry to the next.
It prints one summary line per snapshot and exits with status 1 if anything is wrong.
Run it with Debian's /usr/bin/python3, which has h5py.
"""

import math
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np


class Checker:
    def __init__(self, outdir):
        self.outdir = outdir
        self.problems = []

    def fail(self, msg):
        self.problems.append(f"{self.outdir}: {msg}")

    def check_dataitem(self, item, files, where):
        """Check one DataItem; return its dimensions (a tuple) or None."""
        dims = tuple(int(d) for d in item.get("Dimensions", "").split())
        if item.get("Format", "XML") != "HDF":
            return dims
        ref = (item.text or "").strip()
        if ":" not in ref:
            self.fail(f"{where}: DataItem '{ref}' does not name file:/dataset")
            return None
        fname, dset = ref.split(":", 1)
        h5 = files.get(fname)
        if h5 is None:  # missing: reported once, by check_snapshot
            return None
        if dset not in h5 or not isinstance(h5[dset], h5py.Dataset):
            self.fail(f"{where}: {fname} has no dataset {dset}")
            return None
        shape = h5[dset].shape
        squeeze = lambda s: tuple(d for d in s if d != 1)
        if math.prod(shape) != math.prod(dims) or squeeze(shape) != squeeze(dims):
            self.fail(f"{where}: {fname}:{dset} has shape {shape}, the index says {dims}")
        return dims

    def check_particles(self, grid, files, where):
        topo = grid.find("Topology")
        n = int(topo.get("NumberOfElements", "-1"))
        conn = topo.find("DataItem")
        cdims = self.check_dataitem(conn, files, where + "/Topology") if conn is not None else None
        if cdims != (n,):
            self.fail(f"{where}: Polyvertex connectivity {cdims}, not ({n},)")
        else:
            fname, _, dset = (conn.text or "").strip().partition(":")
            if fname in files and dset in files[fname]:
                if not np.array_equal(files[fname][dset][()], np.arange(n)):
                    self.fail(f"{where}: {fname}:{dset} is not 0 .. {n - 1}")
        geom = grid.find("Geometry/DataItem")
        dims = self.check_dataitem(geom, files, where + "/Geometry")
        if dims and dims[0] != n:
            self.fail(f"{where}: {dims[0]} positions for {n} points")
        for attr in grid.findall("Attribute"):
            item = attr.find("DataItem")
            adims = self.check_dataitem(item, files, f"{where}/{attr.get('Name')}")
            if adims and adims[0] != n:
                self.fail(f"{where}/{attr.get('Name')}: {adims[0]} values for {n} points")
        # every field in the phase group, listed or not, has one row per particle
        fname, _, dset = (geom.text or "").strip().partition(":")
        group = files[fname].get(dset.rsplit("/", 1)[0]) if fname in files else None
        if group is not None:
            for name, obj in group.items():
                if isinstance(obj, h5py.Dataset) and obj.shape[:1] != (n,):
                    self.fail(f"{where}: {fname}:{obj.name} has {obj.shape[:1]} rows, not {n}")
        return n

    def check_mesh(self, grid, files, where):
        dims = tuple(int(d) for d in grid.find("Topology").get("Dimensions").split())
        for attr in grid.findall("Attribute"):
            adims = self.check_dataitem(attr.find("DataItem"), files, f"{where}/{attr.get('Name')}")
            if adims and adims[: len(dims)] != dims:
                self.fail(f"{where}/{attr.get('Name')}: extents {adims} on a {dims} lattice")
        return "x".join(str(d) for d in reversed(dims) if d != 1)

    def check_snapshot(self, snap, last_time):
        name = snap.get("Name", "?")
        time_el = snap.find("Time")
        if time_el is None:
            self.fail(f"{name}: no <Time>")
            return last_time
        t = float(time_el.get("Value"))
        if last_time is not None and not t > last_time:
            self.fail(f"{name}: time {t} does not follow {last_time}")
        fnames = {
            (item.text or "").strip().split(":", 1)[0]
            for item in snap.iter("DataItem")
            if item.get("Format") == "HDF"
        }
        fnames.add(name + ".h5")
        files = {}
        try:
            for fname in sorted(fnames):
                path = os.path.join(self.outdir, fname)
                if not os.path.isfile(path):
                    self.fail(f"{name}: {fname} is listed but missing")
                    continue
                files[fname] = h5py.File(path, "r")
            own = files.get(name + ".h5")
            if own is not None:
                for key in ("time", "step", "dim", "config", "version"):
                    if key not in own.attrs:
                        self.fail(f"{name}: no root attribute '{key}'")
                if "time" in own.attrs and float(own.attrs["time"]) != t:
                    self.fail(f"{name}: time attribute {own.attrs['time']} but index time {t}")
            parts = []
            # each block is a temporal collection around one uniform grid (mpm_xdmf.h)
            for grid in snap.iter("Grid"):
                if grid.get("GridType", "Uniform") != "Uniform":
                    continue
                gname = grid.get("Name")
                topo = grid.find("Topology").get("TopologyType", "")
                if topo.lower() == "polyvertex":
                    parts.append(f"{gname}: {self.check_particles(grid, files, f'{name}/{gname}')}")
                elif "corectmesh" in topo.lower():
                    parts.append(f"{gname}: {self.check_mesh(grid, files, f'{name}/{gname}')} nodes")
                else:
                    self.fail(f"{name}/{gname}: unexpected topology {topo}")
            print(f"  {name}  t = {t:<12g} " + ", ".join(parts))
        finally:
            for h5 in files.values():
                h5.close()
        return t

    def run(self):
        self.run_index("series.xmf")
        if os.path.exists(os.path.join(self.outdir, "grid.xmf")):
            self.run_index("grid.xmf")

    def run_index(self, name):
        index = os.path.join(self.outdir, name)
        try:
            root = ET.parse(index).getroot()
        except (OSError, ET.ParseError) as err:
            self.fail(f"cannot parse {name}: {err}")
            return
        series = root.find("Domain/Grid")
        if series is None or series.get("CollectionType") != "Temporal":
            self.fail(f"{name} has no temporal collection")
            return
        snaps = series.findall("Grid")
        print(f"{self.outdir}/{name}: {len(snaps)} snapshot(s)")
        last = None
        for snap in snaps:
            last = self.check_snapshot(snap, last)


def main(argv):
    if any(a in ("-h", "--help") for a in argv[1:]):
        print(__doc__.strip())
        return 0
    if len(argv) < 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    problems = []
    for outdir in argv[1:]:
        checker = Checker(outdir)
        checker.run()
        problems += checker.problems
    for p in problems:
        print("error: " + p, file=sys.stderr)
    print("OK" if not problems else f"{len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

"""Helpers for the end-to-end tests: run mpmfsi (serially or under mpiexec) and read its
output. Run with Debian's /usr/bin/python3, which has h5py."""
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import h5py
import numpy as np

BIN = os.environ.get("MPMFSI_BIN", "mpmfsi")
MPIEXEC = os.environ.get("MPIEXEC", "mpiexec")
SOURCE = os.environ.get("MPMFSI_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


def case(name):
    return os.path.join(SOURCE, "cases", name)


def outdir(name):
    """A fresh output folder for one run of a test (runs never share folders)."""
    return tempfile.mkdtemp(prefix=name + "_", dir=".")


def run(args, ranks=1, check=True):
    """Run `mpmfsi args...`; returns the CompletedProcess (stdout, stderr as text)."""
    cmd = [BIN] + list(args)
    if ranks > 1:
        cmd = [MPIEXEC, "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=1200)
    if check and p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"command failed ({p.returncode}): {' '.join(cmd)}")
    return p


def snapshots(outdir):
    """(time, path) of every snapshot named in series.xmf, in time order. Each snapshot is a
    child grid of the temporal collection, with a <Time> and HDF data items."""
    root = ET.parse(os.path.join(outdir, "series.xmf")).getroot()
    series = root.find("Domain/Grid")
    files = []
    for grid in series.findall("Grid"):
        t = grid.find("Time")
        item = grid.find(".//DataItem")
        path = item.text.strip().split(":")[0]
        files.append((float(t.get("Value")), os.path.join(outdir, path)))
    return sorted(files)


def particles(path, phase="solid"):
    """dict id -> row of field values; and the fields as arrays sorted by id."""
    with h5py.File(path, "r") as f:
        g = f[phase]
        ids = g["id"][()]
        order = np.argsort(ids)
        out = {"id": ids[order]}
        for name in g:
            if name != "id":
                out[name] = g[name][()][order]
        out["time"] = float(f.attrs["time"])
    return out


class Checks:
    """Counts and prints checks; finish() prints the closing 'N passed, N failed' line and
    returns the exit status."""

    def __init__(self, name):
        self.name, self.passed, self.failed = name, 0, 0

    def __call__(self, cond, msg):
        if cond:
            self.passed += 1
        else:
            self.failed += 1
        print(("ok   " if cond else "FAIL ") + msg)

    def finish(self):
        print(f"{self.name}: {self.passed} passed, {self.failed} failed")
        return 1 if self.failed else 0

"""Helpers for the end-to-end tests: run mpmfsi (serially or under mpiexec) and read its
output. Run with Debian's /usr/bin/python3, which has h5py."""
import csv
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


def _scratch_cwd():
    """Keep run folders out of the source tree: ctest runs the drivers in the build tree, and a
    driver started by hand from a tracked folder of the checkout moves to out/tests/ (ignored
    by git), so that the folders its runs create (dir=".") never land beside tracked files."""
    here, top = os.path.realpath(os.getcwd()), os.path.realpath(SOURCE)
    rel = os.path.relpath(here, top)
    if rel.startswith(".."):
        return  # outside the checkout: the caller chose the place
    first = rel.split(os.sep)[0]
    if first.startswith(("build", "out")):
        return  # already in an ignored build or output folder
    scratch = os.path.join(top, "out", "tests")
    os.makedirs(scratch, exist_ok=True)
    os.chdir(scratch)
    sys.stderr.write(f"mpmtest: writing run folders under {scratch}\n")


_scratch_cwd()


def case(name):
    return os.path.join(SOURCE, "cases", name)


def outdir(name):
    """A fresh output folder for one run of a test (runs never share folders)."""
    return tempfile.mkdtemp(prefix=name + "_", dir=".")


def run(args, ranks=1, check=True, timeout=1200):
    """Run `mpmfsi args...`; returns the CompletedProcess (stdout, stderr as text). A run
    longer than timeout seconds raises (the ctest TIMEOUT of a long test may allow more)."""
    cmd = [BIN] + list(args)
    if ranks > 1:
        cmd = [MPIEXEC, "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if check and p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"command failed ({p.returncode}): {' '.join(cmd)}")
    return p


def run_text(name, text, args=(), ranks=1):
    """Write text as case.ini in a fresh folder named after name, run it there (output in its
    run/, no progress line) with the overrides args on `ranks` ranks; returns the run folder."""
    out = outdir(name)
    path = os.path.join(out, "case.ini")
    with open(path, "w") as f:
        f.write(text)
    run(["run", path, f"output.dir={out}/run", "run.progress=false"] + list(args), ranks=ranks)
    return os.path.join(out, "run")


def csv_rows(out, name):
    """A CSV file of a run folder as a numpy structured array (names from its header)."""
    return np.genfromtxt(os.path.join(out, name), delimiter=",", names=True)


def cost(outdir):
    """The cost of a run, from its summary.json, as one line: steps, wall time, particle-steps."""
    import json
    with open(os.path.join(outdir, "summary.json")) as f:
        s = json.load(f)
    return (f"{s['steps']} steps, {s['wall_s']:.2f} s wall on {s['ranks']} rank(s), "
            f"{s['particle_steps']:.3g} particle-steps")


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

    def expect_fail(self, cond, msg, reason):
        """A check known to fail on this code, for `reason`: printed as EXPECTED-FAIL and not
        counted as a failure; if it passes, XPASS says to make it an ordinary check."""
        self.expected = getattr(self, "expected", 0) + (not cond)
        if cond:
            self.passed += 1
            print(f"XPASS {msg} (expected to fail: {reason}; make it an ordinary check)")
        else:
            print(f"EXPECTED-FAIL {msg} ({reason})")

    def finish(self):
        xf = getattr(self, "expected", 0)
        more = f", {xf} expected to fail" if xf else ""
        print(f"{self.name}: {self.passed} passed, {self.failed} failed{more}")
        return 1 if self.failed else 0


def coupling_energy_jump(outdir):
    """The largest change of the booked interface work W_net in one coupling step, from the
    run's coupling.csv: (jump in J, t at the end of that step, the solid's largest energy
    E_solid in J, W_net at the end)."""
    with open(os.path.join(outdir, "coupling.csv")) as f:
        r = list(csv.DictReader(f))
    w = np.array([float(x["W_net"]) for x in r])
    k = int(np.argmax(np.abs(np.diff(w))))
    e_max = max(float(x["E_solid"]) for x in r)
    return abs(w[k + 1] - w[k]), float(r[k + 1]["t"]), e_max, float(w[-1])


def time_mean(t, F, a, b):
    """Time average over (a, b] of a per-step history (each row holds the step ending at t)."""
    dt = np.diff(np.concatenate([[0.0], t]))
    m = (t > a) & (t <= b * (1 + 1e-12))
    return float((F[m] * dt[m]).sum() / dt[m].sum())


def worst_difference(a, b, scales=None):
    """Largest difference over the fields of two particle sets with the same ids (from
    particles()), each relative to the field's largest magnitude, or to scales[field] where
    given (a field whose values are all far below its natural size, such as a rate that is
    nearly zero in a uniform stream); and the fields compared."""
    fields = [k for k in a if k not in ("id", "time")]
    scales = scales or {}
    worst = max(float(np.abs(a[k] - b[k]).max())
                / max(scales.get(k, float(np.abs(a[k]).max())), 1e-300) for k in fields)
    return worst, fields


def check_ranks_agree(check, case_path, args, name, tol=1e-12, phase="solid", scales=None):
    """Run case_path with args on 1 and 2 ranks and check that the final snapshots hold the
    same particle ids of `phase` and agree in every field to tol relative (worst_difference,
    with its scales)."""
    finals = []
    for ranks in (1, 2):
        out = outdir(f"{name}_np{ranks}")
        run(["run", case_path, f"output.dir={out}", "run.progress=false"] + list(args), ranks)
        finals.append(particles(snapshots(out)[-1][1], phase))
    a, b = finals
    same = np.array_equal(a["id"], b["id"])
    check(same, f"2 ranks vs 1: the same {len(a['id'])} particle ids")
    if same:
        worst, fields = worst_difference(a, b, scales)
        scaled = "".join(f"; {k} relative to {v:g}" for k, v in (scales or {}).items())
        check(worst <= tol, f"2 ranks vs 1 at t = {float(a['time']):g} s: fields "
              f"{', '.join(fields)} agree to {worst:.1e} relative{scaled} (tolerance {tol:g})")


def expect_input_error(check, name, text, key, line, words=""):
    """Run `mpmfsi run` on case text that must be rejected: exit status 2, one `error:` line
    that names case.ini:LINE and the key (and holds `words`), and no output folder."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "case.ini")
        with open(path, "w") as f:
            f.write(text)
        out = os.path.join(tmp, "out")
        p = run(["run", path, f"output.dir={out}", "run.progress=false"], check=False)
        errors = [l for l in p.stderr.splitlines() if l.startswith("error:")]
        ok = (p.returncode == 2 and len(errors) == 1 and f"case.ini:{line}:" in errors[0]
              and key in errors[0] and words in errors[0] and not os.path.exists(out))
        check(ok, f"{name}: exit {p.returncode}: {errors[0] if errors else p.stderr[-300:]}")


def line_starting(text, prefix):
    """Number of the last line of text that starts with prefix."""
    return [k for k, l in enumerate(text.splitlines(), 1) if l.startswith(prefix)][-1]


def restart_difference(case_path, args, T, name, phase="solid"):
    """Run a case to T with a checkpoint at T/2, restart from that checkpoint to T, and
    compare the two final states of `phase` by particle id: (ids equal, worst_difference,
    fields)."""
    full, rest = outdir(f"{name}_full"), outdir(f"{name}_restarted")
    common = [f"time.t_end={T}", "run.progress=false"] + list(args)
    run(["run", case_path, f"output.dir={full}", f"output.checkpoint_interval={T / 2}"] + common)
    run(["restart", os.path.join(full, "checkpoint_000001.h5"), f"output.dir={rest}"] + common)
    a, b = (particles(snapshots(d)[-1][1], phase) for d in (full, rest))
    if not np.array_equal(a["id"], b["id"]):
        return False, float("inf"), []
    return (True,) + worst_difference(a, b)


def time_errors(label, run_at, cfls, ref_cfl, norm):
    """The time error of a gas run at each of `cfls` against the same run at `ref_cfl` (same
    grid, same particles): `run_at(cfl)` runs it and returns its output folder; the error is
    `norm` of the final particle velocity difference (matched by id) over the largest reference
    velocity. Prints each run's cost; returns the errors."""
    def final(cfl):
        out = run_at(cfl)
        p = particles(snapshots(out)[-1][1], "fluid")
        return p["id"], p["v"], cost(out)

    ids, v_ref, c = final(ref_cfl)
    print(f"{label}: reference at time.cfl = {ref_cfl}: {c}")
    scale = float(np.max(np.abs(v_ref)))
    e = []
    for cfl in cfls:
        i, v, c = final(cfl)
        if not np.array_equal(i, ids):
            raise SystemExit(f"{label}, time.cfl = {cfl}: particle ids differ from the reference")
        e.append(norm(v - v_ref) / scale)
        print(f"{label}, time.cfl = {cfl}: velocity error {e[-1]:.3e}; {c}")
    return e


def orders(e):
    """Observed orders of errors at halved steps: per halving, and first to last."""
    return [np.log2(a / b) for a, b in zip(e, e[1:])], np.log2(e[0] / e[-1]) / (len(e) - 1)

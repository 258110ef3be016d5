r"""Coupling-scheme ablation: one case under every combination of spatial scheme x temporal
scheme x time method, at several coupling steps, against a fine monolithic reference.

    /usr/bin/python3 bench/ablate.py CASE [options] [key=value ...]

For each spatial scheme a reference run (monolithic, usl, time.cfl = --ref-cfl) gives the
quantity's history; every other run's coupling error is the largest and the RMS difference of
its history from the reference's (interpolated to the reference's times). The quantity is a
probe column of probes.csv (--quantity, default the first probe's x displacement). Each run
records its wall time, steps and RHS evaluations, the interface energy the coupling created
(W_net, J, and relative to the case's --energy-scale if given), the largest interface momentum
imbalance, and whether it stayed stable (exit 0, no blow-up) or failed, with the message; and
its CPU time (cpu_s: the user + system time of mpiexec and its ranks, which a shared machine
changes less than the wall time; the first round's with --repeat).

Combinations: temporal `monolithic` with usl, musl and bs32; `staggered` with coupling.order =
solid_first, gas_first, parallel, and solid_first strongly coupled (`strong`: sub-iterations to
a relative interface residual of 1e-6, at most 60, Aitken relaxation), and `multirate` with
coupling.load = held, interpolated, each with usl and musl (the subcycled classic update),
`predictor` (held, with coupling.predictor = linear: the gas meets the solid's interface
velocity extrapolated from its last two coupling steps; every other run, the references too,
sets coupling.predictor = none, the default, whatever the case file says),
`multirate` `lag` (coupling.slow_substeps = 0: both modules at the fast one's rate, the fast one
held over the coupling step: what separates it from monolithic is the coupling lag (and the work
between steps, done once per coupling step), and the rest of `held`'s error is the slow module's
own step; an ablation), and `multirate` `mristep` with bs32 (ARKODE MRIStep, fixed steps:
time.adaptive = false); `contact` with the classic update only (its own restriction). Coupling
steps: time.cfl in --cfl. --skip leaves out runs by name (shell patterns), --skip-variants whole
variants.

Results go to --out (default out/ablate/<case>/, never the tracked bench/results/; give
--out bench/results/ablate_<case> to update a committed study), the runs' own output to
--scratch (default <out>/runs/ without --out, out/ablate/<the results folder's name>/ with it):
runs.csv (one row per run, written as each run ends: an interrupted sweep resumes without
redoing finished runs; delete a row to redo it; a reference run again, because the binary or
the overrides changed, redoes its scheme's rows; the file is replaced whole, and a row cut or
damaged, or unlike its run's summary.json, is run again, never tabulated), ablation.md (the table and the findings'
figures), and ablation.png: the error against wall time, and the interface energy against the
coupling step. --replot DIR redraws DIR/ablation.png from DIR/runs.csv alone (no run, no
reference needed). --ranks 2 runs every run on 2 ranks. The sweep prints progress and its own
wall time.

Example (a small sweep: 1 reference and 12 runs, 34-62 s on the shared 2-core machine; results
in out/ablate/fsi_piston/):
    /usr/bin/python3 bench/ablate.py cases/fsi_piston.ini solid.slab.E=5200 time.t_end=1.5 \
        --spatial velocity --temporal monolithic staggered multirate --methods usl \
        --cfl 0.4 0.2 --skip-variants strong lag mristep

Cost at equal error: for every run that is not monolithic, ablation.md gives the wall time
monolithic (the same spatial scheme and time method) would need for the same error,
interpolated log-log between the two monolithic runs whose errors bracket it (extrapolated
from the nearest two where none does, and marked so, by at most a factor 1.5 in error), and
the ratio of the two; the same in CPU time (when every row has it) and in steps.

Noise: the wall times of one run each are as noisy as the machine (on a shared 2-core machine
the same run took 20.7 and 26.6 s minutes apart). --repeat N runs the sweep N times over, in
rounds (every combination once per round, so a slow spell touches all of them alike), and
reports the median of each combination's wall times, all of which runs.csv keeps (`walls`).
A repeated run must take the same number of steps as the first (the runs are deterministic);
a resumed sweep finishes the rounds it has not made.
"""
import argparse
import csv
import fnmatch
import json
import math
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from benchrun import ENV, ROOT, loglog  # noqa: E402

FIELDS = ["name", "spatial", "temporal", "variant", "method", "cfl", "status", "wall_s",
          "steps", "rhs_evals", "err_max", "err_rms", "err_rel", "W_net", "W_rel",
          "imbalance", "message", "walls", "cpu_s"]
VARIANTS = [("monolithic", "", []),
            ("staggered", "solid_first", ["coupling.order=solid_first"]),
            ("staggered", "gas_first", ["coupling.order=gas_first"]),
            ("staggered", "parallel", ["coupling.order=parallel"]),
            ("staggered", "strong", ["coupling.order=solid_first", "coupling.iterations=60",
                                     "coupling.tolerance=1e-6"]),
            ("multirate", "held", ["coupling.load=held"]),
            ("multirate", "predictor", ["coupling.load=held", "coupling.predictor=linear"]),
            ("multirate", "interpolated", ["coupling.load=interpolated"]),
            ("multirate", "lag", ["coupling.slow_substeps=0"]),
            ("multirate", "mristep", ["time.adaptive=false"])]


SPATIAL = ["velocity", "contact", "traction"]
TEMPORAL = ["monolithic", "staggered", "multirate"]
METHODS = ["usl", "musl", "euler", "ralston21", "bs32", "zonneveld43", "dp54"]  # time.method


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Defaults shown after every option's help (but None and False, which the help says in
    words); the description and epilog as written."""

    def _get_help_string(self, action):
        if action.default in (None, False):
            return action.help
        return super()._get_help_string(action)


def parse(argv=None):
    doc = __doc__.split("\n\n")
    example = next(p for p in doc if p.startswith("Example"))
    ap = argparse.ArgumentParser(
        prog="ablate.py", formatter_class=HelpFormatter,
        description=doc[0] + "\n\n" + doc[1] + "\n\nWhat every run records, the variants, "
        "the cost at equal error and the noise: the docstring of bench/ablate.py.",
        epilog=example + "\n\nRedraw a committed study's plot without running:\n"
        "    /usr/bin/python3 bench/ablate.py --replot bench/results/ablate_fsi_piston")
    ap.add_argument("case", nargs="?", help="the case file (not needed with --replot)")
    ap.add_argument("overrides", nargs="*", help="key=value for every run")
    ap.add_argument("--spatial", nargs="+", default=SPATIAL, choices=SPATIAL, metavar="SCHEME",
                    help=f"spatial coupling schemes (coupling.scheme): {', '.join(SPATIAL)}")
    ap.add_argument("--temporal", nargs="+", default=TEMPORAL, choices=TEMPORAL,
                    metavar="SCHEME",
                    help=f"temporal coupling schemes (coupling.time): {', '.join(TEMPORAL)}")
    variants = [v for _, v, _ in VARIANTS if v]
    ap.add_argument("--skip-variants", nargs="+", default=[], choices=variants,
                    metavar="VARIANT", help=f"variants to leave out: {', '.join(variants)}")
    ap.add_argument("--skip", nargs="+", default=[], metavar="PATTERN",
                    help="run names to leave out, as shell patterns (names are "
                         "SPATIAL-TEMPORAL[-VARIANT]-METHOD-CFL, e.g. '*-monolithic-bs32-*': "
                         "monolithic bs32 at a stiff solid's step costs most of a sweep)")
    ap.add_argument("--methods", nargs="+", default=["usl", "musl", "bs32"], choices=METHODS,
                    metavar="METHOD", help=f"time methods (time.method): {', '.join(METHODS)}; "
                    "the partitioned schemes and contact take usl and musl only, mristep the "
                    "ERK pairs only")
    ap.add_argument("--cfl", nargs="+", type=float, default=[0.4, 0.2, 0.1],
                    help="coupling steps, as time.cfl (fraction of the stable step, below 1)")
    ap.add_argument("--ref-cfl", type=float, default=0.05,
                    help="time.cfl of the monolithic usl reference runs")
    ap.add_argument("--quantity", default=None, help="probes.csv column whose history is "
                    "compared (default: the first probe's x displacement)")
    ap.add_argument("--energy-scale", type=float, default=None,
                    help="J (J/m in 2-D): also report W_net relative to it")
    ap.add_argument("--ranks", type=int, default=1, help="MPI ranks of every run")
    ap.add_argument("--timeout", type=float, default=1800, help="s per run")
    ap.add_argument("--out", default=None, help="results folder: runs.csv, ablation.md, "
                    "ablation.png (default: out/ablate/<case>)")
    ap.add_argument("--scratch", default=None, help="the runs' own output (default: <out>/runs "
                    "without --out, out/ablate/<the results folder's name> with it)")
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "app", "mpmfsi"),
                    help="the mpmfsi executable")
    ap.add_argument("--report-only", action="store_true",
                    help="make no run: write the table and plot from runs.csv as it stands "
                         "(needs the reference runs in --scratch)")
    ap.add_argument("--replot", metavar="DIR", default=None,
                    help="make no run: redraw DIR/ablation.png from DIR/runs.csv alone (the "
                         "rows ablation.md lists, if it exists), then stop")
    ap.add_argument("--sweep-s", type=float, default=None,
                    help="with every run already in runs.csv: the sweep's wall time to report")
    ap.add_argument("--repeat", type=int, default=1,
                    help="run every combination this many times, in rounds, and report the "
                         "median wall time")
    args = ap.parse_args(argv)
    if args.replot is None and args.case is None:
        fail("give a case file (e.g. cases/fsi_piston.ini), or --replot DIR")
    for opt, values in (("--cfl", args.cfl), ("--ref-cfl", [args.ref_cfl])):
        bad = [v for v in values if not 0 < v <= 0.999]
        if bad:
            fail(f"{opt} {bad[0]:g}: a coupling step is time.cfl, a fraction of the stable step "
                 "in (0, 0.999]")
    for opt, value in (("--repeat", args.repeat), ("--ranks", args.ranks)):
        if value < 1:
            fail(f"{opt} {value}: give 1 or more")
    if not args.timeout > 0:
        fail(f"--timeout {args.timeout:g}: give the seconds allowed per run, above 0")
    if args.replot is None:
        if not os.path.exists(args.case):
            fail(f"no case file {args.case}: give the path of a case file (e.g. "
                 "cases/fsi_piston.ini)")
        if os.path.isdir(args.case):
            fail(f"{args.case} is a folder: give the path of a case file")
        check_binary(args)
        check_overrides(args)
    return args


def fail(message, code=2):
    """Stop with one line on stderr: code 2 for bad input (as mpmfsi), 1 for a failed run."""
    print(f"ablate.py: error: {message}", file=sys.stderr)
    sys.exit(code)


def check_binary(args):
    """The binary exists, is executable and runs (`--version`); else stop, saying which."""
    path = args.binary if os.path.sep in args.binary else shutil.which(args.binary)
    if not path or not os.path.exists(path):
        fail(f"no executable {args.binary}: build first (cmake --build build) or give --binary")
    if os.path.isdir(path) or not os.access(path, os.X_OK):
        fail(f"--binary {args.binary} is not an executable file: give the mpmfsi built here "
             "(build/app/mpmfsi)")
    try:
        p = subprocess.run([path, "--version"], env=ENV, capture_output=True, text=True,
                           timeout=120)
        why = "" if p.returncode == 0 and p.stdout.startswith("mpmfsi") else \
            f"exit {p.returncode}, {first_line(p.stderr or p.stdout) or 'no output'}"
    except (OSError, subprocess.SubprocessError) as e:
        why = str(e)
    if why:
        fail(f"--binary {args.binary} does not run as mpmfsi (`{args.binary} --version`: {why}): "
             "rebuild it (cmake --build build) or give another --binary")
    if args.ranks > 1 and not shutil.which("mpiexec"):
        fail(f"--ranks {args.ranks} needs mpiexec, which is not on PATH: install Open MPI or "
             "give --ranks 1")


def first_line(text):
    return next((x.strip() for x in text.splitlines() if x.strip()), "")


def check_overrides(args):
    """No override sets a key the harness sets itself in some run (mpmfsi refuses a key given
    twice, so every such run would fail)."""
    own = {k.split("=", 1)[0] for k in ["output.dir=", "output.overwrite=", "output.interval="]
           + REFERENCE + [f"time.cfl={args.ref_cfl}"]}
    own |= {k.split("=", 1)[0] for c in combos(args) for k in c[-1]}
    for o in args.overrides:
        if "=" in o and o.split("=", 1)[0].strip() in own:
            key = o.split("=", 1)[0].strip()
            fail(f"override {o}: the harness sets {key} itself in its runs (the schemes and steps "
                 "swept: --spatial, --temporal, --methods, --cfl, --skip-variants); leave it out")


def check_case(args):
    """Validate the case with `mpmfsi check` before any run and relay its first error (exit 2);
    the case must hold a solid and a gas to couple, and a probe whose history is compared.
    Returns the probe names."""
    cmd = [args.binary, "check", args.case] + args.overrides
    try:
        p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600)
    except (OSError, subprocess.SubprocessError) as e:
        fail(f"`mpmfsi check {args.case}` did not finish: {e}", 1)
    errors = [x.split("error: ", 1)[-1] for x in p.stderr.splitlines() if "error: " in x]
    if p.returncode != 0:
        more = (f" ({len(errors) - 1} more: run `mpmfsi check {args.case}` to see them)"
                if len(errors) > 1 else "")
        fail((errors[0] if errors else first_line(p.stderr) or f"exit {p.returncode}") + more,
             2 if p.returncode == 2 else 1)
    sections = re.findall(r"^\[([^\]\s]+)\]", p.stdout, re.M)
    kinds = {k: [s.split(".", 1)[1] for s in sections if s.startswith(k + ".")]
             for k in ("solid", "gas", "probe")}
    if not kinds["solid"] or not kinds["gas"]:
        has = "a solid" if kinds["solid"] else "a gas" if kinds["gas"] else "no body"
        fail(f"{args.case}: the ablation couples a solid and a gas, and this case has only {has}: "
             "give a case with both a [solid.NAME] and a [gas.NAME]")
    if not kinds["probe"]:
        fail(f"{args.case}: no [probe.NAME]: the ablation compares a probe's history "
             "(probes.csv); add one, e.g. [probe.tip] with point = x y at the solid")
    return kinds["probe"]


def run(args, out, extra):
    """Run one case; returns (status, message, summary or None)."""
    cmd = [args.binary, "run", args.case, f"output.dir={out}", "output.overwrite=true",
           "output.interval=1e9"] + args.overrides + extra
    if args.ranks > 1:
        cmd = ["mpiexec", "-n", str(args.ranks)] + cmd
    cpu0 = children_cpu()
    try:
        p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=args.timeout)
    except subprocess.TimeoutExpired:
        return "timeout", f"stopped after {args.timeout:.0f} s", None
    cpu = children_cpu() - cpu0
    if p.returncode == 2:
        line = next((x for x in p.stderr.splitlines() if "error" in x), p.stderr.strip()[-200:])
        return "not offered", line.split("error: ")[-1][:200], None
    if p.returncode != 0:
        line = next((x for x in p.stderr.splitlines() if "error" in x), "")
        return "unstable", line.split("error: ")[-1][:200], None
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    s["cpu_s"] = cpu
    return "ok", "", s


def children_cpu():
    """User + system CPU seconds of this process's finished children and theirs (mpiexec
    waits for its ranks, so a run's ranks count): a run's CPU time is the difference over it,
    which a loaded machine changes far less than its wall time."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def history(out, quantity):
    with open(os.path.join(out, "probes.csv")) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        fail(f"{out}/probes.csv has no rows: the case needs a [probe.NAME]", 1)
    col = quantity or [k for k in rows[0] if k != "t"][0]
    if col not in rows[0]:
        fail(f"--quantity {col}: no such column in probes.csv; give one of "
             f"{', '.join(k for k in rows[0] if k != 't')}")
    return col, np.array([float(r["t"]) for r in rows]), np.array([float(r[col]) for r in rows])


# The reference's time scheme, given whatever the case file sets: until 2026-11-29 it was left
# to the case, so the shock panel's references (coupling.time = multirate in its file) were
# multirate runs at the reference step, not monolithic ones.
# coupling.predictor = none in it and in every run but the predictor variant's: a case may set
# the predictor for its own multirate runs, and the other schemes refuse the key away from its
# default, none.
REFERENCE = ["coupling.time=monolithic", "time.method=usl", "coupling.predictor=none"]


def reference_key(args):
    """What a reference run depends on: the overrides, its scheme and step, the ranks and the
    binary (its path, size and modification time, so that a rebuilt binary counts as
    another)."""
    path = os.path.abspath(shutil.which(args.binary) or args.binary)
    st = os.stat(path)
    return {"overrides": args.overrides, "reference": REFERENCE, "ref_cfl": args.ref_cfl,
            "ranks": args.ranks, "binary": [path, st.st_size, st.st_mtime]}


def reference_current(args, out):
    """Is the reference in out finished and made as this sweep would make it? A reference left
    by another binary or other overrides is run again (a resumed sweep kept such a stale one)."""
    try:
        with open(os.path.join(out, "reference.json")) as f:
            key = json.load(f)
    except (OSError, ValueError):
        return False
    return os.path.exists(os.path.join(out, "summary.json")) and key == reference_key(args)


def combos(args):
    for spatial in args.spatial:
        for temporal, variant, keys in VARIANTS:
            if temporal not in args.temporal or variant in args.skip_variants:
                continue
            for method in args.methods:
                classic = method in ("usl", "musl")
                # The partitioned schemes take the classic update, but for MRIStep, which
                # takes an ERK pair only.
                erk_ok = temporal == "monolithic" or variant == "mristep"
                if (not erk_ok or spatial == "contact") and not classic:
                    continue
                if variant == "mristep" and classic:
                    continue
                for cfl in args.cfl:
                    name = f"{spatial}-{temporal}{'-' + variant if variant else ''}-{method}-{cfl:g}"
                    if any(fnmatch.fnmatchcase(name, pat) for pat in args.skip):
                        continue
                    extra = [f"coupling.scheme={spatial}", f"coupling.time={temporal}",
                             f"time.method={method}", f"time.cfl={cfl}"] + keys
                    if not any(k.startswith("coupling.predictor=") for k in keys):
                        extra.append("coupling.predictor=none")  # (see REFERENCE)
                    yield name, spatial, temporal, variant, method, cfl, extra


STATUSES = ("ok", "unstable", "not offered", "timeout")
NUMBERS = ["wall_s", "steps", "rhs_evals", "err_max", "err_rms", "err_rel", "W_net", "imbalance"]


def row_error(row):
    """Why a row of runs.csv cannot be a finished run (a cut or edited line), or None: its
    name is the one its columns make, its status is known, and an ok row's figures are finite
    numbers whose wall_s is the median of its walls."""
    try:
        cfl = float(row["cfl"])
        name = (f"{row['spatial']}-{row['temporal']}{'-' + row['variant'] if row['variant'] else ''}"
                f"-{row['method']}-{cfl:g}")
    except (TypeError, ValueError):
        return f"cfl '{row.get('cfl')}' is not a number"
    if row["name"] != name:
        return f"its name is not {name}"
    if row["status"] not in STATUSES:
        return f"status '{row['status']}' is not one of {', '.join(STATUSES)}"
    if row["status"] != "ok":
        return None
    try:
        values = {k: float(row[k]) for k in NUMBERS}
        walls = walls_of(row)
        if row.get("W_rel"):
            float(row["W_rel"])
    except (TypeError, ValueError) as e:
        return f"a figure is not a number ({e})"
    if values["steps"] != int(values["steps"]) or values["rhs_evals"] != int(values["rhs_evals"]):
        return "steps or rhs_evals is not a whole number"
    # walls written with 6 digits before 2026-12 (a relative rounding of 5e-6 at most)
    if not walls or abs(float(np.median(walls)) - values["wall_s"]) > 1e-5 * max(walls):
        return f"wall_s {row['wall_s']} is not the median of walls {row.get('walls')}"
    return None


def run_error(row, out):
    """Why an ok row does not match the output of its run in out (missing, or other figures),
    or None: a row is kept on resume only if its run's summary.json says the same."""
    try:
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return f"its run's output {os.path.join(out, 'summary.json')} is missing or unreadable"
    try:
        same = (int(float(row["steps"])) == int(s["steps"])
                and int(float(row["rhs_evals"])) == int(s["rhs_evals"])
                and equal(float(row["W_net"]), float(s["coupling_work"]))
                and equal(float(row["imbalance"]), float(s["coupling_imbalance"])))
    except (KeyError, TypeError, ValueError):
        same = False
    return None if same else f"its figures differ from its run's {out}/summary.json"


def equal(a, b):
    return a == b or (math.isnan(a) and math.isnan(b))


def load_rows(path, scratch=None, verb="not tabulated"):
    """The rows of runs.csv by name, each checked (row_error) and, given the runs' folder
    scratch, matched to its run's output (run_error). A row that fails, or a last line without
    its end of line (a cut file), is left out with one line saying why and what happens to it
    (verb: run again, not tabulated). Returns the rows and the number left out."""
    if not os.path.exists(path):
        return {}, 0
    with open(path, newline="") as f:
        text = f.read()
    lines = list(csv.reader(text.splitlines(keepends=True)))
    if not lines:
        return {}, 0
    header, rows, dropped = lines[0], {}, 0
    # (files before 2026-11 have no walls, before 2026-12-02 no cpu_s)
    if header not in (FIELDS, FIELDS[:-1], FIELDS[:-2]):
        fail(f"{path}: its header is not a runs.csv one ({','.join(FIELDS)}): give the results "
             "folder of a sweep, or move the file away to start afresh")
    for k, values in enumerate(lines[1:], 2):
        row = dict(zip(header, values))
        label = f"{path}:{k} ({values[0] if values else 'empty'})"
        if len(values) != len(header):
            why = f"{len(values)} fields, not {len(header)}"
        elif k == len(lines) and not text.endswith(("\n", "\r")):
            why = "the file ends inside it"
        else:
            why = row_error(row)
            if why is None and scratch is not None and row["status"] == "ok":
                why = run_error(row, os.path.join(scratch, row["name"]))
        if why:
            print(f"{label}: a partial or damaged row ({why}): {verb}", flush=True)
            rows.pop(row.get("name"), None)
            dropped += 1
            continue
        rows[row["name"]] = row
    return rows, dropped


def write_atomic(path, write, binary=False):
    """Write path whole or not at all: write(f) fills a temporary beside it, which is synced
    and renamed over path (an interrupted sweep leaves the old file or the new one, never a
    cut one; a link named path is replaced, not written through)."""
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp",
                               dir=folder)
    try:
        mask = os.umask(0)
        os.umask(mask)
        os.fchmod(fd, 0o666 & ~mask)
        with os.fdopen(fd, "wb" if binary else "w", **({} if binary else {"newline": ""})) as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    dirfd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(dirfd)
    finally:
        os.close(dirfd)


def rewrite_rows(path, rows):
    """runs.csv with these rows, replaced whole (write_atomic)."""
    def write(f):
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in FIELDS})
    write_atomic(path, write)


def walls_of(row):
    """The wall times a row holds: its `walls` list, or its one wall_s (a row written before
    --repeat)."""
    if row.get("walls"):
        return [float(w) for w in row["walls"].split(";")]
    return [float(row["wall_s"])] if row.get("wall_s") not in (None, "") else []


def repeat_rounds(args, todo, done, table, scratch):
    """Rounds 2 .. --repeat: each stable combination once more per round, until it has
    --repeat wall times; wall_s becomes their median. Returns the number of runs made."""
    made = 0
    for rnd in range(2, args.repeat + 1):
        due = [c for c in todo if c[0] in done and done[c[0]]["status"] == "ok"
               and len(walls_of(done[c[0]])) < rnd]
        for k, (rname, *_rest, extra) in enumerate(due, 1):
            row = done[rname]
            out = os.path.join(scratch, rname + "-repeat")
            status, msg, s = run(args, out, extra)
            made += 1
            shutil.rmtree(out, ignore_errors=True)
            if status != "ok" or int(s["steps"]) != int(row["steps"]):
                fail(f"{rname}, round {rnd}: {status} {msg} (steps {s['steps'] if s else '-'} "
                     f"against {row['steps']}): the runs are not repeatable; check the machine "
                     "and the binary", 1)
            walls = walls_of(row) + [float(s["wall_s"])]
            # Every digit (repr reads back the same float): wall_s is the median of the walls
            # runs.csv holds, whatever their size (6 digits lost some of a wall above 1 s).
            row["walls"] = ";".join(repr(w) for w in walls)
            row["wall_s"] = float(np.median(walls))
            rewrite_rows(table, done.values())
            print(f"[round {rnd}, {k}/{len(due)}] {rname}: {s['wall_s']:.1f} s (median of "
                  f"{len(walls)}: {row['wall_s']:.1f} s)", flush=True)
    return made


# How far (a factor in error) the cost at equal error is extrapolated beyond the monolithic runs.
EXTRAPOLATE = 1.5


# The costs compared at equal error: a column of runs.csv, what it is, its unit and format.
COSTS = {"wall_s": ("wall time", "s", ".2f"), "cpu_s": ("CPU time (all ranks)", "s", ".2f"),
         "steps": ("steps (coupling steps for the partitioned schemes)", "", ".0f")}


def equal_error(rows, key="wall_s"):
    """Lines of ablation.md: each non-monolithic run's cost (key: a column of COSTS) against
    monolithic's at its error."""
    what, unit, spec = COSTS[key]
    unit = f" ({unit})" if unit else ""
    mono = {}
    for r in rows:
        if r["temporal"] == "monolithic":
            mono.setdefault((r["spatial"], r["method"]), []).append(
                (float(r["err_max"]), float(r[key])))
    lines = []
    for r in rows:
        ref = sorted(mono.get((r["spatial"], r["method"]), []))
        if r["temporal"] == "monolithic" or len(ref) < 2:
            continue
        e, t = float(r["err_max"]), float(r[key])
        # the bracketing pair by error, else the nearest two
        k = next((j for j in range(len(ref) - 1) if ref[j][0] <= e <= ref[j + 1][0]), None)
        extrap = k is None
        if extrap:
            k = 0 if e < ref[0][0] else len(ref) - 2
        (e1, _), (e2, _) = ref[k], ref[k + 1]
        if not (e1 > 0 and e2 > 0 and e1 != e2 and e > 0):
            continue
        if extrap and not ref[0][0] / EXTRAPOLATE <= e <= ref[-1][0] * EXTRAPOLATE:
            lines.append(f"| {r['name']} | {fmt(e)} | {fmt(t, spec)} | beyond monolithic's "
                         f"errors ({fmt(ref[0][0])} to {fmt(ref[-1][0])}) by more than "
                         f"{EXTRAPOLATE:g}x | |")
            continue
        tm = loglog(e, ref[k], ref[k + 1])
        lines.append(f"| {r['name']} | {fmt(e)} | {fmt(t, spec)} | {fmt(tm, '.1f')}"
                     f"{' (extrapolated)' if extrap else ''} | {tm / t:.2f} |")
    if not lines:
        return []
    return ["", f"Cost at equal error: monolithic's {what} at each run's error (the same spatial "
            "scheme and time method; log-log between the monolithic runs that bracket it):", "",
            f"| run | error max | {what.split(' (')[0]}{unit} | monolithic at that error{unit} "
            "| ratio |", "|---|---|---|---|---|"] + lines


def fmt(x, spec=".3g"):
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "" if math.isnan(v) else format(v, spec)


def report(args, rows, outdir, col, sweep_s, nruns, partial=""):
    ok = [r for r in rows if r["status"] == "ok"]
    nrep = max((len(walls_of(r)) for r in ok), default=1)
    lines = [f"# Coupling ablation: {os.path.basename(args.case)}", "",
             f"Quantity: `{col}` (probes.csv); error against a monolithic usl run at time.cfl = "
             f"{args.ref_cfl:g} with the same spatial scheme; {args.ranks} rank(s); overrides: "
             f"{' '.join(args.overrides) or 'none'}. "
             + (f"This sweep's wall time {sweep_s:.0f} s for {nruns} runs made in it "
                f"({sweep_s / max(nruns, 1):.1f} s each); " if sweep_s > 0 else "")
             + f"{'the' if sweep_s > 0 else 'The'} {len(rows)} runs' own wall times sum to "
             f"{sum(sum(walls_of(r)) for r in rows):.0f} s (references not included)"
             + (f"; wall times are the median of {nrep} runs each, made in rounds"
                if nrep > 1 else "") + ".", "",
             "| run | status | wall (s) | CPU (s) | steps | RHS | error max | error RMS | "
             "error / max | W_net (J) | W_net rel. | imbalance |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['name']} | {r['status']} | {fmt(r['wall_s'], '.2f')} | "
                     f"{fmt(r.get('cpu_s'), '.2f')} | {r['steps']} | "
                     f"{r['rhs_evals']} | {fmt(r['err_max'])} | {fmt(r['err_rms'])} | "
                     f"{fmt(r['err_rel'])} | {fmt(r['W_net'])} | {fmt(r['W_rel'])} | "
                     f"{fmt(r['imbalance'], '.1e')} |")
    bad = [r for r in rows if r["status"] != "ok"]
    lines += ["", "Not stable or not offered:" if bad else "Every combination ran stably."]
    lines += [f"- {r['name']}: {r['status']}: {r['message']}" for r in bad]
    if ok:
        best = {}
        for r in ok:
            key = (r["spatial"], float(r["cfl"]))
            if key not in best or float(r["err_max"]) < float(best[key]["err_max"]):
                best[key] = r
        lines += ["", "Least error at each coupling step:"]
        lines += [f"- {k[0]}, cfl {k[1]}: {v['name']} ({fmt(v['err_max'])} in "
                  f"{fmt(v['wall_s'], '.2f')} s)" for k, v in sorted(best.items())]
        lines += equal_error(ok)
        if all(r.get("cpu_s") not in (None, "") for r in ok):
            lines += equal_error(ok, "cpu_s")
        lines += equal_error(ok, "steps")
    lines += [partial] if partial else []
    write_atomic(os.path.join(outdir, "ablation.md"), lambda f: f.write("\n".join(lines) + "\n"))
    plot(ok, outdir, col, case_dim(args.case, args.overrides))


def case_dim(case, overrides=()):
    """domain.dim of a case file (an override wins); None when it cannot be read."""
    import configparser
    for o in overrides:
        if o.startswith("domain.dim="):
            return int(o.split("=", 1)[1])
    c = configparser.ConfigParser(inline_comment_prefixes=("#", ";"), strict=False)
    try:
        c.read(case)
        return c.getint("domain", "dim")
    except (configparser.Error, ValueError, TypeError):
        return None


# Units of a probes.csv column NAME_uq (displacement, m) and NAME_vq (velocity, m/s).
def quantity_unit(col):
    tail = col.rsplit("_", 1)[-1]
    return {"u": "m", "v": "m/s"}.get(tail[:1], "") if len(tail) == 2 else ""


def energy_unit(dim):
    """The unit of an energy in a run of that many dimensions: per m of span in 2-D."""
    return {1: "J/m^2", 2: "J/m", 3: "J"}.get(dim, "J, per unit span in 2-D")


def plot(rows, outdir, col, dim=None):
    """Error against wall time and |W_net| against the coupling step: colour = temporal scheme
    and variant, marker = spatial scheme, line = time method; the legend lists only what the
    rows hold. A zero (or missing) value has no place on a log axis: it is left out and
    counted in the title."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    variants = sorted({(r["temporal"], r["variant"]) for r in rows})
    colour = {v: plt.cm.tab10(k % 10) for k, v in enumerate(variants)}
    marker = {"velocity": "o", "contact": "s", "traction": "^"}
    line = {"usl": "-", "musl": "--", "bs32": ":"}
    fig, ax = plt.subplots(1, 2, figsize=(13, 5.5))
    groups, dropped = {}, [0, 0]
    for r in rows:
        groups.setdefault((r["spatial"], r["temporal"], r["variant"], r["method"]), []).append(r)

    def positive(xs, ys, k):
        keep = [(x, y) for x, y in zip(xs, ys) if y > 0 and math.isfinite(y)]
        dropped[k] += len(xs) - len(keep)
        return [x for x, _ in keep], [y for _, y in keep]

    def num(v):
        try:
            return float(v)
        except (TypeError, ValueError):
            return float("nan")
    for (spatial, temporal, variant, method), rs in groups.items():
        rs.sort(key=lambda r: float(r["cfl"]))
        # monolithic underneath, thicker: a partitioned scheme that matches it stays visible
        mono = temporal == "monolithic"
        style = dict(color=colour[(temporal, variant)], marker=marker.get(spatial, "x"),
                     ls=line.get(method, "-."), ms=8 if mono else 5, lw=3 if mono else 1,
                     zorder=1 if mono else 2)
        ax[0].loglog(*positive([num(r["wall_s"]) for r in rs], [num(r["err_max"]) for r in rs],
                               0), **style)
        ax[1].loglog(*positive([num(r["cfl"]) for r in rs],
                               [abs(num(r["W_net"])) for r in rs], 1), **style)
    unit = quantity_unit(col)
    ax[0].set_xlabel("wall time (s)")
    ax[0].set_ylabel(f"coupling error: max |{col} - reference|" + (f" ({unit})" if unit else ""))
    ax[0].set_title("coupling error against cost (points: time.cfl)"
                    + (f"; {dropped[0]} run(s) with zero error not shown" if dropped[0] else ""),
                    fontsize=10)
    ax[1].set_xlabel("coupling step: time.cfl (fraction of the stable step, -)")
    ax[1].set_ylabel(f"|W_net|: energy the coupling created or destroyed ({energy_unit(dim)})")
    ax[1].set_title("interface energy"
                    + (f"; {dropped[1]} run(s) with W_net = 0 not shown" if dropped[1] else ""),
                    fontsize=10)
    for a in ax:
        a.grid(alpha=0.3, which="both")
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    # Wall times in plain seconds at 1, 2, 5 x 10^k: a decade alone often holds one label.

    def readable(axis, lo, hi):
        """Labels at 1, 2, 5 x 10^k on a log axis spanning less than three decades (one decade
        alone often holds a single label)."""
        if lo > 0 and hi / lo < 1e3:
            axis.set_major_locator(LogLocator(subs=(1, 2, 5)))
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(NullFormatter())
    for a in ax:
        if a.get_xscale() == "log":  # (a table without a stable run has no log axis)
            readable(a.xaxis, *a.get_xlim())
            readable(a.yaxis, *a.get_ylim())
    cfls = sorted({num(r["cfl"]) for r in rows if num(r["cfl"]) > 0})
    if cfls and ax[1].get_xscale() == "log":  # ticks at the coupling steps swept, plain
        ax[1].set_xticks(cfls, [f"{c:g}" for c in cfls])
        ax[1].set_xticks([], minor=True)
    methods = sorted({r["method"] for r in rows}, key=lambda m: list(line).index(m)
                     if m in line else len(line))
    spatials = sorted({r["spatial"] for r in rows}, key=lambda m: list(marker).index(m)
                      if m in marker else len(marker))
    handles = [Line2D([], [], color=colour[v], lw=3, label=" ".join(x for x in v if x))
               for v in variants]
    handles += [Line2D([], [], color="k", marker=marker.get(k, "x"), ls="", label=k)
                for k in spatials]
    handles += [Line2D([], [], color="k", ls=line.get(k, "-."), label=k) for k in methods]
    fig.legend(handles=handles, fontsize=8, loc="center left", bbox_to_anchor=(1.0, 0.5),
               title="temporal scheme (colour),\nspatial (marker), method (line)",
               title_fontsize=8)
    fig.tight_layout()
    write_atomic(os.path.join(outdir, "ablation.png"),
                 lambda f: fig.savefig(f, format="png", dpi=110, bbox_inches="tight"), binary=True)
    plt.close(fig)


def replot(folder, quantity=None):
    """Redraw folder/ablation.png from folder/runs.csv: the rows its ablation.md lists (all
    of runs.csv's if there is none), the quantity's name from --quantity or ablation.md."""
    table = os.path.join(folder, "runs.csv")
    if not os.path.exists(table):
        print(f"ablate.py: error: no {table}: --replot needs the runs.csv a sweep wrote (give "
              "its --out folder)", file=sys.stderr)
        sys.exit(2)
    rows = list(load_rows(table)[0].values())
    md = os.path.join(folder, "ablation.md")
    col, dim = quantity, None
    if os.path.exists(md):
        with open(md) as f:
            text = f.read()
        listed = {ln.split("|")[1].strip() for ln in text.splitlines() if ln.startswith("| ")}
        rows = [r for r in rows if r["name"] in listed] or rows
        if col is None and "Quantity: `" in text:
            col = text.split("Quantity: `", 1)[1].split("`", 1)[0]
        head = text.splitlines()[0] if text else ""
        if head.startswith("# Coupling ablation: "):
            case = os.path.join(ROOT, "cases", head.split(": ", 1)[1].strip())
            overrides = text.split("overrides: ", 1)[1].split(". ")[0].split() if \
                "overrides: " in text else []
            dim = case_dim(case, overrides) if os.path.exists(case) else None
    ok = [r for r in rows if r["status"] == "ok"]
    plot(ok, folder, col or "quantity", dim)
    print(f"wrote {os.path.join(folder, 'ablation.png')} from {len(ok)} stable run(s) of "
          f"{table}")


def main():
    args = parse()
    if args.replot:
        replot(args.replot, args.quantity)
        return
    if not args.report_only:  # (a report makes no run: it needs no valid case)
        check_case(args)
    args.case = os.path.abspath(args.case)
    name = os.path.splitext(os.path.basename(args.case))[0]
    # Without --out the results go to the untracked out/ (a trial sweep must not overwrite a
    # committed study in bench/results/), and the runs beside them.
    outdir = os.path.abspath(args.out or os.path.join(ROOT, "out", "ablate", name))
    # With --out, the runs' own output, not committed: one folder per results folder, so that
    # two sweeps of one case (another --out) never share runs or references.
    scratch = os.path.abspath(args.scratch or (os.path.join(outdir, "runs") if args.out is None
                                               else os.path.join(ROOT, "out", "ablate",
                                                                 os.path.basename(outdir))))
    os.makedirs(scratch, exist_ok=True)
    os.makedirs(outdir, exist_ok=True)
    table = os.path.join(outdir, "runs.csv")
    if args.report_only:
        done, _ = load_rows(table)
    else:  # a cut or damaged row, or one whose run's output says otherwise, is run again
        done, dropped = load_rows(table, scratch, "run again")
        if dropped:
            rewrite_rows(table, done.values())
    refs, failed = {}, []
    for spatial in args.spatial:
        out = os.path.join(scratch, f"reference-{spatial}")
        status, msg, _ = ("ok", "", None)
        if args.report_only:
            if not os.path.exists(os.path.join(out, "summary.json")):
                continue
        elif not reference_current(args, out):
            print(f"reference for {spatial} (monolithic usl, cfl {args.ref_cfl:g}) ...", flush=True)
            status, msg, s = run(args, out, REFERENCE + [f"coupling.scheme={spatial}",
                                                         f"time.cfl={args.ref_cfl}"])
            if s:
                print(f"  reference: {s['steps']} steps, wall {float(s['wall_s']):.1f} s, "
                      f"CPU {s['cpu_s']:.1f} s", flush=True)
            if status == "ok":
                write_atomic(os.path.join(out, "reference.json"),
                             lambda f: json.dump(reference_key(args), f))
            stale = [n for n, r in done.items() if r["spatial"] == spatial]
            if stale:  # their errors were taken against the reference just replaced
                print(f"  {len(stale)} {spatial} row(s) of runs.csv were measured against "
                      "another reference: they are run again")
                for n in stale:
                    del done[n]
                rewrite_rows(table, done.values())
        if status != "ok":
            print(f"  reference for {spatial} failed ({status}: {msg}); its runs are skipped")
            failed.append(f"{spatial}: {status}: {msg}")
            continue
        refs[spatial] = history(out, args.quantity)
    if failed and not refs:
        fail(f"every reference run failed ({'; '.join(failed)}): nothing to measure against; "
             "fix what the message says, then run again", 1)
    todo = [c for c in combos(args) if c[1] in refs]
    t0, made = time.time(), 0
    for k, (rname, spatial, temporal, variant, method, cfl, extra) in enumerate(todo, 1):
        if rname in done or args.report_only:
            continue
        out = os.path.join(scratch, rname)
        t_run = time.time()
        status, msg, s = run(args, out, extra)
        made += 1
        row = dict(name=rname, spatial=spatial, temporal=temporal, variant=variant, method=method,
                   cfl=cfl, status=status, message=msg, wall_s="", steps="", rhs_evals="",
                   err_max="", err_rms="", err_rel="", W_net="", W_rel="", imbalance="",
                   walls="", cpu_s="")
        if s:
            col, tr, ur = refs[spatial]
            _, t, u = history(out, col)
            diff = np.interp(tr, t, u) - ur
            scale = max(float(np.max(np.abs(ur))), 1e-300)
            row.update(wall_s=float(s["wall_s"]), walls=repr(float(s["wall_s"])), steps=s["steps"],
                       rhs_evals=s["rhs_evals"], cpu_s=s["cpu_s"],
                       err_max=float(np.max(np.abs(diff))),
                       err_rms=float(np.sqrt(np.mean(diff**2))),
                       err_rel=float(np.max(np.abs(diff))) / scale, W_net=s["coupling_work"],
                       W_rel=(s["coupling_work"] / args.energy_scale if args.energy_scale
                              else ""), imbalance=s["coupling_imbalance"])
        done[rname] = row
        rewrite_rows(table, done.values())
        elapsed = time.time() - t0
        eta = elapsed / made * sum(1 for c in todo[k:] if c[0] not in done)
        err = f", error {row['err_max']:.3g}" if s else ""
        print(f"[{k}/{len(todo)}] {rname}: {status} in {time.time() - t_run:.1f} s{err} "
              f"(sweep {elapsed:.0f} s, ETA {eta:.0f} s)", flush=True)
    if args.repeat > 1 and not args.report_only:
        made += repeat_rounds(args, todo, done, table, scratch)
    rows = [done[c[0]] for c in todo if c[0] in done]
    if len(rows) < len(todo):
        print(f"{len(todo) - len(rows)} of {len(todo)} runs not made yet: the table is partial")
    col = refs[next(iter(refs))][0] if refs else "?"
    sweep = time.time() - t0 if made or args.sweep_s is None else args.sweep_s
    missing = [c[0] for c in todo if c[0] not in done]
    partial = (f"\n**Partial**: {len(missing)} of {len(todo)} runs not made yet ({missing[0]} ... "
               f"{missing[-1]}); run the same command again to finish." if missing else "")
    report(args, rows, outdir, col, sweep if made or args.sweep_s is not None else 0.0,
           made or len(rows), partial)
    print(f"wrote {table}, {outdir}/ablation.md, {outdir}/ablation.png")


if __name__ == "__main__":
    main()

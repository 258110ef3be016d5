"""Input limits (issue 54, items 3 and 4): input that is huge, runaway, non-normal or edited
is refused before the run, with one line naming where it was set and the key, never a crash.

1. Expressions: the issue's 180,000-term field (a case file of 1 MB) crashed libmatheval's
   recursive tree walks (exit 139) in check and run; it and expressions over the limits
   (4096 characters, 1000 operators, 100 nested parentheses) are refused, also with a 1 MiB
   stack. An expression at the limits is accepted with a 256 KiB stack. (Under
   AddressSanitizer every stack limit is 4 times larger.)
2. Reals: NaN, infinities, overflows, subnormal values (1e-320) and texts that underflow to 0
   (1e-400) are refused for a real key and for each value of a reals key, from a file and the
   command line; a field expression that evaluates to a subnormal number is refused too.
3. Runaway settings, refused by check and run with the key to change: coupling.substeps at the
   old maximum (1e6) and at the new one when its substeps exceed run.max_steps, the slow
   substeps, strong coupling's sub-iterations, and time.dt_max = 1e-300 (multirate and
   monolithic). A small time.dt_max that fits the budget runs to its end (the blow-up guard
   used to call its steps a collapse and blame time.cfl).
4. A checkpoint edited with valid checksums: a time of -1 is refused on reading; a time so
   large that a step does not change it (1e17, where a double resolves 16 s, restarted to
   1e18) is refused too.
Every refusal: exit 2, one error line, no crash; run writes no output folder.
"""
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile

import h5py

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_input_limits")
FSI = mt.case("fsi_pulse.ini")  # a gas with a pressure_field expression, and a solid
PANEL = mt.case("shock_panel.ini")  # multirate: the panel substeps inside the air's step
BAR = mt.case("supersonic_bar.ini")  # the main job, monolithic
QUIET = ["run.progress=false"]
with open(mt.BIN, "rb") as f:
    # AddressSanitizer's instrumented frames are several times larger: its stacks are scaled.
    STACK_SCALE = 4 if b"__asan_init" in f.read() else 1


def errors_of(p):
    return [l for l in p.stderr.splitlines() if l.startswith("error:")]


def mpmfsi(args, stack_kib=None, timeout=120):
    """mpmfsi args, with the stack limited to stack_kib KiB if given; None after a timeout."""
    def limit():
        if stack_kib:
            b = stack_kib * 1024 * STACK_SCALE
            resource.setrlimit(resource.RLIMIT_STACK, (b, b))
    try:
        return subprocess.run([mt.BIN] + list(args), capture_output=True, text=True,
                              timeout=timeout, preexec_fn=limit)
    except subprocess.TimeoutExpired:
        return None


def refused(name, args, where, *words, stack_kib=None, out=None):
    """args must exit 2 with one error line that starts with `where` and holds every word;
    with out, that folder must not exist afterwards."""
    p = mpmfsi(args, stack_kib)
    if p is None:
        check(False, f"{name}: still running after the timeout")
        return
    errs = errors_of(p)
    ok = (p.returncode == 2 and len(errs) == 1 and errs[0].startswith("error: " + where)
          and all(w in errs[0] for w in words) and not (out and os.path.exists(out)))
    shown = errs[0] if errs else p.stderr.strip()[-300:]
    check(ok, f"{name}: exit {p.returncode}: {shown[:330]}")


def both(name, case, overrides, where, *words, stack_kib=None):
    """check and run of case with overrides are both refused alike."""
    refused(f"check, {name}", ["check", case] + overrides, where, *words, stack_kib=stack_kib)
    out = os.path.join(TMP, "out_" + re.sub(r"\W+", "_", name))
    refused(f"run, {name}", ["run", case, f"output.dir={out}"] + QUIET + overrides, where,
            *words, stack_kib=stack_kib, out=out)


def with_field(name, expr):
    """fsi_pulse.ini with gas.air.pressure_field = expr, written to TMP; (path, line)."""
    with open(FSI) as f:
        lines = f.read().split("\n")
    k = next(i for i, l in enumerate(lines) if l.startswith("pressure_field"))
    lines[k] = "pressure_field = " + expr
    path = os.path.join(TMP, name + ".ini")
    with open(path, "w") as f:
        f.write("\n".join(lines))
    return path, k + 1


def expressions():
    big, line = with_field("terms_180000", "1" + "+0.0*x" * 180000)
    check(os.path.getsize(big) > 1_000_000, f"the issue's field: {os.path.getsize(big)} bytes")
    for stack in (None, 1024):
        tag = f", stack {stack} KiB" if stack else ""
        both(f"180,000 terms{tag}", big, [], f"{big}:{line}: gas.air.pressure_field",
             "1080001 characters", "limit of 4096", stack_kib=stack)
    for name, expr, words in (
            ("1500 operators", "1" + "+x" * 1500, ["1500 operators", "limit of 1000"]),
            ("200 nested parentheses", "(" * 200 + "1" + ")" * 200, ["200 deep", "limit of 100"]),
            ("150 nested functions", "sin(" * 150 + "1" + ")" * 150, ["150 deep"]),
            ("3000 unary minuses", "1+" + "-" * 3000 + "x", ["3001 operators"])):
        path, line = with_field(name.replace(" ", "_"), expr)
        both(name + ", stack 1024 KiB", path, [], f"{path}:{line}: gas.air.pressure_field",
             *words, stack_kib=1024)
    # At the limits: 1000 operators (a chain, the deepest tree), 100 nested parentheses.
    path, _ = with_field("at_limits", "1+0*(" * 100 + "x" + ")" * 100 + "+0*x" * 399)
    p = mpmfsi(["check", path], stack_kib=256)
    check(p is not None and p.returncode == 0,
          f"an expression at the limits (1000 operators, 100 nested), stack 256 KiB: accepted "
          f"(exit {p.returncode if p else 'timeout'}) {(errors_of(p) or [''])[0] if p else ''}")
    path, line = with_field("subnormal_field", "1e-320 + 0*x")
    both("a field that evaluates to 1e-320", path, ["time.t_end=1e-3"],
         f"{path}:{line}: gas.air.pressure_field", "subnormal")


def reals():
    with open(FSI) as f:
        text = f.read()
    for value, words in (("1e-320", ["2.2e-308", "subnormal"]), ("1e-400", ["rounds to 0"]),
                         ("0x1p-1074", ["subnormal"]), ("nan", ["not finite"]),
                         ("inf", ["not finite"]), ("-inf", ["not finite"]),
                         ("1e309", ["not finite"])):
        both(f"density = {value} on the command line", FSI, [f"solid.block.density={value}"],
             "command line: solid.block.density", *words)
        path = os.path.join(TMP, f"density_{value}.ini")
        lines = text.split("\n")
        k = lines.index("density = 5")  # the block's (the gas has density = 1)
        lines[k] = f"density = {value}"
        with open(path, "w") as f:
            f.write("\n".join(lines))
        line = k + 1
        refused(f"check, density = {value} in the file", ["check", path],
                f"{path}:{line}: solid.block.density", *words)
    both("a reals key with 1e-320", FSI, ["solid.block.velocity=0 1e-320"],
         "command line: solid.block.velocity", "value 2", "subnormal")
    p = mpmfsi(["check", FSI, "solid.block.density=2.3e-308", "time.t_end=1e-300"])
    check(p is not None and not any("density" in l for l in errors_of(p)),
          "the smallest normal numbers are accepted (density 2.3e-308)")


def runaway():
    both("multirate, coupling.substeps = 1e6 (the old maximum)", PANEL,
         ["coupling.substeps=1000000"], "command line: coupling.substeps", "[1, 10000]")
    both("multirate, coupling.substeps = 1e4 (the maximum), about 700 times what it needs",
         PANEL, ["coupling.substeps=10000"], "command line: coupling.substeps",
         "that the fast module's stable step needs", "at most")
    p = mpmfsi(["check", PANEL, "coupling.substeps=10000"])
    most = re.search(r"give at most (\d+)", p.stderr if p else "")
    p = mpmfsi(["check", PANEL, f"coupling.substeps={most.group(1)}"]) if most else None
    check(p is not None and p.returncode == 0,
          f"multirate, coupling.substeps = {most.group(1) if most else '?'} (the most the "
          "refusal offers, 100 times what stability needs) is accepted")
    both("multirate, coupling.substeps = 1000 over run.max_steps", PANEL,
         ["coupling.substeps=1000", "run.max_steps=1e6"], "command line: coupling.substeps",
         "substeps of the fast module", "lower coupling.substeps")
    both("multirate, coupling.slow_substeps = 1e4, far more than the fast module takes", PANEL,
         ["coupling.slow_substeps=10000"], "command line: coupling.slow_substeps", "at most")
    both("multirate, coupling.slow_substeps = 1000 over run.max_steps", PANEL,
         ["coupling.slow_substeps=1000", "run.max_steps=1e6"],
         "command line: coupling.slow_substeps", "substeps of the slow module")
    both("strong coupling, coupling.iterations = 1000 over run.max_steps", BAR,
         ["coupling.time=staggered", "coupling.iterations=1000", "coupling.tolerance=1e-6",
          "run.max_steps=1e6"], "command line: coupling.iterations", "sub-iterations")
    for name, case in (("multirate", PANEL), ("monolithic", BAR)):
        both(f"{name}, time.dt_max = 1e-300", case, ["time.dt_max=1e-300"],
             "command line: time.dt_max", "raise time.dt_max")
    p = mpmfsi(["check", PANEL])
    check(p is not None and re.search(r"^estimate: about \S+ steps, each with \d+ substeps",
                                      p.stderr, re.M) is not None,
          "the estimate counts the panel's substeps: "
          + next((l for l in (p.stderr if p else "").splitlines() if "estimate" in l), "none"))
    # A time.dt_max far below the stable step (1e-6 s against 3.4e-3 s) is a choice, not a
    # collapse: 200 steps, to the end.
    out = os.path.join(TMP, "dt_max_small")
    p = mpmfsi(["run", FSI, f"output.dir={out}", "time.dt_max=1e-6", "time.t_end=2e-4"] + QUIET,
               timeout=300)
    check(p is not None and p.returncode == 0 and "done: t = 0.0002, 200 steps" in p.stderr,
          f"time.dt_max = 1e-6 runs its 200 steps (exit {p.returncode if p else 'timeout'}) "
          f"{(errors_of(p) or [''])[0] if p else ''}")


def checkpoints():
    out = os.path.join(TMP, "ck")
    p = mpmfsi(["run", mt.case("axial_bar.ini"), f"output.dir={out}", "time.t_end=0.3",
                "output.snapshots=false"] + QUIET, timeout=300)
    ck = os.path.join(out, "checkpoint_final.h5")
    if not (p and p.returncode == 0 and os.path.exists(ck)):
        check(False, "axial_bar: a checkpoint to edit")
        return
    for label, t, tend, words in (("t = -1", -1.0, "time.t_end=0.4", ["time t is -1", "below"]),
                                  ("t = 1e17", 1e17, "time.t_end=1e18",
                                   ["cannot be continued", "does not change the time"])):
        path = os.path.join(TMP, f"edited_{t:g}.h5")
        shutil.copy(ck, path)
        with h5py.File(path, "r+") as f:  # HDF5 recomputes the checksums
            f.attrs.modify("t", t)
        refused(f"restart of a checkpoint edited to {label} (checksums valid)",
                ["restart", path, tend, f"output.dir={path}_out"] + QUIET, "", path, *words,
                out=path + "_out")


TMP = tempfile.mkdtemp(prefix="input_limits_", dir=".")
try:
    expressions()
    reals()
    runaway()
    checkpoints()
finally:
    shutil.rmtree(TMP, ignore_errors=True)
sys.exit(check.finish())

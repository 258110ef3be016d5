"""Input that must neither hang, flood nor slip through, and a resolved case that reads back.

- Every cases/*.ini: `check` prints the resolved configuration; `check` of that text prints
  the same text, byte for byte (defaults are comments, provenance comments are carried
  over). A case with an obstacle restarts from its checkpoint (the checkpoint stores that
  text).
- The command line is one source, like a file: a key given twice there is refused, naming
  both assignments.
- An incomplete instance section on the command line is refused with the message the same
  section gets in a file (solid, gas, obstacle, probe, traction).
- A self-crossing outline is refused for a solid's [geometry] polygon as for an obstacle.
- A device, a folder, a FIFO or a file over 16 MiB given as the case is refused at once.
- A field expression that gives NaN, +inf or -inf is reported with that value and where.
- Megabytes of garbage give at most 20 error lines and one line counting the rest.
Every refusal: exit status 2, and each error line names the file (or the command line).
"""
import os
import random
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_input_safety")
CASES = sorted(f for f in os.listdir(os.path.join(mt.SOURCE, "cases")) if f.endswith(".ini"))


def errors_of(p):
    return [l for l in p.stderr.splitlines() if l.startswith("error:")]


def run_quick(args, timeout=60):
    """mpmfsi args, which must end well within timeout (a hang is a failure, not a wait)."""
    try:
        return subprocess.run([mt.BIN] + list(args), capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired:
        return None


def refused(name, args, *words, lines=1, timeout=60):
    """args must exit 2 with `lines` error lines, the first holding every word."""
    p = run_quick(args, timeout)
    if p is None:
        check(False, f"{name}: still running after {timeout} s")
        return None
    errs = errors_of(p)
    ok = p.returncode == 2 and len(errs) == lines and all(w in errs[0] for w in words)
    check(ok, f"{name}: exit {p.returncode}: {errs[0] if errs else p.stderr.strip()[-300:]}")
    return errs


def strip_where(line):
    """An error line without its location ("case.ini:12: ", "command line: ")."""
    return re.sub(r"^error: (command line|\S+:\d+): ", "error: ", line)


with tempfile.TemporaryDirectory() as tmp:
    # 1. check -> check again gives the same text, for every case.
    for name in CASES:
        p = mt.run(["check", mt.case(name)], check=False)
        if p.returncode != 0:
            check(False, f"{name}: check fails: {(errors_of(p) or [p.stderr[-200:]])[0]}")
            continue
        path = os.path.join(tmp, "resolved_" + name)
        with open(path, "w") as f:
            f.write(p.stdout)
        q = mt.run(["check", path], check=False)
        same = q.returncode == 0 and q.stdout == p.stdout
        first = next((a for a, b in zip(p.stdout.splitlines(), q.stdout.splitlines()) if a != b),
                     (errors_of(q) or [""])[0])
        check(same, f"{name}: the resolved text reads back to itself"
              + ("" if same else f" (exit {q.returncode}; first difference: {first})"))

    # ... and the checkpoint, which stores that text, restarts a case with obstacles.
    out = os.path.join(tmp, "obst")
    mt.run(["run", mt.case("gas_obstacles.ini"), f"output.dir={out}", "time.t_end=1e-5",
            "run.progress=false"])
    p = mt.run(["restart", os.path.join(out, "checkpoint_final.h5"), "time.t_end=2e-5",
                f"output.dir={out}_restarted", "run.progress=false"], check=False)
    check(p.returncode == 0, f"gas_obstacles restarts from its checkpoint: exit {p.returncode} "
          f"{(errors_of(p) or [''])[0]}")

    # 2. A key twice on the command line.
    refused("a key twice on the command line",
            ["check", mt.case("sod.ini"), "time.t_end=1", "time.t_end=2"],
            "command line", "time.t_end", "time.t_end=1", "time.t_end=2", "twice")

    # 3. Incomplete instance sections: the command line as the file.
    SECTIONS = [
        ("ballistic2d.ini", "solid.extra", {"density": "5"}),
        ("ballistic2d.ini", "solid.extra", {"geometry": "block"}),
        ("gas_obstacles.ini", "gas.extra", {"density": "5"}),
        ("gas_obstacles.ini", "gas.extra", {"geometry": "all"}),
        ("gas_obstacles.ini", "obstacle.extra", {"radius": "0.1"}),
        ("gas_obstacles.ini", "obstacle.extra", {"shape": "circle"}),
        ("ballistic2d.ini", "probe.extra", {"phase": "solid"}),
        ("ballistic2d.ini", "traction.extra", {"value": "1 0"}),
    ]
    for base, section, keys in SECTIONS:
        text = open(mt.case(base)).read().rstrip("\n") + f"\n\n[{section}]\n" + "".join(
            f"{k} = {v}\n" for k, v in keys.items())
        path = os.path.join(tmp, "section.ini")
        with open(path, "w") as f:
            f.write(text)
        pf = mt.run(["check", path], check=False)
        pc = mt.run(["check", mt.case(base)] + [f"{section}.{k}={v}" for k, v in keys.items()],
                    check=False)
        ef, ec = errors_of(pf), errors_of(pc)
        same = [strip_where(l) for l in ef] == [strip_where(l) for l in ec]
        located = all(l.startswith("error: command line: ") for l in ec)
        check(pf.returncode == 2 and pc.returncode == 2 and ef and same and located,
              f"[{section}] with {', '.join(keys)} only: refused alike from the file (exit "
              f"{pf.returncode}) and the command line (exit {pc.returncode}): "
              f"{ec[0] if ec else pc.stderr.strip()[-200:]}")

    # 4. A self-crossing outline for a solid body: a bow tie with lobes of unequal size, so
    # that its signed area is not zero (a symmetric one is caught as enclosing no area).
    bow = os.path.join(tmp, "bow.csv")
    with open(bow, "w") as f:
        f.write("0.5 2.0\n1.0 2.4\n1.0 2.0\n0.5 2.5\n")
    base = open(mt.case("ballistic2d.ini")).read()
    old = "type = box\nlo = 0.5 2.0\nhi = 1.0 2.5"
    assert old in base
    text = base.replace(old, f"type = polygon\nfile = {bow}", 1)
    mt.expect_input_error(check, "self-crossing solid outline", text, "geometry.block.file",
                          mt.line_starting(text, "file = "), "crosses itself")

    # 5. Files that are no case files.
    fifo = os.path.join(tmp, "pipe.ini")
    os.mkfifo(fifo)
    big = os.path.join(tmp, "big.ini")
    with open(big, "w") as f:
        f.write(("# " + "x" * 1021 + "\n") * (17 * 1024))
    for name, path, kind in [("/dev/zero", "/dev/zero", "character device"),
                             ("a folder", tmp, "folder"), ("a FIFO", fifo, "FIFO"),
                             ("17 MiB", big, "larger than 16 MiB")]:
        refused(f"{name} as the case", ["check", path], path, kind, timeout=30)
    # ... and as a file a key names.
    text = base.replace(old, "type = polygon\nfile = /dev/zero", 1)
    mt.expect_input_error(check, "/dev/zero as a polygon file", text, "geometry.block.file",
                          mt.line_starting(text, "file = "), "not a regular file")

    # 6. Expressions that are not finite: the value as it is, and where.
    sod = open(mt.case("sod.ini")).read()
    left = "density = 1\npressure = 1"
    assert left in sod
    EXPR = [("density_field = 1/(x-x)\npressure = 1", "gas.left.density_field", "+inf"),
            ("density = 1\npressure_field = log(0*x)", "gas.left.pressure_field", "-inf"),
            ("density_field = sqrt(-1-x)\npressure = 1", "gas.left.density_field", "NaN"),
            ("density = 1\npressure = 1\nvelocity_field = 0; sqrt(-1-x)",
             "gas.left.velocity_field", "NaN in component 2")]
    for new, key, value in EXPR:
        text = sod.replace(left, new, 1)
        mt.expect_input_error(check, f"{key} giving {value}", text, key,
                              mt.line_starting(text, key.split(".")[-1] + " ="),
                              f"gives {value} at (")
    text = base.replace("[solid.block]", "[solid.block]\nvelocity_field = 1/(y-y); 0", 1)
    if "velocity = " in text.split("[solid.block]")[1].split("[")[0]:
        text = re.sub(r"(\[solid\.block\][^\[]*?)\nvelocity = [^\n]*", r"\1", text, count=1)
    mt.expect_input_error(check, "solid velocity_field giving +inf", text,
                          "solid.block.velocity_field",
                          mt.line_starting(text, "velocity_field ="), "gives +inf in component 1")

    # 7. Megabytes of garbage: a screenful of errors and a count.
    rnd = random.Random(7)
    chars = "".join(chr(c) for c in range(32, 127))
    junk = os.path.join(tmp, "junk.ini")
    with open(junk, "w") as f:
        for _ in range(60000):
            f.write("".join(rnd.choice(chars) for _ in range(rnd.randint(0, 90))) + "\n")
    p = run_quick(["check", junk], timeout=60)
    errs = errors_of(p) if p else []
    ok = (p is not None and p.returncode == 2 and 2 <= len(errs) <= 21
          and re.match(r"error: \.\.\. and \d+ more errors in " + re.escape(junk), errs[-1])
          and all(junk in l for l in errs))
    check(ok, f"{os.path.getsize(junk) / 1e6:.1f} MB of garbage: exit "
          f"{p.returncode if p else 'timeout'}, {len(errs)} error lines, the last: "
          f"{errs[-1] if errs else ''}")

sys.exit(check.finish())

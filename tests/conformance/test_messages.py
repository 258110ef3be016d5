"""Messages name the key or the real cause (issue 54, item 7): input errors found before a run.

1. A misspelt section ([tmie], 4 keys; [solidd.block]; [phisycs]) is one error line naming the
   file, the line, the section and the nearest valid one; a section with no near one lists the
   sections; [solid] says it needs a name. (Before: one "unknown key" line per key.)
2. A 300-character instance name ([solid.<300>], [probe.<300>], [clamp.<300>]) is refused with
   one line and the limit, exit 2 (before: "internal error" or a truncated key); a name at the
   limit (63) runs, with its probe columns named in full.
3. At Mach 50 (cases/supersonic_bar.ini, usl, 1 cm cells to keep it short) the bar is torn
   from its clamp and swept onto the outflow face: the message names the solid particle, the
   face key boundary.x_hi and that a smaller step does not help (before: "the particle left
   the domain. Reduce time.cfl ..."), exit 1.
"""
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_messages")
QUIET = ["run.progress=off"]


def errors(p):
    return [l for l in p.stderr.splitlines() if l.startswith("error:")]


def edited(name, subs):
    """The case file cases/<name> with the regular-expression substitutions subs, written
    to a fresh file; returns its path."""
    with open(mt.case(name)) as f:
        text = f.read()
    for a, b in subs:
        text, n = re.subn(a, b, text, flags=re.M)
        assert n > 0, a
    fd, path = tempfile.mkstemp(prefix="case_", suffix=".ini", dir=".")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    return path


def one_line(p, *words):
    e = errors(p)
    return p.returncode == 2 and len(e) == 1 and all(w in e[0] for w in words), e[:3]


# ---- 1. a bad section name: one line --------------------------------------------------------
B = "ballistic2d.ini"
for header, words in (
        ("tmie", ["unknown section '[tmie]'; did you mean '[time]'?"]),
        ("solidd.block", ["unknown section '[solidd.block]'; did you mean '[solid.block]'?"]),
        ("xyzzy", ["unknown section '[xyzzy]'; the sections are run, domain", "solid.NAME"]),
        ("solid", ["section '[solid]' needs a name: write '[solid.NAME]'"])):
    old = "solid.block" if header.startswith("solid") else "time"
    path = edited(B, [(rf"^\[{re.escape(old)}\]", f"[{header}]")])
    with open(path) as f:
        first_key = [k for k, l in enumerate(f.read().splitlines(), 1)
                     if l.startswith(f"[{header}]")][0] + 1
    p = mt.run(["check", path] + QUIET, check=False)
    ok, e = one_line(p, f"{os.path.basename(path)}:{first_key}:", *words)
    check(ok, f"[{header}] for [{old}]: exit {p.returncode}, {len(errors(p))} line(s): {e}")
p = mt.run(["check", mt.case(B), "tmie.t_end=1", "tmie.method=usl"] + QUIET, check=False)
ok, e = one_line(p, "command line: unknown section '[tmie]'; did you mean '[time]'?")
check(ok, f"the same on the command line: {e}")

# ---- 2. a 300-character instance name -------------------------------------------------------
S = "supersonic_bar.ini"
long = "b" * 300
for section in ("solid.bar", "probe.tip", "clamp.base", "gas.air"):
    kind = section.split(".")[0]
    path = edited(S, [(rf"^\[{re.escape(section)}\]", f"[{kind}.{long}]")])
    p = mt.run(["check", path] + QUIET, check=False)
    ok, e = one_line(p, f"the name in '[{kind}.bbbb", "is 300 characters long",
                     "at most 63")
    check(ok and "internal error" not in p.stderr,
          f"[{kind}.<300 characters>]: exit {p.returncode}: {[l[:160] for l in e]}")
n63 = "n" * 63
path = edited(S, [(r"^\[solid\.bar\]", f"[solid.{n63}]"), (r"^\[probe\.tip\]", f"[probe.{n63}]"),
                  (r"^\[clamp\.base\]", f"[clamp.{n63}]"), (r"^\[geometry\.bar\]", f"[geometry.{n63}]"),
                  (r"^geometry = bar", f"geometry = {n63}"), (r"^of = channel bar", f"of = channel {n63}")])
o = mt.outdir("name63")
p = mt.run(["run", path, f"output.dir={o}", "grid.dx=0.01", "time.t_end=2e-5"] + QUIET, check=False)
with open(os.path.join(o, "probes.csv")) if p.returncode == 0 else open(os.devnull) as f:
    head = f.readline()
check(p.returncode == 0 and f"{n63}_ux" in head,
      f"names of 63 characters (solid, geometry, clamp, probe) run: exit {p.returncode}, "
      f"probe column {n63[:8]}..._ux {'present' if f'{n63}_ux' in head else 'missing'}")

# ---- 3. Mach 50: the real cause -------------------------------------------------------------
path = edited(S, [(r"^velocity = 854 0", "velocity = 17080 0")])
o = mt.outdir("mach50")
p = mt.run(["run", path, f"output.dir={o}", "time.method=usl", "grid.dx=0.01",
            "time.t_end=2e-4"] + QUIET, check=False)
e = [l for l in errors(p) if "particle" in l]
msg = e[0] if e else p.stderr[-300:]
check(p.returncode == 1 and len(e) == 1 and "the solid particle reached the domain's face "
      "boundary.x_hi, which no body may cross" in msg and "A smaller step does not help" in msg
      and "left the domain" not in msg and "Reduce time.cfl" not in msg,
      f"Mach 50, usl: exit {p.returncode}: {msg}")

sys.exit(check.finish())

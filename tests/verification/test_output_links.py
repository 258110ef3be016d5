"""Output folders that cannot redirect or hurt a run (issue 54, items 1 and 3). Every check
here failed on the code before the fix.

1. Links: a symbolic link in the output folder named like any file a run writes (every result,
   its temporary NAME.tmp, the lock test Open MPI makes beside an HDF5 temporary, .lock,
   run.id, the next snapshot and checkpoint numbers) never has its target created, written or
   truncated: on 1 and 2 ranks, for an FSI case with probes (coupling.csv, probes.csv) and a
   gas case with an obstacle's surface output and grid fields (obstacles.csv,
   surface_NAME.csv, grid.xmf); a fresh run without output.overwrite is refused (exit 2, one
   line "... is a symbolic link; mpmfsi does not write through links: remove it"), and so is
   `check`; with output.overwrite the links themselves are deleted and the run writes regular
   files; a restart in place is refused, or with output.overwrite runs, alike.
2. System folders: output.dir naming the root or a system folder (also through "..") or a
   folder inside one that belongs to root is refused by check and run (exit 2, one line naming
   case.ini, the line and output.dir); /var/tmp/x and /tmp/x are allowed.
3. Long paths: an output.dir of 213 characters (the limit) runs on 2 ranks with a checkpoint;
   214 is refused by check and run naming the limit (before, 221 and more aborted inside Open
   MPI after check accepted them)."""
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_output_links")
QUIET = ["run.progress=false"]
SHORT = ["time.t_end=0.002", "output.interval=0.001", "output.checkpoint_interval=0.001"] + QUIET
CASES = {
    "fsi_piston.ini": [],
    "wedge.ini": ["obstacle.wedge.surface_interval=0.001", "output.grid_fields=true"],
}
MAX_DIR = 213
PRECIOUS = b"precious: never to be written by mpmfsi\n"


def errors(p):
    return [l for l in p.stderr.splitlines() if l.startswith("error:")]


def link_names(ref):
    """Every name a run of the case writes in its folder (from a reference run), with the
    temporaries, Open MPI's lock tests and the next snapshot and checkpoint numbers."""
    names = set(os.listdir(ref)) | {".lock", "run.id", "run.log"}
    names |= {"snap_000003.h5", "snap_000004.h5", "checkpoint_000002.h5",
              "checkpoint_000003.h5"}
    for n in list(names):
        if n != ".lock":
            names.add(n + ".tmp")
        if n.endswith(".h5"):
            names |= {n + ".tmp.locktest.0", n + ".tmp.locktest.1"}
    return sorted(names)


def plant(out, names, victims, replace=False):
    """A link out/NAME -> victims/NAME for every name: every other target exists (PRECIOUS,
    to catch a write or a truncation), the rest do not (to catch a creation). With replace,
    an existing entry of that name is replaced by the link."""
    os.makedirs(out, exist_ok=True)
    os.makedirs(victims, exist_ok=True)
    for k, n in enumerate(names):
        target, path = os.path.join(os.path.abspath(victims), n), os.path.join(out, n)
        if k % 2 == 0:
            with open(target, "wb") as f:
                f.write(PRECIOUS)
        if os.path.lexists(path):
            if not replace:
                continue
            os.remove(path)
        os.symlink(target, path)


def untouched(victims, names):
    """The victims folder holds exactly the PRECIOUS files it was given, unchanged."""
    want = {n for k, n in enumerate(names) if k % 2 == 0}
    have = set(os.listdir(victims))
    same = all(open(os.path.join(victims, n), "rb").read() == PRECIOUS for n in want & have)
    return have == want and same, sorted(have ^ want)[:4]


def links_left(out):
    return [n for n in os.listdir(out) if os.path.islink(os.path.join(out, n))]


def link_refused(p):
    e = errors(p)
    return (p.returncode == 2 and len(e) == 1 and "is a symbolic link" in e[0]
            and "does not write through links: remove it" in e[0])


# ---- 1. links --------------------------------------------------------------------------------
for name, extra in CASES.items():
    ini = mt.case(name)
    ref = mt.outdir("ref_" + name[:-4])
    mt.run(["run", ini, f"output.dir={ref}"] + SHORT + extra)
    names = link_names(ref)
    for ranks in (1, 2):
        tag = f"{name} on {ranks} rank{'s' if ranks > 1 else ''}"
        # check and a fresh run without overwrite: refused, nothing touched
        out, vic = mt.outdir("fresh"), mt.outdir("victims")
        plant(out, names, vic)
        if ranks == 1:
            p = mt.run(["check", ini, f"output.dir={out}"] + SHORT + extra, check=False)
            check(link_refused(p), f"{tag}: check with links in the folder is refused: exit "
                  f"{p.returncode}: {(errors(p) or [p.stderr[-200:]])[0]}")
        p = mt.run(["run", ini, f"output.dir={out}"] + SHORT + extra, ranks=ranks, check=False)
        ok, diff = untouched(vic, names)
        check(link_refused(p) and ok, f"{tag}: a fresh run into links is refused, no target "
              f"touched: exit {p.returncode}, differences {diff}: "
              f"{(errors(p) or [p.stderr[-200:]])[0]}")
        # with overwrite: the links go, the run writes regular files
        p = mt.run(["run", ini, f"output.dir={out}", "output.overwrite=true"] + SHORT + extra,
                   ranks=ranks, check=False)
        ok, diff = untouched(vic, names)
        check(p.returncode == 0 and ok and not links_left(out)
              and os.path.isfile(os.path.join(out, "checkpoint_final.h5")),
              f"{tag}: output.overwrite deletes the links, not their targets: exit "
              f"{p.returncode}, differences {diff}, links left {links_left(out)[:3]}")
        # restart in place, with links where the restart writes
        for overwrite in (False, True):
            vic2 = mt.outdir("victims")
            plant(out, [n for n in names if not n.startswith("checkpoint_final")], vic2,
                  replace=True)
            args = ["restart", os.path.join(out, "checkpoint_final.h5"), "time.t_end=0.004"]
            args += QUIET + (["output.overwrite=true"] if overwrite else [])
            p = mt.run(args, ranks=ranks, check=False)
            ok, diff = untouched(vic2, [n for n in names if not n.startswith("checkpoint_final")])
            want = p.returncode == 0 and not links_left(out) if overwrite else link_refused(p)
            check(want and ok, f"{tag}: restart in place into links"
                  f"{' with overwrite' if overwrite else ''}: exit {p.returncode}, no target "
                  f"touched ({diff}): {(errors(p) or [''])[0]}")
        shutil.rmtree(out)

# ---- 2. system folders -----------------------------------------------------------------------
BASE = open(mt.case("ballistic2d.ini")).read()
DIR_LINE = next(k for k, l in enumerate(BASE.splitlines(), 1) if l.startswith("dir ="))


def with_dir(d):
    lines = BASE.splitlines()
    lines[DIR_LINE - 1] = f"dir = {d}"
    return "\n".join(lines) + "\n"


def check_dir(d, ranks=1, cmd="check", extra=()):
    tmp = tempfile.mkdtemp(prefix="sysdir_", dir=".")
    path = os.path.join(tmp, "case.ini")
    with open(path, "w") as f:
        f.write(with_dir(d))
    p = mt.run([cmd, path, "time.t_end=0.002", "output.interval=0.001"] + QUIET + list(extra),
               ranks=ranks, check=False)
    shutil.rmtree(tmp)
    return p


# Both are given an error found only after output.dir is read, so that code without the check
# (the old one) fails this test with that error instead of writing into the system folder.
LATER_ERROR = ["solid.block.geometry=nosuch"]
for d in ["/", "/usr/../", "//", "/etc", "/usr", "/var", "/lib", "/usr/share/mpmfsi-test",
          "/var/lib/mpmfsi-test", "/etc/../bin"]:
    for cmd in ("check", "run") if d in ("/", "/usr/../", "/usr/share/mpmfsi-test") else ("check",):
        p = check_dir(d, cmd=cmd, extra=LATER_ERROR)
        e = errors(p)
        ok = (p.returncode == 2 and len(e) == 1 and f"case.ini:{DIR_LINE}" in e[0]
              and "output.dir" in e[0] and "does not write there" in e[0]
              and ("system folder" in e[0] or "root folder" in e[0]))
        check(ok and not os.path.exists("/usr/share/mpmfsi-test")
              and not os.path.exists("/var/lib/mpmfsi-test"),
              f"{cmd} refuses output.dir = {d}: exit {p.returncode}: {(e or [p.stderr[-200:]])[0]}")
for d in [tempfile.mkdtemp(prefix="mpmfsi_links_", dir="/var/tmp") + "/x",
          tempfile.mkdtemp(prefix="mpmfsi_links_", dir="/tmp") + "/x"]:
    p = check_dir(d)
    check(p.returncode == 0, f"check accepts output.dir = {d}: exit {p.returncode} "
          f"{(errors(p) or [''])[0]}")
    shutil.rmtree(os.path.dirname(d))

# ---- 3. long paths ---------------------------------------------------------------------------
top = os.path.abspath(mt.outdir("long"))


def long_dir(n):
    """An absolute folder path of exactly n characters under top (components <= 100)."""
    d = top
    while len(d) + 101 < n:
        d += "/" + "d" * 100
    return d + "/" + "e" * (n - len(d) - 1)


for n in (MAX_DIR,):
    d = long_dir(n)
    p = check_dir(d)
    q = check_dir(d, ranks=2, cmd="run")
    check(p.returncode == 0 and q.returncode == 0
          and os.path.isfile(os.path.join(d, "checkpoint_final.h5")),
          f"output.dir of {n} characters: check exit {p.returncode}, run on 2 ranks exit "
          f"{q.returncode} {(errors(p) + errors(q) + [q.stderr[-300:]])[0]}")
for n in (MAX_DIR + 1, 221, 300):
    d = long_dir(n)
    for cmd in ("check", "run") if n < 300 else ("check",):
        p = check_dir(d, cmd=cmd)
        e = errors(p)
        ok = (p.returncode == 2 and len(e) == 1 and "output.dir" in e[0]
              and f"at most {MAX_DIR}" in e[0] and not os.path.exists(d))
        check(ok, f"{cmd} refuses an output.dir of {n} characters naming the limit: exit "
              f"{p.returncode}: {(e or [p.stderr[-300:]])[0]}")
shutil.rmtree(top)

sys.exit(check.finish())

"""Checkpoint integrity: a restart either continues exactly the run that wrote the checkpoint
or refuses the file as bad input (exit 2, one line naming the file and what is wrong).

1. Bit-flip fuzz. Small checkpoints of a solid (cases/axial_bar.ini) and of gas with a solid
   (cases/fsi_box.ini, coarse and short) are restarted unmodified for a reference; then
   copies with 1-4 random bits flipped (fixed seed, positions uniform over the file) are
   restarted. Each must end with exit 0 or 2 (never a signal, an abort or a hang), without
   HDF5's error trace, and every exit-0 restart must have produced exactly the reference
   state (its final checkpoint's particle data, time and step, bit for bit): a flip that
   went unnoticed is harmless only where it changed nothing the run reads.
2. Targeted edits, written with h5py. HDF5 recomputes the checksums of what it rewrites (the
   object header of an edited attribute, the Fletcher32 sum of an edited chunk), and the test
   verifies that h5py reads the edited file back without a checksum error: these cases get
   past the checksums and prove the validation after them (t = NaN, a negative step or
   h_next, a negative mass, a non-positive gas energy, a body index out of range or not an
   integer, a duplicate id on one rank and across two ranks).
3. Raw byte edits (no checksum recomputed) in a data chunk and in the stored case text prove
   the checksums themselves and name them in the message: Fletcher32 for the data, and for the
   case text HDF5's own metadata checksum (checkpoints store their strings as fixed-length
   attributes in the checksummed object header; the variable-length strings of older
   checkpoints sat in the unchecksummed global heap, where one fuzzed copy crashed HDF5's read,
   and only the text hash caught an edit).
4. A full disk (a 1 MiB tmpfs; skipped, with the reason, where mounting is not allowed): a
   restart that cannot write its outputs fails with one line naming the file and the full
   file system, no HDF5 trace, and the checkpoint it would have replaced is left intact.

`python3 test_checkpoint_integrity.py [N]` runs N fuzz copies in all (default 240)."""
import concurrent.futures
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

COMMON = ["run.progress=false"]
# name, case, overrides of the writing run, the restart's t_end, share of the fuzz copies
CASES = [
    ("axial_bar", "axial_bar.ini", ["time.t_end=0.3"], "time.t_end=0.4", 0.5),
    ("fsi_box", "fsi_box.ini", ["grid.dx=0.0625", "time.t_end=0.01"], "time.t_end=0.015", 0.5),
]
TIMEOUT = 60


def env():
    e = dict(os.environ)
    e.setdefault("OMPI_MCA_btl_vader_single_copy_mechanism", "none")
    return e


def restart(ck, out, tend, ranks=1, snapshots=False):
    """Restart from ck into out; (returncode or 'timeout', stdout + stderr)."""
    cmd = [mt.BIN, "restart", ck, f"output.dir={out}", tend,
           f"output.snapshots={'true' if snapshots else 'false'}"] + COMMON
    if ranks > 1:
        cmd = [mt.MPIEXEC, "-n", str(ranks)] + cmd
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=env())
    except subprocess.TimeoutExpired:
        return "timeout", ""
    return p.returncode, p.stdout + p.stderr


def state(path):
    """What a restart continues from, as bytes: every phase's ids, data and counts, and the
    root's t and step."""
    with h5py.File(path, "r") as f:
        parts = [np.float64(f.attrs["t"]).tobytes(), np.float64(f.attrs["step"]).tobytes()]
        for name in sorted(f):
            g = f[name]
            parts += [name.encode()] + [g[d][()].tobytes() for d in ("id", "data", "counts")]
    return b"".join(parts)


def error_lines(text):
    return [l for l in text.splitlines() if "error:" in l]


def kind_of(line):
    """Which defence refused a damaged copy, from its message."""
    if "text_hash" in line:
        return "hash of the stored strings (text_hash)"
    if "checksum mismatch in its data" in line:
        return "Fletcher32 checksum of a dataset chunk"
    if "checksum mismatch" in line:
        return "HDF5 metadata checksum (superblock, object header, chunk index)"
    if "not an HDF5 file" in line:
        return "HDF5 signature"
    if "cannot open it" in line:
        return "HDF5 cannot open the file"
    return "other: " + line.split(" is damaged: ")[-1][:70]


def flip(data, rng):
    """A copy of data with 1-4 bits flipped at uniform positions."""
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        pos = rng.randrange(len(b) * 8)
        b[pos // 8] ^= 1 << (pos % 8)
    return bytes(b)


def write_checkpoint(check, tmp, name, case, args, ranks=1):
    out = os.path.join(tmp, f"{name}_np{ranks}")
    cmd = ["run", mt.case(case), f"output.dir={out}", "output.snapshots=false"] + COMMON + args
    mt.run(cmd, ranks)
    ck = os.path.join(out, "checkpoint_final.h5")
    check(os.path.exists(ck), f"{name}: checkpoint written on {ranks} rank(s) "
          f"({os.path.getsize(ck)} bytes)")
    return ck


def fuzz(check, tmp, total, seed=20240611):
    rng = random.Random(seed)
    counts = {"detected": 0, "harmless": 0, "bad": 0}
    kinds = {}
    t0 = time.time()
    for name, case, args, tend, share in CASES:
        ck = write_checkpoint(check, tmp, name, case, args)
        rc, text = restart(ck, os.path.join(tmp, f"{name}_ref"), tend)
        check(rc == 0, f"{name}: the unmodified checkpoint restarts (exit {rc})")
        ref = state(os.path.join(tmp, f"{name}_ref", "checkpoint_final.h5"))
        with open(ck, "rb") as f:
            orig = f.read()
        n = int(round(total * share))
        jobs = []
        for k in range(n):
            path = os.path.join(tmp, f"{name}_flip{k:04d}.h5")
            with open(path, "wb") as f:
                f.write(flip(orig, rng))
            jobs.append((k, path, os.path.join(tmp, f"{name}_flip{k:04d}_out")))

        def one(job):
            k, path, out = job
            rc, text = restart(path, out, tend)
            if rc == "timeout":
                # Once more before calling it a hang: on 2026-11-29 CI's sanitizer pass had two
                # copies, run together, time out at 60 s beside a 2-rank job, where each is
                # refused in 0.5 s alone. A hang times out again; the retry is printed.
                print(f"     {name} copy {k}: timed out after {TIMEOUT} s, run again", flush=True)
                shutil.rmtree(out, ignore_errors=True)
                rc, text = restart(path, out, tend)
            verdict, why = "bad", ""
            if rc == 2:
                lines = error_lines(text)
                ok = len(lines) == 1 and "HDF5-DIAG" not in text and path in lines[0]
                verdict, why = ("detected", lines[0]) if ok else ("bad", "exit 2 but: " + text[-600:])
            elif rc == 0:
                final = os.path.join(out, "checkpoint_final.h5")
                same = os.path.exists(final) and state(final) == ref
                verdict, why = ("harmless", "") if same else ("bad", "exit 0 with a changed state")
            else:
                why = f"exit {rc}: {text[-600:]}"
            shutil.rmtree(out, ignore_errors=True)
            if verdict != "bad":
                os.remove(path)
            return k, verdict, why

        with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
            for k, verdict, why in pool.map(one, jobs):
                counts[verdict] += 1
                if verdict == "bad":
                    print(f"FAIL {name} copy {k} (kept as {jobs[k][1]}): {why}")
                elif verdict == "detected":
                    key = kind_of(why)
                    kinds[key] = kinds.get(key, 0) + 1
    n = sum(counts.values())
    print(f"fuzz: {n} copies with 1-4 flipped bits: {counts['detected']} refused (exit 2), "
          f"{counts['harmless']} harmless (exit 0, state bit for bit the reference), "
          f"{counts['bad']} wrong; {time.time() - t0:.1f} s")
    for key, c in sorted(kinds.items(), key=lambda kv: -kv[1])[:8]:
        print(f"     {c:4d} x {key}")
    # n == total: every copy was judged (the issue asks for >= 200; the plain build runs 240,
    # the sanitizer build 48, see checkpoint.cmake).
    check(counts["bad"] == 0 and n == total and n > 0,
          f"fuzz: no crash, hang or undetected change in {n} damaged copies")


def field_offset(g, field):
    names = g.attrs["field_names"]
    names = names.decode() if isinstance(names, bytes) else names
    ncomp = list(g.attrs["field_ncomp"])
    k = names.split(",").index(field)
    return int(sum(ncomp[:k]))


def expect_refused(check, label, ck, tend, words, ranks=1):
    rc, text = restart(ck, ck + "_out", tend, ranks)
    lines = error_lines(text)
    ok = (rc == 2 and len(lines) == 1 and all(w in lines[0] for w in words)
          and "HDF5-DIAG" not in text and "checksum" not in lines[0])
    check(ok, f"{label}: exit {rc}: {lines[0] if lines else text[-400:]}")


def edited(tmp, ck, label, edit):
    """A copy of ck edited through h5py (checksums recomputed), and a check that h5py reads
    every dataset of it back (Fletcher32 verified) and its attributes."""
    path = os.path.join(tmp, label + ".h5")
    shutil.copy(ck, path)
    with h5py.File(path, "r+") as f:
        edit(f)
    with h5py.File(path, "r") as f:
        for g in f.values():
            for d in g.values():
                d[()]
        dict(f.attrs)
    return path


def set_value(dset, comp, i, value):
    a = dset[()]
    a[comp, i] = value
    dset[...] = a


def targeted(check, tmp):
    ck = write_checkpoint(check, tmp, "edit_bar", "axial_bar.ini", ["time.t_end=0.3"])
    tend = "time.t_end=0.4"
    cases = [
        ("t = NaN", lambda f: f.attrs.modify("t", np.nan), ["'t'", "not a finite"]),
        ("step = -3", lambda f: f.attrs.modify("step", -3.0), ["step count"]),
        ("h_next = -1e-3", lambda f: f.attrs.modify("h_next", -1e-3), ["h_next"]),
        ("negative mass",
         lambda f: set_value(f["solid/data"], field_offset(f["solid"], "m"), 3, -2.0),
         ["m[0] = -2", "must be"]),
        ("mass NaN in x",
         lambda f: set_value(f["solid/data"], 0, 7, np.nan), ["x[0] = nan"]),
        ("body index 7 of 1 body",
         lambda f: set_value(f["solid/data"], field_offset(f["solid"], "body"), 5, 7.0),
         ["body[0] = 7", "[0, 0]"]),
        ("body index 0.5",
         lambda f: set_value(f["solid/data"], field_offset(f["solid"], "body"), 5, 0.5),
         ["body[0] = 0.5", "integer"]),
        ("duplicate id", lambda f: f["solid/id"].__setitem__(9, f["solid/id"][10]),
         ["held twice"]),
        ("negative id", lambda f: f["solid/id"].__setitem__(9, -5), ["id -5 is negative"]),
    ]
    for label, edit, words in cases:
        path = edited(tmp, ck, label.replace(" ", "_"), edit)
        expect_refused(check, f"edited with h5py, checksums valid: {label}", path, tend, words)

    gas = write_checkpoint(check, tmp, "edit_fsi", "fsi_box.ini", CASES[1][2])
    path = edited(tmp, gas, "gas_energy", lambda f: set_value(
        f["fluid/data"], field_offset(f["fluid"], "e"), 4, 0.0))
    expect_refused(check, "edited with h5py: gas internal energy 0", path, CASES[1][3],
                   ["phase 'fluid'", "e[0] = 0"])

    # Across ranks: rank 1's block gets an id of rank 0's block; restarted on 2 ranks, the
    # distributed check finds it (and on 1 rank too).
    ck2 = write_checkpoint(check, tmp, "edit_bar2", "axial_bar.ini", ["time.t_end=0.3"], ranks=2)

    def cross(f):
        n0 = int(f["solid/counts"][0])
        ids = f["solid/id"][()]
        ids[n0 + 3] = ids[1]
        f["solid/id"][...] = ids
    path = edited(tmp, ck2, "dup_across_ranks", cross)
    for ranks in (2, 1):
        expect_refused(check, f"id duplicated across the writing ranks, restart on {ranks}",
                       path, tend, ["held twice"], ranks)

    # Raw edits: no checksum is recomputed, so these prove the checksums.
    with h5py.File(ck, "r") as f:
        info = f["solid/data"].id.get_chunk_info(0)
    with open(ck, "rb") as f:
        raw = bytearray(f.read())
    b = bytearray(raw)
    b[info.byte_offset + 100] ^= 0x10
    path = os.path.join(tmp, "raw_chunk.h5")
    with open(path, "wb") as f:
        f.write(b)
    rc, text = restart(path, path + "_out", tend)
    lines = error_lines(text)
    check(rc == 2 and len(lines) == 1 and "checksum mismatch in its data" in lines[0]
          and "/solid/data" in lines[0] and "HDF5-DIAG" not in text,
          f"one flipped bit in a data chunk: exit {rc}: {lines[0] if lines else text[-400:]}")
    b = bytearray(raw)
    k = bytes(raw).find(b"name = axial_bar")
    b[k + 7] ^= 0x01
    path = os.path.join(tmp, "raw_config.h5")
    with open(path, "wb") as f:
        f.write(b)
    rc, text = restart(path, path + "_out", tend)
    lines = error_lines(text)
    check(rc == 2 and len(lines) == 1 and "case text" in lines[0]
          and "checksum mismatch" in lines[0] and "HDF5-DIAG" not in text,
          f"one flipped bit in the stored case text: exit {rc}: "
          f"{lines[0] if lines else text[-400:]}")


def full_disk(check, tmp):
    mnt = os.path.join(tmp, "fulldisk")
    os.makedirs(mnt)
    m = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", mnt],
                       capture_output=True, text=True)
    if m.returncode != 0:
        print(f"skip full disk: cannot mount a small tmpfs here ({(m.stderr or m.stdout).strip()})")
        return
    try:
        # Without snapshots the checkpoint write fails; with them, a snapshot's. Each in a
        # folder of its own (a failed run still records how far it got in its folder).
        for snapshots, kind in ((False, "checkpoint"), (True, "snapshot")):
            out = os.path.join(mnt, kind)
            filler = os.path.join(mnt, "filler")
            if os.path.exists(filler):
                os.remove(filler)
            mt.run(["run", mt.case("axial_bar.ini"), f"output.dir={out}", "time.t_end=0.3",
                    "output.snapshots=false"] + COMMON)
            ck = os.path.join(out, "checkpoint_final.h5")
            with open(ck, "rb") as f:
                before = f.read()
            # Fill the file system but for 6 pages: room for the small text files a run
            # keeps (run.id, the CSV files, series.xmf), none for a snapshot or checkpoint
            # (27 kB and more), so that the HDF5 write is what fails.
            st = os.statvfs(mnt)
            with open(filler, "wb") as f:
                f.write(b"\0" * max(st.f_bavail * st.f_frsize - 6 * 4096, 0))
            rc, text = restart(ck, out, "time.t_end=0.4", snapshots=snapshots)
            lines = error_lines(text)
            with open(ck, "rb") as f:
                after = f.read()
            print(f"     full disk, {kind}: exit {rc}; {len(lines)} error line(s): "
                  f"{lines[0] if lines else text[-300:]}")
            check(rc not in (0, "timeout") and len(lines) == 1 and ".h5.tmp" in lines[0]
                  and f"cannot write the {kind}" in lines[0]
                  and "file system is full" in lines[0] and "HDF5-DIAG" not in text,
                  f"full disk: the {kind} write fails with one line naming the file and the "
                  "full file system")
            check(after == before,
                  f"full disk ({kind}): the checkpoint a failed write would have replaced is intact")
    finally:
        subprocess.run(["umount", mnt])


def main():
    total = int(sys.argv[1]) if len(sys.argv) > 1 else 240
    check = mt.Checks("checkpoint integrity")
    tmp = tempfile.mkdtemp(prefix="ckint_", dir=".")
    t0 = time.time()
    targeted(check, tmp)
    print(f"     targeted: {time.time() - t0:.1f} s")
    full_disk(check, tmp)
    fuzz(check, tmp, total)
    status = check.finish()
    if status == 0:
        shutil.rmtree(tmp, ignore_errors=True)
    return status


if __name__ == "__main__":
    sys.exit(main())

"""Every C source and header of the project is formatted as the root .clang-format says: the
check a reviewer runs (`clang-format --dry-run --Werror`), so a formatting slip fails here
rather than in review. The files are git's tracked ones when the source is a checkout, every
*.c and *.h under the modules, app/ and tests/ otherwise (a source tarball)."""
import glob
import os
import shutil
import subprocess
import sys

SOURCE = os.environ.get("MPMFSI_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
FOLDERS = ("common", "fluid", "solid", "coupler", "app", "tests")


def c_files():
    try:
        out = subprocess.run(["git", "-C", SOURCE, "ls-files", "*.c", "*.h"], capture_output=True,
                             text=True, check=True).stdout.split()
        if out:
            return [os.path.join(SOURCE, f) for f in out]
    except (OSError, subprocess.CalledProcessError):
        pass
    return sorted(f for d in FOLDERS for ext in ("c", "h")
                  for f in glob.glob(os.path.join(SOURCE, d, "**", "*." + ext), recursive=True))


def main():
    tool = shutil.which("clang-format")
    if not tool:
        sys.exit("test_format: clang-format not found; install Debian's clang-format package "
                 "(tools/run_tests.sh does)")
    files = c_files()
    if len(files) < 50:
        sys.exit(f"test_format: found only {len(files)} C files under {SOURCE}: wrong source dir?")
    bad = []
    for k in range(0, len(files), 64):
        p = subprocess.run([tool, "--dry-run", "--Werror", f"--style=file"] + files[k:k + 64],
                           capture_output=True, text=True, cwd=SOURCE)
        if p.returncode != 0:
            bad += sorted({line.split(":")[0] for line in p.stderr.splitlines()
                           if ": error:" in line})
    if bad:
        print("\n".join(os.path.relpath(f, SOURCE) for f in bad))
        sys.exit(f"test_format: {len(bad)} file(s) differ from .clang-format; run "
                 f"`clang-format -i FILE` on each")
    print(f"test_format: {len(files)} C files formatted as .clang-format says")


main()

"""Every case file in cases/ passes `mpmfsi check`: it parses, validates, builds its grid and
seeds its solid bodies or gas regions. Keeps the shipped cases in step with the schema."""
import glob
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_cases")
for path in sorted(glob.glob(os.path.join(mt.SOURCE, "cases", "*.ini"))):
    p = mt.run(["check", path], check=False)
    check(p.returncode == 0 and ("[solid." in p.stdout or "[gas." in p.stdout),
          f"{os.path.basename(path)}: exit {p.returncode} {p.stderr.strip()[:200]}")
sys.exit(check.finish())

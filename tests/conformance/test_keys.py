"""docs/keys.md is the output of `mpmfsi keys --markdown`, so the key reference cannot drift
from the schema that `mpmfsi check` validates against.

1. `mpmfsi keys --markdown` equals docs/keys.md in the source tree; on a difference the first
   differing lines and the command that regenerates the file are printed.
2. Every key `mpmfsi keys` lists is in docs/keys.md, and every key of docs/keys.md is listed,
   each missing key named.
3. The comparison itself: a copy of the reference with one row dropped is reported as missing
   that key, so a checker that passes everything fails here.
"""
import difflib
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_keys")
DOC = os.path.join(os.path.realpath(mt.SOURCE), "docs", "keys.md")
REGENERATE = f"{mt.BIN} keys --markdown > {DOC}"


def mpmfsi(*args):
    p = subprocess.run([mt.BIN, *args], capture_output=True, text=True, timeout=120)
    check(p.returncode == 0, f"`mpmfsi {' '.join(args)}` exits 0 ({p.returncode}: {p.stderr.strip()[:300]})")
    return p.stdout


def listed_keys(text):
    """Keys of the terminal listing: the lines that start with a key ("grid.dx = ...")."""
    return [ln.split(" = ")[0] for ln in text.splitlines() if ln and ln[0] not in " ["]


def table_keys(markdown):
    """Keys of the Markdown tables: the first cell of each row, `key`."""
    return re.findall(r"^\| `([^`]+)` \|", markdown, re.M)


def missing(a, b):
    """Keys of a not in b, in a's order."""
    bs = set(b)
    return [k for k in a if k not in bs]


generated = mpmfsi("keys", "--markdown")
try:
    with open(DOC) as f:
        doc = f.read()
except OSError as e:
    doc = ""
    print(f"cannot read {DOC}: {e}")

# 1. the same text
same = generated == doc
if not same:
    diff = list(difflib.unified_diff(doc.splitlines(), generated.splitlines(), "docs/keys.md",
                                     "mpmfsi keys --markdown", lineterm="", n=1))
    print("\n".join(diff[:40]) + ("\n..." if len(diff) > 40 else ""))
check(same, "docs/keys.md is `mpmfsi keys --markdown`" +
      ("" if same else f"; regenerate it with:\n    {REGENERATE}"))

# 2. the same keys, named
keys = listed_keys(mpmfsi("keys"))
rows = table_keys(doc)
check(len(keys) > 100, f"mpmfsi keys lists {len(keys)} keys")
gone = missing(keys, rows)
check(not gone, f"every key of `mpmfsi keys` is in docs/keys.md (missing: {', '.join(gone) or 'none'})")
extra = missing(rows, keys)
check(not extra, f"every key of docs/keys.md is a key of the program (not one: {', '.join(extra) or 'none'})")
check(table_keys(generated) == keys, "the Markdown lists the same keys, in the same order, as the terminal listing")

# 3. the checker finds a dropped row
row = next((ln for ln in generated.splitlines() if ln.startswith("| `grid.dx` |")), "")
check(row != "" and missing(keys, table_keys(generated.replace(row + "\n", ""))) == ["grid.dx"],
      "a reference without the grid.dx row is reported as missing grid.dx")

sys.exit(check.finish())

"""The documentation a newcomer meets: README.md and the user guide under docs/.

1. README.md is short (at most 220 lines) and gives the two commands, `bash tools/run_main.sh`
   and `bash tools/run_tests.sh`, within its first 40 lines; .ci/run calls exactly that test
   command (CI runs what the README tells users to run).
2. Every relative link and image in README.md, docs/*.md, CHANGELOG.md and bench/results/*.md
   resolves: the file (or folder) exists, and an #anchor names a heading of the target
   (GitHub's slug rules: the heading's text lowercased, punctuation dropped, spaces to '-', a
   repeated heading gets -1, -2, ...) or an explicit <a name/id>. An anchor into a file that is
   not Markdown must be a line anchor (#L12, #L12-L20). Links that leave the repository
   (http, https, mailto) are not fetched; links from the site root (/path) are refused:
   they break on forks and in clones, and the plan asks for relative links only.
   Each failure names file:line and the link.
3. The checker itself: the slugs of a few headings of the kind the pages use, and a made-up
   page with a good link, a missing file, a missing anchor and a link inside a code span
   (ignored), so that a checker that passes everything fails here.
Reads the files under $MPMFSI_SOURCE_DIR; runs nothing else.
"""
import glob
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_docs")
SRC = os.path.realpath(mt.SOURCE)

FENCE = re.compile(r"^\s{0,3}(`{3,}|~{3,})")
ATX = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
SETEXT = re.compile(r"^\s{0,3}(=+|-+)\s*$")
# Inline links and images: [text](target "title") / ![alt](<target>); the text may hold one
# level of brackets (an image inside a link).
INLINE = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>]*>|[^)\s]*)(?:\s+\"[^\"]*\")?\s*\)")
REFDEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
HTML = re.compile(r"<(?:a|img)\b[^>]*?\b(?:href|src)\s*=\s*[\"']([^\"']*)[\"']", re.I)
HTML_ANCHOR = re.compile(r"<a\b[^>]*?\b(?:name|id)\s*=\s*[\"']([^\"']*)[\"']", re.I)
CODE_SPAN = re.compile(r"(`+)(.+?)\1")


def slug(text):
    """GitHub's heading anchor: the rendered text, lowercased, anything but letters, digits,
    '_', '-' and spaces dropped, each space a '-'."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)  # HTML tags
    text = text.replace("`", "")
    text = re.sub(r"(\*\*|__|\*)(.+?)\1", r"\2", text)  # emphasis markers
    text = re.sub(r"[^\w\- ]", "", text.strip().lower())
    return text.replace(" ", "-")


def prose_lines(text):
    """(line number, line) outside fenced code blocks."""
    fence = None
    for n, line in enumerate(text.split("\n"), 1):
        m = FENCE.match(line)
        if m:
            mark = m.group(1)
            if fence is None:
                fence = mark[0]
            elif mark[0] == fence:
                fence = None
            continue
        if fence is None:
            yield n, line


def anchors(path, cache={}):
    """Every anchor a Markdown file defines (heading slugs with GitHub's -N suffixes for
    repeats, and explicit <a name/id>)."""
    if path in cache:
        return cache[path]
    seen, found = {}, set()
    lines = list(prose_lines(open(path, encoding="utf-8").read()))
    for k, (n, line) in enumerate(lines):
        heading = None
        m = ATX.match(line)
        if m:
            heading = m.group(2)
        elif k + 1 < len(lines) and lines[k + 1][0] == n + 1 and SETEXT.match(lines[k + 1][1]) \
                and line.strip() and not line.lstrip().startswith(("-", "*", ">", "|")):
            heading = line.strip()
        if heading is not None:
            s = slug(heading)
            found.add(s if s not in seen else f"{s}-{seen[s]}")
            seen[s] = seen.get(s, 0) + 1
        for a in HTML_ANCHOR.findall(line):
            found.add(a)
    cache[path] = found
    return found


def links(text):
    """(line number, target) of every link and image outside code."""
    for n, line in prose_lines(text):
        bare = CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line)
        for m in INLINE.finditer(bare):
            yield n, m.group(1)
        m = REFDEF.match(bare)
        if m:
            yield n, m.group(1)
        for t in HTML.findall(bare):
            yield n, t


def broken(path, top):
    """Messages 'file:line: ...' for every link of `path` that does not resolve."""
    out = []
    rel = os.path.relpath(path, top)
    for n, target in links(open(path, encoding="utf-8").read()):
        t = target[1:-1] if target.startswith("<") and target.endswith(">") else target
        where = f"{rel}:{n}: link '{target}'"
        if re.match(r"^[a-z][a-z0-9+.-]*:", t, re.I):
            continue  # http(s), mailto, ...: leaves the repository, not fetched
        if t.startswith("/"):
            out.append(f"{where}: from the site root; make it relative to {rel}")
            continue
        t = t.split("?", 1)[0]
        file, _, anchor = t.partition("#")
        dest = os.path.normpath(os.path.join(os.path.dirname(path), file)) if file else path
        if not os.path.exists(dest):
            out.append(f"{where}: no file {os.path.relpath(dest, top)}")
            continue
        if not os.path.realpath(dest).startswith(top + os.sep) and os.path.realpath(dest) != top:
            out.append(f"{where}: outside the repository")
            continue
        if not anchor:
            continue
        if dest.endswith(".md") and os.path.isfile(dest):
            if anchor not in anchors(dest):
                near = sorted(anchors(dest), key=lambda a: -len(os.path.commonprefix([a, anchor])))
                hint = f" (nearest: #{near[0]})" if near else ""
                out.append(f"{where}: no heading #{anchor} in {os.path.relpath(dest, top)}{hint}")
        elif not re.fullmatch(r"L\d+(-L\d+)?", anchor):
            out.append(f"{where}: #{anchor} in a file that is not Markdown (only #L<n> works)")
    return out


# 3. The checker on known input first: a checker that passes everything must fail here.
for heading, want in [("Runs, restarts and output folders", "runs-restarts-and-output-folders"),
                      ("Temporal coupling (`coupling.time`)", "temporal-coupling-couplingtime"),
                      ("Gas (fluid module)", "gas-fluid-module"),
                      ("Main job: the supersonic elastic bar", "main-job-the-supersonic-elastic-bar"),
                      ("`probes.csv`", "probescsv"), ("[RAE 2822](x.md) at M 0.729", "rae-2822-at-m-0729"),
                      ("What *is* new", "what-is-new"), ("Exit codes & signals", "exit-codes--signals")]:
    check(slug(heading) == want, f"slug({heading!r}) = {slug(heading)!r} (GitHub: {want!r})")
with tempfile.TemporaryDirectory() as tmp:
    tmp = os.path.realpath(tmp)
    with open(os.path.join(tmp, "b.md"), "w") as f:
        f.write("# Top\n\n## Twice\n\n## Twice\n\nSetext heading\n---\n")
    with open(os.path.join(tmp, "a.md"), "w") as f:
        f.write("[ok](b.md#twice-1) [ok](b.md#setext-heading) ![ok](b.md) [ok](#here)\n"
                "# Here\n`[code](nowhere.md)`\n```\n[fenced](nowhere.md)\n```\n"
                "[gone](missing.md)\n[bad](b.md#twice-2)\n[root](/b.md)\n<img src=\"none.png\">\n")
    got = broken(os.path.join(tmp, "a.md"), tmp)
    want = ["a.md:7: link 'missing.md'", "a.md:8: link 'b.md#twice-2'", "a.md:9: link '/b.md'",
            "a.md:10: link 'none.png'"]
    check([g.split(": ", 1)[0] + ": " + g.split(": ", 2)[1] for g in got] == want,
          f"the checker on a made-up page reports exactly the 4 broken links: {got}")

# 1. README.md: short, the two commands near the top, and CI runs the README's test command.
readme = os.path.join(SRC, "README.md")
text = open(readme, encoding="utf-8").read().split("\n")
nlines = len(text) - (text[-1] == "")
check(nlines <= 220, f"README.md has {nlines} lines (at most 220: details go to docs/)")
for cmd in ("bash tools/run_main.sh", "bash tools/run_tests.sh"):
    at = [n for n, line in enumerate(text, 1) if cmd in line]
    check(bool(at) and at[0] <= 40,
          f"README.md gives `{cmd}` within its first 40 lines (first at line {at[0] if at else None})")
ci = open(os.path.join(SRC, ".ci", "run"), encoding="utf-8").read().split("\n")
calls = [line.strip() for line in ci if line.strip() and not line.lstrip().startswith("#")
         and "run_tests" in line]
check(calls == ["bash tools/run_tests.sh"],
      f".ci/run calls exactly the README's test command `bash tools/run_tests.sh` (it calls {calls})")

# 2. Links and images in every page.
pages = [readme] + sorted(glob.glob(os.path.join(SRC, "docs", "*.md")))
pages += [p for p in [os.path.join(SRC, "CHANGELOG.md")] if os.path.exists(p)]
pages += sorted(glob.glob(os.path.join(SRC, "bench", "results", "*.md")))
for page in pages:
    bad = broken(page, SRC)
    for msg in bad:
        print("  " + msg)
    nlinks = sum(1 for _ in links(open(page, encoding="utf-8").read()))
    check(not bad, f"{os.path.relpath(page, SRC)}: {nlinks} links, {len(bad)} broken")

sys.exit(check.finish())

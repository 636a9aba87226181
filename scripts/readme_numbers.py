#!/usr/bin/env python3
"""Every measured number in a results README must be a generated number.

Usage: readme_numbers.py RESULTS_FOLDER[:README]...

Issue 34: a results README may only quote numbers that the study's tables
script prints.  This checker reads README.md (or the README after the colon) of each
results folder and every generated file beside it -- tables.md and, where a
tables script writes one, values.md, and the rerun's changes.md (whose numbers, the previous run's
among them, count only in a section headed "What changed ..."); the
tables.md of each sub-study folder one level down (results/avg/speed/, and
for results/ itself each study folder); for results/ also startup.md,
reference_speed.md and regenerate_times.csv (each step's time as `make
results` ran it) -- and prints each measured number of
the README that no generated file holds, with its line, then exits 1.

What counts as a measured number (docs/studies.md, "Numbers in results
READMEs"):
  - a number with a decimal point (0.96, 1.09), a thousands separator
    (1,839) or a power of ten (2.7e-5, 2.7·10⁻⁵), or
  - any number directly followed by a unit: ms, s, µs, min, h, MiB, GiB,
    KiB, MB, GB, KB, %, ×, x (attached, "3.1x"), fps, CPU-s.
Plain integers without a unit (4 bounces, N = 12, 64 VPLs) are settings.
Exempt: headings, code spans and fenced blocks, link targets, HTML
comments, references (§4.2, Fig. 8, Figure 8, Table 1, Eq. 3, Section 4,
issue 28), sizes (64x64, 128²; "2k" has no unit), dates and clock times, versions (GL 4.5,
glTF 2.0), settings written key=value, and numbers quoted from a paper:
inside a parenthesis that starts with "paper" -- "(paper: 6.7 s)" -- or in
a table column whose header says "paper"; numbers no committed file
holds, kept with the way to measure them, inside a parenthesis that starts
with "not in the tables" (the rerun of issue 34 is to move them into the
tables); numbers a README's note of what changed quotes from its earlier
prose, inside a parenthesis that starts with "earlier prose" --
"(earlier prose: 3.4 s)"; and a whole section whose heading says "not in the tables" (side measurements that no
study records), up to the next heading of its level or above.
A README number matches a generated one when both are the same value at
the README's precision (the README may round; a sign written as a word,
"7.9 % darker", matches -7.9; a percentage also matches the same fraction,
1.6 % matching 0.016, and a time in s or ms matches the same time printed
in the other unit).
"""

import csv
import io
import os
import re
import sys

SUP = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")
UNITS = r"(?:ms|s|µs|us|min|h|MiB|GiB|KiB|MB|GB|KB|fps|CPU-s)"
NUM = (r"(?<![\w.,])(?P<num>[-−]?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?)"
       r"(?P<exp>(?:e[-+]?\d+(?!\w))|(?:\s?[·×]\s?10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+))?")
TOKEN = re.compile(NUM + r"(?P<unit>\s?(?:" + UNITS + r"\b|%)|[×x](?![\w]))?(?!\w)(?!\.\d)")

# A quoted number's parenthesis may run over several lines: blanked over
# the whole README before it is read line by line.
QUOTED = re.compile(r"\((?:the |on the |in the )?(?:paper|earlier prose|not in the tables)\b[^)]*\)", re.I)

# Spans removed before numbers are looked for: the reason each is exempt is
# in the module docstring.
EXEMPT = [
    re.compile(r"`[^`]*`"),                                    # code spans
    re.compile(r"\]\([^)]*\)"),                                # link targets
    re.compile(r"<!--.*?-->"),                                 # comments
    re.compile(r"§\s?\d+(?:\.\d+)*"),
    re.compile(r"\b(?:Figs?\.|Figures?|Tables?|Tab\.|Eqs?\.|Equations?|Sections?|Sec\.|[Ii]ssues?|"
               r"PR|step|part|round|Alg\.|Algorithm|Listing|Appendix|line|lines)"
               r"\s?\d+(?:\.\d+)*[a-z]?(?:\s?(?:,|and|–|-|/|&)\s?\d+[a-z]?)*"),
    re.compile(r"\b(?:GL|OpenGL|GLSL|glTF|EGL|C|C\+\+|Python|python|LLVM|Mesa|CMake|Embree|version|v)"
               r"\s?\d+(?:\.\d+)*"),
    re.compile(r"\d+\s?[x×]\s?\d+(?:\s?[x×]\s?\d+)?"),         # sizes 64x64
    re.compile(r"\d+(?:\.\d+)?[²³]"),                          # sizes 128²
    re.compile(r"\b\d{4}-\d{2}-\d{2}\b"),                      # dates
    re.compile(r"\b\d{1,2}:\d{2}(?::\d{2})?\b"),               # clock times
    re.compile(r"[\w.]+\s?=\s?[-−]?[\d.]+(?:e[-+]?\d+)?"),     # key=value
]


def value(num, exp):
    """Parse a token's number and power of ten; returns (value, decimals)."""
    text = num.replace("−", "-").replace(",", "")
    dec = len(text.split(".")[1]) if "." in text else 0
    v = float(text)
    if exp:
        e = exp.translate(SUP).replace(" ", "")
        e = re.sub(r"^[·×]10", "e", e)
        v *= 10.0 ** int(e[1:] if e.startswith("e") else e)
        dec += -int(e[1:] if e.startswith("e") else e)
    return v, dec


# The files a results folder's scripts generate: the tables scripts'
# tables.md and values.md, the rerun's changes.md (scripts/results_changes.py);
# at the top of results/ also the start-up and reference-speed measurements
# (scripts/startup_time.py, scripts/ref-vs-embree.sh) written by
# scripts/regenerate_results.sh.
GENERATED = ("tables.md", "values.md", "changes.md", "startup.md", "reference_speed.md",
             "regenerate_times.csv")


def generated_files(folder):
    """The generated files a folder's README may quote: its own (GENERATED)
    and the tables.md of each folder one level down (a sub-study such as
    results/avg/speed/; for results/ itself, whose README sums the studies
    up, each study's tables)."""
    out = [os.path.join(folder, n) for n in GENERATED]
    if os.path.isdir(folder):
        out += [os.path.join(folder, d, "tables.md") for d in sorted(os.listdir(folder))
                if os.path.isdir(os.path.join(folder, d))]
    return [p for p in out if os.path.isfile(p)]


def generated_values(folder):
    """The numbers in the folder's generated files (generated_files): those
    of every file but changes.md, and those of changes.md (the previous
    run's numbers among them, which only a "What changed" section may
    quote)."""
    vals, change_vals = [], []
    for path in generated_files(folder):
        if not os.path.exists(path):
            continue
        into = change_vals if os.path.basename(path) == "changes.md" else vals
        with open(path, encoding="utf-8") as f:
            text = f.read()
        if path.endswith(".csv"):  # only the measured columns (*_s), not dates or commits
            rows = list(csv.DictReader(io.StringIO(text)))
            text = " ".join(v for r in rows for k, v in r.items() if k and k.endswith("_s") and v)
        for m in TOKEN.finditer(text):
            into.append(abs(value(m.group("num"), m.group("exp"))[0]))
    return vals, change_vals


# Other ways a generated table may print the same value: a percentage as a
# fraction, seconds in milliseconds and back.
SCALES = {"%": [(1, 0), (0.01, -2)], "s": [(1, 0), (1000, 3)], "ms": [(1, 0), (0.001, -3)]}


def matches(v, dec, vals):
    """True when some generated value equals v at the README's precision."""
    half = 0.5 * 10.0 ** (-dec) * (1 + 1e-9)
    return any(abs(g - abs(v)) <= half + 1e-12 * abs(v) for g in vals)


def paper_columns(header):
    """Indices of a markdown table's columns whose header names the paper."""
    cells = header.strip().strip("|").split("|")
    return {i for i, c in enumerate(cells) if re.search(r"paper", c, re.I)}


def strip(line):
    for rx in EXEMPT:
        line = rx.sub(" ", line)
    return line


def measured(line):
    """The measured numbers of one prose or table line."""
    out = []
    for m in TOKEN.finditer(strip(line)):
        num, exp, unit = m.group("num"), m.group("exp"), m.group("unit")
        if "." in num or "," in num or exp or unit:
            v, dec = value(num, exp)
            out.append((m.group(0).strip(), v, dec, (unit or "").strip()))
    return out


def offenders(readme, vals, change_vals=()):
    """(line number, token, line) for each README number not generated. The
    numbers of changes.md (change_vals) count only inside a section whose
    heading starts with "What changed": elsewhere a README quoting the
    previous run would pass on the "before" columns."""
    bad = []
    in_fence, paper_cols, prev, skip_level, changes_level = False, set(), "", 0, 0
    both = list(vals) + list(change_vals)
    with open(readme, encoding="utf-8") as f:
        raw = f.read()
    lines = QUOTED.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), raw).splitlines()
    for no, (line, orig) in enumerate(zip(lines, raw.splitlines()), 1):
        if line.lstrip().startswith("```"):
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        if line.lstrip().startswith("#"):
            level = len(line.lstrip()) - len(line.lstrip().lstrip("#"))
            if skip_level and level <= skip_level:
                skip_level = 0
            if not skip_level and re.search(r"not in the tables", orig, re.I):
                skip_level = level
            if changes_level and level <= changes_level:
                changes_level = 0
            if re.match(r"^\s*#+\s*what changed", orig, re.I):
                changes_level = level
            continue
        if skip_level:
            continue
        text = line
        if line.lstrip().startswith("|"):
            if re.match(r"^\s*\|[\s:|-]+\|\s*$", line):
                paper_cols = paper_columns(prev)
                prev = line
                continue
            if not prev.lstrip().startswith("|"):
                paper_cols = set()
            cells = line.strip().strip("|").split("|")
            text = "|".join(c for i, c in enumerate(cells) if i not in paper_cols)
        prev = line
        pool = both if changes_level else vals
        for tok, v, dec, unit in measured(text):
            if not any(matches(v * k, dec - e, pool) for k, e in SCALES.get(unit, [(1, 0)])):
                bad.append((no, tok, line.strip()))
    return bad


def check(folder, readme):
    """Prints a folder's offenders; returns how many there are (-1: no tables)."""
    if not os.path.isfile(readme):
        print(f"readme_numbers: {readme}: no such file", file=sys.stderr)
        return -1
    vals, change_vals = generated_values(folder)
    if not vals and not change_vals:
        print(f"readme_numbers: {folder}: no generated tables (%s)" % ", ".join(GENERATED), file=sys.stderr)
        return -1
    bad = offenders(readme, vals, change_vals)
    for no, tok, line in bad:
        print(f"{readme}:{no}: {tok} is not in the generated tables: {line[:120]}")
    if bad:
        print(f"readme_numbers: {len(bad)} number(s) in {readme} are not generated", file=sys.stderr)
    else:
        print(f"readme_numbers: every measured number in {readme} is generated")
    return len(bad)


def main(argv):
    """Each argument is a results folder, or FOLDER:README to check another README against it."""
    if len(argv) < 2:
        print("usage: readme_numbers.py RESULTS_FOLDER[:README]...", file=sys.stderr)
        return 2
    worst = 0
    for arg in argv[1:]:
        folder, _, readme = arg.partition(":")
        n = check(folder, readme or os.path.join(folder, "README.md"))
        worst = 2 if n < 0 else max(worst, min(n, 1))
    return worst


if __name__ == "__main__":
    sys.exit(main(sys.argv))

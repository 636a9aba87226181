"""Helpers shared by the scripts that turn a study's runs.csv into
Markdown tables (compare_all_tables.py, stress_tables.py). Stdlib only."""

import csv
import json
import math
import os


def num(x):
    """A finite-or-infinite float from a CSV cell; None when empty or NaN."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if v == v else None


def fmt(v, spec="%.3g", none="–"):
    return none if v is None else spec % v


def scene_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def load_runs_csv(d):
    with open(os.path.join(d, "runs.csv"), newline="") as fh:
        return list(csv.DictReader(fh))


def matrix(w, rows, cols, cell):
    """A Markdown table with a row per item of `rows` and a column per item
    of `cols`; cell(row, col) gives each cell's text. w writes a line."""
    w("| method | " + " | ".join(cols) + " |")
    w("|---|" + "---:|" * len(cols))
    for r in rows:
        w("| %s | %s |" % (r, " | ".join(cell(r, c) for c in cols)))


def load_references(d):
    """run id -> (full-GI reference file name, bounce-matched one), from
    DIR/runs.json; {} when the study has none."""
    try:
        with open(os.path.join(d, "runs.json")) as fh:
            records = json.load(fh)
    except (OSError, ValueError):
        return {}
    out = {}
    for r in records if isinstance(records, list) else []:
        m = r.get("metrics") or {}
        names = tuple(os.path.basename(((m.get(k) or {}).get("reference") or {}).get("path") or "")
                      for k in ("full", "matched"))
        if r.get("run") and names[0]:
            out[r["run"]] = names
    return out


def load_trivial(d):
    """reference file name -> the black image's relMSE against it, from
    DIR/trivial.csv (scripts/trivial_scores.py); {} without one."""
    try:
        with open(os.path.join(d, "trivial.csv"), newline="") as fh:
            return {r["reference"]: num(r["relmse"]) for r in csv.DictReader(fh)}
    except OSError:
        return {}


def report_fronts(d):
    """The path tracer's convergence lines and the equal-error tables of the
    study's report.md (written by gibench study from curves.csv), copied so
    that the README's speed-against-accuracy numbers are generated ones."""
    path = os.path.join(d, "report.md")
    if not os.path.exists(path):
        return []
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    out = ["\n### Speed against accuracy (copied from report.md: the path tracer's convergence, the equal-error "
           "fronts)\n"]
    i = 0
    while i < len(lines):
        ln = lines[i]
        if ln.startswith("Path tracer convergence on "):
            out.append(ln + "\n")
        elif ln.startswith("#### ") and ": equal error" in ln:
            out.append(ln + "\n")
            j = i + 1
            while j < len(lines) and not lines[j].startswith("|"):
                j += 1
            while j < len(lines) and lines[j].startswith("|"):
                out.append(lines[j])
                j += 1
            out.append("")
            i = j
            continue
        i += 1
    return out if len(out) > 1 else []


def fit_exponent(xs, ys):
    """Least-squares slope of log y against log x (y ~ x^slope); None with
    fewer than two usable points."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x and y and x > 0 and y > 0]
    if len(pts) < 2:
        return None
    mx = sum(a for a, _ in pts) / len(pts)
    my = sum(b for _, b in pts) / len(pts)
    sxx = sum((a - mx) ** 2 for a, _ in pts)
    return sum((a - mx) * (b - my) for a, b in pts) / sxx if sxx > 0 else None

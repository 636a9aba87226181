"""Helpers shared by the scripts that turn a study's runs.csv into
Markdown tables (compare_all_tables.py, stress_tables.py). Stdlib only."""

import csv
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

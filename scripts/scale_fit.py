#!/usr/bin/env python3
"""Scale fits: time and memory against triangle count, log-log least squares.

    scripts/scale_fit.py DIR [--y FIELD]... [--where FIELD=VALUE]... [--group FIELD]...
                         [--claim METHOD=EXPONENT]... [--gibench PATH] [--json OUT.json]

DIR is a study's output folder (gibench study --out DIR): the script reads
DIR/runs.json, every run record of the study (a path to a runs.json file is
taken too). Each record carries the triangle count of its scene
(scene_triangles, added by the study); records made before that field
existed get it from `gibench info SCENE --json` when --gibench names the
binary.

For every group of runs (by default: method, its full parameter string,
label and GL renderer, so that the runs of one group differ only in their
scene) and every FIELD (default: frame_ms.median, prepare_ms, peak_rss_mib,
stats.data_bytes; a FIELD is a key or a dotted path of the run record, as in
the study's charts), the runs with status "ok" and a positive value are
reduced to one point per triangle count (the median of its repeats) and
fitted as

    ln y = a + b ln T        (T triangles; y ~ T^b)

by least squares. Printed per fit (markdown): the number of scenes n, the
triangle range, the exponent b with its standard error and 95 % confidence
interval (Student's t with n - 2 degrees of freedom; needs n >= 3), R^2 and,
with --claim METHOD=EXPONENT (a paper's stated complexity, e.g.
--claim avg=1), whether the claim lies in the interval. --json writes the
same as a list of objects. Exit 2 on bad input, 1 when no group has three
scenes.
"""
import argparse
import json
import math
import os
import subprocess
import sys

DEFAULT_FIELDS = ["frame_ms.median", "prepare_ms", "peak_rss_mib", "stats.data_bytes"]
DEFAULT_GROUP = ["method", "params_full", "label", "renderer"]

# two-sided 95 % quantiles of Student's t, by degrees of freedom
T975 = [None, 12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052,
        2.048, 2.045, 2.042]


def t975(df):
    if df < len(T975):
        return T975[df]
    z = 1.959964  # Cornish-Fisher expansion of t about the normal quantile
    return z + (z ** 3 + z) / (4 * df) + (5 * z ** 5 + 16 * z ** 3 + 3 * z) / (96 * df ** 2)


def field(rec, name):
    o = rec
    for k in name.split("."):
        if not isinstance(o, dict) or k not in o:
            return None
        o = o[k]
    return o


def fit(points):
    """Least squares of ln y on ln x; points: [(x, y)] with x, y > 0."""
    u = [math.log(x) for x, _ in points]
    v = [math.log(y) for _, y in points]
    n = len(points)
    mu, mv = sum(u) / n, sum(v) / n
    sxx = sum((a - mu) ** 2 for a in u)
    sxy = sum((a - mu) * (b - mv) for a, b in zip(u, v))
    syy = sum((b - mv) ** 2 for b in v)
    if sxx <= 0:
        return None
    b = sxy / sxx
    a = mv - b * mu
    res = sum((vi - a - b * ui) ** 2 for ui, vi in zip(u, v))
    out = {"n": n, "exponent": b, "intercept": a, "r2": 1 - res / syy if syy > 0 else 1.0}
    if n >= 3:
        se = math.sqrt(res / (n - 2) / sxx)
        h = t975(n - 2) * se
        out.update({"se": se, "ci95": [b - h, b + h]})
    return out


def load(path, gibench):
    p = os.path.join(path, "runs.json") if os.path.isdir(path) else path
    try:
        runs = json.load(open(p))
    except (OSError, ValueError) as e:
        sys.stderr.write(f"scale_fit: {p}: {e}\n")
        sys.exit(2)
    if not isinstance(runs, list):
        sys.stderr.write(f"scale_fit: {p}: not a list of run records\n")
        sys.exit(2)
    cache = {}
    for r in runs:
        if "scene_triangles" not in r and gibench and r.get("scene"):
            s = r["scene"]
            if s not in cache:
                out = subprocess.run([gibench, "info", s, "--json"], capture_output=True, text=True)
                cache[s] = json.loads(out.stdout).get("triangles") if out.returncode == 0 else None
            if cache[s]:
                r["scene_triangles"] = cache[s]
    return runs


def main():
    ap = argparse.ArgumentParser(description="log-log fits of time and memory against triangle count")
    ap.add_argument("study", help="a study's output folder (its runs.json) or a runs.json file")
    ap.add_argument("--y", action="append", help="a run-record field to fit (repeatable)")
    ap.add_argument("--x", default="scene_triangles", help="the size field (default scene_triangles)")
    ap.add_argument("--where", action="append", default=[], help="FIELD=VALUE: only the runs that match")
    ap.add_argument("--group", action="append", help="fields that name a group (default: method, "
                    "params_full, label, renderer)")
    ap.add_argument("--claim", action="append", default=[], help="METHOD=EXPONENT, a paper's claim")
    ap.add_argument("--gibench", help="gibench binary, to count triangles for records without scene_triangles")
    ap.add_argument("--json", help="write the fits here as JSON")
    a = ap.parse_args()
    claims = {}
    for c in a.claim:
        m, _, e = c.partition("=")
        try:
            claims[m] = float(e)
        except ValueError:
            sys.stderr.write(f"scale_fit: --claim '{c}' is not METHOD=EXPONENT\n")
            sys.exit(2)
    where = []
    for w in a.where:
        if "=" not in w:
            sys.stderr.write(f"scale_fit: --where '{w}' is not FIELD=VALUE\n")
            sys.exit(2)
        where.append(w.split("=", 1))
    fields = a.y or DEFAULT_FIELDS
    group = a.group or DEFAULT_GROUP
    runs = load(a.study, a.gibench)
    groups = {}
    for r in runs:
        if r.get("status") != "ok" or any(str(field(r, k)) != v for k, v in where):
            continue
        key = tuple(str(field(r, g) or "") for g in group)
        groups.setdefault(key, []).append(r)
    fits = []
    for key, rs in groups.items():
        for f in fields:
            by_x = {}
            for r in rs:
                x, y = field(r, a.x), field(r, f)
                if isinstance(x, (int, float)) and isinstance(y, (int, float)) and x > 0 and y > 0:
                    by_x.setdefault(x, []).append(y)
            pts = [(x, sorted(ys)[len(ys) // 2] if len(ys) % 2 else
                    0.5 * (sorted(ys)[len(ys) // 2 - 1] + sorted(ys)[len(ys) // 2])) for x, ys in sorted(by_x.items())]
            if len(pts) < 2:
                continue
            res = fit(pts)
            if not res:
                continue
            res.update({"group": dict(zip(group, key)), "field": f, "x": a.x,
                        "x_range": [pts[0][0], pts[-1][0]], "points": pts})
            method = res["group"].get("method")
            if method in claims:
                res["claim"] = claims[method]
                if "ci95" in res:
                    res["claim_within_ci95"] = res["ci95"][0] <= claims[method] <= res["ci95"][1]
            fits.append(res)
    print(f"Log-log least-squares fits, y ~ {a.x}^b (one point per {a.x}: the median of its repeats; "
          "95 % interval from Student's t with n - 2 degrees of freedom).\n")
    print("| group | y | n | " + a.x + " | exponent b | SE | 95 % CI | R² | claim | claim in CI |")
    print("|---|---|---:|---|---:|---:|---|---:|---:|---|")
    for r in fits:
        g = ", ".join(f"{k}={v}" for k, v in r["group"].items() if v)
        ci = "[%.3g, %.3g]" % tuple(r["ci95"]) if "ci95" in r else "– (n < 3)"
        se = "%.3g" % r["se"] if "se" in r else "–"
        claim = "%g" % r["claim"] if "claim" in r else "–"
        within = ("yes" if r["claim_within_ci95"] else "no") if "claim_within_ci95" in r else "–"
        print(f"| {g} | {r['field']} | {r['n']} | {r['x_range'][0]:g}–{r['x_range'][1]:g} | {r['exponent']:.3g} | "
              f"{se} | {ci} | {r['r2']:.3f} | {claim} | {within} |")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(fits, fh, indent=1)
    if not any("ci95" in r for r in fits):
        sys.stderr.write("scale_fit: no group has three or more scenes with values\n")
        sys.exit(1)


if __name__ == "__main__":
    main()

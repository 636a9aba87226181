#!/usr/bin/env python3
"""Scores the trivial answer "black" against every reference of a study.

    scripts/trivial_scores.py DIR [--gibench PATH]

For each reference image DIR/references/*.exr that the study's runs are
compared with (not the convergence images, not the second-seed `_alt`
copies), runs `gibench diff --black REF --json` and writes DIR/trivial.csv:
reference (file name), relmse, rmse, mae, mean_lum_ref. The reference EXR
images are not committed; trivial.csv is, so the tables scripts
(compare_all_tables.py, stress_tables.py) can put the black image beside
the unshadowed baseline from committed files alone. Exit 2 on bad input,
1 when a diff fails.
"""
import argparse
import csv
import json
import os
import subprocess
import sys


def main():
    ap = argparse.ArgumentParser(description="black image's error against every reference of a study")
    ap.add_argument("study", help="a study's output folder")
    ap.add_argument("--gibench", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build",
                                                      "release", "bin", "gibench"))
    a = ap.parse_args()
    refdir = os.path.join(a.study, "references")
    if not os.path.isdir(refdir):
        sys.stderr.write("trivial_scores.py: %s: no references folder\n" % a.study)
        sys.exit(2)
    names = sorted(f for f in os.listdir(refdir)
                   if f.endswith(".exr") and not f.endswith("_alt.exr") and "_conv_" not in f)
    if not names:
        sys.stderr.write("trivial_scores.py: %s has no reference images\n" % refdir)
        sys.exit(2)
    rows = []
    for f in names:
        p = subprocess.run([a.gibench, "diff", "--black", os.path.join(refdir, f), "--json"],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.stderr.write("trivial_scores.py: %s: %s" % (f, p.stderr))
            sys.exit(1)
        d = json.loads(p.stdout)
        rows.append({"reference": f, "relmse": d["relmse"], "rmse": d["rmse"], "mae": d["mae"],
                     "mean_lum_ref": d["mean_lum_ref"]})
    tmp = os.path.join(a.study, "trivial.csv.tmp")
    with open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["reference", "relmse", "rmse", "mae", "mean_lum_ref"])
        w.writeheader()
        for r in rows:
            w.writerow({k: ("%.6g" % v if isinstance(v, float) else v) for k, v in r.items()})
    os.replace(tmp, os.path.join(a.study, "trivial.csv"))


if __name__ == "__main__":
    main()

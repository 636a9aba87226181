#!/usr/bin/env python3
"""scripts/results_changes.py on a synthetic study rerun with known answers.

results_changes_test.py SCRIPT OUTDIR makes a git repository in OUTDIR with
results/s/runs.csv committed (four runs), then rewrites the file as a
rerun would: a new default parameter on every run (new run ids), one
run's relMSE halved and its frame time doubled, one run gone and one new.
The pairs must be found by their swept parameter despite the new ids, the
ratios must be 0.5 and 2, the changed default listed, the new and gone
runs named; a folder without runs.csv and a base without the file must be
refused with exit 1 and one line.
"""
import csv
import os
import shutil
import subprocess
import sys

script, out = sys.argv[1], sys.argv[2]
shutil.rmtree(out, ignore_errors=True)
d = os.path.join(out, "results", "s")
os.makedirs(d)
cols = ["run", "scene", "method", "params", "status", "label", "width", "height", "relmse_full",
        "frame_ms_median", "prepare_ms", "speedup_vs_pt"]


def write(rows):
    with open(os.path.join(d, "runs.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow(r)


def row(rid, n, extra="", rel=0.1, ms=10.0):
    return {"run": rid, "scene": "scenes/box.gltf", "method": "m", "params": "n=%d,k=1%s,label=sweep" % (n, extra),
            "status": "ok", "label": "sweep", "width": 64, "height": 64, "relmse_full": rel,
            "frame_ms_median": ms, "prepare_ms": 1000, "speedup_vs_pt": 2.0}


def git(*a):
    subprocess.run(["git", "-C", out] + list(a), check=True, capture_output=True)


git("init", "-q")
git("config", "user.email", "t@t")
git("config", "user.name", "t")
write([row("a1", 1), row("a2", 2), row("a3", 3), row("a4", 4)])
git("add", "-A")
git("commit", "-qm", "before")
write([row("b1", 1, ",z=0"), row("b2", 2, ",z=0", rel=0.05, ms=20.0), row("b3", 3, ",z=0"),
       row("b5", 5, ",z=0")])
p = subprocess.run([sys.executable, script, d], capture_output=True, text=True)
fails = []
if p.returncode != 0:
    sys.exit("results_changes.py failed (exit %d): %s" % (p.returncode, p.stderr))
o = p.stdout
for want in ("| before | 4 |", "| after | 4 |", "| in both | 3 |", "| new | 1 |", "| gone | 1 |",
             "| box | m | sweep | 64x64 | n=2 † | ok | 0.1 | 0.05 | 0.5 | 10 | 20 | 2 |",
             "| box | m | sweep | 64x64 | n=1 † | ok | 0.1 | 0.1 | 1 | 10 | 10 | 1 |",
             "- box m sweep 64x64 n=5 (ok)", "- box m sweep 64x64 n=4 (ok)", "z: – → 0"):
    if want not in o:
        fails.append("missing: %s" % want)
for args, why in (([os.path.join(out, "none")], "no runs.csv"), ([d, "--base", "HEAD~5"], "bad base")):
    q = subprocess.run([sys.executable, script] + args, capture_output=True, text=True)
    if q.returncode != 1 or len(q.stderr.strip().splitlines()) != 1:
        fails.append("%s: want exit 1 and one line, got %d: %r" % (why, q.returncode, q.stderr))
if fails:
    sys.exit("\n".join(fails) + "\n--- output:\n" + o)
print("results_changes.py: pairs, ratios, new and gone runs and changed defaults as expected")

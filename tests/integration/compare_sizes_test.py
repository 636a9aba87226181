#!/usr/bin/env python3
"""harness/studies/compare_all_tables.py's speed-up against image size on
synthetic studies with known answers.

compare_sizes_test.py SCRIPT OUTDIR writes three study folders (64x64,
128x128, 256x256) whose runs.csv hold two methods on two scenes. The 256x256
study runs only one of "fast"'s two settings, so the table must compare
that setting alone at every size (not the other one, better at 64x64);
"slow" declines scene b at 128x128, so it has no row for b. Every cell, its
spread and the chart must come out as stated; the same size twice, a folder
without runs and --chart without another size must be refused with exit 1.
"""
import csv
import os
import subprocess
import sys

script, out = sys.argv[1], sys.argv[2]
cols = ["run", "scene", "method", "params", "status", "reason", "renderer", "timer", "width", "height",
        "relmse_full", "relmse_matched", "time_to_final_error_s", "prepare_ms", "speedup_vs_pt",
        "speedup_vs_pt_min", "speedup_vs_pt_max", "speedup_vs_pt_matched", "speedup_extrapolated"]


def study(name, size, runs):
    d = os.path.join(out, name)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "runs.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for i, (scene, method, params, status, sp) in enumerate(runs):
            r = {c: "" for c in cols}
            r.update(run="%s-%s-%d" % (scene, method, i), scene="scenes/%s.gltf" % scene, method=method,
                     params=params + ",label=" + method, status=status, renderer="test", timer="cputime",
                     width=size, height=size)
            if status == "ok":
                r.update(relmse_full="0.1", relmse_matched="0.1", time_to_final_error_s="1", prepare_ms="0",
                         speedup_vs_pt=str(sp), speedup_vs_pt_min=str(sp * 0.5), speedup_vs_pt_max=str(sp * 2),
                         speedup_vs_pt_matched=str(sp), speedup_extrapolated="0")
            else:
                r.update(reason="declined: test")
            w.writerow(r)
    return d


def runs(k, slow_b="ok"):
    return [("a", "fast", "n=1,x=0", "ok", 2 * k), ("a", "fast", "n=2,x=0", "ok", 100 * k if k == 1 else 1),
            ("b", "fast", "n=1,x=0", "ok", 3 * k), ("a", "slow", "m=1", "ok", 0.5 * k),
            ("b", "slow", "m=1", slow_b, 0.25 * k)]


d64 = study("s64", 64, runs(1))
d128 = study("s128", 128, runs(2, slow_b="declined"))
d256 = study("s256", 256, [r for r in runs(4) if r[2] != "n=2,x=0"])
chart = os.path.join(out, "chart.svg")
p = subprocess.run([sys.executable, script, d64, "--size-dir", d256, "--size-dir", d128, "--chart", chart],
                   capture_output=True, text=True)
fails = []
if p.returncode != 0:
    sys.exit("tables script failed (exit %d): %s" % (p.returncode, p.stderr))
sec = p.stdout.split("## Equal-error speed-up against image size", 1)
if len(sec) != 2:
    sys.exit("no size section in:\n" + p.stdout)
lines = [ln for ln in sec[1].splitlines() if ln.startswith("| ")]
want = {
    "| method | scene | 64x64 | 128x128 | 256x256 | setting at 256x256 |": True,
    "| fast | a | 2 (1–4) | 4 (2–8) | 8 (4–16) | `n=1` |": True,
    "| fast | b | 3 (1.5–6) | 6 (3–12) | 12 (6–24) | `n=1` |": True,
    "| slow | a | 0.5 (0.25–1) | 1 (0.5–2) | 2 (1–4) | `defaults` |": True,
}
for ln in want:
    if ln not in lines:
        fails.append("missing row: %s" % ln)
if any(ln.startswith("| slow | b |") for ln in lines):
    fails.append("slow on b has a row though it declined b at 128x128")
if len(lines) != len(want):
    fails.append("expected %d table lines, got %d:\n%s" % (len(want), len(lines), "\n".join(lines)))
if not os.path.exists(chart) or "<svg" not in open(chart).read() or open(chart).read().count("<polyline") != 3:
    fails.append("chart missing or without one line per (method, scene) with two or more sizes")
for args, why in (([d64, "--size-dir", d64], "same size twice"), ([d64, "--chart", chart], "--chart alone"),
                  ([os.path.join(out, "none")], "no runs.csv")):
    q = subprocess.run([sys.executable, script] + args, capture_output=True, text=True)
    if q.returncode != 1 or len(q.stderr.strip().splitlines()) != 1:
        fails.append("%s: want exit 1 and one line, got %d: %r" % (why, q.returncode, q.stderr))
if fails:
    sys.exit("\n".join(fails))
print("compare_all_tables.py size section: %d rows as expected, chart with 3 lines" % (len(want) - 1))

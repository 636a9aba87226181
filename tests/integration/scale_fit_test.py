#!/usr/bin/env python3
"""scripts/scale_fit.py on synthetic study records with known exponents.

scale_fit_test.py SCRIPT OUTDIR: method "cubic" has frame times 2e-3 T^1.5
with a known, seeded +-2 % noise (two repeats per scene), "flat" a memory
that does not grow; a failed run with an absurd value is ignored. The fit
must find 1.5 (within 0.05, inside its interval) and 0 for the flat one,
and put the trivial claims (linear, constant) outside the interval.
"""
import json
import os
import random
import subprocess
import sys

script, out = sys.argv[1], sys.argv[2]
os.makedirs(out, exist_ok=True)
rng = random.Random(7)
runs = []
for T in (1000, 2000, 4000, 8000, 16000, 32000):
    for rep in range(2):
        runs.append({"run": f"c{T}-{rep}", "status": "ok", "method": "cubic", "params_full": "k=1",
                     "scene_triangles": T, "frame_ms": {"median": 2e-3 * T ** 1.5 * (1 + rng.uniform(-0.02, 0.02))},
                     "peak_rss_mib": 100.0})
        runs.append({"run": f"f{T}-{rep}", "status": "ok", "method": "flat", "params_full": "",
                     "scene_triangles": T, "frame_ms": {"median": 5.0}, "peak_rss_mib": 80.0})
runs.append({"run": "bad", "status": "failed", "method": "cubic", "params_full": "k=1", "scene_triangles": 64000,
             "frame_ms": {"median": 1e12}})
with open(os.path.join(out, "runs.json"), "w") as fh:
    json.dump(runs, fh)
fails = []
p = subprocess.run([sys.executable, script, out, "--y", "frame_ms.median", "--y", "peak_rss_mib",
                    "--claim", "cubic=1.5", "--json", os.path.join(out, "fits.json")], capture_output=True, text=True)
if p.returncode != 0:
    sys.exit(f"scale_fit.py failed ({p.returncode}): {p.stderr}")
fits = {(f["group"]["method"], f["field"]): f for f in json.load(open(os.path.join(out, "fits.json")))}
c = fits[("cubic", "frame_ms.median")]
if abs(c["exponent"] - 1.5) > 0.05 or not c["ci95"][0] <= 1.5 <= c["ci95"][1]:
    fails.append(f"cubic: exponent {c['exponent']} CI {c['ci95']}, expected 1.5")
if c["n"] != 6:
    fails.append(f"cubic: {c['n']} points (the failed run counted, or repeats not pooled)")
for trivial in (1.0, 0.0, 2.0):
    if c["ci95"][0] <= trivial <= c["ci95"][1]:
        fails.append(f"cubic: the trivial exponent {trivial} lies in the interval {c['ci95']}")
if not c.get("claim_within_ci95"):
    fails.append("cubic: the true claim 1.5 reported outside the interval")
f = fits[("flat", "peak_rss_mib")]
if abs(f["exponent"]) > 1e-9 or f["se"] > 1e-9:
    fails.append(f"flat: exponent {f['exponent']} SE {f['se']}, expected 0 exactly")
if "| cubic" not in p.stdout and "method=cubic" not in p.stdout:
    fails.append("no markdown row for cubic:\n" + p.stdout)
# a false claim is told apart
p2 = subprocess.run([sys.executable, script, out, "--y", "frame_ms.median", "--claim", "cubic=1"],
                    capture_output=True, text=True)
if "| 1 | no |" not in p2.stdout:
    fails.append("a wrong claim (exponent 1) was not marked outside the interval:\n" + p2.stdout)
# bad input: exit 2
bad = os.path.join(out, "bad.json")
open(bad, "w").write("{not json")
if subprocess.run([sys.executable, script, bad], capture_output=True).returncode != 2:
    fails.append("a malformed runs.json did not exit 2")
for m in fails:
    print(m)
print(f"scale_fit: {len(fails)} failures")
sys.exit(1 if fails else 0)

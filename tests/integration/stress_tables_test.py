#!/usr/bin/env python3
"""harness/studies/stress_tables.py on a synthetic stress study with known answers.

stress_tables_test.py SCRIPT OUTDIR writes OUTDIR/runs.csv and runs.json:
a static scene where "good" beats the direct baseline by far, "leaky" is
accurate but puts 5 % of the energy where the reference is dark (its own
noise there 0.1 %), "bad" is worse than the baseline and "half" is at 0.6
of it, "declines" was refused, and "shadows" (direct light only, sharing the
baseline's bounce-matched reference) is worse than the baseline on full GI
but far better on that reference, where it must be judged; an animated scene where "shaky" flickers
at 5x the noise floor and "steady" at 0.5x; scale runs whose frame time is
T^1.5, in a dim scene where a black image scores 0.2 (trivial.csv) "dimbad"
at 0.5 fails though far below the baseline's 3.0; vlf's precomputation T^1 (its paper's claim) and implicit_vis's T^2
(outside its N log N). Every verdict, the declined reason and the exponent must come out
as stated, and a folder without runs must be refused with exit 1.
"""
import csv
import json
import os
import subprocess
import sys

script, out = sys.argv[1], sys.argv[2]
os.makedirs(out, exist_ok=True)
cols = ["run", "scene", "method", "params", "status", "reason", "renderer", "timer", "label", "width", "height",
        "relmse_full", "relmse_matched", "leaked_energy_full", "dark_energy_ref_full", "scene_triangles",
        "anim_relmse_full_mean", "anim_relmse_full_max", "anim_relmse_matched_mean", "anim_frame_ms_median",
        "anim_flicker_full", "anim_noise_floor_full"]
rows, recs = [], []


def add(scene, method, label, status="ok", mref=None, **v):
    r = {c: "" for c in cols}
    r.update(run="%s-%s-%s" % (scene, method, label), scene="scenes/%s.gltf" % scene, method=method,
             status=status, renderer="test", timer="cputime", label=label, width=8, height=8)
    r.update({k: str(x) for k, x in v.items() if k in cols})
    rows.append(r)
    recs.append({"run": r["run"], "scene": r["scene"], "method": method, "label": label, "status": status,
                 "reason": r["reason"], "scene_triangles": v.get("scene_triangles"),
                 "frame_ms": {"median": v.get("frame_ms")}, "prepare_ms": v.get("prepare_ms"),
                 "metrics": {"full": {"reference": {"path": "refs/%s_b64.exr" % scene}},
                             "matched": {"reference": {"path": mref or "refs/%s_%s.exr" % (scene, method)}}}})


add("room", "direct", "static", mref="refs/room_b1.exr", relmse_full=1.0, relmse_matched=1.0,
    leaked_energy_full=0.04, dark_energy_ref_full=0.001)
add("room", "shadows", "static", mref="refs/room_b1.exr", relmse_full=1.2, relmse_matched=0.05,
    leaked_energy_full=0.0, dark_energy_ref_full=0.001)
add("room", "good", "static", relmse_full=0.1, relmse_matched=0.1, leaked_energy_full=0.0, dark_energy_ref_full=0.001)
add("room", "leaky", "static", relmse_full=0.2, relmse_matched=0.2, leaked_energy_full=0.05, dark_energy_ref_full=0.001)
add("room", "bad", "static", relmse_full=1.5, relmse_matched=1.5, leaked_energy_full=0.0, dark_energy_ref_full=0.001)
add("room", "half", "static", relmse_full=0.6, relmse_matched=0.6, leaked_energy_full=0.0, dark_energy_ref_full=0.001)
add("room", "declines", "static", status="n/a", reason="n/a: no point lights")
add("orbit", "direct", "animation", anim_relmse_full_mean=1.0, anim_flicker_full=0.0, anim_noise_floor_full=0.01)
add("orbit", "shaky", "animation", anim_relmse_full_mean=0.1, anim_flicker_full=0.05, anim_noise_floor_full=0.01)
add("orbit", "steady", "animation", anim_relmse_full_mean=0.1, anim_flicker_full=0.005, anim_noise_floor_full=0.01)
add("dim", "direct", "static", relmse_full=3.0, relmse_matched=3.0)
add("dim", "dimgood", "static", relmse_full=0.05, relmse_matched=0.05)
add("dim", "dimbad", "static", relmse_full=0.5, relmse_matched=0.5)
for t in (100, 400, 1600, 6400):
    add("scale_%d" % t, "good", "scale", scene_triangles=t, frame_ms=0.01 * t ** 1.5)
    add("scale_%d" % t, "vlf", "scale", scene_triangles=t, prepare_ms=0.5 * t)
    add("scale_%d" % t, "implicit_vis", "scale", scene_triangles=t, frame_ms=1e-3 * t * t)
with open(os.path.join(out, "runs.csv"), "w", newline="") as fh:
    wr = csv.DictWriter(fh, fieldnames=cols)
    wr.writeheader()
    wr.writerows(rows)
with open(os.path.join(out, "runs.json"), "w") as fh:
    json.dump(recs, fh)
with open(os.path.join(out, "trivial.csv"), "w") as fh:
    fh.write("reference,relmse,rmse,mae,mean_lum_ref\nroom_b64.exr,5,1,1,1\ndim_b64.exr,0.2,1,1,1\n")

p = subprocess.run([sys.executable, script, out], capture_output=True, text=True)
if p.returncode != 0:
    sys.exit("stress_tables.py exit %d: %s" % (p.returncode, p.stderr))
lines = p.stdout.splitlines()
fails = 0


def expect(prefix, *parts):
    global fails
    hit = [ln for ln in lines if ln.startswith(prefix)]
    if not hit or not all(x in hit[0] for x in parts):
        print("FAIL: a line starting %r with %r; got %r" % (prefix, parts, hit[:1]))
        fails += 1
    else:
        print("ok: %s" % hit[0])


expect("| direct | 1 (1) baseline")
expect("| good | 0.1 (0.1) ok")
expect("| leaky | 0.2 (0.2) leaks")
expect("| bad | 1.5 (1.5) fails")
expect("| half | 0.6 (0.6) degraded")
expect("| declines | n/a")
expect("| declines | room | n/a: no point lights")
expect("| orbit | shaky |", "flickers")
expect("| orbit | steady |", "| ok |")
expect("| good | 100–6400 | 1.50 [")
expect("| vlf | prepare_ms |", "| consistent |")
expect("| implicit_vis | frame_ms.median |", "| 2.00 [", "| 2.00 |", "| not consistent |")
expect("| shadows | 1.2 (0.05) ok†")
expect("| dimgood | – | 0.05 (0.05) ok")
expect("| dimbad | – | 0.5 (0.5) fails")
expect("| black | 5 (–) trivial | 0.2 (–) trivial")
empty = os.path.join(out, "empty")
os.makedirs(empty, exist_ok=True)
open(os.path.join(empty, "runs.csv"), "w").write(",".join(cols) + "\n")
open(os.path.join(empty, "runs.json"), "w").write("[]")
q = subprocess.run([sys.executable, script, empty], capture_output=True, text=True)
if q.returncode != 1 or "no runs" not in q.stderr:
    print("FAIL: an empty study: exit %d, %r" % (q.returncode, q.stderr))
    fails += 1
sys.exit(1 if fails else 0)

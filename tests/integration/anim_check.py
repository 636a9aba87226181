#!/usr/bin/env python3
"""Checks of an animated study's records (tests/integration/anim_study.cmake).

anim_check.py GIBENCH STUDY_DIR: every number of each animated run's
"animation" record is recomputed here by another path, `gibench diff --json`
on the frames and references the run used (its relMSE; its MAE, the mean
absolute difference per pixel and channel, is the frame-to-frame change and
the noise floor), and the summary values from the per-frame lists. Exit 1
with one line per failure.
"""
import json
import math
import os
import subprocess
import sys

gib, d = sys.argv[1], sys.argv[2]
fails = []


def diff(a, b):
    out = subprocess.run([gib, "diff", a, b, "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def close(a, b, what, rel=1e-9):
    if a is None or b is None or not math.isclose(a, b, rel_tol=rel, abs_tol=1e-15):
        fails.append(f"{what}: {a} vs {b}")


runs = json.load(open(os.path.join(d, "runs.json")))
anim = [r for r in runs if "animation" in r]
if len(anim) != 2:
    sys.exit(f"expected 2 animated runs with an 'animation' record, got {len(anim)}")
refs = os.path.join(d, "references")
for r in anim:
    a = r["animation"]
    n = a["frames"]
    rd = os.path.join(d, "runs", r["run"])
    frames = [os.path.join(rd, "frames", "frame_%04d.exr" % f) for f in range(n)]
    for f in frames:
        if not os.path.isfile(f):
            fails.append(f"{r['run']}: no {f}")
    # the reference of each frame: the set named after the frame's scene time
    # (frame 0 at time 0 shares the still runs' set "cornell_moving")
    def ref(f, bounces, alt=False):
        t = a["scene_time"][f]
        stem = "cornell_moving" if f == 0 else "cornell_moving_24x24_t%g" % t
        return os.path.join(refs, "%s_b%d_32spp_center%s.exr" % (stem, bounces, "_alt" if alt else ""))
    for k in ("relmse_full", "relmse_matched", "change_method", "change_ref_full", "noise_floor_full", "frame_ms"):
        if len(a[k]) != n:
            fails.append(f"{r['run']}: {k} has {len(a[k])} values for {n} frames")
    for f in range(n):
        close(a["relmse_full"][f], diff(frames[f], ref(f, 8))["relmse"], f"{r['run']} frame {f} relMSE full")
        close(a["relmse_matched"][f], diff(frames[f], ref(f, 1))["relmse"], f"{r['run']} frame {f} relMSE matched")
        close(a["leaked_energy_full"][f], diff(frames[f], ref(f, 8))["leaked_energy"], f"{r['run']} frame {f} leak")
        close(a["noise_floor_full"][f], diff(ref(f, 8), ref(f, 8, True))["mae"], f"{r['run']} frame {f} noise floor")
        if f == 0:
            if a["change_method"][0] is not None or a["frame_ms"][0] is not None:
                fails.append(f"{r['run']}: frame 0 has a change or (warm-up) a time")
            continue
        close(a["change_method"][f], diff(frames[f], frames[f - 1])["mae"], f"{r['run']} frame {f} change")
        close(a["change_ref_full"][f], diff(ref(f, 8), ref(f - 1, 8))["mae"], f"{r['run']} frame {f} ref change")
        if not (a["frame_ms"][f] or 0) > 0:
            fails.append(f"{r['run']}: frame {f} has no time")
    mean = lambda v: sum(x for x in v if x is not None) / len([x for x in v if x is not None])
    close(a["flicker_full"], mean(a["change_method"]) - mean(a["change_ref_full"]), f"{r['run']} flicker")
    close(a["noise_floor_full_mean"], mean(a["noise_floor_full"]), f"{r['run']} noise floor mean")
    if not a["noise_floor_full_mean"] > 0:
        fails.append(f"{r['run']}: the two reference seeds gave the same image")
    # the run's final image is its last frame, compared with the reference of its time
    close(r["metrics"]["full"]["relmse"], a["relmse_full"][n - 1], f"{r['run']} final image against the last frame's reference")
    if "curve" in r:
        fails.append(f"{r['run']}: an animated run got a convergence curve")
for r in runs:
    if not (r.get("peak_rss_mib") or 0) > 10 or not r.get("peak_rss_prepare_mib", 0) <= r["peak_rss_mib"]:
        fails.append(f"{r['run']}: peak RSS {r.get('peak_rss_prepare_mib')} / {r.get('peak_rss_mib')} MiB")
    if not r.get("scene_triangles", 0) > 0:
        fails.append(f"{r['run']}: no scene_triangles")
    if "leaked_energy" not in r["metrics"]["full"]:
        fails.append(f"{r['run']}: no leaked energy in its metrics")
for f in fails:
    print(f)
print(f"{len(anim)} animated runs checked, {len(fails)} failures")
sys.exit(1 if fails else 0)

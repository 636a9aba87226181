#!/usr/bin/env python3
"""The avg speed-ups of issue 14 as a Markdown table.

Reads DIR/runs.csv of a study that holds the avg study's "speed" runs
(label "speed": shadow_lod x voxeliser on the Cornell box and Cornell
moving, and shadow_lod=1 with perspective maps), either the whole study
    gibench study plugins/avg/study.json --out DIR
or those runs alone (results/avg/README.md, "Speed-ups (issue 14)"), and
prints, per scene, each run's stage times (vox, sha; minimum over the
timed frames), frame time (minimum and median), the
ratios against the paper's configuration measured in the same run
(shadow_lod=1, voxeliser=conservative: "before"), and its error against
the bounce-matched and full references. Stdlib only.

Usage: plugins/avg/speed_table.py DIR > table.md
"""

import csv
import os
import sys


def params(row):
    return dict(kv.split("=", 1) for kv in row["params"].split(",") if "=" in kv)


def num(row, key):
    try:
        return float(row[key])
    except (KeyError, ValueError, TypeError):
        return float("nan")


def f(x, fmt="%.3g"):
    return "–" if x != x else fmt % x


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    path = os.path.join(sys.argv[1], "runs.csv")
    with open(path, newline="") as fh:
        runs = [r for r in csv.DictReader(fh) if r["label"] == "speed"]
    bad = [r["run"] for r in runs if r["status"] != "ok"]
    runs = [r for r in runs if r["status"] == "ok"]
    if not runs:
        print("%s: no finished runs labelled 'speed'" % path, file=sys.stderr)
        return 1
    out = []
    w = out.append
    w("GL renderer: %s; timer: %s. Medians of the timed frames; ratios against the paper's configuration "
      "(shadow_lod=1, voxeliser=conservative, the same scene) in the same run. Stage and frame times are the "
      "minimum over the timed frames (the frame least disturbed by other work on the shared machine), the "
      "median frame beside them.\n" % (runs[0]["renderer"], runs[0]["timer"]))
    w("| scene | voxeliser | shadow_lod | maps | triangles a map | vox ms | sha ms | frame ms | median frame ms "
      "| vox / before | sha / before | frame / before | vox share | relMSE matched | mean matched | FLIP matched "
      "| relMSE full |")
    w("|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene in sorted({r["scene"] for r in runs}):
        rows = [r for r in runs if r["scene"] == scene]
        base = [r for r in rows if params(r).get("shadow_lod") == "1" and params(r).get("voxeliser") == "conservative"
                and params(r).get("projection", "auto") == "auto"]
        b = base[0] if base else None

        def key(r):
            p = params(r)
            return (p.get("projection", "auto") != "auto", p.get("voxeliser"), -float(p.get("shadow_lod", "1")))

        for r in sorted(rows, key=key):
            p = params(r)
            vox, sha, frame = num(r, "stage_vox_ms_min"), num(r, "stage_sha_ms_min"), num(r, "frame_ms_min")
            para = num(r, "stat_shadow_paraboloid")
            maps = "–" if para != para else ("paraboloid" if para > 0.5 else "perspective")
            if p.get("projection", "auto") != "auto":
                maps += " (forced)"
            ratio = (lambda k: num(r, k) / num(b, k)) if b else (lambda k: float("nan"))
            mean = num(r, "mean_lum_diff_pct_matched")
            w("| %s | %s | %s | %s | %s | %.0f | %.0f | %.0f | %.0f | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                os.path.basename(scene), p.get("voxeliser"), p.get("shadow_lod"), maps,
                f(num(r, "stat_shadow_triangles"), "%.0f"), vox, sha, frame, num(r, "frame_ms_median"),
                f(ratio("stage_vox_ms_min"), "%.2f"), f(ratio("stage_sha_ms_min"), "%.2f"),
                f(ratio("frame_ms_min"), "%.2f"), f(100.0 * vox / frame, "%.0f %%"),
                f(num(r, "relmse_matched")), "–" if mean != mean else "%+.1f %%" % mean,
                f(num(r, "flip_matched")), f(num(r, "relmse_full"))))
    if bad:
        w("\nNot finished: %s" % ", ".join(bad))
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Tables of the avg study next to the paper's numbers.

Reads DIR/runs.csv and DIR/frames.csv written by
    gibench study plugins/avg/study.json --out DIR
and prints Markdown (Table I, Table II, Fig. 6 with the direct AVG-against-
exact image difference, Fig. 7, the 64^3 against 128^3 grid, the U room's
VPL sweep, the references) to stdout. The paper's numbers are those printed
in Bashford-Rogers et al. (Table I, Table II, the text of §IV). The triangle
counts come from `gibench info` (GIBENCH, default build/release/bin/gibench).

The numbers that need the study's EXR images (which are not committed: the
Fig. 6 difference between the AVG-traced and the exactly traced image, and
the references' statistics) are measured with `--measure`, right after the
study: `gibench diff` on the EXRs, the references' JSON statistics, the Fig. 6
heat maps written to DIR/fig6_<scene>_avg_vs_exact.png, and all of it kept in
DIR/image_stats.csv, which is committed. Without `--measure` the tables are
made from the committed files alone (runs.csv, frames.csv, image_stats.csv),
so they can be regenerated, and checked, on a checkout without the EXRs.
Stdlib only.

Usage: plugins/avg/tables.py DIR [GIBENCH] [--measure] > DIR/tables.md
"""

import argparse
import csv
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from study_tables import report_fronts  # noqa: E402

# Paper, Table I (1024x768, GeForce 8800 GTX): ms per stage and FPS.
PAPER_T1 = [("U Room", 156, 0.4, 1.8, 19.9, 19.1, 62.1, 22.3),
            ("Elephant", 2113, 1.4, 1.9, 28.6, 19.7, 61.8, 21.1),
            ("Office", 28218, 2.2, 2.3, 112.3, 21.4, 23.7, 7.2),
            ("Sibenik", 80062, 3.2, 2.2, 80.6, 19.7, 45.5, 9.1)]
# Paper, Table II: resolution -> FPS (Office, Sibenik).
PAPER_T2 = [((640, 480), 7.9, 10.2), ((800, 600), 7.5, 9.9), ((1024, 768), 7.2, 8.9),
            ((1280, 1024), 6.9, 8.1), ((1920, 1080), 6.7, 7.2), ((1920, 1200), 5.5, 6.9)]
SCENES = [("U room", "scenes/u_room.gltf"), ("Cornell moving", "scenes/cornell_moving.gltf")]


def params(row):
    return dict(kv.split("=", 1) for kv in row["params"].split(",") if "=" in kv)


def num(row, key):
    try:
        return float(row[key])
    except (KeyError, ValueError, TypeError):
        return float("nan")


def f(x, fmt="%.3g"):
    return "–" if x != x else fmt % x


def pct(x):
    return "–" if x != x else "%+.1f %%" % x


def find(runs, label, scene, **want):
    for r in runs:
        p = params(r)
        if r["label"] == label and r["scene"] == scene and all(p.get(k) == v for k, v in want.items()):
            return r
    return None


def gibench_json(exe, args):
    out = subprocess.run([exe] + args + ["--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


IMAGE_STATS_FIELDS = ["kind", "scene", "bounces", "relmse", "mean_lum_diff_pct", "flip", "ssim", "mean_rel_se",
                      "wall_seconds"]


def measure_image_stats(d, exe, runs):
    """The statistics that need the EXR images: Fig. 6's AVG-against-exact
    difference per scene and the references' statistics; writes the heat
    maps and returns the rows of image_stats.csv."""
    rows = []
    for _, scene in SCENES:
        a, e = find(runs, "still", scene, visibility="true"), find(runs, "fig6", scene)
        if not a or not e:
            continue
        stem = os.path.splitext(os.path.basename(scene))[0]
        m = gibench_json(exe, ["diff", os.path.join(d, "runs", a["run"], "image.exr"),
                               os.path.join(d, "runs", e["run"], "image.exr"),
                               "--heatmap", os.path.join(d, "fig6_%s_avg_vs_exact.png" % stem)])
        rows.append({"kind": "fig6", "scene": scene,
                     **{k: "" if m.get(k) is None else repr(m[k])
                        for k in ("relmse", "mean_lum_diff_pct", "flip", "ssim")}})
    for _, scene in SCENES:
        stem = os.path.splitext(os.path.basename(scene))[0]
        full = os.path.join(d, "references", "%s_b64_512spp_center.exr" % stem)
        for b in (4, 64):
            p = os.path.join(d, "references", "%s_b%d_512spp_center.exr" % (stem, b))
            if not os.path.exists(p + ".json"):
                continue
            with open(p + ".json") as fh:
                st = json.load(fh)
            diff = gibench_json(exe, ["diff", p, full])["mean_lum_diff_pct"] if b == 4 else None
            rows.append({"kind": "reference", "scene": scene, "bounces": str(b),
                         "mean_lum_diff_pct": "" if diff is None else repr(diff),
                         "mean_rel_se": repr(st["mean_rel_se"]), "wall_seconds": repr(st["wall_seconds"])})
    return rows


def main():
    ap = argparse.ArgumentParser(description="Tables of the avg study (DIR: the study's --out directory)")
    ap.add_argument("dir")
    ap.add_argument("gibench", nargs="?", default="build/release/bin/gibench")
    ap.add_argument("--measure", action="store_true",
                    help="measure DIR/image_stats.csv from the study's EXR images first")
    args = ap.parse_args()
    d, exe = args.dir, args.gibench
    with open(os.path.join(d, "runs.csv"), newline="") as fh:
        runs = [r for r in csv.DictReader(fh) if r["status"] == "ok"]
    with open(os.path.join(d, "frames.csv"), newline="") as fh:
        frames = list(csv.DictReader(fh))
    stats_path = os.path.join(d, "image_stats.csv")
    if args.measure:
        stats = measure_image_stats(d, exe, runs)
        with open(stats_path, "w", newline="") as fh:
            wr = csv.DictWriter(fh, fieldnames=IMAGE_STATS_FIELDS, restval="", lineterminator="\n")
            wr.writeheader()
            wr.writerows(stats)
    with open(stats_path, newline="") as fh:
        stats = list(csv.DictReader(fh))
    renderer = runs[0]["renderer"] if runs else "?"
    timer = runs[0]["timer"] if runs else "?"
    out = []
    w = out.append
    w("GL renderer: %s; timer: %s (CPU time of the process around glFinish, all llvmpipe threads). "
      "Only ratios within this run mean anything.\n" % (renderer, timer))

    # ---- Table I
    w("### Table I: time per stage, with (V) and without (NV) VPL visibility\n")
    w("Ours: 128×128, defaults (64³ grid, 1024 VPL slots, B = 3, M = 16, 32² paraboloid maps), CPU ms per "
      "frame (median of the timed frames), and each stage's share of the frame. The paper: 1024×768, "
      "GeForce 8800 GTX, ms, frame = 1000 / FPS.\n")
    w("| scene | triangles | live VPLs | vox | tra | sha | ill | frame (V) | frame (NV) | vox % | tra % | sha % "
      "| ill % | NV / V speed-up |")
    w("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    rows = [("U room (still)", "scenes/u_room.gltf", "still"),
            ("Cornell moving (animated, 15 frames/s)", "scenes/cornell_moving.gltf", "table1_moving"),
            ("Cornell moving (still, t = 1 s)", "scenes/cornell_moving.gltf", "still")]
    for name, scene, label in rows:
        v, nv = find(runs, label, scene, visibility="true"), find(runs, label, scene, visibility="false")
        if not v or not nv:
            continue
        tri = gibench_json(exe, ["info", scene])["triangles"]
        st = [num(v, "stage_%s_ms_median" % s) for s in ("vox", "tra", "sha", "ill")]
        fr, frn = num(v, "frame_ms_median"), num(nv, "frame_ms_median")
        w("| %s | %d | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %.1f × |" % (
            name, tri, int(num(v, "stat_vpls_live")), *(f(x, "%.1f") for x in st), f(fr, "%.0f"), f(frn, "%.0f"),
            *(f(100 * x / fr, "%.1f") for x in st), fr / frn))
    for name, tri, vox, tra, sha, ill, fps_nv, fps_v in PAPER_T1:
        fr = 1000.0 / fps_v
        w("| paper: %s | %d | – | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f × |" % (
            name, tri, vox, tra, sha, ill, fr, 1000.0 / fps_nv, 100 * vox / fr, 100 * tra / fr, 100 * sha / fr,
            100 * ill / fr, fps_nv / fps_v))
    mv = [r for r in runs if r["label"] == "table1_moving"]
    for r in mv:
        fs = [float(x["frame_ms"]) for x in frames if x["run"] == r["run"]]
        if fs:
            w("\nCornell moving, visibility=%s: %d timed frames of %.0f to %.0f ms (max / min %.2f)." % (
                params(r)["visibility"], len(fs), min(fs), max(fs), max(fs) / min(fs)))
    w("")

    # ---- Table II
    t2all = [r for r in runs if r["label"] == "table2"]
    if t2all:
        w("### Table II: time per frame against resolution\n")
        w("Ratios to 640×480. Ours: one warm-up and one timed frame per size (CPU ms; Cornell moving animated). "
          "The paper: FPS of the Office and Sibenik scenes, as frame time 1000 / FPS relative to 640×480.\n")
        w("| scene | resolution | pixels / 640×480 | frame ms | frame ratio | ill ms | ill ratio "
          "| rest (frame − ill) ms | paper Office: frame ratio | paper Sibenik: frame ratio |")
        w("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        paper = {res: (o, s) for res, o, s in PAPER_T2}
        for sname, scene in SCENES:
            t2 = sorted((r for r in t2all if r["scene"] == scene), key=lambda r: num(r, "width") * num(r, "height"))
            if not t2:
                continue
            base = t2[0]
            for r in t2:
                wd, ht = int(num(r, "width")), int(num(r, "height"))
                po, ps = paper.get((wd, ht), (float("nan"), float("nan")))
                w("| %s | %d×%d | %.2f | %.0f | %.2f | %.0f | %.2f | %.0f | %s | %s |" % (
                    sname, wd, ht, wd * ht / (640.0 * 480.0), num(r, "frame_ms_median"),
                    num(r, "frame_ms_median") / num(base, "frame_ms_median"), num(r, "stage_ill_ms_median"),
                    num(r, "stage_ill_ms_median") / num(base, "stage_ill_ms_median"),
                    num(r, "frame_ms_median") - num(r, "stage_ill_ms_median"),
                    f(PAPER_T2[0][1] / po, "%.2f"), f(PAPER_T2[0][2] / ps, "%.2f")))
        w("")

    # ---- Fig. 6, Fig. 7, grid
    w("### Fig. 6, Fig. 7, 64³ against 128³: errors against the references\n")
    w("128×128 at t = 1 s; `matched`: the 4-bounce reference (direct + 3 bounces, the method's own), `full`: "
      "64 bounces; image mean: the mean luminance's difference from the reference's.\n")
    w("| scene | variant | live VPLs | relMSE matched | image mean matched | FLIP matched | relMSE full "
      "| image mean full | frame ms | frame / defaults |")
    w("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    variants = [("defaults (AVG tracing)", "still", {"visibility": "true"}),
                ("`tracing=exact` (Fig. 6)", "fig6", {}),
                ("`vpls=256` (Fig. 7)", "fig7", {}),
                ("`grid=128`", "grid128", {}),
                ("`visibility=false`", "still", {"visibility": "false"})]
    for sname, scene in SCENES:
        base = find(runs, "still", scene, visibility="true")
        for vname, label, want in variants:
            r = find(runs, label, scene, **want)
            if not r:
                continue
            w("| %s | %s | %d | %s | %s | %s | %s | %s | %.0f | %.2f |" % (
                sname, vname, int(num(r, "stat_vpls_live")), f(num(r, "relmse_matched")),
                pct(num(r, "mean_lum_diff_pct_matched")), f(num(r, "flip_matched")), f(num(r, "relmse_full")),
                pct(num(r, "mean_lum_diff_pct_full")), num(r, "frame_ms_median"),
                num(r, "frame_ms_median") / num(base, "frame_ms_median") if base else float("nan")))
    w("")
    w("Fig. 6 directly: the AVG-traced image against the exactly traced one (`gibench diff`, the exact one as "
      "the reference; heat map of the relative error: `fig6_<scene>_avg_vs_exact.png`).\n")
    w("| scene | relMSE | image mean (AVG vs exact) | FLIP | SSIM |")
    w("|---|---:|---:|---:|---:|")
    for sname, scene in SCENES:
        for r in stats:
            if r["kind"] == "fig6" and r["scene"] == scene:
                g = {k: num(r, k) for k in ("relmse", "mean_lum_diff_pct", "flip", "ssim")}
                w("| %s | %s | %s | %s | %s |" % (sname, f(g["relmse"]), pct(g["mean_lum_diff_pct"]), f(g["flip"]),
                                                  f(g["ssim"])))
    w("")

    # ---- U room VPL sweep
    w("### U room: image mean against the number of VPL slots\n")
    w("| tracing | grid | VPL slots | live VPLs | relMSE matched | image mean matched | image mean full | frame ms |")
    w("|---|---:|---:|---:|---:|---:|---:|---:|")
    # the speed sweep (label "speed", issue 14) has its own table in speed/
    sweep = [r for r in runs if r["scene"] == "scenes/u_room.gltf" and r["label"] not in ("table2", "speed")
             and params(r).get("visibility") == "true"]
    for r in sorted(sweep, key=lambda r: (params(r)["tracing"], int(params(r)["grid"]), int(params(r)["vpls"]))):
        p = params(r)
        w("| %s | %s³ | %s | %d | %s | %s | %s | %.0f |" % (
            p["tracing"], p["grid"], p["vpls"], int(num(r, "stat_vpls_live")), f(num(r, "relmse_matched")),
            pct(num(r, "mean_lum_diff_pct_matched")), pct(num(r, "mean_lum_diff_pct_full")), num(r, "frame_ms_median")))
    w("")

    # ---- references
    w("### References (Embree path tracer, 512 spp, one sample at each pixel's centre)\n")
    w("| scene | bounces | mean relative standard error | wall s | matched against full: image mean |")
    w("|---|---:|---:|---:|---:|")
    for sname, scene in SCENES:
        for r in stats:
            if r["kind"] == "reference" and r["scene"] == scene:
                diff = num(r, "mean_lum_diff_pct")
                w("| %s | %s | %.1f %% | %.0f | %s |" % (sname, r["bounces"], 100 * num(r, "mean_rel_se"),
                                                      num(r, "wall_seconds"), pct(diff) if diff == diff else "–"))
    out.extend(report_fronts(d))
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())

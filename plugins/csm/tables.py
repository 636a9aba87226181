#!/usr/bin/env python3
"""Tables of the csm study next to the paper's numbers.

Reads DIR/runs.csv and DIR/frames.csv written by
    gibench study plugins/csm/study.json --out DIR
and prints Markdown (Table 1, the exponent of the ratio's growth, Table 2,
Fig. 9, Fig. 14, the moving object) to stdout. The paper's numbers are
those printed in Ritschel et al. 2007 (Table 1: the Bunny rows; Table 2:
the Buddha rows; Fig. 9: the caption's times). Stdlib only.

Usage: plugins/csm/tables.py DIR > DIR/tables.md
"""

import csv
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from study_tables import report_fronts  # noqa: E402

# Paper, Table 1, "Distant Lat-long Bunny", M = 128: total maps ->
# (uncompressed, compressed, time, ratio) as printed.
PAPER_T1 = {1024: ("32.0 MB", "3.9 MB", "4 s", 8.2),
            16384: ("512.0 MB", "19.9 MB", "50 s", 25.4),
            262144: ("8.0 GB", "242.8 MB", "844 s", 86.2)}
PAPER_T1_TIME_S = {1024: 4.0, 16384: 50.0, 262144: 844.0}
PAPER_T1_COMPRESSED_MIB = {1024: 3.9, 16384: 19.9, 262144: 242.8}
# Paper, Table 1, local lights (6 N maps, M = 128): (object, light points,
# enumeration, total maps, uncompressed, compressed, time, ratio) as printed.
PAPER_T1_LOCAL = [("Dragon", "8×8", "scanline", 384, "12.0 MB", "2.3 MB", "3 s", 5.2),
                  ("Dragon", "8×8", "hilbert", 384, "12.0 MB", "1.9 MB", "3 s", 6.3),
                  ("Plant", "32×32", "hilbert", 6144, "192 MB", "4.5 MB", "13 s", 42.0)]
# Paper, Table 2, Buddha, 1024x768, N = 128^2, M = 128: S -> M samples/s.
PAPER_T2 = {"shade": {16: 66.2, 64: 69.9, 625: 81.9},
            "random": {16: 85.0, 625: 132.5},
            "coherent": {16: 163.5, 625: 190.4}}
# Paper, Fig. 9 caption: time to the (same) image per filter, seconds.
PAPER_F9 = {"nearest": 11.5, "pcf": 198.0, "rr": 15.4}


def params(row):
    return dict(kv.split("=", 1) for kv in row["params"].split(",") if "=" in kv)


def num(row, key):
    try:
        return float(row[key])
    except (KeyError, ValueError):
        return float("nan")


def merge_repeats(rows):
    """One row per configuration (label + parameters): the repeats of a
    timing entry merged. render_min: the least render-pass time over every
    timed frame of every repeat (contention on a shared machine only adds
    time); render_med: the median of the repeats' medians; metrics: means."""
    groups = {}
    for r in rows:
        groups.setdefault((r["label"], r["params"]), []).append(r)
    out = []
    for (_, _), rs in groups.items():
        m = dict(rs[0])
        m["repeats"] = len(rs)
        m["render_min"] = min(num(r, "stage_render_ms_min") for r in rs)
        m["render_med"] = statistics.median(num(r, "stage_render_ms_median") for r in rs)
        for k in ("relmse_matched", "flip_matched", "mean_lum_diff_pct_matched"):
            m[k] = str(statistics.mean(num(r, k) for r in rs))
        out.append(m)
    return out


def fit_exponent(points):
    """Least-squares slope of log(y) against log(x)."""
    xs = [math.log(x) for x, _ in points]
    ys = [math.log(y) for _, y in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx


def fit_line(points):
    """(e, a): least-squares log(y) = a + e log(x)."""
    xs = [math.log(x) for x, _ in points]
    ys = [math.log(y) for _, y in points]
    e = fit_exponent(points)
    return e, sum(ys) / len(ys) - e * sum(xs) / len(xs)


def mb(b):
    return "%.1f MB" % (b / 2 ** 20) if b < 2 ** 30 else "%.2f GB" % (b / 2 ** 30)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: csm_tables.py DIR (the study's --out directory)")
    d = sys.argv[1]
    with open(os.path.join(d, "runs.csv"), newline="") as f:
        runs = [r for r in csv.DictReader(f) if r["status"] == "ok"]
    with open(os.path.join(d, "frames.csv"), newline="") as f:
        frames = list(csv.DictReader(f))
    by = {}
    for r in runs:
        by.setdefault(r["label"], []).append(r)
    renderer = runs[0]["renderer"] if runs else "?"
    out = []
    w = out.append
    w("GL renderer: %s. Timings are software-rasterised; only ratios within this run mean anything.\n" % renderer)

    # ---- Table 1, local lights (plugins/csm/study_local.json)
    tl = sorted(by.get("table1_local", []),
                key=lambda r: (params(r)["light_enumeration"], int(params(r)["N_local"])))
    if tl:
        w("### Table 1, local lights: the teapot's depth cube maps at N × N points on the area light of teapot_area.glb, "
          "M = 128\n")
        w("Ground and light receiver-only (`receivers=planar`), so only the teapot's maps are built; storage as in "
          "the distant table. The paper's local rows are other objects (Dragon, Plant) and are listed after ours.\n")
        w("| light points | maps (6 N) | enumeration | uncompressed | compressed | segments / texel | precompute (s) "
          "| ratio |")
        w("|---|---:|---|---:|---:|---:|---:|---:|")
        lfits = {}
        for r in tl:
            p = params(r)
            n = int(p["N_local"])
            maps = int(num(r, "stat_maps_local"))
            t = (num(r, "prepare_depth_render_ms") + num(r, "prepare_compress_ms")) / 1000.0
            w("| %d×%d | %d | %s | %s | %s | %.1f | %.1f | %.1f : 1 |" % (
                n, n, maps, p["light_enumeration"], mb(num(r, "stat_bytes_uncompressed")),
                mb(num(r, "stat_bytes_compressed")), num(r, "stat_segments_per_texel_local"), t,
                num(r, "stat_ratio")))
            lfits.setdefault(p["light_enumeration"], []).append((maps, num(r, "stat_ratio")))
        w("\nPaper (other objects):\n")
        w("| object | light points | enumeration | maps | uncompressed | compressed | time | ratio |")
        w("|---|---|---|---:|---:|---:|---:|---:|")
        for o, lp, e, m, u, c, t, ratio in PAPER_T1_LOCAL:
            w("| %s | %s | %s | %d | %s | %s | %s | %.1f : 1 |" % (o, lp, e, m, u, c, t, ratio))
        w("\nGrowth with the number of maps (ratio ∝ N^e): " + "; ".join(
            "%s e = %.3f" % (e, fit_exponent(pts)) for e, pts in sorted(lfits.items()) if len(pts) >= 2) + ".")
        if "table1" not in by:
            print("\n".join(out))
            return

    # ---- Table 1
    t1 = sorted(by.get("table1", []), key=lambda r: (params(r)["enumeration"], int(params(r)["N"])))
    w("### Table 1: bunny alone, distant lat-long light, M = 128\n")
    w("Ours: compressed = 4 B per texel (offsets) + 6 B per segment (float z_avg, uint16 i_end); "
      "'ratio at 4 B/seg.' counts 4 B per segment (16-bit z_avg and i_end, as a 2-byte depth suggests) for "
      "comparison with the paper, whose format is not stated; 'paper seg./texel' is the paper's compressed size "
      "read back with that 4 B-per-segment assumption.\n")
    w("| N | maps | enumeration | uncompressed | compressed | segments / texel | precompute (s) "
      "(depth maps + compression) | ratio | ratio at 4 B/seg. | paper: uncompressed | compressed | time "
      "| ratio | paper seg./texel |")
    w("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    fits = {}
    times = {}
    for r in t1:
        p = params(r)
        n = int(p["N"])
        maps = int(num(r, "stat_maps"))
        t = (num(r, "prepare_depth_render_ms") + num(r, "prepare_compress_ms")) / 1000.0
        pap = PAPER_T1.get(maps, ("–", "–", "–", None))
        m2 = int(p["M"]) ** 2
        ratio4 = num(r, "stat_bytes_uncompressed") / (4 * (m2 + 1) + 4 * num(r, "stat_segments_per_texel") * m2)
        pseg = ((PAPER_T1_COMPRESSED_MIB[maps] * 2 ** 20 / m2) - 4) / 4 if maps in PAPER_T1_COMPRESSED_MIB else None
        w("| %d×%d | %d | %s | %s | %s | %.1f | %.1f (%.1f + %.1f) | %.1f : 1 | %.1f : 1 | %s | %s | %s | %s | %s |" % (
            n, n, maps, p["enumeration"], mb(num(r, "stat_bytes_uncompressed")),
            mb(num(r, "stat_bytes_compressed")), num(r, "stat_segments_per_texel"), t,
            num(r, "prepare_depth_render_ms") / 1000.0, num(r, "prepare_compress_ms") / 1000.0,
            num(r, "stat_ratio"), ratio4, pap[0], pap[1], pap[2],
            "%.1f : 1" % pap[3] if pap[3] else "–", "%.0f" % pseg if pseg else "–"))
        fits.setdefault(p["enumeration"], []).append((maps, num(r, "stat_ratio")))
        times.setdefault(p["enumeration"], {})[maps] = t
    w("")
    paper_fit = fit_exponent([(k, v[3]) for k, v in PAPER_T1.items()])
    w("Growth of the ratio with the number of maps N (least-squares fit of ratio ∝ N^e over the rows above; "
      "√N would be e = 0.5):\n")
    w("| | values of N (total maps) | exponent e |")
    w("|---|---|---:|")
    for e, pts in sorted(fits.items()):
        if len(pts) >= 2:
            w("| ours, %s | %s | %.3f |" % (e, ", ".join(str(m) for m, _ in sorted(pts)), fit_exponent(pts)))
    w("| paper, bunny | 1024, 16384, 262144 | %.3f |" % paper_fit)
    if "hilbert" in times and "scanline" in fits:
        ratios = dict(fits["hilbert"])
        sc = dict(fits["scanline"])
        w("\nHilbert over scan-line, ratio of ratios: " + ", ".join(
            "N = %d: %.2f" % (m, ratios[m] / sc[m]) for m in sorted(ratios) if m in sc) + ".")
    for e, ts in sorted(times.items()):
        ms = sorted(ts)
        if len(ms) >= 2:
            w("\nPrecompute time, %s: %s (seconds per 1000 maps: %s; paper: 3.9, 3.1, 3.2)." % (
                e, ", ".join("%d maps %.1f s" % (m, ts[m]) for m in ms),
                ", ".join("%.2f" % (1000 * ts[m] / m) for m in ms)))
    # extrapolation to 512 x 512: time at the largest run's rate, ratio along the fitted power law
    for e, ts in sorted(times.items()):
        big = max(ts)
        ex, a = fit_line(fits[e])
        r512 = math.exp(a + ex * math.log(262144))
        w("\nAt the same rate, %s at 512×512 (262144 maps) would take ≈ %.0f s (%.1f min) here; the fitted power "
          "law gives a ratio of ≈ %.0f : 1 there (paper 86.2 : 1)." % (
              e, ts[big] / big * 262144, ts[big] / big * 262144 / 60, r512))

    # ---- Table 2
    t2 = merge_repeats(by.get("table2", []))
    w("\n### Table 2: Monte Carlo samples per second, bunny alone, N = 128², M = 128\n")
    w("MS/s = samples per frame (S × pixels that hit the bunny) / `render` pass time, the least over %s "
      "interleaved repeats × %s timed frames (median of the repeats' medians beside it). Paper: Buddha at "
      "1024×768 on a GeForce 8800, samples counted over all pixels.\n" % (
          t2[0]["repeats"] if t2 else "?",
          int(num(t2[0], "frames")) - 1 if t2 else "?"))
    w("| mode | S | render pass min (median) ms | samples / frame | MS/s (llvmpipe) | vs shade | paper MS/s "
      "| paper vs shade |")
    w("|---|---:|---:|---:|---:|---:|---:|---:|")
    rate = {}
    for r in t2:
        p = params(r)
        rate[(p["mode"], int(p["S"]))] = num(r, "stat_samples_per_frame") / (r["render_min"] * 1000.0)
    for mode in ("shade", "random", "coherent"):
        for s in (16, 64, 625):
            if (mode, s) not in rate:
                continue
            r = next(x for x in t2 if params(x)["mode"] == mode and int(params(x)["S"]) == s)
            pap = PAPER_T2[mode].get(s)
            pshade = PAPER_T2["shade"].get(s)
            w("| %s | %d | %.1f (%.1f) | %d | %.2f | %.2f | %s | %s |" % (
                mode, s, r["render_min"], r["render_med"], num(r, "stat_samples_per_frame"),
                rate[(mode, s)], rate[(mode, s)] / rate[("shade", s)],
                "%.1f" % pap if pap else "–", "%.2f" % (pap / pshade) if pap and pshade else "–"))
    if t2:
        w("\nCoherent over random: " + ", ".join(
            "S = %d: %.2f (paper %s)" % (s, rate[("coherent", s)] / rate[("random", s)],
                                         "%.2f" % (PAPER_T2["coherent"][s] / PAPER_T2["random"][s])
                                         if s in PAPER_T2["random"] else "–")
            for s in (16, 64, 625) if ("coherent", s) in rate and ("random", s) in rate) + ".")

    # ---- Fig. 9
    f9 = {params(r)["filter"]: r for r in merge_repeats(by.get("fig9", []))}
    if f9:
        p = params(next(iter(f9.values())))
        w("\n### Fig. 9: filters (bunny on the ground, N = %s², M = %s, S = %s × %s frames)\n" % (
            p["N"], p["M"], p["S"], next(iter(f9.values()))["frames"]))
        w("Render pass: the least over %d interleaved repeats × %d timed frames (median of medians in "
          "brackets); errors: mean over the repeats.\n" % (next(iter(f9.values()))["repeats"],
                                                          int(num(next(iter(f9.values())), "frames")) - 1))
        w("| filter | render pass min (median) ms | vs nearest | paper time | paper vs nearest | "
          "relMSE vs 1-bounce | FLIP vs 1-bounce | mean lum. diff % |")
        w("|---|---:|---:|---:|---:|---:|---:|---:|")
        base = f9["nearest"]["render_min"] if "nearest" in f9 else float("nan")
        for k in ("nearest", "pcf", "rr"):
            if k not in f9:
                continue
            r = f9[k]
            t = r["render_min"]
            w("| %s | %.1f (%.1f) | %.2f | %.1f s | %.2f | %.4g | %.4f | %+.2f |" % (
                k, t, r["render_med"], t / base, PAPER_F9[k], PAPER_F9[k] / PAPER_F9["nearest"],
                num(r, "relmse_matched"),
                num(r, "flip_matched"), num(r, "mean_lum_diff_pct_matched")))

    # ---- Fig. 14
    f14 = by.get("fig14", [])
    if f14:
        ns = sorted({int(params(r)["N"]) for r in f14})
        ms_ = sorted({int(params(r)["M"]) for r in f14})
        cell = {(int(params(r)["N"]), int(params(r)["M"])): r for r in f14}
        w("\n### Fig. 14: CSM visibility against ray-traced visibility (bunny on the ground, nearest filter, "
          "S = %s × %s frames)\n" % (params(f14[0])["S"], f14[0]["frames"]))
        for key, name in (("relmse_matched", "relMSE"), ("flip_matched", "FLIP"),
                          ("mean_lum_diff_pct_matched", "mean luminance difference %")):
            w("%s against the 1-bounce (direct light) path-traced reference; rows N (N² maps), columns M:\n" % name)
            w("| N \\ M | " + " | ".join(str(m) for m in ms_) + " |")
            w("|---|" + "---:|" * len(ms_))
            for n in ns:
                w("| %d | " % n + " | ".join(
                    ("%.4g" % num(cell[(n, m)], key)) if (n, m) in cell else "–" for m in ms_) + " |")
            w("")
        un = by.get("fig14_unshadowed", [])
        if un:
            w("Unshadowed direct light (`direct`, env_samples = %s, no visibility at all) against the same "
              "reference: relMSE %.4g, FLIP %.4f, mean luminance %+.2f %%.\n" % (
                  params(un[0]).get("env_samples", "?"), num(un[0], "relmse_matched"), num(un[0], "flip_matched"),
                  num(un[0], "mean_lum_diff_pct_matched")))
        prep = "; ".join("N = %d, M = %d: %.1f s" % (n, m, num(cell[(n, m)], "prepare_ms") / 1000.0)
                         for n, m in ((32, 128), (32, 256)) if (n, m) in cell)
        if prep:
            w("Precomputation (both objects, cached after the first run of a configuration): %s.\n" % prep)

    # ---- moving
    mv = [r for r in runs if r["label"] in ("moving", "still")]
    if mv:
        w("\n### Moving object: bunny looping behind a still teapot (`bunny_teapot_moving.glb`)\n")
        w("| run | frames timed | frame ms median | min | max | mean | render pass median | precompute (s) |")
        w("|---|---:|---:|---:|---:|---:|---:|---:|")
        for r in mv:
            fr = [float(x["frame_ms"]) for x in frames if x["run"] == r["run"]]
            w("| %s (`%s`) | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |" % (
                r["label"], r["run"], len(fr), statistics.median(fr), min(fr), max(fr), statistics.mean(fr),
                num(r, "stage_render_ms_median"), num(r, "prepare_ms") / 1000.0))
    out.extend(report_fronts(d))
    print("\n".join(out))


if __name__ == "__main__":
    main()

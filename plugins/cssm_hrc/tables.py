#!/usr/bin/env python3
"""Tables of the cssm_hrc study (results/cssm_hrc/README.md) from its runs.csv.

Usage: plugins/cssm_hrc/tables.py results/cssm_hrc [--measure] > results/cssm_hrc/tables.md

--measure: measure what needs the study's EXR images, which are not
committed (Fig. 14's relMSE between the cssm and the trace image, with
gibench diff; GIBENCH names the binary), into the committed
pair_relmse.csv; without it the tables read that file, so that they
regenerate the same from a clean clone (scripts/regenerate_results.sh
passes --measure after a study).
"""
import csv
import os
import sys

# Ritschel et al. 2008, Table 2: compression factors, Cornell box, 6 x 32 x 32.
PAPER_T2 = {32: {"greedy": 5.6, "zigzag": 7.1, "spiral": 7.4},
            64: {"greedy": 8.8, "zigzag": 11.2, "spiral": 11.7},
            128: {"greedy": 12.8, "zigzag": 15.7, "spiral": 16.9}}
# Table 1: fps (GeForce 8800); Cornell box rows.
PAPER_T1 = {("pixels", 1): 5.2, ("pixels", 2): 1.4, ("texels", 1): 35.7, ("texels", 2): 10.4}


def num(r, k):
    try:
        return float(r.get(k, "") or "nan")
    except ValueError:
        return float("nan")


def params(r):
    out = {}
    for kv in r["params"].split(","):
        if "=" in kv:
            k, v = kv.split("=", 1)
            out[k] = v
    return out


def main():
    d = sys.argv[1]
    measure = "--measure" in sys.argv[2:]
    rows = list(csv.DictReader(open(os.path.join(d, "runs.csv"))))
    ok = [r for r in rows if r["status"] == "ok"]
    print("# cssm_hrc study tables (made by plugins/cssm_hrc/tables.py from runs.csv)\n")
    if len(ok) != len(rows):
        print("Runs not ok: " + ", ".join("%s (%s: %s)" % (r["run"], r["status"], r["reason"]) for r in rows
                                          if r["status"] != "ok") + "\n")

    print("## Table 2: compression, Cornell box, 6 x 32 x 32 cube maps\n")
    print("| atlas | texels | traversal | ratio (here) | paper | segments / face texel | cube maps render (s) | compress (s) |")
    print("|---|---|---|---|---|---|---|---|")
    t2 = [r for r in ok if r["label"] == "table2"]
    t2.sort(key=lambda r: (int(params(r)["atlas"]), ["greedy", "zigzag", "spiral", "greedy_atlas"].index(params(r)["traversal"])))
    for r in t2:
        p = params(r)
        a, t = int(p["atlas"]), p["traversal"]
        paper = PAPER_T2.get(a, {}).get(t)
        print("| %d² | %d | %s | %.1f : 1 | %s | %.2f | %.1f | %.1f |" % (
            a, num(r, "stat_atlas_texels"), t, num(r, "stat_compression_ratio"),
            "%.1f : 1" % paper if paper else "—",
            num(r, "stat_segments_per_texel"), num(r, "prepare_cssm_render_ms") / 1000, num(r, "prepare_compress_ms") / 1000))

    print("\n## Table 1 as ratios: bounces and samples\n")
    print("Per frame: the final gather (`frame_ms_median`); per lighting change: the atlas' lighting as prepare() "
          "measured it (`direct` + `bounce` + `pull`, which includes the punctual lights' shadow maps) plus a frame. "
          "The paper recomputes the lighting every frame; its fps are for that case.\n")
    print("| scene | mode | n | texels | frame (ms) | lighting (ms) | lighting + frame (ms) | mean cut (pixels) | mean cut (atlas) |")
    print("|---|---|---|---|---|---|---|---|---|")
    t1 = [r for r in ok if r["label"] == "table1"]
    t1.sort(key=lambda r: (r["scene"], params(r).get("mode", "pixels"), int(params(r)["bounces"])))
    tot = {}
    for r in t1:
        p = params(r)
        light = num(r, "prepare_direct_ms") + (num(r, "prepare_bounce_ms") if r.get("prepare_bounce_ms") else 0) + \
            num(r, "prepare_pull_ms")
        f = num(r, "frame_ms_median")
        key = (os.path.basename(r["scene"]), p.get("mode", "pixels"), int(p["bounces"]))
        tot[key] = (f, light + f)
        print("| %s | %s | %d | %d | %.0f | %.0f | %.0f | %.0f | %.0f |" % (
            key[0], key[1], key[2], num(r, "stat_atlas_texels"), f, light, light + f,
            num(r, "stat_cut_size_pixels"), num(r, "stat_cut_size_atlas")))
    print("\n| scene | ratio | here (lighting + frame) | here (frame only) | paper (Cornell box) |")
    print("|---|---|---|---|---|")
    for scene in sorted({k[0] for k in tot}):
        for mode in ("pixels", "texels"):
            a, b = tot.get((scene, mode, 1)), tot.get((scene, mode, 2))
            if a and b:
                pp = PAPER_T1[(mode, 1)] / PAPER_T1[(mode, 2)]
                print("| %s | time(n=2) / time(n=1), %s | %.2f | %.2f | %.2f |" % (scene, mode, b[1] / a[1], b[0] / a[0], pp))
        for n in (1, 2):
            a, b = tot.get((scene, "pixels", n)), tot.get((scene, "texels", n))
            if a and b:
                pp = PAPER_T1[("texels", n)] / PAPER_T1[("pixels", n)]
                print("| %s | time(pixels) / time(texels), n = %d | %.2f | %.2f | %.2f |" % (scene, n, a[1] / b[1], a[0] / b[0], pp))

    def metrics_table(label_prefix, keys, title, extra=(), where=None):
        """Runs whose label starts with label_prefix (or, given, for which
        where(run) holds): their parameters `keys`, the errors, and `extra`
        columns (header, runs.csv column, format[, scale])."""
        sel = [r for r in ok if (where(r) if where else r["label"].startswith(label_prefix))]
        if not sel:
            return
        print("\n## %s\n" % title)
        print("| run | scene | " + " | ".join(keys) + " | frames | relMSE full | relMSE matched (4 bounces) | FLIP matched | "
              "mean lum. diff. matched (%) |" + "".join(" %s |" % e[0] for e in extra))
        print("|---|---|" + "---|" * len(keys) + "---|---|---|---|---|" + "---|" * len(extra))
        sel.sort(key=lambda r: (r["label"].split("_")[0], int(r["frames"]), r["params"]))
        for r in sel:
            p = params(r)
            print("| %s | %s | " % (r["run"], os.path.basename(r["scene"])) + " | ".join(p.get(k, "") for k in keys) +
                  " | %s | %.4f | %.4f | %.4f | %+.1f |" % (r["frames"], num(r, "relmse_full"), num(r, "relmse_matched"),
                                                         num(r, "flip_matched"), num(r, "mean_lum_diff_pct_matched")) +
                  "".join(" %s |" % (e[2] % (num(r, e[1]) * (e[3] if len(e) > 3 else 1)) if r.get(e[1]) else "—")
                          for e in extra))

    metrics_table("fig15", ["atlas", "M", "bounces", "clamp"], "Fig. 15: against the path-traced reference")
    metrics_table("fig16", ["atlas", "bounces"], "Fig. 16: bounce count n (pixels get 0 .. n + 1 bounces)")
    fig14(d, ok, measure)
    # the PCF runs: label fig14_pcf (runs before issue 34: fig14 without vis)
    metrics_table("fig14_pcf", ["atlas", "pcf"], "Fig. 14: nearest against PCF look-ups",
                  where=lambda r: r["label"] == "fig14_pcf" or (r["label"] == "fig14" and "vis" not in params(r)))
    metrics_table("fig12", ["jitter"], "Fig. 12: highly glossy Cornell box, jittering, error over accumulated frames")
    metrics_table("deficit12", ["atlas", "threshold", "max_cut", "vis", "clamp"],
                  "Fig. 12's mean-luminance deficit: one candidate changed at a time; the blocks black (kd = ks = 0)",
                  [("cut (pixels)", "stat_cut_size_pixels", "%.0f")])
    metrics_table("mc", ["indirect", "mc_samples"], "Sec. 4.6: indirect light by Monte Carlo from the atlas as a pdf, against the cuts")
    metrics_table("clamp", ["clamp"], "Clamping: darkening against the clamp distance")
    timing = [("prepare (s; CSSMs read from the cache where an earlier run made them)", "prepare_ms", "%.1f", 1e-3), ("frame (ms)", "frame_ms_median", "%.0f")]
    metrics_table("alt_direct", ["direct"], "Sec. 4.7: direct light by the shadow maps and gathers (maps) or by CSM Monte Carlo (csm)",
                  timing + [("CSM precompute (s)", "prepare_csm_precompute_ms", "%.1f", 1e-3), ("CSM bytes", "stat_csm_bytes", "%.0f")])
    metrics_table("alt_nodes", ["atlas", "nodes"], "Sec. 4.2.1: float nodes against the compact 128-bit nodes",
                  timing + [("node bytes", "stat_node_bytes", "%.0f")])
    metrics_table("alt_env", ["env"], "Environment light: ray traced (trace) or from the texels' own CSSMs (env=cssm)",
                  timing + [("compression", "stat_compression_ratio", "%.1f : 1"), ("CSSM bytes", "stat_cssm_bytes", "%.0f")])
    atlas_use(ok)
    motion_table(ok)


def trivial_black(d):
    """relMSE of a black image against each reference (trivial.csv of the study)."""
    path = os.path.join(d, "trivial.csv")
    if not os.path.exists(path):
        return {}
    return {r["reference"]: float(r["relmse"]) for r in csv.DictReader(open(path))}


def pair_relmse(d, a, b, measure):
    """relMSE of run a's image against run b's, read from the committed
    pair_relmse.csv; with measure, first measured by gibench diff of the
    study's EXR images (not committed) and written there. None where the
    file has no such pair."""
    saved = os.path.join(d, "pair_relmse.csv")
    if measure:
        gib = os.environ.get("GIBENCH", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                                      "build", "release", "bin", "gibench"))
        ia, ib = (os.path.join(d, "runs", r["run"], "image.exr") for r in (a, b))
        import json
        import subprocess
        out = subprocess.run([gib, "diff", "--json", ia, ib], capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit("tables.py: gibench diff %s %s: %s" % (ia, ib, out.stderr.strip()))
        with open(saved + ".tmp", "w") as f:
            f.write("test,reference,relmse\n%s,%s,%.17g\n" % (a["run"], b["run"], json.loads(out.stdout)["relmse"]))
        os.replace(saved + ".tmp", saved)
    if os.path.exists(saved):
        for row in csv.DictReader(open(saved)):
            if row["test"] == a["run"] and row["reference"] == b["run"]:
                return float(row["relmse"])
    return None


def fig14(d, ok, measure):
    """Fig. 14: the CSSM visibility against an exact ray query to each gathered
    point (vis=trace), same atlas, maps and cuts; the trivial black image
    scored against the same references."""
    sel = {params(r)["vis"]: r for r in ok if r["label"] == "fig14" and "vis" in params(r)}
    if not sel:
        return
    print("\n## Fig. 14: CSSM visibility against exact ray-cast visibility (vis=trace)\n")
    print("| vis | scene | atlas | M | relMSE full | relMSE matched (4 bounces) | FLIP matched | mean lum. diff. matched (%) |")
    print("|---|---|---|---|---|---|---|---|")
    for v in ("cssm", "trace"):
        r = sel.get(v)
        if r:
            p = params(r)
            print("| %s | %s | %s² | %s | %.4f | %.4f | %.4f | %+.2f |" % (
                v, os.path.basename(r["scene"]), p.get("atlas"), p.get("M"), num(r, "relmse_full"),
                num(r, "relmse_matched"), num(r, "flip_matched"), num(r, "mean_lum_diff_pct_matched")))
    black = trivial_black(d)
    stem = os.path.splitext(os.path.basename(next(iter(sel.values()))["scene"]))[0]
    bm = [v for k, v in black.items() if k.startswith(stem + "_b4_")]
    bf = [v for k, v in black.items() if k.startswith(stem + "_b64_")]
    if bm or bf:
        print("| (black) | %s | | | %s | %s | | -100 |" % (stem, "%.4f" % bf[0] if bf else "—", "%.4f" % bm[0] if bm else "—"))
    if "cssm" in sel and "trace" in sel:
        c, t = sel["cssm"], sel["trace"]
        e = pair_relmse(d, c, t, measure)
        print("\nBetween them: relMSE(cssm image, trace image) %s; mean luminance cssm against trace %+.2f %% "
              "(from the two differences to the matched reference); relMSE cssm / trace against it %.3f" % (
                  "%.4f" % e if e is not None else "— (not measured: tables.py --measure where the EXRs are)",
                  100 * ((1 + num(c, "mean_lum_diff_pct_matched") / 100) / (1 + num(t, "mean_lum_diff_pct_matched") / 100) - 1),
                  num(c, "relmse_matched") / num(t, "relmse_matched")))


def atlas_use(ok):
    """Sec. 4.1's atlases: the share of texels the charts use, and the U room's compression."""
    print("\n## Atlas use and the U room's compression\n")
    print("| scene | atlas | texels | share of the atlas (%) | compression |")
    print("|---|---|---|---|---|")
    seen = set()
    for r in ok:
        p = params(r)
        lab = r["label"]
        if not ((lab == "table2" and p.get("traversal") == "spiral") or (lab == "table1" and "u_room" in r["scene"])):
            continue
        key = (r["scene"], p.get("atlas"))
        if key in seen:
            continue
        seen.add(key)
        a = int(p["atlas"])
        print("| %s | %d² | %d | %.0f | %.1f : 1 |" % (os.path.basename(r["scene"]), a, num(r, "stat_atlas_texels"),
                                                     100 * num(r, "stat_atlas_texels") / (a * a),
                                                     num(r, "stat_compression_ratio")))


def motion_table(ok):
    """Sec. 3.3, moving objects: the update's per-frame cost beside the still scene."""
    by = {r["label"]: r for r in ok}
    names = [n for n in ("moving", "moving_still", "hull_intrusion", "moving2") if n in by]
    if not names:
        return
    stages = ["bounce", "direct", "hierarchy", "hull", "motion"]
    print("\n## Sec. 3.3: moving objects, per-frame update against the still scene\n")
    print("| run | frames | frame (median, ms) | " + " | ".join("%s (ms)" % s for s in stages) + " | prepare (s) |")
    print("|---|---|---|" + "---|" * len(stages) + "---|")
    for n in names:
        r = by[n]
        cells = ["%.3g" % num(r, "stage_%s_ms_median" % s) if r.get("stage_%s_ms_median" % s) else "—" for s in stages]
        print("| %s | %s | %.1f | %s | %.1f |" % (n, r["frames"], num(r, "frame_ms_median"), " | ".join(cells),
                                                num(r, "prepare_ms") * 1e-3))
    if "moving" in by and "moving_still" in by:
        print("\nFrame of the moving scene over the still one: %.2f x" %
              (num(by["moving"], "frame_ms_median") / num(by["moving_still"], "frame_ms_median")))


if __name__ == "__main__":
    main()

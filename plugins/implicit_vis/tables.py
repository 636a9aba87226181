#!/usr/bin/env python3
"""Tables of the implicit_vis study next to the paper's numbers.

Reads DIR/runs.csv written by
    gibench study plugins/implicit_vis/study.json --out DIR
and prints Markdown to stdout: Table 1 (per-stage times at 6x8x8, 6x12x12,
6x16x16 bins beside the paper's), the images against the path-traced
references with the equal-error speed-ups (Fig. 9/10), hierarchical against
brute-force links (Fig. 10 b/c), the re-meshed teapot (Fig. 10 d), the
area-light shadows as N grows (Fig. 7; each error column names its
reference), the O(N log N) sweep with its fitted exponents, the moving and
deforming scenes, and the GPU gather against the CPU one. Stdlib only.

Usage: plugins/implicit_vis/tables.py DIR > DIR/tables.md
"""

import csv
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from study_tables import fit_exponent, num  # noqa: E402

# The bounce-matched reference of each method: its declared bounce count + 1
# (implicit_vis declares 3, direct 0; docs/studies.md), the study's b4 and b1.
MATCHED_BOUNCES = {"implicit_vis": 4, "direct": 1}

STAGES = ("update_elements", "create_links", "refine_push", "illumination", "display")

# Paper, Table 1 (NVIDIA 8800, the monster, 1 bounce): ms (share of the frame) at N = 8 / 12 / 16.
PAPER_T1 = {
    "update_elements": "12 (6 %) / 12 (8 %) / 12 (11 %)",
    "create_links": "23 (21 %) / 43 (29 %) / 78 (38 %)",
    "refine_push": "30 (29 %) / 35 (24 %) / 60 (30 %)",
    "illumination": "35 (35 %) / 40 (28 %) / 48 (24 %)",
    "display": "(in the total)",
    "frame": "112 / 148 / 218",
    "ratio": "1 / 1.32 / 1.95",
}


def params(s):
    out = {}
    for kv in (s or "").split(","):
        if "=" in kv:
            k, v = kv.split("=", 1)
            out[k] = v
    return out


def load_runs(d):
    """runs.csv rows that finished, with their parameters parsed."""
    with open(os.path.join(d, "runs.csv"), newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["status"] == "ok"]
    for r in rows:
        r["p"] = params(r["params"])
        r["scene_name"] = os.path.splitext(os.path.basename(r["scene"]))[0]
    return rows


def stage(r, name):
    return num(r.get("stage_" + name + "_ms_median"))


def fmt(x, nd=3):
    """x to nd significant digits (fixed notation from 0.001 up)."""
    if x is None:
        return "–"
    if x == 0:
        return "0"
    if abs(x) >= 10 ** nd:
        return f"{x:.0f}"
    if abs(x) < 1e-3:
        return f"{x:.{nd}g}"
    dec = max(0, nd - 1 - int(math.floor(math.log10(abs(x)))))
    return f"{x:.{dec}f}"


def pct(x, nd=1):
    return "–" if x is None else f"{x:+.{nd}f}"




def ratio(a, b):
    return a / b if a is not None and b else None


def table1(out, runs):
    t1 = sorted((r for r in runs if r["label"] == "table1"), key=lambda r: int(r["p"].get("N", 0)))
    out.append("## Table 1: per-stage times (bunny on a ground plane, environment map, 1 bounce)\n")
    if not t1:
        out.append("No run labelled table1 in runs.csv.\n")
        return
    base = num(t1[0]["frame_ms_median"])
    out.append("Median of the timed frames, ms (share of the frame). Paper: NVIDIA 8800, the monster model.\n")
    out.append("| stage | " + " | ".join("6×{0}×{0}".format(r["p"]["N"]) for r in t1) + " | paper 8 / 12 / 16 |")
    out.append("|---|" + "---:|" * len(t1) + "---|")
    for s in STAGES:
        cells = []
        for r in t1:
            v, f = stage(r, s), num(r["frame_ms_median"])
            cells.append(f"{fmt(v)} ms ({fmt(100 * v / f, 2)} %)" if v is not None and f else "–")
        paper = PAPER_T1[s] + ("" if s == "display" else " ms")
        out.append(f"| {s} | " + " | ".join(cells) + f" | {paper} |")
    out.append("| **frame** | " + " | ".join(f"**{fmt(num(r['frame_ms_median']))} ms**" for r in t1)
               + f" | {PAPER_T1['frame']} ms |")
    out.append("| frame ratio to the first | " + " | ".join(fmt(ratio(num(r["frame_ms_median"]), base))
                                                     for r in t1) + f" | {PAPER_T1['ratio']} |")
    out.append("| link tries / leaf links (M) | " + " | ".join(
        f"{fmt(num(r['stat_link_tries']) / 1e6)} / {fmt(num(r['stat_leaf_links']) / 1e6)}" for r in t1) + " | – |")
    out.append("| relMSE (64-bounce) / image mean (%) | " + " | ".join(
        f"{fmt(num(r['relmse_full']))} / {pct(num(r['mean_lum_diff_pct_full']))}" for r in t1)
        + " | \"minor differences\" |")
    first, last = t1[0], t1[-1]
    out.append("\nGrowth from N = {} to N = {}: frame ×{}, create_links ×{}, illumination ×{} "
               "(paper: frame ×{}, create_links ×{}, illumination ×{}).\n".format(
                   first["p"]["N"], last["p"]["N"], fmt(ratio(num(last["frame_ms_median"]), num(first["frame_ms_median"]))),
                   fmt(ratio(stage(last, "create_links"), stage(first, "create_links"))),
                   fmt(ratio(stage(last, "illumination"), stage(first, "illumination"))),
                   fmt(218 / 112), fmt(78 / 23), fmt(48 / 35)))
    out.append("Scene: {} elements, {} hierarchy nodes, {} segments.\n".format(
        int(num(first["stat_elements"])), int(num(first["stat_nodes"])), int(num(first["stat_segments"]))))


def against_pt(out, runs):
    out.append("## Against the path tracer (Fig. 9/10) and the equal-error speed-ups\n")
    out.append("64-bounce = the study's full reference (256 spp, 64 bounces); matched = the bounce-matched reference "
               "(256 spp, the method's declared bounce count + 1: 4 bounces for implicit_vis whatever its `bounces`, "
               "1 for `direct`). Speed-up = the path tracer's time to the same relMSE ÷ the method's time to its "
               "image (runs.csv's `speedup_vs_pt` and `speedup_vs_pt_matched`; report.md marks the extrapolated "
               "ones).\n")
    out.append("| label | scene | method | params | relMSE 64-bounce | mean 64-bounce (%) | matched reference | "
               "relMSE matched | mean matched (%) | FLIP 64-bounce | time to image (s) | display (ms) | "
               "speed-up 64-bounce | speed-up matched |")
    out.append("|---|---|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for r in runs:
        if num(r.get("relmse_full")) is None:
            continue
        p = r["p"]
        ps = ",".join(f"{k}={p[k]}" for k in ("N", "bounces", "links", "remesh", "bilinear", "coverage", "illum")
                      if k in p) if r["method"] == "implicit_vis" else "–"
        mb = MATCHED_BOUNCES.get(r["method"])
        out.append("| {} | {} | {} | `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
            r["label"], r["scene_name"], r["method"], ps, fmt(num(r["relmse_full"])),
            pct(num(r["mean_lum_diff_pct_full"])), f"{mb}-bounce" if mb else "?", fmt(num(r["relmse_matched"])),
            pct(num(r["mean_lum_diff_pct_matched"])), fmt(num(r["flip_full"])),
            fmt(num(r["time_to_final_error_s"])), fmt(stage(r, "display")),
            fmt(num(r["speedup_vs_pt"]), 2), fmt(num(r["speedup_vs_pt_matched"]), 2)))
    out.append("")


def hier_brute(out, runs):
    f10 = {r["p"].get("links"): r for r in runs if r["label"] == "fig10"}
    out.append("## Hierarchical against brute-force links (Fig. 10 b/c)\n")
    if "hierarchical" not in f10 or "brute" not in f10:
        out.append("No pair of fig10 runs (hierarchical, brute) in runs.csv.\n")
        return
    h, b = f10["hierarchical"], f10["brute"]
    out.append("{}, N = {}, {} bounces, same run.\n".format(h["scene_name"], h["p"]["N"], h["p"]["bounces"]))
    out.append("| links | create_links (ms) | frame (ms) | pair tries (M) | leaf links (M) | relMSE 64-bounce | "
               "mean 64-bounce (%) | relMSE 4-bounce | mean 4-bounce (%) |")
    out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, r in (("hierarchical", h), ("brute force", b)):
        out.append("| {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
            name, fmt(stage(r, "create_links")), fmt(num(r["frame_ms_median"])), fmt(num(r["stat_link_tries"]) / 1e6),
            fmt(num(r["stat_leaf_links"]) / 1e6), fmt(num(r["relmse_full"])), pct(num(r["mean_lum_diff_pct_full"])),
            fmt(num(r["relmse_matched"])), pct(num(r["mean_lum_diff_pct_matched"]))))
    out.append("\nBrute force ÷ hierarchical: create_links ×{}, frame ×{}, pair tries ×{}, leaf links ×{}.\n".format(
        fmt(ratio(stage(b, "create_links"), stage(h, "create_links")), 2),
        fmt(ratio(num(b["frame_ms_median"]), num(h["frame_ms_median"])), 2),
        fmt(ratio(num(b["stat_link_tries"]), num(h["stat_link_tries"])), 2),
        fmt(ratio(num(b["stat_leaf_links"]), num(h["stat_leaf_links"])), 3)))


def weights(out, runs):
    out.append("## Fig. 10: a link's weight, Eq. 5 as printed against the earlier default and the remedy\n")
    out.append("The Cornell box of Fig. 10 with the default `weight=eq5` (the `fig10` hierarchical run), the default "
               "before issue 28 (`weight=bin splat=true`) and the remedy's weight (`weight=surface splat=true`), "
               "N = 12, 3 bounces (plugin README, \"Weights\").\n")
    rows = [r for r in runs if r["label"] == "fig10" and r["p"].get("links") == "hierarchical"]
    rows += sorted((r for r in runs if r["label"] == "fig10_weights"), key=lambda r: r["p"].get("weight", ""))
    if not any(r["label"] == "fig10_weights" for r in rows):
        out.append("No run labelled fig10_weights in runs.csv (the study predates the entry).\n")
        return
    out.append("| weight | splat | relMSE 64-bounce | mean 64-bounce (%) | relMSE 4-bounce | mean 4-bounce (%) | frame (ms) |")
    out.append("|---|---|---:|---:|---:|---:|---:|")
    for r in rows:
        out.append("| {} | {} | {} | {} | {} | {} | {} |".format(
            r["p"].get("weight", "eq5 (default)"), r["p"].get("splat", "false"), fmt(num(r["relmse_full"])),
            pct(num(r["mean_lum_diff_pct_full"])), fmt(num(r["relmse_matched"])),
            pct(num(r["mean_lum_diff_pct_matched"])), fmt(num(r["frame_ms_median"]))))
    out.append("")


def fig10d(out, runs):
    out.append("## Fig. 10(d): the 792-vertex teapot as it is and re-meshed\n")
    rows = [r for r in runs if r["label"] in ("fig10d", "fig10d_grid")]
    out.append("| label | remesh | remesher | discs | relMSE 64-bounce | mean 64-bounce (%) | frame (s) |")
    out.append("|---|---:|---|---:|---:|---:|---:|")
    for r in rows:
        rem = r["p"].get("remesh", "0")
        out.append("| {} | {} | {} | {} | {} | {} | {} |".format(
            r["label"], rem, r["p"].get("remesher", "–" if rem == "0" else "not recorded (the run predates `remesher`)"),
            int(num(r["stat_elements"])), fmt(num(r["relmse_full"]), 4), pct(num(r["mean_lum_diff_pct_full"])),
            fmt(num(r["frame_ms_median"]) / 1000, 2)))
    if not any(r["label"] == "fig10d_grid" for r in rows):
        out.append("\nNo run labelled fig10d_grid in runs.csv (the study predates the entry).")
    out.append("")


def fig7(out, runs):
    out.append("## Fig. 7: area-light shadows as N grows (teapot_area, direct light only)\n")
    out.append("The study has no 1-bounce (direct light) reference for this scene: the errors are against its 64-bounce "
               "reference and its 4-bounce one (implicit_vis's bounce-matched reference); with `bounces=0` the method "
               "computes direct light only and misses the indirect light against both.\n")
    rows = sorted((r for r in runs if r["label"] in ("fig7", "fig7_links")),
                  key=lambda r: (r["label"], int(r["p"].get("N", 0)), r["p"].get("coverage", "")))
    out.append("| label | N | bilinear | coverage | relMSE 64-bounce | mean 64-bounce (%) | relMSE 4-bounce | "
               "mean 4-bounce (%) | frame (ms) |")
    out.append("|---|---:|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        p = r["p"]
        out.append("| {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
            r["label"], p.get("N"), p.get("bilinear"), p.get("coverage"), fmt(num(r["relmse_full"])),
            pct(num(r["mean_lum_diff_pct_full"])), fmt(num(r["relmse_matched"])),
            pct(num(r["mean_lum_diff_pct_matched"])), fmt(num(r["frame_ms_median"]))))
    d = next((r for r in rows if r["label"] == "fig7" and r["p"].get("N") == "12"), None)
    for r in rows:
        if r["label"] == "fig7_links" and d is not None:
            out.append("\nN = 12, `coverage={}` against the default: relMSE 64-bounce ÷{}.".format(
                r["p"].get("coverage"), fmt(ratio(num(d["relmse_full"]), num(r["relmse_full"])), 3)))
    out.append("")


def scaling(out, runs):
    out.append("## O(N log N) (§5): time against surface elements\n")
    rows = sorted((r for r in runs if r["label"] == "scaling"), key=lambda r: num(r["stat_elements"]))
    if not rows:
        out.append("No run labelled scaling in runs.csv.\n")
        return
    out.append("{}, N = {}, {} bounce, re-meshed to each size.\n".format(
        rows[0]["scene_name"], rows[0]["p"]["N"], rows[0]["p"]["bounces"]))
    out.append("| remesh | discs | create_links (ms) | illumination (ms) | display (ms) | frame (ms) | pair tries (M) | "
               "leaf links (M) |")
    out.append("|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        out.append("| {} | {} | {} | {} | {} | {} | {} | {} |".format(
            r["p"].get("remesh"), int(num(r["stat_elements"])), fmt(stage(r, "create_links")),
            fmt(stage(r, "illumination")), fmt(stage(r, "display")), fmt(num(r["frame_ms_median"])),
            fmt(num(r["stat_link_tries"]) / 1e6), fmt(num(r["stat_leaf_links"]) / 1e6)))
    n = [num(r["stat_elements"]) for r in rows]
    out.append("\nLeast-squares exponents e of y ∝ n^e (n = discs), log-log:\n")
    out.append("| y | e |")
    out.append("|---|---:|")
    for name, ys in (("create_links", [stage(r, "create_links") for r in rows]),
                     ("illumination", [stage(r, "illumination") for r in rows]),
                     ("frame", [num(r["frame_ms_median"]) for r in rows]),
                     ("pair tries", [num(r["stat_link_tries"]) for r in rows]),
                     ("leaf links", [num(r["stat_leaf_links"]) for r in rows]),
                     ("n log n (for comparison)", [x * math.log(x) for x in n])):
        out.append(f"| {name} | {fmt(fit_exponent(n, ys))} |")
    out.append("")


def moving(out, runs):
    out.append("## Moving and deforming objects (links rebuilt every frame)\n")
    rows = [r for r in runs if r["label"] == "moving"]
    out.append("| scene | N | bounces | frames | discs | frame (ms) | create_links (ms) | update_elements (ms) | "
               "illumination (ms) |")
    out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        out.append("| {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
            r["scene_name"], r["p"]["N"], r["p"]["bounces"], r["frames"], int(num(r["stat_elements"])),
            fmt(num(r["frame_ms_median"])), fmt(stage(r, "create_links")), fmt(stage(r, "update_elements"), 2),
            fmt(stage(r, "illumination"))))
    out.append("")


def gpu_cpu(out, runs):
    out.append("## Gathering on the GPU against the CPU (§4.3.1; labels illum and flicker, same run)\n")
    out.append("| label | scene | illum | frames | leaf links (M) | illumination (ms) | create_links (ms) | display (ms) | "
               "frame (ms) | relMSE 64-bounce | mean 64-bounce (%) |")
    out.append("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    pairs = {}
    for r in runs:
        if r["label"] not in ("illum", "flicker"):
            continue
        pairs.setdefault((r["label"], r["scene"]), {})[r["p"].get("illum")] = r
        out.append("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
            r["label"], r["scene_name"], r["p"].get("illum"), r["frames"], fmt(num(r["stat_leaf_links"]) / 1e6),
            fmt(stage(r, "illumination")),
            fmt(stage(r, "create_links")), fmt(stage(r, "display")), fmt(num(r["frame_ms_median"])),
            fmt(num(r["relmse_full"]), 6), pct(num(r["mean_lum_diff_pct_full"]), 4)))
    out.append("\n| label | scene | illumination CPU ÷ GPU | illumination GPU ÷ CPU | frame CPU ÷ GPU |")
    out.append("|---|---|---:|---:|---:|")
    for (label, scene), m in pairs.items():
        if "gpu" in m and "cpu" in m:
            out.append("| {} | {} | {} | {} | {} |".format(
                label, os.path.splitext(os.path.basename(scene))[0],
                fmt(ratio(stage(m["cpu"], "illumination"), stage(m["gpu"], "illumination")), 2),
                fmt(ratio(stage(m["gpu"], "illumination"), stage(m["cpu"], "illumination")), 2),
                fmt(ratio(num(m["cpu"]["frame_ms_median"]), num(m["gpu"]["frame_ms_median"])), 2)))
    out.append("")


def main():
    if len(sys.argv) != 2:
        print("usage: plugins/implicit_vis/tables.py DIR > DIR/tables.md", file=sys.stderr)
        return 2
    d = sys.argv[1]
    if not os.path.isfile(os.path.join(d, "runs.csv")):
        print(f"implicit_vis/tables.py: {d}/runs.csv: no such file", file=sys.stderr)
        return 2
    runs = load_runs(d)
    renderer = runs[0]["renderer"] if runs else "?"
    timer = runs[0]["timer"] if runs else "?"
    out = ["# implicit_vis study tables\n",
           f"Made by `plugins/implicit_vis/tables.py results/implicit_vis` from runs.csv. GL renderer: {renderer}; "
           f"timer: {timer} (CPU time of the process, llvmpipe's threads included). Times are only comparable as "
           f"ratios within this study. {len(runs)} runs.\n"]
    for part in (table1, against_pt, hier_brute, weights, fig10d, fig7, scaling, moving, gpu_cpu):
        part(out, runs)
    print("\n".join(out).rstrip("\n"))
    return 0


if __name__ == "__main__":
    sys.exit(main())

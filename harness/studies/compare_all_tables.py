#!/usr/bin/env python3
"""The five-way comparison's summary tables (issue 18).

Reads DIR/runs.csv written by
    gibench study harness/studies/compare_all.json --out DIR
and prints Markdown to stdout:
  - per method and scene, its most accurate setting's relMSE against the
    full-GI reference, next to the unshadowed direct baseline's (the
    trivial answer every method must beat), or why the method cannot
    render the scene (its caps);
  - per method and scene, its best equal-error speed-up over the path
    tracer (the path tracer's time to the method's error / the method's
    time to its image; precomputation excluded, as in the study's own
    equal-error tables);
  - per scene, each method's most accurate setting in full: error against
    the full-GI and the bounce-matched reference, time to image, speed-ups,
    precomputation time and memory in their own columns.
The per-scene Pareto fronts, equal-error and equal-time tables and charts
are in DIR/report.md (written by the study itself). Stdlib only; runs from
the committed runs.csv alone.

With --size-dir (repeatable), the same comparison at other image sizes
(compare_all_128.json, compare_all_256.json, each its own invocation and so
its own path-tracer clock) is set beside DIR's: per method and scene the
best equal-error speed-up at each size, over the settings every size ran,
with its spread over the path tracer's repeated curve points; --chart
draws it as an SVG, one panel per method, one line per scene; tables.md
links it by its file name, as a file beside it in DIR (the test writes it
elsewhere and compares it with the committed one).

Usage: harness/studies/compare_all_tables.py DIR [--size-dir DIR2]...
                                                 [--chart FILE.svg] > DIR/tables.md
"""

import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from study_tables import fmt, load_references, load_runs_csv, load_trivial, matrix, num, scene_name  # noqa: E402

METHODS = ["csm", "cssm_hrc", "avg", "implicit_vis", "vlf", "direct"]
PAPER = {
    "csm": "CSM (Ritschel et al. 2007)",
    "cssm_hrc": "CSSM+HRC (Ritschel et al. 2008)",
    "avg": "AVG (Bashford-Rogers et al. 2011)",
    "implicit_vis": "implicit visibility (Dong et al. 2007)",
    "vlf": "VLF (Mortensen et al. 2007)",
    "direct": "unshadowed direct (baseline)",
}


def memory_cells(row):
    """The method's own data (stat data_bytes) and the render process's
    peak resident memory, MiB; "–" where not measured."""
    data = num(row.get("data_bytes"))
    return fmt(None if data is None else data / 2**20, "%.3g"), fmt(num(row.get("peak_rss_mib")), "%.3g")


def with_prep(r):
    """Speed-up over the path tracer with precomputation paid once."""
    sp, t, prep = num(r.get("speedup_vs_pt")), num(r.get("time_to_final_error_s")), num(r.get("prepare_ms"))
    if sp is None or t is None or prep is None or t + prep / 1000.0 <= 0:
        return None
    return sp * t / (t + prep / 1000.0)


def spread(r, prep):
    """The speed-up's spread over the path tracer's repeated curve points,
    (min, max), scaled like with_prep when prep; None when not measured."""
    lo, hi, sp = num(r.get("speedup_vs_pt_min")), num(r.get("speedup_vs_pt_max")), num(r.get("speedup_vs_pt"))
    if lo is None or hi is None or not sp:
        return None
    k = with_prep(r) / sp if prep else 1.0
    return lo * k, hi * k


def speedup_cell(r, prep):
    """A speed-up, with its spread "(min–max)" where the study repeated the
    path tracer's curve, and "*" where the path tracer's time is
    extrapolated outside its measured convergence curve."""
    v = with_prep(r) if prep else num(r["speedup_vs_pt"])
    sp = spread(r, prep)
    return "%.3g%s%s" % (v, " (%.3g–%.3g)" % sp if sp and sp[1] > sp[0] else "",
                         "*" if num(r.get("speedup_extrapolated")) == 1 else "")


def size_of(rows):
    """The one image size of a study's runs, as "WxH"."""
    sizes = sorted({"%sx%s" % (r["width"], r["height"]) for r in rows if r.get("width")})
    if len(sizes) != 1:
        sys.exit("compare_all_tables.py: expected one image size per study, found %s" % (sizes or "none"))
    return sizes[0]


def setting(r):
    """A run's setting: its method and parameters without the label."""
    return (r["method"], r["params"].split(",label=")[0])


def short_setting(r, varying):
    """The parameters of a run that vary over its method's runs, "k=v,..."."""
    kv = [p.split("=", 1) for p in setting(r)[1].split(",") if "=" in p]
    return ",".join("%s=%s" % (k, v) for k, v in kv if k in varying.get(r["method"], ())) or "defaults"


def varying_keys(studies):
    """method -> the parameter names whose values differ between its runs."""
    seen = {}
    for _, rows in studies:
        for r in rows:
            for p in setting(r)[1].split(","):
                if "=" in p:
                    k, v = p.split("=", 1)
                    seen.setdefault(r["method"], {}).setdefault(k, set()).add(v)
    return {m: {k for k, vs in d.items() if len(vs) > 1} for m, d in seen.items()}


def by_size(studies):
    """studies: [(size, rows)]. Per (method, scene): at each size the run
    with the best equal-error speed-up among the settings every size ran
    for that method and scene."""
    common = None
    for _, rows in studies:
        have = {(setting(r), scene_name(r["scene"])) for r in rows
                if r["status"] == "ok" and num(r.get("speedup_vs_pt")) is not None}
        common = have if common is None else common & have
    out = {}
    for size, rows in studies:
        for r in rows:
            s = scene_name(r["scene"])
            if (setting(r), s) not in common or r["status"] != "ok" or num(r.get("speedup_vs_pt")) is None:
                continue
            key = (r["method"], s)
            cur = out.setdefault(key, {}).get(size)
            if cur is None or num(r["speedup_vs_pt"]) > num(cur["speedup_vs_pt"]):
                out[key][size] = r
    return out


def svg_chart(path, sizes, table, methods, scenes):
    """Speed-up against image size: a panel per method (log-log), a line
    per scene, the spread as a vertical bar at each point."""
    pw, ph, m = 300, 220, 46
    cols = 3
    rows_n = (len(methods) + cols - 1) // cols
    colours = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
               "#7f7f7f", "#bcbd22", "#17becf", "#000000", "#aec7e8"]
    vals = [v for key in table for r in table[key].values()
            for v in (num(r.get("speedup_vs_pt")), num(r.get("speedup_vs_pt_min")), num(r.get("speedup_vs_pt_max")))
            if v is not None and v > 0]
    if not vals:
        sys.exit("compare_all_tables.py: no speed-ups to draw")
    lo, hi = math.floor(math.log10(min(vals))), math.ceil(math.log10(max(vals)))
    hi = max(hi, lo + 1)
    px = [int(z.split("x")[0]) for z in sizes]
    x0, x1 = math.log2(min(px)), math.log2(max(px))
    x1 = max(x1, x0 + 1)
    legend_h = 16 * ((len(scenes) + 3) // 4) + 10
    W, H = cols * (pw + m) + m, rows_n * (ph + m) + m + legend_h
    o = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" '
         'font-size="11"><rect width="100%%" height="100%%" fill="white"/>' % (W, H)]
    for i, meth in enumerate(methods):
        ox, oy = m + (i % cols) * (pw + m), m + (i // cols) * (ph + m)
        X = lambda z: ox + (math.log2(z) - x0) / (x1 - x0) * pw  # noqa: E731
        Y = lambda v: oy + ph - (math.log10(v) - lo) / (hi - lo) * ph  # noqa: E731
        o.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#888"/>' % (ox, oy, pw, ph))
        o.append('<text x="%d" y="%d" font-weight="bold">%s</text>' % (ox, oy - 6, meth))
        for e in range(lo, hi + 1):
            y = Y(10.0 ** e)
            o.append('<line x1="%d" x2="%d" y1="%.1f" y2="%.1f" stroke="#ddd"/>' % (ox, ox + pw, y, y))
            o.append('<text x="%d" y="%.1f" text-anchor="end">1e%d</text>' % (ox - 4, y + 4, e))
        y1 = Y(1.0)
        o.append('<line x1="%d" x2="%d" y1="%.1f" y2="%.1f" stroke="#888" stroke-dasharray="4"/>' % (ox, ox + pw, y1, y1))
        for z in px:
            o.append('<text x="%.1f" y="%d" text-anchor="middle">%d²</text>' % (X(z), oy + ph + 14, z))
        for j, s in enumerate(scenes):
            pts = [(int(z.split("x")[0]), table.get((meth, s), {}).get(z)) for z in sizes]
            pts = [(z, r) for z, r in pts if r is not None and num(r.get("speedup_vs_pt"))]
            c = colours[j % len(colours)]
            if len(pts) > 1:
                o.append('<polyline fill="none" stroke="%s" points="%s"/>' % (c, " ".join(
                    "%.1f,%.1f" % (X(z), Y(num(r["speedup_vs_pt"]))) for z, r in pts)))
            for z, r in pts:
                o.append('<circle cx="%.1f" cy="%.1f" r="2.5" fill="%s"/>' % (X(z), Y(num(r["speedup_vs_pt"])), c))
                a, b = num(r.get("speedup_vs_pt_min")), num(r.get("speedup_vs_pt_max"))
                if a and b:
                    o.append('<line x1="%.1f" x2="%.1f" y1="%.1f" y2="%.1f" stroke="%s"/>' % (X(z), X(z), Y(a), Y(b), c))
    ly = rows_n * (ph + m) + m
    o.append('<text x="%d" y="%d">Equal-error speed-up over path tracing (log) against image size; '
             'dashed: 1; bars: spread over the path tracer\'s repeated curve points.</text>' % (m, ly - 8))
    for j, s in enumerate(scenes):
        x, y = m + (j % 4) * 230, ly + 10 + 16 * (j // 4)
        o.append('<line x1="%d" x2="%d" y1="%d" y2="%d" stroke="%s" stroke-width="3"/>'
                 '<text x="%d" y="%d">%s</text>' % (x, x + 18, y, y, colours[j % len(colours)], x + 22, y + 4, s))
    o.append("</svg>")
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        fh.write("\n".join(o) + "\n")
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(prog="compare_all_tables.py")
    ap.add_argument("dir")
    ap.add_argument("--size-dir", action="append", default=[])
    ap.add_argument("--chart")
    a = ap.parse_args()
    d = a.dir

    def load(dd):
        try:
            got = load_runs_csv(dd)
        except OSError as e:
            sys.exit("compare_all_tables.py: %s" % e)
        if not got:
            sys.exit("compare_all_tables.py: %s/runs.csv has no runs" % dd)
        return got
    rows = load(d)
    others = [load(dd) for dd in a.size_dir]
    # The samples per pixel of the path tracer's measured curve, from the
    # study's pt_curves.csv (each size's study sets its own).
    curve_spp = []
    try:
        with open(os.path.join(d, "pt_curves.csv"), newline="") as f:
            curve_spp = sorted({int(r["spp"]) for r in csv.DictReader(f) if r.get("spp", "").isdigit()})
    except OSError:
        pass
    curve_range = ("%d to %d samples per pixel" % (curve_spp[0], curve_spp[-1]) if curve_spp
                   else "the study's `convergence_spp`")
    if a.chart and not others:
        sys.exit("compare_all_tables.py: --chart needs at least one --size-dir")

    scenes = []
    for r in rows:
        s = scene_name(r["scene"])
        if s not in scenes:
            scenes.append(s)
    methods = [m for m in METHODS if any(r["method"] == m for r in rows)]
    methods += sorted({r["method"] for r in rows} - set(methods))

    ok = {}   # (method, scene) -> runs with status ok and an error
    na = {}   # (method, scene) -> reason
    for r in rows:
        key = (r["method"], scene_name(r["scene"]))
        if r["status"] == "ok" and num(r.get("relmse_full")) is not None:
            ok.setdefault(key, []).append(r)
        elif r["status"] != "ok":
            reason = r.get("reason", "")
            na.setdefault(key, reason if reason.startswith(r["status"]) else "%s: %s" % (r["status"], reason))

    shown = os.path.relpath(d)
    renderers = sorted({r["renderer"] for r in rows if r.get("renderer")})
    timers = sorted({r["timer"] for r in rows if r.get("timer")})
    sizes = sorted({"%sx%s" % (r["width"], r["height"]) for r in rows if r.get("width")})
    out = []
    w = out.append
    w("# The five-way comparison: summary\n")
    w("Made by `harness/studies/compare_all_tables.py %s` from `runs.csv` of "
      "`gibench study harness/studies/%s --out %s --jobs 1`. "
      "GL renderer: %s; timer: %s; image size %s. Lower relMSE is better. "
      "The per-scene Pareto fronts, equal-error and equal-time tables and "
      "the error-against-time charts are in [report.md](report.md).\n"
      % (shown, "compare_all.json" if sizes == ["64x64"] else "compare_all_%s.json" % sizes[0].split("x")[0]
         if len(sizes) == 1 else "?", shown, ", ".join(renderers) or "?", ", ".join(timers) or "?", ", ".join(sizes)))

    def best(key):
        runs = ok.get(key)
        if not runs:
            return None
        return min(runs, key=lambda r: num(r["relmse_full"]))

    # 1. best error per method and scene, with the trivial answers' beside it
    refs, trivial = load_references(d), load_trivial(d)

    def black(s):
        """The black image's relMSE against scene s's full-GI reference."""
        names = {refs[r["run"]][0] for r in rows if scene_name(r["scene"]) == s and r["run"] in refs}
        got = [trivial[n] for n in names if trivial.get(n) is not None]
        return got[0] if len(got) == 1 else None

    def trivial_best(s):
        """The better of the two trivial answers on scene s: the unshadowed
        direct baseline's best setting and the black image."""
        base = best(("direct", s))
        vals = [v for v in (num(base["relmse_full"]) if base else None, black(s)) if v is not None]
        return min(vals) if vals else None

    w("## Best relMSE against the full-GI reference\n")
    w("Each cell: the method's most accurate setting of its sweep. \"n/a\": "
      "its caps do not cover the scene (the reason is in the per-scene "
      "tables below). The trivial answers on the same reference: the "
      "unshadowed direct baseline (`direct`) and a black image (`black`, "
      "scored by `scripts/trivial_scores.py` into `trivial.csv`); relMSE "
      "weighs an over-bright pixel without bound and a black one at most 1, "
      "so black is hard to beat where a scene is mostly dim. **Bold**: not "
      "better than the better of the two.\n")

    def error_cell(m, s):
        if m == "black":
            return fmt(black(s))
        b = best((m, s))
        if b is None:
            return "n/a" if (m, s) in na else "–"
        e, t = num(b["relmse_full"]), trivial_best(s)
        return "**%.3g**" % e if m != "direct" and t is not None and not e < t else "%.3g" % e
    matrix(w, methods + (["black"] if trivial else []), scenes, error_cell)
    w("")

    # 2. best equal-error speed-up over the path tracer
    w("## Best equal-error speed-up over path tracing\n")
    w("Each cell: the largest speed-up over the method's sweep: the path "
      "tracer's time to the run's error, divided by the run's time to its "
      "image (the frames it needs; precomputation not included: see the "
      "per-scene tables). Below 1: path tracing reaches that error sooner. "
      "\"*\": the error (full or bounce-matched) lies outside the path "
      "tracer's measured curve (%s; report.md's \"Path tracer convergence\" "
      "lines), below its most "
      "converged image or above its least converged one, and the path "
      "tracer's time is extrapolated (slope -1 on log-log axes).\n" % curve_range)
    def speedup(m, s, prep):
        runs = [r for r in ok.get((m, s), []) if (with_prep(r) if prep else num(r.get("speedup_vs_pt"))) is not None]
        if not runs:
            return "n/a" if (m, s) in na else "–"
        return speedup_cell(max(runs, key=(with_prep if prep else lambda r: num(r["speedup_vs_pt"]))), prep)
    matrix(w, methods, scenes, lambda m, s: speedup(m, s, 0))
    w("")
    w("The same with the method's precomputation paid once: the path tracer's "
      "time to the run's error / (precompute + time to image). This is the "
      "speed-up for a single still image; the per-scene equal-error tables in "
      "report.md amortise precomputation over 100 and 10,000 images.\n")
    matrix(w, methods, scenes, lambda m, s: speedup(m, s, 1))
    w("")

    # 3. per scene, each method's most accurate setting
    w("## Per scene: each method's most accurate setting\n")
    w("Time to image: the sum of frame times up to the first frame within "
      "1 % of the final error. Precompute: `prepare` (in these runs "
      "csm and cssm_hrc, the methods that cache precomputation, run with `\"cache\": false`, so it is measured). Memory: the "
      "method's own data as it reports it (stat `data_bytes`, what it "
      "counts is in docs/measurement.md \"Memory\") and the render process's peak "
      "resident memory (on llvmpipe GPU buffers are process memory).\n")
    for s in scenes:
        w("### %s\n" % s)
        w("| method | params | relMSE full | relMSE matched | time to image (s) | "
          "speed-up | speed-up matched | precompute (s) | data (MiB) | peak RSS (MiB) |")
        w("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for m in methods:
            b = best((m, s))
            if b is None:
                if (m, s) in na:
                    w("| %s | %s | | | | | | | | |" % (m, na[(m, s)].replace("|", "/")))
                continue
            prep = num(b.get("prepare_ms"))
            w("| %s | `%s` | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                m, b["params"].split(",label=")[0], fmt(num(b["relmse_full"]), "%.4g"),
                fmt(num(b.get("relmse_matched")), "%.4g"), fmt(num(b.get("time_to_final_error_s")), "%.4g"),
                speedup_cell(b, 0) if num(b.get("speedup_vs_pt")) is not None else "–",
                fmt(num(b.get("speedup_vs_pt_matched"))),
                fmt(None if prep is None else prep / 1000.0, "%.3g"), *memory_cells(b)))
        w("")

    # 4. the same comparison at other sizes
    if others:
        studies = sorted([(size_of(rows), rows)] + [(size_of(o), o) for o in others],
                         key=lambda t: int(t[0].split("x")[0]))
        sizes = [z for z, _ in studies]
        if len(set(sizes)) != len(sizes):
            sys.exit("compare_all_tables.py: two studies at the same size %s" % sizes)
        table = by_size(studies)
        w("## Equal-error speed-up against image size\n")
        w("Each study (%s) is its own invocation: its path-tracer curve and its "
          "methods are timed together, never across studies. Each cell: the best "
          "speed-up at that size over the settings that every size ran for the "
          "method and scene, with its spread (min–max over the path tracer's "
          "repeated curve points) and its setting (the swept parameters); "
          "\"*\": extrapolated, as above.%s\n"
          % (", ".join("`%s` %s" % (os.path.relpath(dd), z) for dd, z in
                      sorted(zip([d] + a.size_dir, [size_of(rows)] + [size_of(o) for o in others]),
                             key=lambda t: int(t[1].split("x")[0]))),
             " Chart: [%s](%s)." % ((os.path.basename(a.chart),) * 2) if a.chart else ""))
        varying = varying_keys(studies)
        w("| method | scene | " + " | ".join(sizes) + " | setting at %s |" % sizes[-1])
        w("|---|---|" + "---:|" * len(sizes) + "---|")
        all_scenes = []
        for _, rr in studies:
            for r in rr:
                if scene_name(r["scene"]) not in all_scenes:
                    all_scenes.append(scene_name(r["scene"]))
        for m in methods:
            for s in all_scenes:
                got = table.get((m, s))
                if not got:
                    continue
                last = got.get(sizes[-1])
                w("| %s | %s | %s | `%s` |" % (m, s, " | ".join(
                    speedup_cell(got[z], 0) if z in got else "–" for z in sizes),
                    short_setting(last, varying) if last else "–"))
        w("")
        if a.chart:
            svg_chart(a.chart, sizes, table, [m for m in methods if any(k[0] == m for k in table)],
                      [s for s in all_scenes if any(k[1] == s for k in table)])
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()

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

Usage: harness/studies/compare_all_tables.py DIR > DIR/tables.md
"""

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


def speedup_cell(r, prep):
    """A speed-up, with "*" where the path tracer's time is extrapolated
    outside its measured convergence curve."""
    v = with_prep(r) if prep else num(r["speedup_vs_pt"])
    return "%.3g%s" % (v, "*" if num(r.get("speedup_extrapolated")) == 1 else "")


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: compare_all_tables.py DIR")
    d = sys.argv[1]
    try:
        rows = load_runs_csv(d)
    except OSError as e:
        sys.exit("compare_all_tables.py: %s" % e)
    if not rows:
        sys.exit("compare_all_tables.py: %s/runs.csv has no runs" % d)

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
      "`gibench study harness/studies/compare_all.json --out %s --jobs 1`. "
      "GL renderer: %s; timer: %s; image size %s. Lower relMSE is better. "
      "The per-scene Pareto fronts, equal-error and equal-time tables and "
      "the error-against-time charts are in [report.md](report.md).\n"
      % (shown, shown, ", ".join(renderers) or "?", ", ".join(timers) or "?", ", ".join(sizes)))

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
      "tracer's measured curve (4 to 256 samples per pixel), below its most "
      "converged image or above its least converged one, and the path "
      "tracer's time is extrapolated (slope -1 on log-log axes).\n")
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
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()

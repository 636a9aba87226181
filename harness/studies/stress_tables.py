#!/usr/bin/env python3
"""Stability and failure tables of the stress study (issue 18).

Reads DIR/runs.csv and DIR/runs.json written by
    gibench study harness/studies/stress.json --out DIR
and prints Markdown to stdout:
  - the scenes and what each isolates (from their glTF asset extras);
  - static cases: per method and scene, relMSE against the full-GI
    reference beside the unshadowed direct baseline's, the leaked energy
    beside the reference's own energy in the same dark pixels, and a
    verdict by the rules below;
  - animation: per method and scene, the per-frame relMSE (mean, max),
    median frame time, flicker and the references' noise floor, verdict;
  - scale: per method, the log-log exponents of frame time, precomputation,
    peak resident memory and the method's own data against the triangle
    count (scripts/scale_fit.py's least squares, 95 % intervals), and the
    papers' scaling claims (CLAIMS) against them.

Verdict rules (stated in the output too):
  fails     relMSE not below the direct baseline's on the same scene
            (the trivial answer; for animation the per-frame means);
  leaks     leaked energy above 1 % of the reference's total and above
            3x the reference's own energy in its dark pixels;
  flickers  flicker above 2x the noise floor of the references;
  degraded  relMSE at least half the baseline's;
  ok        none of these.
Several may apply; all are listed. Stdlib only; runs from the committed
runs.csv and runs.json alone.

Usage: harness/studies/stress_tables.py DIR > DIR/tables.md
"""

import json
import math
import os
import re
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from scale_fit import field, fit  # noqa: E402
from study_tables import fmt, load_references, load_runs_csv, load_trivial, matrix, num, scene_name  # noqa: E402

METHODS = ["direct", "csm", "cssm_hrc", "avg", "implicit_vis", "vlf"]
LEAK_SHARE = 0.01      # leaks: above 1 % of the reference's energy ...
LEAK_OVER_REF = 3.0    # ... and 3x the reference's own dark-pixel energy
FLICKER_OVER_FLOOR = 2.0
DEGRADED_SHARE = 0.5
# The papers' scaling claims, as a range of the log-log exponent of the
# stage where the claimed algorithm runs (implicit_vis: the frame, which
# updates the hierarchy and creates the links afresh; vlf: precomputation,
# the propagation). N log N over the sweep's range has a local exponent
# 1 + 1/ln N, 1.1 to 1.2 for N from 300 to 30,000.
CLAIMS = {
    ("implicit_vis", "frame_ms.median"): (1.0, 1.2, "O(N log N) in vertices (Dong et al. 2007, §5)"),
    ("vlf", "prepare_ms"): (1.0, 1.0, "propagation O(n) in polygons (Mortensen et al. 2007, §7)"),
}


def scene_purpose(path):
    """What the scene isolates, from its asset extras (gibench.isolates)."""
    try:
        with open(path, "rb") as fh:
            data = fh.read()
        if data[:4] == b"glTF":
            n = struct.unpack_from("<I", data, 12)[0]
            doc = json.loads(data[20:20 + n])
        else:
            doc = json.loads(data)
        return doc.get("asset", {}).get("extras", {}).get("gibench", {}).get("isolates", "")
    except (OSError, ValueError, struct.error):
        return ""


def reason(r):
    t = r.get("reason", "").replace("|", "/")
    return t if t.startswith(r["status"]) else "%s: %s" % (r["status"], t)


def verdict(e, base, leak=None, ref_leak=None, flicker=None, floor=None):
    if e is None:
        return "–"
    v = []
    if base is not None and not e < base:
        v.append("fails")
    if leak is not None and ref_leak is not None and leak > LEAK_SHARE and leak > LEAK_OVER_REF * ref_leak:
        v.append("leaks")
    if flicker is not None and floor is not None and flicker > FLICKER_OVER_FLOOR * floor:
        v.append("flickers")
    if base is not None and "fails" not in v and e >= DEGRADED_SHARE * base:
        v.append("degraded")
    return ", ".join(v) or "ok"


def fmt_range(lo, hi):
    return "%g" % lo if lo == hi else "%g–%g" % (lo, hi)


def ordered(names, preferred):
    return [m for m in preferred if m in names] + sorted(set(names) - set(preferred))


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: stress_tables.py DIR")
    d = sys.argv[1]
    try:
        rows = load_runs_csv(d)
        with open(os.path.join(d, "runs.json")) as fh:
            records = json.load(fh)
    except (OSError, ValueError) as e:
        sys.exit("stress_tables.py: %s" % e)
    if not rows or not isinstance(records, list):
        sys.exit("stress_tables.py: %s has no runs" % d)

    refs, trivial = load_references(d), load_trivial(d)
    by_run = {r.get("run"): r for r in records}

    def black(run, which):
        """The black image's relMSE against run's full-GI (which 0) or
        bounce-matched (1) reference; for an animated run the mean over its
        frames' references (named by scene time, as the study names them)."""
        name = refs.get(run, ("", ""))[which]
        if not name:
            return None
        times = ((by_run.get(run) or {}).get("animation") or {}).get("scene_time")
        if not times:
            return trivial.get(name)
        got = [trivial.get(re.sub(r"_t[-0-9.e+]+_b", "_t%g_b" % t, name, count=1)) for t in times]
        return sum(got) / len(got) if got and None not in got else None

    def judged(r, base, key_full, key_matched):
        """The error a run is judged on and the better trivial answer's on
        the same data (the direct baseline's, the black image's): full GI,
        or for a method whose bounce-matched reference is the baseline's own
        (direct light only) that reference."""
        which, mark = 0, ""
        if base is not None and base["status"] == "ok" and refs.get(r["run"]) and \
                refs[r["run"]][1] == refs.get(base["run"], ("", ""))[1]:
            which, mark = 1, "†"
        key = key_matched if which else key_full
        vals = [v for v in (num(base.get(key)) if base is not None and base["status"] == "ok" else None,
                            black(r["run"], which)) if v is not None]
        return num(r.get(key)), (min(vals) if vals else None), mark

    shown = os.path.relpath(d)
    out = []
    w = out.append
    renderers = sorted({r["renderer"] for r in rows if r.get("renderer")})
    timers = sorted({r["timer"] for r in rows if r.get("timer")})
    sizes = sorted({"%sx%s" % (r["width"], r["height"]) for r in rows if r.get("width")})
    w("# Stress study: stability and failure\n")
    w("Made by `harness/studies/stress_tables.py %s` from `runs.csv` and `runs.json` of "
      "`gibench study harness/studies/stress.json --out %s --jobs 1`. GL renderer: %s; "
      "timer: %s; image size %s. Each method runs at its defaults (the study file's "
      "entries). The report with every metric, the per-frame charts and the images "
      "is [report.md](report.md).\n" % (shown, shown, ", ".join(renderers) or "?",
                                         ", ".join(timers) or "?", ", ".join(sizes)))
    w("Verdicts: **fails**: relMSE not below the better of the trivial "
      "answers on the same reference, the unshadowed direct baseline and a "
      "black image (scored by `scripts/trivial_scores.py` into "
      "`trivial.csv`; relMSE weighs an over-bright pixel without bound and "
      "a black one at most 1); **leaks**: leaked energy above %g %% of the "
      "reference's total and above %gx the reference's own energy in its dark "
      "pixels; **flickers**: flicker above %gx the references' noise floor; "
      "**degraded**: relMSE at least %g of that; **ok**: none.\n"
      % (100 * LEAK_SHARE, LEAK_OVER_REF, FLICKER_OVER_FLOOR, DEGRADED_SHARE))

    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    w("## Scenes\n")
    w("| scene | triangles | what it isolates |")
    w("|---|---:|---|")
    for s in scenes:
        tri = next((r.get("scene_triangles") for r in rows if r["scene"] == s and r.get("scene_triangles")), "")
        w("| %s | %s | %s |" % (scene_name(s), tri, scene_purpose(s).replace("|", "/")))
    w("")

    def by_label(label):
        got = {}
        for r in rows:
            if r.get("label") == label:
                got[(r["method"], scene_name(r["scene"]))] = r
        return got

    # static cases
    st = by_label("static")
    if st:
        sc = ordered({s for _, s in st}, [scene_name(s) for s in scenes])
        methods = ordered({m for m, _ in st}, METHODS)

        w("## Static cases: relMSE against the full-GI reference\n")
        w("Each cell: relMSE against the full-GI reference (against the "
          "reference limited to the method's bounce count in brackets), then "
          "the verdict, judged on full GI, the data every method and the "
          "baseline share; †: judged on the bounce-matched reference instead, "
          "where it is the baseline's own (methods of direct light only, "
          "which full GI would fault for the indirect light they do not "
          "claim); \"n/a\": the method declines the scene (reason in the "
          "last table). The row `black` is the black image against the same "
          "references (in brackets: against the baseline's bounce-matched "
          "one, the data of the † verdicts).\n")

        def static_cell(m, s):
            if m == "black":
                base = st.get(("direct", s))
                if base is None:
                    return "–"
                return "%s (%s) trivial" % (fmt(black(base["run"], 0)), fmt(black(base["run"], 1)))
            r = st.get((m, s))
            if r is None:
                return "–"
            if r["status"] != "ok":
                return "n/a"
            if m == "direct":
                return "%s (%s) baseline" % (fmt(num(r.get("relmse_full"))), fmt(num(r.get("relmse_matched"))))
            e, be, mark = judged(r, st.get(("direct", s)), "relmse_full", "relmse_matched")
            v = verdict(e, be, num(r.get("leaked_energy_full")), num(r.get("dark_energy_ref_full")))
            return "%s (%s) %s%s" % (fmt(num(r.get("relmse_full"))), fmt(num(r.get("relmse_matched"))), v, mark)
        matrix(w, methods + (["black"] if trivial else []), sc, static_cell)
        w("")
        w("## Static cases: leaked energy\n")
        w("Each cell: the method's energy in the pixels the reference shows "
          "dark (below 1 % of its mean luminance), as a share of the "
          "reference's total / the reference's own energy there (its noise).\n")

        def leak_cell(m, s):
            r = st.get((m, s))
            if r is None or r["status"] != "ok":
                return "–" if r is None else "n/a"
            return "%s / %s" % (fmt(num(r.get("leaked_energy_full"))), fmt(num(r.get("dark_energy_ref_full"))))
        matrix(w, methods, sc, leak_cell)
        w("")
        declined = [(m, s, reason(r)) for (m, s), r in sorted(st.items()) if r["status"] != "ok"]
        if declined:
            w("Declined or failed static runs:\n")
            w("| method | scene | reason |")
            w("|---|---|---|")
            for m, s, t in declined:
                w("| %s | %s | %s |" % (m, s, t))
            w("")

    # animation
    an = by_label("animation")
    if an:
        sc = ordered({s for _, s in an}, [scene_name(s) for s in scenes])
        methods = ordered({m for m, _ in an}, METHODS)
        w("## Animation, frame by frame\n")
        w("Per run: relMSE against each frame's full-GI reference (mean, max over "
          "frames), median frame time (update + render), flicker (the method's "
          "mean frame-to-frame change minus the reference's) and the noise floor "
          "(mean difference of two reference seeds). A |flicker| below the noise "
          "floor is not told apart from reference noise. The verdict is on "
          "the relMSE mean (†: as above, on the bounce-matched reference).\n")
        w("| scene | method | relMSE mean | relMSE max | relMSE matched mean | frame (ms) | flicker | noise floor | verdict |")
        w("|---|---|---:|---:|---:|---:|---:|---:|---|")
        for s in sc:
            b = an.get(("direct", s))
            for m in methods:
                r = an.get((m, s))
                if r is None:
                    continue
                if r["status"] != "ok":
                    w("| %s | %s | | | | | | | n/a: %s |" % (s, m, reason(r)))
                    continue
                e = num(r.get("anim_relmse_full_mean"))
                fl, floor = num(r.get("anim_flicker_full")), num(r.get("anim_noise_floor_full"))
                if m == "direct":
                    v = "baseline"
                else:
                    je, be, mark = judged(r, b, "anim_relmse_full_mean", "anim_relmse_matched_mean")
                    v = verdict(je, be, flicker=fl, floor=floor) + mark
                w("| %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                    s, m, fmt(e), fmt(num(r.get("anim_relmse_full_max"))), fmt(num(r.get("anim_relmse_matched_mean"))),
                    fmt(num(r.get("anim_frame_ms_median"))), fmt(fl, "%.2g"), fmt(floor, "%.2g"), v))
            if trivial and b is not None:
                w("| %s | black | %s | | %s | | | | trivial |" % (s, fmt(black(b["run"], 0)), fmt(black(b["run"], 1))))
        w("")

    # scale
    recs = [r for r in records if r.get("label") == "scale" and r.get("status") == "ok"]
    if recs:
        fields = [("frame_ms.median", "frame time"), ("prepare_ms", "precompute"),
                  ("peak_rss_mib", "peak RSS"), ("stats.data_bytes", "own data")]
        methods = ordered({r["method"] for r in recs}, METHODS)
        w("## Scale: exponents against the triangle count\n")
        w("y ~ T^b by least squares on log-log axes over the scale_t* scenes "
          "(one point per scene); each cell: b [95 % interval] (n scenes). "
          "\"–\": fewer than 3 scenes with a positive value. Peak RSS includes "
          "the GL driver and the scene (on llvmpipe GPU buffers are process "
          "memory).\n")
        w("| method | triangles | " + " | ".join(f for _, f in fields) + " |")
        w("|---|---|" + "---:|" * len(fields))
        for m in methods:
            mine = [r for r in recs if r["method"] == m and num(r.get("scene_triangles"))]
            tris = sorted({int(r["scene_triangles"]) for r in mine})
            cells = []
            for key, _ in fields:
                pts = [(num(r["scene_triangles"]), num(field(r, key))) for r in mine]
                pts = [(x, y) for x, y in pts if x and y is not None and y > 0]
                f = fit(pts) if len(pts) >= 3 else None
                cells.append("–" if not f or "ci95" not in f else "%.2f [%.2f, %.2f] (%d)" % (
                    f["exponent"], f["ci95"][0], f["ci95"][1], f["n"]))
            w("| %s | %s | %s |" % (m, "%d–%d" % (tris[0], tris[-1]) if tris else "–", " | ".join(cells)))
        w("")
        w("The papers' scaling claims against the exponent measured (the other "
          "three papers state none): \"consistent\" where the 95 % interval "
          "meets the claimed range. Fixed costs that do not grow with the "
          "scene flatten the fit at small triangle counts; the slope between "
          "the two largest scenes shows the trend where the scene dominates.\n")
        w("| method | stage | claim | claimed exponent | measured | two largest scenes | verdict |")
        w("|---|---|---|---:|---:|---:|---|")
        for (m, key), (lo, hi, text) in sorted(CLAIMS.items()):
            pts = [(num(r.get("scene_triangles")), num(field(r, key))) for r in recs if r["method"] == m]
            pts = [(x, y) for x, y in pts if x and y is not None and y > 0]
            f = fit(pts) if len(pts) >= 3 else None
            if not f or "ci95" not in f:
                w("| %s | %s | %s | %s | – | – | not measured |" % (m, key, text, fmt_range(lo, hi)))
                continue
            ok = f["ci95"][0] <= hi and f["ci95"][1] >= lo
            top = sorted(pts)[-2:]
            w("| %s | %s | %s | %s | %.2f [%.2f, %.2f] | %.2f | %s |" % (
                m, key, text, fmt_range(lo, hi), f["exponent"], f["ci95"][0], f["ci95"][1],
                math.log(top[1][1] / top[0][1]) / math.log(top[1][0] / top[0][0]),
                "consistent" if ok else "not consistent"))
        w("")
        failed = [r for r in records if r.get("label") == "scale" and r.get("status") != "ok"]
        for r in failed:
            w("- scale run %s on %s: %s" % (r["method"], scene_name(r.get("scene", "")),
                                           (r.get("reason") or r.get("status", "")).replace("|", "/")))
        if failed:
            w("")
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()

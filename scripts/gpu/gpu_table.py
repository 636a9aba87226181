#!/usr/bin/env python3
"""The GPU comparison table (results/gpu/README.md): a bench.sh output folder
set beside the papers' numbers and the committed llvmpipe runs.

    python3 scripts/gpu/gpu_table.py BENCH_DIR [--results results] [--out FILE.md]

For every finished part of BENCH_DIR (a study folder with runs.csv), each run
is matched with the committed llvmpipe run of the same scene, method and
parameters (every parameter both name; results/<plugin>/runs.csv, results/compare_all/runs.csv for the
compare part; the llvmpipe runs are at their own, smaller sizes, named in the
table). Per stage: the GPU's median ms, llvmpipe's, the ratio GPU/llvmpipe and,
where the paper gives that stage for that setting, the paper's ms (paper
numbers from plugins/<id>/tables.py). Stdlib only."""
import argparse
import csv
import importlib.util
import os
import sys

PARTS = {  # part -> (plugin whose committed llvmpipe runs and paper numbers apply)
    "gpu_paths": "gpu_paths",  # no paper table: matched with results/gpu_paths/ if committed
    "cssm_table1": "cssm_hrc", "vlf_table1": "vlf", "avg_tables": "avg",
    "ivis_table1": "implicit_vis", "csm_table2": "csm", "compare": None,
}


def num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def read_runs(path):
    if not os.path.isfile(path):
        return []
    with open(path, newline="") as fh:
        return [r for r in csv.DictReader(fh) if r.get("status") == "ok"]


def paper_module(root, plugin):
    """plugins/<plugin>/tables.py, for its PAPER_* constants (None if absent)."""
    if not plugin:
        return None
    path = os.path.join(root, "plugins", plugin, "tables.py")
    if not os.path.isfile(path):
        return None
    spec = importlib.util.spec_from_file_location("tables_" + plugin, path)
    mod = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(mod)
    except Exception:  # a tables.py that needs its own arguments at import
        return None
    return mod


def params_of(run):
    return dict(kv.split("=", 1) for kv in run.get("params", "").split(",") if "=" in kv)


def paper_ms(part, run, mod):
    """{stage: ms} the paper gives for this run's setting, or {}."""
    if mod is None:
        return {}
    p, scene = params_of(run), os.path.basename(run["scene"])
    try:
        if part == "cssm_table1" and scene.startswith("cornell_box"):
            fps = mod.PAPER_T1.get((p.get("mode"), int(p.get("bounces", 0))))
            return {"frame": 1000.0 / fps} if fps else {}
        if part == "vlf_table1" and scene.startswith("cornell_box"):
            return {"frame": 1000.0 / mod.PAPER_T1[0][-1]}
        if part == "avg_tables" and run.get("label") == "table1" and scene.startswith("u_room"):
            _, _, vox, tra, sha, ill, fps_nv, fps_v = mod.PAPER_T1[0]
            if p.get("visibility") == "false":
                return {"frame": 1000.0 / fps_nv}
            return {"frame": 1000.0 / fps_v, "vox": vox, "tra": tra, "sha": sha, "ill": ill}
        if part == "avg_tables" and run.get("label") == "table2":
            size = (int(run["width"]), int(run["height"]))
            for res, office, sibenik in mod.PAPER_T2:
                if res == size:  # the paper's scenes are not here: Office's fps, for scale
                    return {"frame": 1000.0 / office}
    except (AttributeError, KeyError, ValueError, TypeError, ZeroDivisionError, IndexError):
        return {}
    return {}


def stages(run):
    """{stage: median ms}: the frame, prepare, and every stage_*_ms_median."""
    out = {}
    for k, v in run.items():
        x = num(v)
        if x is None:
            continue
        if k == "frame_ms_median":
            out["frame"] = x
        elif k == "prepare_ms":
            out["prepare"] = x
        elif k.startswith("stage_") and k.endswith("_ms_median"):
            out[k[len("stage_"):-len("_ms_median")]] = x
    return out


def llvmpipe_match(run, pool):
    # the same values of every parameter both runs name (a parameter added to
    # the method after the llvmpipe study ran is at its default there)
    mine = params_of(run)

    def agrees(r):
        theirs = params_of(r)
        return all(theirs[k] == v for k, v in mine.items() if k in theirs)

    same = [r for r in pool if r["scene"] == run["scene"] and r["method"] == run["method"]
            and agrees(r)]
    if not same:
        return None
    def area(r):
        return (num(r.get("width")) or 0) * (num(r.get("height")) or 0)

    # the same label first, then the size nearest the GPU run's
    same.sort(key=lambda r: (r.get("label") == run.get("label"), -abs(area(r) - area(run))))
    return same[-1]


def fmt(x, digits=3):
    return "–" if x is None else ("%.*g" % (digits, x))


def timer_check(bench):
    """The timer_check part: each run's stages by the wall clock around
    glFinish beside the same run's by GL queries (vlf_table1, avg_tables)."""
    runs = read_runs(os.path.join(bench, "timer_check", "runs.csv"))
    if not runs:
        return ["## timer_check: not in this bench folder (not finished)", ""]
    pool = read_runs(os.path.join(bench, "vlf_table1", "runs.csv")) + \
        read_runs(os.path.join(bench, "avg_tables", "runs.csv"))
    lines = ["## timer_check (GL queries against the wall clock)", "",
             "| run | size | stage | %s ms | finish ms | query/finish |" % "query", "| --- | --- | --- | --- | --- | --- |"]
    for run in runs:
        same = [r for r in pool if r["scene"] == run["scene"] and r["method"] == run["method"]
                and r.get("params") == run.get("params") and r.get("width") == run.get("width")
                and r.get("height") == run.get("height")]
        q = stages(same[0]) if same else {}
        for st, f in sorted(stages(run).items()):
            g = q.get(st)
            lines.append("| %s %s | %sx%s | %s | %s | %s | %s |" % (
                os.path.basename(run["scene"]), run["method"], run.get("width"), run.get("height"),
                st, fmt(g), fmt(f), fmt(g / f) if g is not None and f else "–"))
    return lines + [""]


def gpu_paths(bench):
    """Issue 29's question on this GPU: each GPU path against its C oracle,
    both timed in the one run of the gpu_paths part (frame and preparation
    ms, relMSE to the full reference, equal-error speed-up over the path
    tracer), with the ratio C / GPU of the frame and of the preparation."""
    runs = read_runs(os.path.join(bench, "gpu_paths", "runs.csv"))
    if not runs:
        return []
    lines = ["## gpu_paths: GPU paths against their C oracles (one run)", "",
             "| method | setting | frame ms | prepare ms | relMSE | speed-up vs PT | C/GPU frame | C/GPU prepare |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    pairs = {"cssm_hrc": ("gather", "cpu"), "implicit_vis": ("relink", "always"),
             "vlf": ("propagate", "cpu")}
    for run in runs:
        m = run.get("method", "")
        key, oracle = pairs.get(m, (None, None))
        setting = "%s=%s" % (key, params_of(run).get(key)) if key else run.get("label", "")
        ratio_f = ratio_p = "–"
        base = [r for r in runs if key and r.get("method") == m and
                params_of(r).get(key) == oracle and r is not run]
        if base:
            f0, f1 = num(base[0].get("frame_ms_median")), num(run.get("frame_ms_median"))
            p0, p1 = num(base[0].get("prepare_ms")), num(run.get("prepare_ms"))
            ratio_f = fmt(f0 / f1) if f0 and f1 else "–"
            ratio_p = fmt(p0 / p1) if p0 and p1 else "–"
        lines.append("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
            m, setting, fmt(num(run.get("frame_ms_median"))), fmt(num(run.get("prepare_ms"))),
            fmt(num(run.get("relmse_full"))), fmt(num(run.get("speedup_vs_pt"))), ratio_f, ratio_p))
    return lines + [""]


def table(bench, results, root):
    lines = []
    device = os.path.join(bench, "device.txt")
    if os.path.isfile(device):
        info = dict(l.split(": ", 1) for l in open(device).read().splitlines() if ": " in l)
        lines.append("GPU: %s; GL %s; EGL %s." % (info.get("GL renderer", "?"),
                                                   info.get("GL version", "?"),
                                                   info.get("EGL device", "?")))
        lines.append("")
    found = 0
    for part, plugin in PARTS.items():
        runs = read_runs(os.path.join(bench, part, "runs.csv"))
        if not runs:
            lines += ["## %s: not in this bench folder (not finished)" % part, ""]
            continue
        found += 1
        pool = read_runs(os.path.join(results, plugin or "compare_all", "runs.csv"))
        mod = paper_module(root, plugin)
        lines += ["## %s (%s)" % (part, plugin or "reduced compare_all"), "",
                  "| run | size | timer | stage | GPU ms | llvmpipe ms (size) | GPU/llvmpipe | paper ms |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- |"]
        varying = sorted(k for k in set().union(*(params_of(r) for r in runs))
                         if len({params_of(r).get(k) for r in runs}) > 1)
        for run in runs:
            ref = llvmpipe_match(run, pool)
            gst, lst, pst = stages(run), stages(ref) if ref else {}, paper_ms(part, run, mod)
            p = params_of(run)
            name = "%s %s %s" % (os.path.basename(run["scene"]), run.get("label", ""),
                                 ",".join("%s=%s" % (k, p.get(k)) for k in varying))
            size = "%sx%s" % (run.get("width", "?"), run.get("height", "?"))
            lsize = "%sx%s" % (ref.get("width", "?"), ref.get("height", "?")) if ref else ""
            for st in sorted(gst, key=lambda s: (s != "frame", s != "prepare", s)):
                g, l = gst[st], lst.get(st)
                lines.append("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
                    name, size, run.get("timer", "?"), st, fmt(g),
                    "%s (%s)" % (fmt(l), lsize) if l is not None else "–",
                    fmt(g / l) if l else "–", fmt(pst.get(st))))
        lines.append("")
    lines += gpu_paths(bench)
    lines += timer_check(bench)
    if not found:
        raise SystemExit("gpu_table.py: %s has no finished part (no */runs.csv)" % bench)
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bench", help="a bench.sh --out folder")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap.add_argument("--results", default=os.path.join(root, "results"),
                    help="the committed llvmpipe results (default: results/)")
    ap.add_argument("--out", help="write the table here (default: standard output)")
    a = ap.parse_args()
    if not os.path.isdir(a.bench):
        raise SystemExit("gpu_table.py: no folder %s" % a.bench)
    text = table(a.bench, a.results, root)
    if a.out:
        tmp = a.out + ".tmp"
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, a.out)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()

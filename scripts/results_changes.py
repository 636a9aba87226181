#!/usr/bin/env python3
"""What a study's rerun changed: its new runs.csv against an earlier commit's.

    scripts/results_changes.py DIR [--base REV]

Reads DIR/runs.csv (the working tree: the rerun) and REV:DIR/runs.csv
(default HEAD: the run before it, as committed) and prints Markdown: how
many runs each holds, which are new or gone, and per run found in both its
status, relMSE against the full-GI reference, median frame time,
precomputation and equal-error speed-up, before and after, with the ratio.
A results README opens with what changed against its previous run
(issue 34); `scripts/regenerate_results.sh` keeps this report beside the
study as DIR/changes.md, and scripts/readme_numbers.py lets the README
quote it. The base commit is named in the report, so the same command
with `--base` remakes it.

Runs are paired by scene, method, label, image size and the values of the
parameters that the run's study entry sweeps (those that differ between
the runs of one label), not by run id: a new parameter or a changed
default gives every run a new id, but it is still the same cell of the
study. A pair whose other parameters differ is marked with "†" and the
parameters that changed are listed below the table.
Exit status: 0; 1 on a missing runs.csv or a base without the folder.
"""
import argparse
import csv
import io
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from study_tables import fmt, num, scene_name  # noqa: E402

COLUMNS = [("relMSE", "relmse_full", "%.3g"), ("frame (ms)", "frame_ms_median", "%.3g"),
           ("precompute (s)", "prepare_ms", "%.3g"), ("speed-up", "speedup_vs_pt", "%.3g")]


def params(r):
    """A run's parameters as a dict, its label left out."""
    out = {}
    for p in r.get("params", "").split(","):
        if "=" in p:
            k, v = p.split("=", 1)
            if k != "label":
                out[k] = v
    return out


def swept(rows):
    """(method, label) -> the parameter names whose values differ between its runs."""
    seen = {}
    for r in rows:
        for k, v in params(r).items():
            seen.setdefault((r["method"], r.get("label", "")), {}).setdefault(k, set()).add(v)
    return {key: sorted(k for k, vs in d.items() if len(vs) > 1) for key, d in seen.items()}


def key(r, keys):
    p = params(r)
    ks = keys.get((r["method"], r.get("label", "")), [])
    return (scene_name(r["scene"]), r["method"], r.get("label", ""), "%sx%s" % (r.get("width"), r.get("height")),
            ",".join("%s=%s" % (k, p.get(k, "?")) for k in ks))


def value(r, col):
    v = num(r.get(col))
    return None if v is None else v / 1000.0 if col == "prepare_ms" else v


def main():
    ap = argparse.ArgumentParser(prog="results_changes.py")
    ap.add_argument("dir")
    ap.add_argument("--base", default="HEAD")
    a = ap.parse_args()
    path = os.path.join(a.dir, "runs.csv")
    try:
        with open(path, newline="") as fh:
            new = list(csv.DictReader(fh))
    except OSError as e:
        sys.exit("results_changes.py: %s" % e)
    rel = os.path.relpath(os.path.abspath(path), subprocess.run(
        ["git", "rev-parse", "--show-toplevel"], capture_output=True, text=True,
        cwd=os.path.dirname(os.path.abspath(path))).stdout.strip() or ".")
    base = subprocess.run(["git", "rev-parse", "--short", a.base], capture_output=True, text=True,
                          cwd=os.path.dirname(os.path.abspath(path)))
    old_txt = subprocess.run(["git", "show", "%s:%s" % (a.base, rel)], capture_output=True, text=True,
                             cwd=os.path.dirname(os.path.abspath(path)))
    if base.returncode != 0 or old_txt.returncode != 0:
        sys.exit("results_changes.py: no %s at %s" % (rel, a.base))
    old = list(csv.DictReader(io.StringIO(old_txt.stdout)))
    base_rev = base.stdout.strip()

    keys = swept(new)
    for k, v in swept(old).items():
        keys[k] = sorted(set(keys.get(k, [])) | set(v))
    newd = {key(r, keys): r for r in new}
    oldd = {key(r, keys): r for r in old}
    both = [k for k in newd if k in oldd]
    w = print
    w("# What the rerun changed\n")
    w("Made by `scripts/results_changes.py %s --base %s`: `%s` now against the same file at commit "
      "`%s`. Runs are paired by scene, method, label, size and swept parameters; ratios are new ÷ "
      "old. The times were measured in different invocations (and sessions): their ratios mix the "
      "code's change with the machine's drift; speed-ups are ratios within each invocation.\n"
      % (a.dir, base_rev, rel, base_rev))
    w("| | runs |")
    w("|---|---:|")
    w("| before | %d |" % len(old))
    w("| after | %d |" % len(new))
    w("| in both | %d |" % len(both))
    w("| new | %d |" % sum(1 for k in newd if k not in oldd))
    w("| gone | %d |" % sum(1 for k in oldd if k not in newd))
    w("")
    ratios = {c: [] for _, c, _ in COLUMNS}
    for k in both:
        for _, c, _ in COLUMNS:
            o, n = value(oldd[k], c), value(newd[k], c)
            if o and n:
                ratios[c].append(n / o)
    w("Median ratio over the pairs (new ÷ old), with the pairs counted:\n")
    w("| quantity | median ratio | pairs |")
    w("|---|---:|---:|")
    for name, c, _ in COLUMNS:
        w("| %s | %s | %d |" % (name, fmt(statistics.median(ratios[c]) if ratios[c] else None), len(ratios[c])))
    w("")
    w("## Per run\n")
    w("| scene | method | label | size | swept | status | " +
      " | ".join("%s before | after | ratio" % n for n, _, _ in COLUMNS) + " |")
    w("|---|---|---|---|---|---|" + "---:|---:|---:|" * len(COLUMNS))
    changed = []
    for k in sorted(both):
        o, n = oldd[k], newd[k]
        po, pn = params(o), params(n)
        diff = sorted(p for p in set(po) | set(pn) if po.get(p) != pn.get(p))
        mark = ""
        if diff:
            mark = " †"
            changed.append((k, ", ".join("%s: %s → %s" % (p, po.get(p, "–"), pn.get(p, "–")) for p in diff)))
        st = o["status"] if o["status"] == n["status"] else "%s → %s" % (o["status"], n["status"])
        cells = []
        for _, c, f in COLUMNS:
            vo, vn = value(o, c), value(n, c)
            cells += [fmt(vo, f), fmt(vn, f), fmt(vn / vo if vo and vn else None, "%.3g")]
        w("| %s | %s | %s | %s | %s%s | %s | %s |" % (k[0], k[1], k[2] or "–", k[3], k[4] or "–", mark, st,
                                                   " | ".join(cells)))
    w("")
    for title, ks, d in (("New runs", [k for k in newd if k not in oldd], newd),
                         ("Runs gone", [k for k in oldd if k not in newd], oldd)):
        if ks:
            w("## %s\n" % title)
            for k in sorted(ks):
                w("- %s %s %s %s %s (%s)" % (k[0], k[1], k[2] or "–", k[3], k[4] or "", d[k]["status"]))
            w("")
    if changed:
        w("## † Parameters that changed in a pair\n")
        for k, text in changed:
            w("- %s %s %s %s %s: %s" % (k[0], k[1], k[2] or "–", k[3], k[4] or "", text))
        w("")


if __name__ == "__main__":
    main()

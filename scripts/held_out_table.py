#!/usr/bin/env python3
"""Markdown tables of held-out results, from the JSON that
`gibench conformance --held-out SEED --json` writes (one file per run; any
number of seeds and methods). Numbers are copied from the files, never
typed: the plugin READMEs and docs/conformance.md quote this script's output.

  held_out_table.py RUN.json... [--method M]

One row per (method, variant) over all the files: the seeds, how many pass,
the median and worst relMSE over its limit (trivial check: at most 1/2 of the
better of black and `direct`), and the furnaces' mean error.
"""
import json
import statistics
import sys


def load(paths):
    rows = []
    for p in paths:
        try:
            with open(p) as f:
                d = json.load(f)
        except (OSError, ValueError) as e:
            sys.exit(f"held_out_table: {p}: {e}")
        for r in d.get("rows", []):
            r = dict(r)
            r["seed"] = d.get("held_out", "?")
            r["size"] = d.get("size", "?")
            rows.append(r)
    return rows


def table(rows, method=None):
    groups = {}
    for r in rows:
        if method and r["method"] != method:
            continue
        groups.setdefault((r["method"], r["variant"]), []).append(r)
    out = ["| method | variant | size | seeds | pass / fail / n/a | median relMSE / limit | worst (seed) |",
           "|---|---|---|---|---|---|---|"]
    for (m, v), rs in sorted(groups.items()):
        seeds = ",".join(sorted({str(r["seed"]) for r in rs}, key=lambda s: (len(s), s)))
        sizes = ",".join(sorted({str(r["size"]) for r in rs}))
        n = {k: sum(1 for r in rs if r["status"] == k) for k in ("pass", "fail")}
        na = len(rs) - n["pass"] - n["fail"]
        ratios = [(r["value"] / r["limit"], r["seed"]) for r in rs
                  if r.get("value") is not None and r.get("limit")]
        if ratios:
            med = statistics.median(x for x, _ in ratios)
            worst = max(ratios)
            q = f"{med:.2f} | {worst[0]:.2f} ({worst[1]})"
        else:
            q = "- | -"
        out.append(f"| {m} | {v} | {sizes} | {seeds} | {n['pass']} / {n['fail']} / {na} | {q} |")
    return "\n".join(out)


def main(argv):
    method = None
    paths = []
    it = iter(argv)
    for a in it:
        if a == "--method":
            method = next(it, None)
            if not method:
                sys.exit("held_out_table: --method needs a value")
        elif a.startswith("-"):
            sys.exit(f"held_out_table: unknown option {a}")
        else:
            paths.append(a)
    if not paths:
        sys.exit(__doc__.strip().splitlines()[4].strip())
    print(table(load(paths), method))


if __name__ == "__main__":
    main(sys.argv[1:])

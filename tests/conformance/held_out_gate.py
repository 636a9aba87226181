#!/usr/bin/python3
"""The held-out gate of CI (docs/conformance.md "CI"): every method on the
fixed CI seeds' variants at 32^2, both furnace orientations, beats black
and `direct` by 2x, read from `gibench conformance --held-out --json`.

A method listed with --known-fail fails the gate only the other way round:
it must still fail at least one check (so the list cannot outlive the
failure it records), and its failures are printed, not counted. Every other
method's failed check fails the gate; so does a run that gives no JSON.

usage: held_out_gate.py GIBENCH --run SEED|DIR:VARIANTS [--run ...]
                        [--known-fail METHOD ...] [--size N] [--method M]
                        [--item-timeout S]
"""
import argparse
import json
import subprocess
import sys


def run_one(gib, seed, variants, size, method, item_timeout):
    cmd = [gib, "-q", "conformance", "--held-out", seed, "--variants", variants,
           "--size", str(size), "--no-converge", "--json"] + (["--method", method] if method else [])
    if item_timeout:
        cmd += ["--item-timeout", str(item_timeout)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    try:
        doc = json.loads(p.stdout)
        rows = doc["rows"]
    except (ValueError, KeyError, TypeError):
        print("held-out gate: seed %s gave no JSON table (exit %d): %s" %
              (seed, p.returncode, (p.stderr.strip().splitlines() or ["no message"])[-1]))
        return None
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("gibench")
    ap.add_argument("--run", action="append", required=True, help="SEED:VARIANTS")
    ap.add_argument("--known-fail", action="append", default=[])
    ap.add_argument("--size", type=int, default=32)
    ap.add_argument("--method", help="one method only (the gate's own test)")
    ap.add_argument("--item-timeout", type=float,
                    help="each child's time limit (gibench's default 60 s when not given)")
    a = ap.parse_args()
    failures, known_fails, broken = [], {m: 0 for m in a.known_fail}, 0
    seen = set()
    for r in a.run:
        seed, _, variants = r.rpartition(":")
        rows = run_one(a.gibench, seed, variants, a.size, a.method, a.item_timeout)
        if rows is None:
            broken += 1
            continue
        for row in rows:
            m, st = row["method"], row["status"]
            seen.add(m)
            val = row.get("value")
            lim = row.get("limit")
            ratio = "%.2f of its limit" % (val / lim) if val is not None and lim else ""
            line = "seed %s %-12s %-11s %-12s %-5s %s" % (seed, m, row["variant"], row["check"],
                                                         st, ratio)
            print(line)
            if st != "fail":
                continue
            if m in known_fails:
                known_fails[m] += 1
            else:
                failures.append(line)
    for m, n in known_fails.items():
        if m not in seen:
            print("held-out gate: known failing method %s did not run" % m)
            broken += 1
        elif n == 0:
            print("held-out gate: %s passes every check now: remove it from --known-fail "
                  "(tests/conformance/CMakeLists.txt, docs/conformance.md)" % m)
            broken += 1
        else:
            print("held-out gate: %s fails %d check(s), a known failure (docs/conformance.md)" %
                  (m, n))
    for f in failures:
        print("FAILED: " + f)
    if failures or broken:
        print("held-out gate: %d failed check(s), %d broken run(s)" % (len(failures), broken))
        return 1
    print("held-out gate: every check passes")
    return 0


if __name__ == "__main__":
    sys.exit(main())

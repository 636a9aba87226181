#!/usr/bin/env python3
"""The held-out tables in docs/held_out/README.md and the plugin READMEs are
the output of scripts/held_out_table.py on the committed JSON files, not
typed: regenerate each and find it, whole, in its README (the CI seeds'
docs/held_out/*.json, and the further seeds' docs/held_out/more/*.json in
docs/held_out/README.md).

  held_out_tables_test.py ROOT
"""
import glob
import os
import subprocess
import sys

root = sys.argv[1]
files = sorted(glob.glob(os.path.join(root, "docs/held_out/*.json")))
script = os.path.join(root, "scripts/held_out_table.py")


def table(method=None):
    args = [sys.executable, script] + (["--method", method] if method else []) + files
    return subprocess.check_output(args, text=True).strip()


fails = 0
if not files:
    print("FAIL: no docs/held_out/*.json")
    sys.exit(1)
cases = [("docs/held_out/README.md", None)]
methods = sorted({os.path.basename(f).split("-", 1)[1][:-5] for f in files})
cases += [(f"plugins/{m}/README.md", m) for m in methods]
for readme, method in cases:
    with open(os.path.join(root, readme)) as f:
        text = f.read()
    if table(method) in text:
        print(f"ok: {readme}")
    else:
        print(f"FAIL: {readme} does not hold the table held_out_table.py makes"
              + (f" for {method}" if method else ""))
        fails += 1
# the ten further seeds run by hand (docs/held_out/more/), their own table
more = sorted(glob.glob(os.path.join(root, "docs/held_out/more/*.json")))
if more:
    out = subprocess.check_output([sys.executable, script] + more, text=True).strip()
    with open(os.path.join(root, "docs/held_out/README.md")) as f:
        if out in f.read():
            print("ok: docs/held_out/README.md (more seeds)")
        else:
            print("FAIL: docs/held_out/README.md does not hold the table of docs/held_out/more/")
            fails += 1
# the script refuses what it cannot read, in one line
bad = subprocess.run([sys.executable, script, os.path.join(root, "README.md")],
                     capture_output=True, text=True)
if bad.returncode == 0 or len(bad.stderr.strip().splitlines()) != 1:
    print(f"FAIL: a non-JSON file: exit {bad.returncode}, stderr {bad.stderr!r}")
    fails += 1
sys.exit(1 if fails else 0)

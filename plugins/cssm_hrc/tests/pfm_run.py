"""Helpers shared by cssm_hrc's command-line tests (env_test.py,
csm_direct_test.py): read the PFM images `gibench render` writes, and run
a command, failing the test with its last words when it fails."""
import struct
import subprocess
import sys


def read_pfm(path):
    """(width, height, flat RGB floats) of a PFM file."""
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    scale = float(parts[2])
    n = w * h * 3
    return w, h, struct.unpack(("<" if scale < 0 else ">") + "%df" % n, parts[3][: 4 * n])


def run(cmd):
    """Runs cmd; returns its standard output, or ends the test with FAIL."""
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("FAIL: %s: %s" % (" ".join(cmd), r.stderr.strip()[-400:]))
    return r.stdout

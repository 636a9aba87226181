"""Helpers of the scripts and tests that drive the gibench command
(plugins/implicit_vis/flicker.py, plugins/cssm_hrc/tests/env_test.py and
csm_direct_test.py): read the PFM images `gibench render` and `gibench
reference` write, and run a command, ending the caller with its last words
when it fails."""
import array
import subprocess
import sys


def read_pfm(path):
    """(width, height, channels, flat floats) of a PFM file: 3 channels
    for "PF", 1 for "Pf". Ends the caller with one line on a malformed file."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind not in (b"PF", b"Pf"):
            sys.exit("FAIL: %s: not a PFM image" % path)
        try:
            w, h = (int(x) for x in f.readline().split())
            scale = float(f.readline())
        except ValueError:
            sys.exit("FAIL: %s: a malformed PFM header" % path)
        data = array.array("f")
        data.frombytes(f.read())
    if (scale > 0) != (sys.byteorder == "big"):
        data.byteswap()
    c = 3 if kind == b"PF" else 1
    if len(data) != w * h * c:
        sys.exit("FAIL: %s: %d values for %d x %d x %d" % (path, len(data), w, h, c))
    return w, h, c, data


def luminance(data):
    """Rec. 709 luminance of flat RGB floats."""
    return [0.2126 * data[3 * i] + 0.7152 * data[3 * i + 1] + 0.0722 * data[3 * i + 2]
            for i in range(len(data) // 3)]


def run(cmd):
    """Runs cmd; returns its standard output, or ends the caller with FAIL."""
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("FAIL (%d): %s: %s" % (r.returncode, " ".join(cmd), r.stderr.strip()[-400:]))
    return r.stdout

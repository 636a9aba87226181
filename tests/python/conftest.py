"""Shared set-up of the Python API tests: the repository, the gibench
command of the same build, and one cornell box scene for the session.

Run by ctest (python.api) with PYTHONPATH=build/<preset>/python and
GIBENCH_BIN set; by hand from the repository root:
    PYTHONPATH=build/release/python /usr/bin/python3 -m pytest -q tests/python
A missing numpy or a package that does not import fails here, never skips.
"""
import os
import subprocess

import numpy  # noqa: F401  (Debian's python3-numpy: a missing one must fail the run)
import pytest

import gibench

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORNELL = os.path.join(ROOT, "scenes", "cornell_box.gltf")


def gibench_bin():
    from gibench import _build
    return os.environ.get("GIBENCH_BIN") or _build.COMMAND


def run_cli(*args, check=True):
    """gibench -q ARGS; the completed process (stderr as text)."""
    p = subprocess.run([gibench_bin(), "-q", *args], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True)
    if check and p.returncode != 0:
        raise AssertionError("gibench %s failed (%d): %s" % (" ".join(args), p.returncode, p.stderr))
    return p


def cli_error(*args):
    """The one-line message the CLI prints for a failing command, and its exit status."""
    p = run_cli(*args, check=False)
    assert p.returncode != 0, "gibench %s did not fail" % " ".join(args)
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("gibench: ")]
    assert lines, p.stderr
    return lines[-1][len("gibench: "):], p.returncode


@pytest.fixture(scope="session")
def cornell():
    s = gibench.Scene(CORNELL)
    yield s
    s.close()

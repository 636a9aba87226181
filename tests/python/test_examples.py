"""examples/python: the tutorial notebook runs top to bottom without a display,
matches its script, and the timing script's comparison holds."""
import os
import subprocess
import sys

import nbclient
import nbformat

from conftest import ROOT

EXAMPLES = os.path.join(ROOT, "examples", "python")


def test_notebook_matches_its_script():
    p = subprocess.run([sys.executable, os.path.join(EXAMPLES, "make_notebook.py"), "--check"],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.returncode == 0, p.stderr


def test_notebook_is_stripped_and_runs(tmp_path):
    nb = nbformat.read(os.path.join(EXAMPLES, "sweep.ipynb"), as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(not c.outputs and c.execution_count is None for c in code)
    fig = str(tmp_path / "fig.png")
    os.environ["GIBENCH_EXAMPLE_OUT"] = fig
    os.environ["MPLBACKEND"] = "Agg"
    try:
        # the kernel is this interpreter (Debian's, with numpy), in the repository root
        nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                                resources={"metadata": {"path": ROOT}}).execute()
    finally:
        del os.environ["GIBENCH_EXAMPLE_OUT"]
    text = "".join(o.get("text", "") for c in code for o in c.outputs)
    assert "M_local=8" in text and "relMSE" in text, text
    assert not [o for c in code for o in c.outputs if o.output_type == "error"]
    assert os.path.getsize(fig) > 1000

"""Writes sweep.ipynb from sweep.py (its "# %%" cells), outputs stripped.

    /usr/bin/python3 examples/python/make_notebook.py [--check]

The script is the source; tests/python/test_examples.py checks that the
notebook matches it (--check exits 1 when it does not) and runs it.
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def cells(text):
    """The cells of a "# %%" script: (kind, source lines)."""
    out = []
    for block in text.split("# %%")[1:]:
        head, _, body = block.partition("\n")
        kind = "markdown" if "[markdown]" in head else "code"
        lines = body.strip("\n").split("\n")
        if kind == "markdown":
            lines = [ln[2:] if ln.startswith("# ") else ln.lstrip("#") for ln in lines]
        out.append((kind, lines))
    return out


def notebook(text):
    nb_cells = []
    for kind, lines in cells(text):
        source = [ln + "\n" for ln in lines[:-1]] + lines[-1:]
        cell = {"cell_type": kind, "id": "cell-%d" % len(nb_cells), "metadata": {},
                "source": source}
        if kind == "code":
            cell["execution_count"] = None
            cell["outputs"] = []
        nb_cells.append(cell)
    return {
        "cells": nb_cells,
        "metadata": {
            "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
            "language_info": {"name": "python"},
        },
        "nbformat": 4,
        "nbformat_minor": 5,
    }


def main():
    with open(os.path.join(HERE, "sweep.py")) as f:
        text = json.dumps(notebook(f.read()), indent=1) + "\n"
    path = os.path.join(HERE, "sweep.ipynb")
    if "--check" in sys.argv[1:]:
        with open(path) as f:
            if f.read() != text:
                sys.exit("sweep.ipynb does not match sweep.py: run examples/python/make_notebook.py")
        return
    with open(path, "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()

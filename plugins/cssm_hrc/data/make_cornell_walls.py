#!/usr/bin/env python3
"""Derives plugins/cssm_hrc/data/cornell_walls.gltf (+ cornell_walls.bin, a copy
of scenes/cornell_box_coarse.bin) from scenes/cornell_box_coarse.gltf:
the same room and light without the two blocks, so that the illumination
atlas has few large charts (the walls, floor, ceiling and the lamp) instead
of the blocks' many small faces. cssm_hrc's Table 2 test (traversal order,
Ritschel et al. 2008 §3.2.3) compares the traversals on it; it lives in the
plugin's data/, not scenes/, because every method's conformance run renders
every scene of scenes/. Python 3 stdlib only.

Usage: plugins/cssm_hrc/data/make_cornell_walls.py [OUTDIR]   (default: plugins/cssm_hrc/data/)
"""
import json
import os
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(HERE, "..", "..", "..", "scenes", "cornell_box_coarse.gltf")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else HERE
    g = json.load(open(SRC))
    drop = {i for i, n in enumerate(g["nodes"]) if n.get("name") in ("short_block", "tall_block")}
    if len(drop) != 2:
        sys.exit("make_cornell_walls: scenes/cornell_box_coarse.gltf has no short_block / tall_block")
    for s in g["scenes"]:
        s["nodes"] = [i for i in s["nodes"] if i not in drop]
    (b,) = g["buffers"]
    shutil.copyfile(os.path.join(os.path.dirname(SRC), b["uri"]), os.path.join(out, "cornell_walls.bin"))
    b["uri"] = "cornell_walls.bin"
    g.setdefault("asset", {})["extras"] = {"derived_from": "scenes/cornell_box_coarse.gltf without its blocks"}
    with open(os.path.join(out, "cornell_walls.gltf"), "w") as f:
        json.dump(g, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()

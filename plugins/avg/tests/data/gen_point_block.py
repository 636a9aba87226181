#!/usr/bin/env python3
"""point_block.gltf: avg's point-light shadow test (issue 28).

A closed 2 x 2 x 2 room (single-sided walls facing in) with a block on the
floor, lit only by a point light ("bulb", KHR_lights_punctual) at about
the block's height, so that the block's shadow on the floor and the back
wall lies in directions more than 60 degrees from the vertical: outside the
120 degree perspective maps of VPLs that cover the hemispheres above and
below the light, which is where avg's point light used to pass the block.

Run: python3 plugins/avg/tests/data/gen_point_block.py (deterministic;
files committed).
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..", "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tests", "data", "truth"))
sys.path.insert(0, os.path.join(ROOT, "tests", "data"))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from gen_truth import block_flat, room_walls  # noqa: E402
from gen_conformance import Writer  # noqa: E402

GEN = "gibench plugins/avg/tests/data/gen_point_block.py"


def main():
    g = Writer(GEN)
    m_wall = g.material("wall", (0.6, 0.6, 0.6))
    m_block = g.material("block", (0.7, 0.5, 0.3))
    nodes = [g.node("room", mesh=g.mesh("room", [(room_walls(1.0, 2.0), m_wall)]))]
    nodes.append(g.node("block", mesh=g.mesh("block", [(block_flat(0.2, 0.35, 0.2), m_block)]),
                        translation=(-0.25, 0.0, -0.4)))
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "bulb", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 3.0}]}}
    g.ext_used.add("KHR_lights_punctual")
    bulb = g.node("bulb", translation=(0.5, 0.6, 0.3))
    g.doc["nodes"][bulb]["extensions"] = {"KHR_lights_punctual": {"light": 0}}
    nodes.append(bulb)
    nodes.append(g.camera_node("camera", (0.3, 1.4, 0.95), (-0.4, 0.3, -1.0), 70.0, znear=0.01, zfar=10.0))
    g.scene("point_block", nodes)
    g.write_gltf(os.path.join(HERE, "point_block.gltf"), "point_block.bin")


if __name__ == "__main__":
    main()

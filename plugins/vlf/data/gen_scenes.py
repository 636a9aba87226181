#!/usr/bin/env python3
"""Scenes of the vlf plugin's rendered-image tests (plugins/vlf/tests/).

Writes plugins/vlf/data/:
  panel_double.gltf   a thin panel (2 x 2, one quad, albedo 0.8) whose front
      (counter-clockwise) side faces away from the camera; an area light
      (0.5 x 0.5, Le = 6, one-sided) on the camera's side, outside the view,
      shines on the panel's back side. The panel's material is glTF
      `doubleSided`: its back side reflects and the methods must store light
      for both sides. The panel fills the whole 40-degree view.
  panel_single.gltf   the same with a single-sided panel (vlf then keeps
      nothing for the side the camera sees: one of the trivial answers)
  mirror_wall.gltf    an ideal mirror (2 x 2, ks 0.9, albedo 0) on the floor
      filling the view of a camera looking down at it at 45 degrees; it
      reflects a diffuse wall (left half red, right half white) lit by an
      area light above the camera (Le = 4, facing the wall and the mirror).
  mirror_back.gltf    the same with the mirror's front side facing down
      (away from the camera and the wall) and its material `doubleSided`:
      the camera sees and the wall lights its back side, which must
      reflect as the front of mirror_wall.gltf does.

Run from anywhere: python3 plugins/vlf/data/gen_scenes.py (deterministic
output; the files are committed).
"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "scripts"))
from gltf_writer import Gltf, Mesh  # noqa: E402

OUT = HERE
GEN = "gibench plugins/vlf/data/gen_scenes.py"


def quad(c, e1, e2):
    """A parallelogram c +- e1 +- e2, counter-clockwise seen from e1 x e2."""
    n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    ln = math.sqrt(sum(x * x for x in n))
    n = [x / ln for x in n]
    m = Mesh()
    for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        m.add_vertex([c[i] + s * e1[i] + t * e2[i] for i in range(3)], n)
    m.idx = [0, 1, 2, 0, 2, 3]
    return m


def unit(v):
    ln = math.sqrt(sum(x * x for x in v))
    return [x / ln for x in v]


def panel(double_sided, path):
    g = Gltf(GEN)
    mp = g.material("panel", (0.8, 0.8, 0.8), double_sided=double_sided)
    ml = g.material("light", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=6.0)
    # front side facing -z (away from the camera at +z)
    p = quad((0.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    # the light at (0, 1.3, 1.0), facing the panel's centre
    n = unit([0.0, -1.3, -1.0])
    e1 = [0.25, 0.0, 0.0]
    e2 = [0.0, 0.25 * n[2], -0.25 * n[1]]  # in the light's plane; e1 x e2 along n
    lt = quad((0.0, 1.3, 1.0), e1, e2)
    assert abs(sum((e1[(i + 1) % 3] * e2[(i + 2) % 3] - e1[(i + 2) % 3] * e2[(i + 1) % 3]) * n[i]
                   for i in range(3)) - 0.0625) < 1e-9
    cam = g.camera_node("camera", (0.0, 0.0, 2.2), (0.0, 0.0, 0.0), 40.0)
    nodes = [cam, g.node("panel", mesh=g.mesh("panel", [(p, mp)])),
             g.node("light", mesh=g.mesh("light", [(lt, ml)]))]
    g.scene("panel_double" if double_sided else "panel_single", nodes)
    g.write_gltf(path, os.path.basename(path).replace(".gltf", ".bin"))


def mirror_wall(path, back=False):
    g = Gltf(GEN)
    mm = g.material("mirror", (0.0, 0.0, 0.0), ks=(0.9, 0.9, 0.9), exponent=1e4, mirror=True,
                    double_sided=back)
    mr = g.material("wall_red", (0.8, 0.2, 0.2))
    mw = g.material("wall_white", (0.8, 0.8, 0.8))
    ml = g.material("light", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=4.0)
    mirror = quad((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0 if back else -1.0))  # facing +y (back: -y)
    red = quad((-1.0, 1.5, -1.2), (1.0, 0.0, 0.0), (0.0, 1.5, 0.0))    # facing +z
    white = quad((1.0, 1.5, -1.2), (1.0, 0.0, 0.0), (0.0, 1.5, 0.0))
    n = unit([0.0, -1.0, -1.0])
    e1 = [0.3, 0.0, 0.0]
    e2 = [0.0, 0.3 * n[2], -0.3 * n[1]]
    lt = quad((0.0, 2.6, 0.9), e1, e2)
    cam = g.camera_node("camera", (0.0, 1.0, 1.0), (0.0, 0.0, 0.0), 30.0)
    nodes = [cam, g.node("mirror", mesh=g.mesh("mirror", [(mirror, mm)])),
             g.node("wall", mesh=g.mesh("wall", [(red, mr), (white, mw)])),
             g.node("light", mesh=g.mesh("light", [(lt, ml)]))]
    name = os.path.basename(path).replace(".gltf", "")
    g.scene(name, nodes)
    g.write_gltf(path, name + ".bin")


def main():
    os.makedirs(OUT, exist_ok=True)
    panel(True, os.path.join(OUT, "panel_double.gltf"))
    panel(False, os.path.join(OUT, "panel_single.gltf"))
    mirror_wall(os.path.join(OUT, "mirror_wall.gltf"))
    mirror_wall(os.path.join(OUT, "mirror_back.gltf"), back=True)


if __name__ == "__main__":
    main()

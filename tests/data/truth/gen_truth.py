#!/usr/bin/env python3
"""Hand-made scenes of issue 28 ("truth on unseen scenes"), outside scenes/.

No method's defaults were chosen on these; they reproduce the failures the
issue reports and are the fixed cases of the regression tests:

  box_light.gltf        a closed 2 x 2 x 2 room (single-sided walls facing in)
                        with a block, lit only by a 0.3 x 0.3 area light
                        5 cm under the ceiling, facing down
  box_light_flat.gltf   the same with no NORMAL attribute anywhere and the
                        block's eight corners shared by its faces: glTF 2.0
                        asks for flat normals, smooth ones darken a wedge
                        across the block's top
  sphere_out_ds.gltf    the furnace sphere (radius 1, Le = 1, rho = 0.5) wound
                        outward with doubleSided: true, seen from its centre:
                        back faces are lit with reversed normals, so the
                        radiance after B bounces is Le (1 + rho + ... + rho^B)
                        (1.9375 at B = 4), as for the inward-wound furnace
  sphere_in_ss.gltf     a sphere wound inward, single-sided, on the floor of a
                        lit room, seen from outside: its near half is culled
                        (back faces), its far half's inside is seen
  tilted_normals.gltf   a floor lit by an area light above it, seen at a slant,
                        whose vertex normals lean away from the camera (each
                        n . wo < 0 at every pixel, as smooth normals are near a
                        silhouette): the reference and the G-buffer both shade
                        it with the geometric normal (gi_facing_normal), so it
                        renders as tilted_normals_flat.gltf, the same floor with
                        normals (0, 1, 0); turning such a normal round instead
                        left it nearly black in the reference only

Run: python3 tests/data/truth/gen_truth.py (deterministic; files committed).
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "scripts"))
from gltf_writer import Mesh  # noqa: E402
from gen_conformance import Writer, icosphere_flat, quad  # noqa: E402

GEN = "gibench tests/data/truth/gen_truth.py"


def room_walls(half, height):
    """Floor, ceiling and four walls of [-half, half] x [0, height] x
    [-half, half], front faces inside."""
    m = Mesh()
    h, y1 = half, height
    faces = [  # (corner list counter-clockwise seen from inside, inward normal)
        ([(-h, 0, -h), (-h, 0, h), (h, 0, h), (h, 0, -h)], (0, 1, 0)),
        ([(-h, y1, -h), (h, y1, -h), (h, y1, h), (-h, y1, h)], (0, -1, 0)),
        ([(-h, 0, -h), (h, 0, -h), (h, y1, -h), (-h, y1, -h)], (0, 0, 1)),
        ([(-h, 0, h), (-h, y1, h), (h, y1, h), (h, 0, h)], (0, 0, -1)),
        ([(-h, 0, -h), (-h, y1, -h), (-h, y1, h), (-h, 0, h)], (1, 0, 0)),
        ([(h, 0, -h), (h, 0, h), (h, y1, h), (h, y1, -h)], (-1, 0, 0)),
    ]
    for corners, n in faces:
        ids = [m.add_vertex(p, n) for p in corners]
        m.idx += [ids[0], ids[1], ids[2], ids[0], ids[2], ids[3]]
    return m


def block_shared(hx, hy, hz):
    """A block on the floor whose eight corners are shared by its faces
    (front faces outside); the normals given are the corner directions, which
    the flat variant drops."""
    m = Mesh()
    for i in range(8):
        x, y, z = (hx if i & 1 else -hx), (2 * hy if i & 2 else 0.0), (hz if i & 4 else -hz)
        n = ((1 if i & 1 else -1), (1 if i & 2 else -1), (1 if i & 4 else -1))
        m.add_vertex((x, y, z), tuple(c / 3 ** 0.5 for c in n))
    quads = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
    for a, b, c, d in quads:
        m.idx += [a, b, c, a, c, d]
    return m


def block_flat(hx, hy, hz):
    """The same block with one vertex per face corner and face normals."""
    s = block_shared(hx, hy, hz)
    m = Mesh()
    for t in range(0, len(s.idx), 3):
        p = [s.pos[3 * s.idx[t + k]:3 * s.idx[t + k] + 3] for k in range(3)]
        e1 = [p[1][i] - p[0][i] for i in range(3)]
        e2 = [p[2][i] - p[0][i] for i in range(3)]
        n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        ln = sum(c * c for c in n) ** 0.5
        for k in range(3):
            m.idx.append(m.add_vertex(tuple(p[k]), tuple(c / ln for c in n)))
    return m


def drop_normals(g):
    for mesh in g.doc["meshes"]:
        for prim in mesh["primitives"]:
            prim["attributes"].pop("NORMAL", None)


def box_light(name, flat):
    g = Writer(GEN)
    m_wall = g.material("wall", (0.6, 0.6, 0.6))
    m_block = g.material("block", (0.7, 0.5, 0.3))
    m_lamp = g.material("lamp", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=30.0)
    nodes = [g.node("room", mesh=g.mesh("room", [(room_walls(1.0, 2.0), m_wall)]))]
    blk = block_shared(0.25, 0.4, 0.3) if flat else block_flat(0.25, 0.4, 0.3)
    nodes.append(g.node("block", mesh=g.mesh("block", [(blk, m_block)]), translation=(-0.3, 0.0, -0.2)))
    nodes.append(g.node("lamp", mesh=g.mesh("lamp", [(quad(0.0, 0.0, 0.0, 0.15, 0.15, down=True), m_lamp)]),
                        translation=(0.2, 1.95, 0.1)))
    nodes.append(g.camera_node("camera", (0.0, 1.2, 0.95), (-0.1, 0.6, -1.0), 65.0, znear=0.01, zfar=10.0))
    if flat:
        drop_normals(g)
    g.scene(name, nodes)
    g.write_gltf(os.path.join(HERE, name + ".gltf"), name + ".bin")


def outward(m):
    """m wound and normalled the other way (the inward furnace sphere made
    outward here; scripts/held_out.py imports it)."""
    o = Mesh()
    o.pos, o.nrm = list(m.pos), [-c for c in m.nrm]
    for t in range(0, len(m.idx), 3):
        o.idx += [m.idx[t], m.idx[t + 2], m.idx[t + 1]]
    return o


def sphere_out_ds():
    g = Writer(GEN)
    mat = g.material("emitter", (0.5, 0.5, 0.5), emission=(1.0, 1.0, 1.0), emission_strength=1.0)
    g.doc["materials"][mat]["doubleSided"] = True  # the writer refuses two-sided emitters
    sphere = g.node("sphere", mesh=g.mesh("sphere", [(outward(icosphere_flat(1.0, 3)), mat)]))
    cam = g.camera_node("centre", (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 70.0, znear=0.01, zfar=10.0)
    g.scene("sphere_out_ds", [sphere, cam])
    g.write_gltf(os.path.join(HERE, "sphere_out_ds.gltf"), "sphere_out_ds.bin")


def sphere_in_ss():
    g = Writer(GEN)
    m_floor = g.material("floor", (0.6, 0.6, 0.6))
    m_ball = g.material("ball", (0.7, 0.5, 0.3))
    m_lamp = g.material("lamp", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=8.0)
    nodes = [g.node("floor", mesh=g.mesh("floor", [(quad(0, 0, 0, 2.0, 2.0), m_floor)]))]
    nodes.append(g.node("ball", mesh=g.mesh("ball", [(icosphere_flat(0.4, 2), m_ball)]),
                        translation=(0.0, 0.4, 0.0)))
    nodes.append(g.node("lamp", mesh=g.mesh("lamp", [(quad(0, 2.0, 0, 0.4, 0.4, down=True), m_lamp)])))
    nodes.append(g.camera_node("camera", (0.0, 2.0, 2.6), (0.0, 0.3, 0.0), 50.0, znear=0.05, zfar=50.0))
    g.scene("sphere_in_ss", nodes)
    g.write_gltf(os.path.join(HERE, "sphere_in_ss.gltf"), "sphere_in_ss.bin")


def tilted_normals(name, lean):
    """A 2 x 2 floor (normals leaning by `lean` towards -z) under a 0.5 x 0.5
    area light, the camera at +z looking down at it."""
    g = Writer(GEN)
    m_floor = g.material("floor", (0.6, 0.6, 0.6))
    m_lamp = g.material("lamp", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0), emission_strength=10.0)
    floor = quad(0.0, 0.0, 0.0, 1.0, 1.0)
    ln = (1.0 + lean * lean) ** 0.5
    floor.nrm = [c for _ in range(len(floor.pos) // 3) for c in (0.0, 1.0 / ln, -lean / ln)]
    nodes = [g.node("floor", mesh=g.mesh("floor", [(floor, m_floor)]))]
    nodes.append(g.node("lamp", mesh=g.mesh("lamp", [(quad(0.0, 1.0, -0.3, 0.25, 0.25, down=True), m_lamp)])))
    nodes.append(g.camera_node("camera", (0.0, 0.8, 2.2), (0.0, 0.0, -0.2), 45.0, znear=0.05, zfar=20.0))
    g.scene(name, nodes)
    g.write_gltf(os.path.join(HERE, name + ".gltf"), name + ".bin")


def main():
    box_light("box_light", flat=False)
    box_light("box_light_flat", flat=True)
    sphere_out_ds()
    sphere_in_ss()
    tilted_normals("tilted_normals", 3.0)
    tilted_normals("tilted_normals_flat", 0.0)


if __name__ == "__main__":
    main()

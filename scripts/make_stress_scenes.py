#!/usr/bin/env python3
"""Generates the stress-case scenes of the comparison (scenes/stress/, issue 18).

Each scene is the smallest one that shows one failure of an interactive GI
method; its `asset.extras.gibench.isolates` says in one line what it isolates
(the same line is in scenes/README.md).  Stdlib only, no inputs, deterministic.

  two_rooms_thin, two_rooms_thick   light leaking through a wall
  light_in_hull                     a point light inside an object's convex hull
  hulls_overlap                     convex hulls that overlap while one object moves
  glossy                            a highly glossy floor lit by an area light
  moving_light, moving_camera       an animated point light / camera (4 s loops)
  scale_tNNNNN                      tessellation sweep, 116 to 57 090 triangles

Usage: scripts/make_stress_scenes.py [--out scenes/stress] [--only NAME.gltf]
"""

import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltf_writer import Gltf, Mesh, look_at_quat, norm  # noqa: E402
from make_scenes import add_quad_grid, grid_counts, orient, centroid, sub  # noqa: E402

GENERATOR = "gibench scripts/make_stress_scenes.py"
COPYRIGHT = "gibench (generated)"
WHITE = (0.73, 0.73, 0.73)
RED = (0.63, 0.065, 0.05)
GREEN = (0.14, 0.45, 0.091)
ALBEDO = {"white": WHITE, "red": RED, "green": GREEN}
CELL = 0.25            # tessellation of walls and blocks (per-vertex methods need some)
LOOP = [0.0, 1.0, 2.0, 3.0, 4.0]

# Room of the small scenes: x in [0, 4], y in [0, 3], z in [0, 4], open at z = 0
# (the camera's side), like the Cornell box.
RW, RH, RD = 4.0, 3.0, 4.0


# ---------------------------------------------------------------- geometry --
def quad(mesh, corners, facing, cell=CELL, n=None):
    """A grid over the quad, its winding (front face) turned towards `facing`."""
    q, _ = orient(corners, facing)
    nu, nv = (n, n) if n else grid_counts(q, cell)
    add_quad_grid(mesh, q, nu, nv)


def room(parts, lo, hi, mats=("white", "white", "white", "white", "white"), cell=CELL, n=None,
         open_front=True):
    """Inward-facing floor, ceiling, back (z = hi), x = lo and x = hi walls of
    the box lo..hi; the z = lo side is left open.  mats: floor, ceiling, back,
    x-lo wall, x-hi wall."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    quad(parts[mats[0]], [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, 1, 0), cell, n)
    quad(parts[mats[1]], [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, -1, 0), cell, n)
    quad(parts[mats[2]], [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, -1), cell, n)
    quad(parts[mats[3]], [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], (1, 0, 0), cell, n)
    quad(parts[mats[4]], [(x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0)], (-1, 0, 0), cell, n)
    assert open_front


def box(mesh, lo, hi, cell=CELL, skip=()):
    """Outward-facing closed box lo..hi (faces named in `skip` left out:
    '-x', '+x', '-y', '+y', '-z', '+z')."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    faces = {
        "-x": ([(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], (-1, 0, 0)),
        "+x": ([(x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0)], (1, 0, 0)),
        "-y": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, -1, 0)),
        "+y": ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, 1, 0)),
        "-z": ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, -1)),
        "+z": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, 1)),
    }
    for k, (q, f) in faces.items():
        if k not in skip:
            quad(mesh, q, f, cell)


def light_quad(size):
    """A size x size emitter facing down, centred on its node's origin."""
    m = Mesh()
    h = size / 2
    quad(m, [(-h, 0.0, -h), (h, 0.0, -h), (h, 0.0, h), (-h, 0.0, h)], (0, -1, 0), n=1)
    return m


def uv_sphere(radius, rings, segments, centre=(0.0, 0.0, 0.0)):
    """Outward sphere with smooth normals; poles as triangle fans, so
    2 * segments * (rings - 1) triangles."""
    m = Mesh()
    cx, cy, cz = centre
    top = m.add_vertex((cx, cy + radius, cz), (0.0, 1.0, 0.0))
    ring_start = []
    for r in range(1, rings):
        th = math.pi * r / rings
        ring_start.append(m.nverts)
        for s in range(segments):
            ph = 2 * math.pi * s / segments
            n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
            m.add_vertex((cx + radius * n[0], cy + radius * n[1], cz + radius * n[2]), n)
    bottom = m.add_vertex((cx, cy - radius, cz), (0.0, -1.0, 0.0))
    # (ph increasing) x (th increasing) points inwards, so these orders wind outwards
    for s in range(segments):
        s1 = (s + 1) % segments
        a = ring_start[0]
        m.idx += [top, a + s1, a + s]
        b = ring_start[-1]
        m.idx += [bottom, b + s, b + s1]
    for r in range(len(ring_start) - 1):
        a, b = ring_start[r], ring_start[r + 1]
        for s in range(segments):
            s1 = (s + 1) % segments
            m.idx += [a + s, a + s1, b + s1, a + s, b + s1, b + s]
    return m


def cup(r_out, height, wall, segments=32, rows=6):
    """A closed, thick-walled cup (open at the top) standing on y = 0 at the
    node origin: outer and inner cylinder walls with smooth radial normals,
    flat rim, inner floor at y = wall and bottom.  Outward winding."""
    m = Mesh()
    r_in = r_out - wall

    def ring(r, y, n_fn):
        start = m.nverts
        for s in range(segments):
            ph = 2 * math.pi * s / segments
            c, sn = math.cos(ph), math.sin(ph)
            m.add_vertex((r * c, y, r * sn), n_fn(c, sn))
        return start

    def strip(a, b, outward):
        for s in range(segments):
            s1 = (s + 1) % segments
            # a: lower ring, b: upper ring; (s -> s1) runs with +phi
            if outward:
                m.idx += [a + s, b + s1, a + s1, a + s, b + s, b + s1]
            else:
                m.idx += [a + s, a + s1, b + s1, a + s, b + s1, b + s]

    def disc(r, y, up):
        n = (0.0, 1.0 if up else -1.0, 0.0)
        c = m.add_vertex((0.0, y, 0.0), n)
        st = ring(r, y, lambda c_, s_: n)
        for s in range(segments):
            s1 = (s + 1) % segments
            m.idx += [c, st + s1, st + s] if up else [c, st + s, st + s1]

    # outer wall (normals outward), inner wall (normals towards the axis)
    rings = [ring(r_out, height * k / rows, lambda c, s: (c, 0.0, s)) for k in range(rows + 1)]
    for k in range(rows):
        strip(rings[k], rings[k + 1], True)
    rings = [ring(r_in, wall + (height - wall) * k / rows, lambda c, s: (-c, 0.0, -s))
             for k in range(rows + 1)]
    for k in range(rows):
        strip(rings[k], rings[k + 1], False)
    # rim annulus (up)
    a = ring(r_in, height, lambda c, s: (0.0, 1.0, 0.0))
    b = ring(r_out, height, lambda c, s: (0.0, 1.0, 0.0))
    for s in range(segments):
        s1 = (s + 1) % segments
        m.idx += [a + s, b + s1, b + s, a + s, a + s1, b + s1]
    disc(r_in, wall, True)     # inner floor
    disc(r_out, 0.0, False)    # bottom
    return m


def check_winding(m, inside_point=None, outward=True):
    """Signed volume of a closed mesh: positive when it winds outwards."""
    v = 0.0
    P = [tuple(m.pos[3 * i:3 * i + 3]) for i in range(m.nverts)]
    for i in range(0, len(m.idx), 3):
        a, b, c = P[m.idx[i]], P[m.idx[i + 1]], P[m.idx[i + 2]]
        v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
              + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
    assert (v > 0) == outward, ("winding", v)
    return v


# ------------------------------------------------------------------ scene --
class Scene:
    """A Gltf with the stress scenes' common materials and bookkeeping."""

    def __init__(self, name, isolates, extra=None):
        self.name = name
        self.g = Gltf(GENERATOR, COPYRIGHT)
        gib = {"isolates": isolates}
        if extra:
            gib.update(extra)
        self.g.doc["asset"]["extras"] = {"gibench": gib}
        self.mats = {}          # created on first use (the validator flags unused ones)
        self.nodes = []
        self.tris = 0
        self.emissive = 0

    def parts(self):
        return {k: Mesh() for k in ALBEDO}

    def mat(self, name):
        if name not in self.mats:
            self.mats[name] = self.g.material(name, ALBEDO[name])
        return self.mats[name]

    def add(self, name, parts, translation=None, rotation=None):
        """parts: {material name: Mesh} or [(Mesh, material index)]."""
        if isinstance(parts, dict):
            parts = [(m, self.mat(k)) for k, m in parts.items() if m.ntris]
        self.tris += sum(m.ntris for m, _ in parts)
        nd = self.g.node(name, mesh=self.g.mesh(name, parts), translation=translation,
                         rotation=rotation)
        self.nodes.append(nd)
        return nd

    def area_light(self, size, radiance, at):
        ml = self.g.material("light", (0.78, 0.78, 0.78), emission=(1.0, 1.0, 1.0),
                             emission_strength=radiance)
        lm = light_quad(size)
        self.emissive += lm.ntris
        return self.add("light", [(lm, ml)], translation=at)

    def camera(self, name, eye, target, yfov):
        nd = self.g.camera_node(name, eye, target, yfov)
        self.nodes.insert(0, nd)
        return nd

    def write(self, out):
        self.g.scene(self.name, self.nodes)
        self.g.write_gltf(os.path.join(out, self.name + ".gltf"), self.name + ".bin")
        return {"tris": self.tris, "emissive_tris": self.emissive}


# --------------------------------------------------------------- the cases --
TWO_ROOMS_W, TWO_ROOMS_H, TWO_ROOMS_D = 2.5, 2.5, 2.5


def build_two_rooms(out, wall):
    """Two rooms side by side along x, sharing one wall `wall` thick; an area
    light on the ceiling of the left-hand (x < 2.5) room only; the front
    (z = 0) is open on both, so the camera sees both.  The right-hand room
    gets no light at all (light leaving through the openings meets nothing):
    the reference is exactly black there."""
    kind = "thin" if wall < 0.1 else "thick"
    w, h, d = TWO_ROOMS_W, TWO_ROOMS_H, TWO_ROOMS_D
    x_wall0, x_wall1 = w, w + wall
    x_end = 2 * w + wall
    dark = [[x_wall1, 0.0, 0.0], [x_end, h, d]]
    s = Scene("two_rooms_" + kind,
              "light leaking through a %g-unit wall: the right-hand room is exactly dark "
              "in the reference, any energy there is leak" % wall,
              {"lit_room_bounds": [[0.0, 0.0, 0.0], [w, h, d]], "dark_room_bounds": dark})
    p = s.parts()
    # floor, ceiling and back wall run under/over/behind the partition
    room(p, (0.0, 0.0, 0.0), (x_end, h, d))
    m = p["white"]
    # the partition: its two big faces, the front end (seen by the camera); top,
    # bottom and back end touch ceiling, floor and back wall and are left out
    box(m, (x_wall0, 0.0, 0.0), (x_wall1, h, d), skip=("-y", "+y", "+z"))
    s.add("rooms", p)
    s.area_light(0.6, 20.0, (w / 2, h - 0.005, d / 2))
    s.camera("camera", (x_end / 2, h / 2, -6.0), (x_end / 2, h / 2, 0.0), 48.0)
    return s.write(out)


def build_light_in_hull(out):
    """A thick open cup on the floor with a point light inside it, below the
    rim: the light sits inside the cup's convex hull (CSM's and CSSM's limit:
    their occluder representation cannot tell inside from outside).  The
    light shines out of the cup's mouth onto the ceiling and the upper walls;
    the rest of the room is lit only indirectly."""
    s = Scene("light_in_hull", "a point light inside a cup's convex hull (below its rim): "
              "the CSM/CSSM occluder-hull limit")
    p = s.parts()
    room(p, (0.0, 0.0, 0.0), (RW, RH, RD), ("white", "white", "white", "green", "red"))
    s.add("room", p)
    c = cup(0.6, 1.0, 0.05)
    check_winding(c)
    s.add("cup", [(c, s.mat("white"))], translation=(2.0, 0.0, 2.0))
    s.nodes.append(s.g.point_light_node("bulb", 20.0, translation=(2.0, 0.6, 2.0)))
    s.camera("camera", (2.0, 2.4, -4.5), (2.0, 1.1, 2.0), 50.0)
    return s.write(out)


def build_hulls_overlap(out):
    """A still arch (two legs and a lintel, one object) and a block that
    slides through the arch's opening and back (4 s loop): while the block
    is in the opening the two objects' convex hulls overlap though the
    objects never touch (CSSM's limit)."""
    s = Scene("hulls_overlap", "a block sliding through an arch's opening: two objects whose "
              "convex hulls overlap while one moves (CSSM's limit)")
    p = s.parts()
    room(p, (0.0, 0.0, 0.0), (RW, RH, RD), ("white", "white", "white", "green", "red"))
    s.add("room", p)
    arch = Mesh()
    # node origin (2, 0, 2): legs x in [-1, -0.6] and [0.6, 1], lintel on top
    box(arch, (-1.0, 0.0, -0.4), (-0.6, 1.6, 0.4))
    box(arch, (0.6, 0.0, -0.4), (1.0, 1.6, 0.4))
    box(arch, (-1.0, 1.6, -0.4), (1.0, 2.0, 0.4))
    s.add("arch", [(arch, s.mat("white"))], translation=(2.0, 0.0, 2.0))
    blk = Mesh()
    box(blk, (-0.35, 0.0, -0.25), (0.35, 0.8, 0.25))
    zs = [0.8, 2.0, 3.3, 2.0, 0.8]
    # clearance: block x in [1.65, 2.35] against the legs' inner faces 1.4 and
    # 2.6; top 0.8 under the lintel 1.6; z within the room
    assert 2.0 - 0.35 > 1.4 and 2.0 + 0.35 < 2.6 and 0.8 < 1.6
    assert min(zs) - 0.25 > 0.0 and max(zs) + 0.25 < RD
    bn = s.add("block", [(blk, s.mat("white"))], translation=(2.0, 0.0, zs[0]))
    s.g.animation("block_path", [(bn, "translation", LOOP,
                                  [c for z in zs for c in (2.0, 0.0, z)])])
    s.area_light(0.8, 20.0, (2.0, RH - 0.005, 2.0))
    s.camera("camera", (0.6, 2.2, -4.0), (2.0, 0.9, 2.0), 50.0)
    return s.write(out)


def build_glossy(out):
    """The Cornell-like room with a highly glossy floor (normalised Phong,
    ks 0.8, exponent 500, albedo 0.1) and nothing else: the camera, inside
    the room and looking down at the floor, sees the light's highlight and
    the coloured walls mirrored in it."""
    s = Scene("glossy", "one highly glossy floor (Phong ks 0.8, n 500) lit by an area light: "
              "VPL spikes, clamping darkening, discretised directions")
    p = s.parts()
    glossy = s.g.material("glossy_floor", (0.1, 0.1, 0.1), ks=(0.8, 0.8, 0.8), exponent=500.0)
    s.mats["glossy"] = glossy
    p["glossy"] = Mesh()
    room(p, (0.0, 0.0, 0.0), (RW, RH, RD), ("glossy", "white", "white", "green", "red"))
    s.add("room", p)
    # the light's mirror image in the floor is seen 50 degrees below the
    # horizon, near the image centre (the camera looks 45 degrees down)
    s.area_light(0.8, 20.0, (2.0, RH - 0.005, 3.4))
    s.camera("camera", (2.0, 1.0, 0.1), (2.0, 0.0, 1.1), 60.0)
    return s.write(out)


def lit_room_with_block(s):
    p = s.parts()
    room(p, (0.0, 0.0, 0.0), (RW, RH, RD), ("white", "white", "white", "green", "red"))
    s.add("room", p)
    blk = Mesh()
    box(blk, (-0.4, 0.0, -0.4), (0.4, 1.2, 0.4))
    s.add("block", [(blk, s.mat("white"))], translation=(2.0, 0.0, 2.0))


def build_moving_light(out):
    """The room with one block, lit only by a point light that circles
    (radius 1, 0.6 below the ceiling) once in 4 s: the block's shadow sweeps
    round the floor.  16 LINEAR keys (a 16-gon)."""
    s = Scene("moving_light", "a point light circling a block (4 s loop): per-frame cost and "
              "flicker when only the light moves")
    lit_room_with_block(s)
    times = [0.25 * k for k in range(17)]
    path = [(2.0 + math.cos(2 * math.pi * t / 4.0), RH - 0.6, 2.0 + math.sin(2 * math.pi * t / 4.0))
            for t in times]
    ln = s.g.point_light_node("bulb", 8.0, translation=path[0])
    s.nodes.append(ln)
    s.g.animation("light_path", [(ln, "translation", times, [c for q in path for c in q])])
    s.camera("camera", (2.0, 1.5, -5.0), (2.0, 1.5, 0.0), 45.0)
    return s.write(out)


def build_moving_camera(out):
    """The room with one block and a still ceiling light; the camera moves
    on a 4 s loop (in through the open front and out again) while looking
    at the block: nothing in the scene changes, only the view."""
    s = Scene("moving_camera", "only the camera moves (4 s loop, into the room and out): "
              "view-dependent flicker and per-frame cost with a still scene")
    lit_room_with_block(s)
    s.area_light(0.8, 20.0, (2.0, RH - 0.005, 2.0))
    target = (2.0, 0.8, 2.0)
    eyes = [(1.0, 1.7, -3.0), (0.9, 1.8, 0.8), (3.0, 1.7, -3.0), (2.0, 2.2, -4.5), (1.0, 1.7, -3.0)]
    quats = [look_at_quat(e, target) for e in eyes]
    for i in range(1, len(quats)):   # keep slerp on the short way
        if sum(a * b for a, b in zip(quats[i - 1], quats[i])) < 0:
            quats[i] = tuple(-c for c in quats[i])
    cam = s.camera("camera", eyes[0], target, 50.0)
    s.g.doc["nodes"][cam]["rotation"] = list(quats[0])
    s.g.animation("camera_path", [(cam, "translation", LOOP, [c for e in eyes for c in e]),
                                  (cam, "rotation", LOOP, [c for q in quats for c in q])])
    return s.write(out)


SCALE_LEVELS = [3, 6, 12, 24, 48, 64]   # cells per wall edge; sphere rings, 2x segments
SCALE_SIZE = 3.0


def build_scale(out, n):
    """A 3-unit cube room (open front, n x n quads a wall) with a sphere on
    the floor and a ceiling light: 10 n^2 + 4 n (n - 1) + 2 triangles."""
    p_tris = 10 * n * n + 4 * n * (n - 1) + 2
    name = "scale_t%05d" % p_tris
    s = Scene(name, "tessellation sweep (%d triangles: walls %dx%d quads, sphere %d rings): "
              "time and memory against triangle count" % (p_tris, n, n, n))
    s.name = name
    p = s.parts()
    room(p, (0.0, 0.0, 0.0), (SCALE_SIZE, SCALE_SIZE, SCALE_SIZE),
         ("white", "white", "white", "green", "red"), n=n)
    s.add("room", p)
    sp = uv_sphere(0.7, n, 2 * n)
    check_winding(sp)
    s.add("sphere", [(sp, s.mat("white"))], translation=(1.5, 0.7, 1.6))
    s.area_light(0.6, 20.0, (1.5, SCALE_SIZE - 0.005, 1.5))
    s.camera("camera", (1.5, 1.5, -3.6), (1.5, 1.5, 0.0), 45.0)
    st = s.write(out)
    assert st["tris"] == p_tris, (st, p_tris)
    return name + ".gltf", st


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--out", default=os.path.join(here, "..", "scenes", "stress"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    stats = {
        "two_rooms_thin.gltf": build_two_rooms(a.out, 0.02),
        "two_rooms_thick.gltf": build_two_rooms(a.out, 0.3),
        "light_in_hull.gltf": build_light_in_hull(a.out),
        "hulls_overlap.gltf": build_hulls_overlap(a.out),
        "glossy.gltf": build_glossy(a.out),
        "moving_light.gltf": build_moving_light(a.out),
        "moving_camera.gltf": build_moving_camera(a.out),
    }
    for n in SCALE_LEVELS:
        k, st = build_scale(a.out, n)
        stats[k] = st
    print("| file | triangles | emissive triangles |")
    print("|---|---:|---:|")
    for k, st in stats.items():
        print("| %s | %d | %d |" % (k, st["tris"], st["emissive_tris"]))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Generates gibench's test scenes (scenes/*.gltf, *.glb) from packaged sources.

Inputs (see scenes/README.md for provenance and licences):
  --cornell-obj  Embree's cornell_box.obj (Debian package embree-tools)
  --meshes-json  JSON {"bunny": {positions, cells}, "teapot": {...}} dumped from
                 the npm packages `bunny` and `teapot` (make-scenes.sh does this)
  --env-name     file name (without .exr) of the environment map already written
                 to <out>/env/ by make-scenes.sh
Stdlib only.  Output is deterministic.  Run through scripts/make-scenes.sh.
"""

import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltf_writer import (Gltf, Mesh, png_rgb8, sub, add, scale, dot, cross, norm,  # noqa: E402
                         lerp, quat_axis_angle, quat_rotate)

GENERATOR = "gibench scripts/make_scenes.py"
CELLS_ACROSS = 32          # Cornell tessellation: cells per box width

CORNELL_COPYRIGHT = ("Cornell box geometry: Cornell University Program of Computer Graphics "
                     "(cornell_box.obj as shipped with Intel Embree, Apache-2.0)")
BUNNY_COPYRIGHT = ("Stanford bunny: Stanford University Computer Graphics Laboratory, "
                   "Stanford 3D Scanning Repository, via npm package bunny (Public Domain)")
TEAPOT_COPYRIGHT = "Utah teapot: Martin Newell (1975), via npm package teapot (Public Domain)"

WHITE = (0.73, 0.73, 0.73)
RED = (0.63, 0.065, 0.05)
GREEN = (0.14, 0.45, 0.091)
CORNELL_LIGHT_RADIANCE = (17.0, 12.0, 4.0)


# ---------------------------------------------------------------- geometry --
def newell(pts):
    n = [0.0, 0.0, 0.0]
    for i, p in enumerate(pts):
        q = pts[(i + 1) % len(pts)]
        n[0] += (p[1] - q[1]) * (p[2] + q[2])
        n[1] += (p[2] - q[2]) * (p[0] + q[0])
        n[2] += (p[0] - q[0]) * (p[1] + q[1])
    return norm(tuple(n))


def centroid(pts):
    c = (0.0, 0.0, 0.0)
    for p in pts:
        c = add(c, p)
    return scale(c, 1.0 / len(pts))


def orient(corners, want):
    """Returns the quad corners ordered so that their winding normal faces `want`."""
    if dot(newell(corners), want) < 0:
        return [corners[0], corners[3], corners[2], corners[1]], True
    return list(corners), False


def add_quad_grid(mesh, corners, nu, nv, uv_fn=None):
    """Bilinear nu x nv grid over quad p0..p3 (winding = front), flat normal."""
    p0, p1, p2, p3 = corners
    n = newell(corners)
    base = mesh.nverts
    for j in range(nv + 1):
        t = j / nv
        a, b = lerp(p0, p3, t), lerp(p1, p2, t)
        for i in range(nu + 1):
            p = lerp(a, b, i / nu)
            mesh.add_vertex(p, n, uv_fn(p) if uv_fn else None)
    row = nu + 1
    for j in range(nv):
        for i in range(nu):
            a = base + j * row + i
            mesh.idx += [a, a + 1, a + row + 1, a, a + row + 1, a + row]


def grid_counts(corners, cell):
    p0, p1, p2, p3 = corners
    lu = 0.5 * (math.dist(p0, p1) + math.dist(p3, p2))
    lv = 0.5 * (math.dist(p0, p3) + math.dist(p1, p2))
    return max(1, round(lu / cell)), max(1, round(lv / cell))


def smooth_normals(pos, cells, weld):
    """Area-weighted vertex normals; weld=True averages over coincident positions."""
    nv = len(pos)
    key = list(range(nv))
    if weld:
        first = {}
        for i, p in enumerate(pos):
            k = tuple(round(c, 5) for c in p)
            key[i] = first.setdefault(k, i)
    acc = [[0.0, 0.0, 0.0] for _ in range(nv)]
    for c in cells:
        a, b, d = (pos[i] for i in c)
        fn = cross(sub(b, a), sub(d, a))
        for i in c:
            k = key[i]
            acc[k][0] += fn[0]
            acc[k][1] += fn[1]
            acc[k][2] += fn[2]
    out = []
    for i in range(nv):
        n = acc[key[i]]
        l = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        out.append((n[0] / l, n[1] / l, n[2] / l) if l > 0 else (0.0, 1.0, 0.0))
    return out


def signed_volume(pos, cells):
    v = 0.0
    for c in cells:
        a, b, d = (pos[i] for i in c)
        v += dot(a, cross(b, d)) / 6.0
    return v


def npm_mesh(data, height):
    """Scale to `height`, origin at the bottom centre of the bounding box."""
    P, C = data["positions"], data["cells"]
    lo = [min(p[k] for p in P) for k in range(3)]
    hi = [max(p[k] for p in P) for k in range(3)]
    s = height / (hi[1] - lo[1])
    c = ((lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2)
    pos = [scale(sub(p, c), s) for p in P]
    cells = [tuple(t) for t in C]
    if signed_volume(pos, cells) < 0:
        cells = [(a, c_, b) for a, b, c_ in cells]
    return pos, cells


def smooth_mesh(pos, cells, weld):
    m = Mesh()
    for p, n in zip(pos, smooth_normals(pos, cells, weld)):
        m.add_vertex(p, n)
    for c in cells:
        m.idx += list(c)
    return m


def ground_grid(size, cells, uv_period=None):
    half = size / 2
    corners = [(-half, 0.0, -half), (-half, 0.0, half), (half, 0.0, half), (half, 0.0, -half)]
    corners, _ = orient(corners, (0, 1, 0))
    uv = None
    if uv_period:
        uv = lambda p: ((p[0] + half) / uv_period, (p[2] + half) / uv_period)  # noqa: E731
    m = Mesh(textured=uv is not None)
    add_quad_grid(m, corners, cells, cells, uv)
    return m


def checker_png(n=256, squares=8, light=203, dark=108):
    sq = n // squares

    def px(x, y):
        v = light if ((x // sq) + (y // sq)) % 2 == 0 else dark
        return (v, v, v)
    return png_rgb8(n, n, px)


def srgb_to_linear(c8):
    c = c8 / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


# ------------------------------------------------------------ Cornell box --
def parse_obj(path):
    """Faces of Embree's cornell_box.obj, in units of 1/100 of the file's.

    Faces commented out as '#f' (the light, the front wall) are returned with
    commented=True.
    """
    verts, faces = [], []
    obj = mtl = None
    with open(path) as f:
        for line in f:
            s = line.strip()
            commented = s.startswith("#f")
            if commented:
                s = s[1:]
            elif not s or s.startswith("#"):
                continue
            tok = s.split()
            if tok[0] == "o":
                obj = tok[1]
            elif tok[0] == "usemtl":
                mtl = tok[1]
            elif tok[0] == "v":
                verts.append(tuple(float(x) / 100.0 for x in tok[1:4]))
            elif tok[0] == "f":
                ids = [int(t.split("/")[0]) for t in tok[1:]]
                ids = [len(verts) + i if i < 0 else i - 1 for i in ids]
                faces.append({"obj": obj, "mtl": mtl, "pts": [verts[i] for i in ids],
                              "commented": commented})
    return faces


def point_in_poly_xz(p, poly):
    x, z = p[0], p[2]
    inside = False
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        if (a[2] > z) != (b[2] > z):
            xi = a[0] + (z - a[2]) * (b[0] - a[0]) / (b[2] - a[2])
            if x < xi:
                inside = not inside
    return inside


class Cornell:
    def __init__(self, obj_path):
        faces = parse_obj(obj_path)
        self.notes = []
        walls = {"floor": [], "ceiling": [], "back_wall": [], "green_wall": [], "red_wall": []}
        blocks = {"short_block": [], "tall_block": []}
        light = None
        floor_extra = []
        for f in faces:
            o = f["obj"]
            if o == "light" and f["commented"]:
                light = f["pts"]
            elif f["commented"]:
                continue                      # front wall: the open side
            elif o == "floor" and walls["floor"]:
                floor_extra.append(f["pts"])  # block bottoms listed under 'floor'
            elif o in walls:
                walls[o].append(f["pts"])
            elif o in blocks:
                blocks[o].append(f["pts"])
            else:
                raise SystemExit("unexpected object in obj: %s" % o)
        assert light is not None and all(len(v) == 1 for v in walls.values())
        for pts in floor_extra:
            for name, bf in blocks.items():
                top = max(bf, key=lambda q: centroid(q)[1])
                if point_in_poly_xz(centroid(pts), top):
                    bf.append(pts)
                    break
            else:
                raise SystemExit("floor face not under a block")
        self.width = max(p[0] for p in walls["ceiling"][0])      # 5.56
        all_wall = [p for v in walls.values() for q in v for p in q]
        lo = [min(p[k] for p in all_wall) for k in range(3)]
        hi = [max(p[k] for p in all_wall) for k in range(3)]
        self.center = tuple((lo[k] + hi[k]) / 2 for k in range(3))
        self.bounds = (lo, hi)
        self.walls = {}
        for name, (q,) in walls.items():
            q, flipped = orient(q, sub(self.center, centroid(q)))
            if flipped:
                self.notes.append("flipped %s to face inwards" % name)
            self.walls[name] = q
        self.blocks = {}
        for name, qs in blocks.items():
            assert len(qs) == 6, (name, len(qs))
            c = centroid([p for q in qs for p in q])
            out = []
            for q in qs:
                q2, flipped = orient(q, sub(centroid(q), c))
                if flipped:
                    self.notes.append("flipped a face of %s to face outwards" % name)
                out.append(q2)
            bottom = min(out, key=lambda q: centroid(q)[1])
            fc = centroid(bottom)
            self.blocks[name] = {"faces": out, "origin": (fc[0], 0.0, fc[2]),
                                 "footprint": bottom}
        self.light, flipped = orient(light, (0.0, -1.0, 0.0))
        if flipped:
            self.notes.append("flipped the light to face down")

    def wall_meshes(self, cell):
        parts = {"white": Mesh(), "red": Mesh(), "green": Mesh()}
        mat_of = {"floor": "white", "ceiling": "white", "back_wall": "white",
                  "red_wall": "red", "green_wall": "green"}
        for name, q in self.walls.items():
            nu, nv = grid_counts(q, cell) if cell else (1, 1)
            add_quad_grid(parts[mat_of[name]], q, nu, nv)
        return parts

    def block_mesh(self, name, cell):
        b = self.blocks[name]
        m = Mesh()
        o = b["origin"]
        for q in b["faces"]:
            ql = [sub(p, o) for p in q]
            nu, nv = grid_counts(ql, cell) if cell else (1, 1)
            add_quad_grid(m, ql, nu, nv)
        return m

    def light_mesh(self):
        c = centroid(self.light)
        m = Mesh()
        add_quad_grid(m, [sub(p, c) for p in self.light], 1, 1)
        return m, c


def cornell_camera(g):
    # Classic Cornell camera: eye (278, 273, -800), looking along +z, 35 mm lens
    # on a 25 mm film -> yfov = 2 atan(12.5 / 35) = 39.31 degrees.
    yfov = math.degrees(2 * math.atan(12.5 / 35.0))
    return g.camera_node("camera", (2.78, 2.73, -8.0), (2.78, 2.73, 0.0), yfov)


def cornell_materials(g):
    m = {"white": g.material("white", WHITE), "red": g.material("red", RED),
         "green": g.material("green", GREEN)}
    L = CORNELL_LIGHT_RADIANCE
    m["light"] = g.material("light", (0.78, 0.78, 0.78),
                            emission=tuple(c / L[0] for c in L), emission_strength=L[0])
    return m


def build_cornell(cb, out_path, tessellate=True, glossy=False, bunny=None, anim=None,
                  deform=False):
    title = os.path.splitext(os.path.basename(out_path))[0]
    cr = CORNELL_COPYRIGHT + ("; " + BUNNY_COPYRIGHT if bunny else "")
    g = Gltf(GENERATOR, cr)
    mats = cornell_materials(g)
    cell = cb.width / CELLS_ACROSS if tessellate else None
    nodes = []
    parts = cb.wall_meshes(cell)
    nodes.append(g.node("walls", mesh=g.mesh("walls", [(parts[k], mats[k])
                                                       for k in ("white", "red", "green")])))
    stats = {"tris": sum(p.ntris for p in parts.values())}
    if glossy:
        short_mat = g.material("glossy", (0.2, 0.2, 0.2), ks=(0.5, 0.5, 0.5), exponent=50)
        tall_mat = g.material("mirror", (0.0, 0.0, 0.0), ks=(0.9, 0.9, 0.9), exponent=10000,
                              mirror=True)
    else:
        short_mat = tall_mat = mats["white"]
    if bunny is None:
        m = cb.block_mesh("short_block", cell)
        stats["tris"] += m.ntris
        if deform:
            m.targets, times, weights = short_block_morph(cb, m)
        sb = g.node("short_block", mesh=g.mesh("short_block", [(m, short_mat)],
                                               weights=[0.0, 0.0] if deform else None),
                    translation=cb.blocks["short_block"]["origin"])
        nodes.append(sb)
        if deform:
            g.animation("short_block_morph", [(sb, "weights", times, weights)])
    m = cb.block_mesh("tall_block", cell)
    stats["tris"] += m.ntris
    nodes.append(g.node("tall_block", mesh=g.mesh("tall_block", [(m, tall_mat)]),
                        translation=cb.blocks["tall_block"]["origin"]))
    lm, lc = cb.light_mesh()
    stats["tris"] += lm.ntris
    stats["emissive_tris"] = lm.ntris
    nodes.append(g.node("light", mesh=g.mesh("light", [(lm, mats["light"])]), translation=lc))
    if bunny is not None:
        stats["tris"] += bunny.ntris
        t0, r0 = anim["translation"][0], anim["rotation"][0]
        mb = g.material("bunny", WHITE)
        bn = g.node("bunny", mesh=g.mesh("bunny", [(bunny, mb)]),
                    translation=t0, rotation=r0)
        nodes.append(bn)
        g.animation("bunny_path", [
            (bn, "translation", anim["times"], [c for t in anim["translation"] for c in t]),
            (bn, "rotation", anim["times"], [c for q in anim["rotation"] for c in q])])
    nodes.insert(0, cornell_camera(g))
    g.scene(title, nodes)
    g.write_gltf(out_path, title + ".bin")
    return stats


# ------------------------------------------------------ deforming block ----
MORPH_STRETCH = 0.5   # target 0: heights grow by this fraction
MORPH_BULGE = 0.2     # target 1: sides bow out by this fraction of their offset at mid-height


def mesh_vertex_normals(pos, idx):
    """Area-weighted vertex normals over the mesh's own index sharing (no welding)."""
    cells = [idx[i:i + 3] for i in range(0, len(idx), 3)]
    return smooth_normals(pos, cells, weld=False)


def short_block_morph(cb, m):
    """Two morph targets of the short block, each a function of the rest
    position alone (so coincident vertices of adjacent faces move together and
    the block stays closed): 'stretch' d = (0, s y, 0) and 'bulge'
    d = b sin(pi y / h) (x, 0, z) in block-local coordinates (origin at the
    centre of the footprint). NORMAL targets are the area-weighted vertex
    normals of the fully displaced mesh minus the rest normals.  Weights
    (stretch, bulge) animate LINEAR over 0..4 s: (0,0) (1,0) (1,1) (0,1) (0,0)."""
    pos = [tuple(m.pos[3 * i:3 * i + 3]) for i in range(m.nverts)]
    h = max(p[1] for p in pos)
    fns = [lambda p: (0.0, MORPH_STRETCH * p[1], 0.0),
           lambda p: (MORPH_BULGE * math.sin(math.pi * p[1] / h) * p[0], 0.0,
                      MORPH_BULGE * math.sin(math.pi * p[1] / h) * p[2])]
    rest_n = mesh_vertex_normals(pos, m.idx)
    targets = []
    for fn in fns:
        d = [fn(p) for p in pos]
        moved = [add(p, q) for p, q in zip(pos, d)]
        n1 = mesh_vertex_normals(moved, m.idx)
        targets.append({"POSITION": [c for q in d for c in q],
                        "NORMAL": [c for a, b in zip(n1, rest_n) for c in sub(a, b)]})
    # Clearance: the fully displaced block (both weights 1) stays inside the
    # room and off the tall block's footprint.
    o = cb.blocks["short_block"]["origin"]
    both = [add(add(p, fns[0](p)), fns[1](p)) for p in pos]
    world = [add(p, o) for p in both]
    lo, hi = cb.bounds
    assert all(lo[k] < p[k] < hi[k] for p in world for k in (0, 2)), "short block leaves the room"
    assert max(p[1] for p in world) < hi[1] - 1.0, "short block reaches the light"
    tall = cb.blocks["tall_block"]["footprint"]
    assert not any(point_in_poly_xz(p, tall) for p in world), "short block enters the tall block"
    times = [0.0, 1.0, 2.0, 3.0, 4.0]
    weights = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0]
    return targets, times, weights


# --------------------------------------------------------- moving bunny ----
def seg_dist2(p, a, b):
    ab = (b[0] - a[0], b[1] - a[1])
    ap = (p[0] - a[0], p[1] - a[1])
    t = max(0.0, min(1.0, (ap[0] * ab[0] + ap[1] * ab[1]) / (ab[0] ** 2 + ab[1] ** 2)))
    d = (ap[0] - t * ab[0], ap[1] - t * ab[1])
    return d[0] ** 2 + d[1] ** 2


def bunny_animation(cb, bunny_pos):
    """Keyframes (LINEAR) of a loop across the floor and back in 4 s with one
    full turn about +Y; checked against the walls and the tall block."""
    times = [0.0, 1.0, 2.0, 3.0, 4.0]
    path = [(1.05, 0.0, 1.25), (2.45, 0.0, 0.95), (4.45, 0.0, 1.35), (2.3, 0.0, 1.75),
            (1.05, 0.0, 1.25)]
    rots = [quat_axis_angle((0, 1, 0), math.radians(90.0 * k)) for k in range(5)]
    # rotations stay sign-continuous, so slerp follows +90 degrees per second
    for a, b in zip(rots, rots[1:]):
        assert sum(x * y for x, y in zip(a, b)) > 0
    foot = cb.blocks["tall_block"]["footprint"]
    poly = [(p[0], p[2]) for p in foot]
    (lo, hi) = cb.bounds
    red_x = min(p[0] for p in cb.walls["red_wall"])
    back_z = min(p[2] for p in cb.walls["back_wall"])
    hull = [(p[0], p[2]) for p in bunny_pos]
    min_clear = 1e9
    steps = 400
    for s in range(steps + 1):
        t = 4.0 * s / steps
        k = min(int(t), 3)
        u = t - k
        tr = lerp(path[k], path[k + 1], u)
        ang = math.radians(90.0 * t)
        q = quat_axis_angle((0, 1, 0), ang)
        pts = []
        for p in hull[::3]:
            w = quat_rotate(q, (p[0], 0.0, p[1]))
            pts.append((w[0] + tr[0], w[2] + tr[2]))
        for x, z in pts:
            assert not point_in_poly_xz((x, 0, z), foot), "bunny enters the tall block"
            clear = min(x - lo[0], red_x - x, z - 0.0, back_z - z,
                        min(math.sqrt(seg_dist2((x, z), poly[i], poly[(i + 1) % 4]))
                            for i in range(4)))
            min_clear = min(min_clear, clear)
        for c in poly:   # block corners must not be inside the bunny's footprint
            assert not point_in_poly_xz((c[0], 0, c[1]), convex_hull_xz(pts))
    assert min_clear > 0.05, "bunny path too close to a wall or the block: %.3f" % min_clear
    return {"times": times, "translation": path, "rotation": rots, "clearance": min_clear}


def convex_hull_xz(pts):
    pts = sorted(set(pts))

    def half(points):
        h = []
        for p in points:
            while len(h) >= 2 and ((h[-1][0] - h[-2][0]) * (p[1] - h[-2][1])
                                   - (h[-1][1] - h[-2][1]) * (p[0] - h[-2][0])) <= 0:
                h.pop()
            h.append(p)
        return h
    lower, upper = half(pts), half(pts[::-1])
    return [(x, 0.0, z) for x, z in lower[:-1] + upper[:-1]]


# ------------------------------------------------------------- env scenes --
def env_extras(env_name):
    return {"gibench": {"environment": {"uri": "env/%s.exr" % env_name, "intensity": 1.0,
                                        "rotation_deg": 0.0}}}


def build_bunny_env(meshes, env_name, out_path):
    g = Gltf(GENERATOR, BUNNY_COPYRIGHT + "; environment map: Blender studiolight "
             + env_name + ".exr (CC0, Greg Zaal, HDRI Haven)")
    pos, cells = npm_mesh(meshes["bunny"], 1.0)
    bunny = smooth_mesh(pos, cells, weld=False)
    ground = ground_grid(10.0, 64)
    mb = g.material("bunny", WHITE)
    mg = g.material("ground", (0.5, 0.5, 0.5))
    # viewed from -z so that the map's brightest region (the sun, towards
    # (0.55, 0.34, -0.76)) lights the bunny from about 85 degrees to the side
    cam = g.camera_node("camera", (-2.4, 1.0, -2.1), (0.0, 0.45, 0.0), 30.0)
    n1 = g.node("bunny", mesh=g.mesh("bunny", [(bunny, mb)]))
    n2 = g.node("ground", mesh=g.mesh("ground", [(ground, mg)]))
    g.scene("bunny_env", [cam, n1, n2], extras=env_extras(env_name))
    g.write_glb(out_path)
    return {"tris": bunny.ntris + ground.ntris, "emissive_tris": 0}


def build_bunny_alone_env(meshes, env_name, out_path):
    """The bunny of bunny_env.glb without the ground: the object alone, as in
    the CSM paper's Table 1 (compression of one object's maps)."""
    g = Gltf(GENERATOR, BUNNY_COPYRIGHT + "; environment map: Blender studiolight "
             + env_name + ".exr (CC0, Greg Zaal, HDRI Haven)")
    pos, cells = npm_mesh(meshes["bunny"], 1.0)
    bunny = smooth_mesh(pos, cells, weld=False)
    mb = g.material("bunny", WHITE)
    cam = g.camera_node("camera", (-2.4, 1.0, -2.1), (0.0, 0.45, 0.0), 30.0)
    n1 = g.node("bunny", mesh=g.mesh("bunny", [(bunny, mb)]))
    g.scene("bunny_alone_env", [cam, n1], extras=env_extras(env_name))
    g.write_glb(out_path)
    return {"tris": bunny.ntris, "emissive_tris": 0}


def moving_bunny_path(bunny_pos, teapot_pos):
    """A 4 s LINEAR loop of the bunny behind the teapot (between it and the
    map's brightest region) with one full turn about +Y; its footprint is
    checked to stay clear of the teapot's at 401 times."""
    times = [0.0, 1.0, 2.0, 3.0, 4.0]
    path = [(-1.7, 0.0, -1.4), (0.0, 0.0, -1.7), (1.7, 0.0, -1.4), (0.0, 0.0, -2.4),
            (-1.7, 0.0, -1.4)]
    rots = [quat_axis_angle((0, 1, 0), math.radians(90.0 * k)) for k in range(5)]
    for a, b in zip(rots, rots[1:]):
        assert sum(x * y for x, y in zip(a, b)) > 0
    teapot_hull = convex_hull_xz([(p[0], p[2]) for p in teapot_pos])
    hull = [(p[0], p[2]) for p in bunny_pos]
    min_clear = 1e9
    for s in range(401):
        t = 4.0 * s / 400
        k = min(int(t), 3)
        tr = lerp(path[k], path[k + 1], t - k)
        q = quat_axis_angle((0, 1, 0), math.radians(90.0 * t))
        for p in hull[::3]:
            w = quat_rotate(q, (p[0], 0.0, p[1]))
            x, z = w[0] + tr[0], w[2] + tr[2]
            assert not point_in_poly_xz((x, 0, z), teapot_hull), "bunny enters the teapot"
            d = min(math.sqrt(seg_dist2((x, z), (teapot_hull[i][0], teapot_hull[i][2]),
                                        (teapot_hull[(i + 1) % len(teapot_hull)][0],
                                         teapot_hull[(i + 1) % len(teapot_hull)][2])))
                    for i in range(len(teapot_hull)))
            min_clear = min(min_clear, d)
    assert min_clear > 0.1, "bunny path too close to the teapot: %.3f" % min_clear
    return {"times": times, "translation": path, "rotation": rots, "clearance": min_clear}


def build_bunny_teapot_moving(meshes, env_name, out_path):
    """Two objects under the environment map, one animated: the teapot stands
    still at the origin, the bunny loops behind it on the ground (4 s)."""
    g = Gltf(GENERATOR, BUNNY_COPYRIGHT + "; " + TEAPOT_COPYRIGHT
             + "; environment map: Blender studiolight " + env_name
             + ".exr (CC0, Greg Zaal, HDRI Haven)")
    bpos, bcells = npm_mesh(meshes["bunny"], 1.0)
    bunny = smooth_mesh(bpos, bcells, weld=False)
    tpos, tcells = npm_mesh(meshes["teapot"], 1.0)
    teapot = smooth_mesh(tpos, tcells, weld=True)
    ground = ground_grid(10.0, 64)
    anim = moving_bunny_path(bpos, tpos)
    mb = g.material("bunny", WHITE)
    mt = g.material("teapot", (0.75, 0.55, 0.3), double_sided=True)
    mg = g.material("ground", (0.5, 0.5, 0.5))
    cam = g.camera_node("camera", (0.0, 2.2, 3.6), (0.0, 0.3, -0.9), 50.0)
    bn = g.node("bunny", mesh=g.mesh("bunny", [(bunny, mb)]),
                translation=anim["translation"][0], rotation=anim["rotation"][0])
    nodes = [cam, g.node("teapot", mesh=g.mesh("teapot", [(teapot, mt)])), bn,
             g.node("ground", mesh=g.mesh("ground", [(ground, mg)]))]
    g.animation("bunny_path", [
        (bn, "translation", anim["times"], [c for t in anim["translation"] for c in t]),
        (bn, "rotation", anim["times"], [c for q in anim["rotation"] for c in q])])
    g.scene("bunny_teapot_moving", nodes, extras=env_extras(env_name))
    g.write_glb(out_path)
    print("note: bunny_teapot_moving clearance %.3f" % anim["clearance"])
    return {"tris": bunny.ntris + teapot.ntris + ground.ntris, "emissive_tris": 0}


def build_teapot(meshes, env_name, out_path, area_light):
    cr = TEAPOT_COPYRIGHT
    if not area_light:
        cr += ("; environment map: Blender studiolight " + env_name
               + ".exr (CC0, Greg Zaal, HDRI Haven)")
    g = Gltf(GENERATOR, cr)
    pos, cells = npm_mesh(meshes["teapot"], 1.0)
    teapot = smooth_mesh(pos, cells, weld=True)
    assert teapot.nverts == 792
    ground = ground_grid(10.0, 64, uv_period=2.0)
    tex = g.png_texture(checker_png(), "checker")
    mt = g.material("teapot", (0.75, 0.55, 0.3), double_sided=True)
    mg = g.material("ground_checker", (1.0, 1.0, 1.0), texture=tex)
    cam = g.camera_node("camera", (0.0, 1.6, 4.0), (0.0, 0.42, 0.0), 38.0)
    nodes = [cam,
             g.node("teapot", mesh=g.mesh("teapot", [(teapot, mt)])),
             g.node("ground", mesh=g.mesh("ground", [(ground, mg)]))]
    stats = {"tris": teapot.ntris + ground.ntris, "emissive_tris": 0}
    extras = None
    if area_light:
        lm = Mesh()
        add_quad_grid(lm, orient([(-0.5, 0.0, -0.5), (0.5, 0.0, -0.5), (0.5, 0.0, 0.5),
                                  (-0.5, 0.0, 0.5)], (0, -1, 0))[0], 1, 1)
        ml = g.material("light", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0),
                        emission_strength=40.0)
        nodes.append(g.node("light", mesh=g.mesh("light", [(lm, ml)]),
                            translation=(0.9, 3.0, 0.7)))
        stats["tris"] += lm.ntris
        stats["emissive_tris"] = lm.ntris
    else:
        extras = env_extras(env_name)
    g.scene(os.path.splitext(os.path.basename(out_path))[0], nodes, extras=extras)
    g.write_glb(out_path)
    return stats


# ----------------------------------------------------------------- U room --
U_CELL = 1.0 / 6.0
U_HEIGHT = 2.5
# floor plan (x, z): near arm x in [0,2], far arm x in [4,6], both z in [0,6];
# connecting corridor x in [0,6], z in [6,8].
U_OUTLINE = [(0, 0), (2, 0), (2, 6), (4, 6), (4, 0), (6, 0), (6, 8), (0, 8)]


def u_inside(x, z):
    return (0 < x < 6 and 6 < z < 8) or (0 < z < 8 and (0 < x < 2 or 4 < x < 6))


def build_u_room(out_path):
    g = Gltf(GENERATOR, "gibench (generated)")
    mw = g.material("white", WHITE)
    room = Mesh()
    # floor and ceiling: masked grids sharing vertices
    nx, nz = round(6 / U_CELL), round(8 / U_CELL)
    for y, up in ((0.0, True), (U_HEIGHT, False)):
        vid = {}
        n = (0.0, 1.0, 0.0) if up else (0.0, -1.0, 0.0)

        def v(i, j):
            if (i, j) not in vid:
                vid[(i, j)] = room.add_vertex((i * U_CELL, y, j * U_CELL), n)
            return vid[(i, j)]
        for j in range(nz):
            for i in range(nx):
                if not u_inside((i + 0.5) * U_CELL, (j + 0.5) * U_CELL):
                    continue
                a, b, c, d = v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)
                # (i,j)->(i+1,j)->(i+1,j+1) winds towards -y
                room.idx += [a, c, b, a, d, c] if up else [a, b, c, a, c, d]
    # walls
    for k in range(len(U_OUTLINE)):
        a2, b2 = U_OUTLINE[k], U_OUTLINE[(k + 1) % len(U_OUTLINE)]
        a, b = (a2[0], 0.0, a2[1]), (b2[0], 0.0, b2[1])
        q = [a, b, (b[0], U_HEIGHT, b[2]), (a[0], U_HEIGHT, a[2])]
        mid = centroid(q)
        n = newell(q)
        probe = add(mid, scale(n, 0.01))
        if not u_inside(probe[0], probe[2]):
            q = [q[0], q[3], q[2], q[1]]
        nu, nv = grid_counts(q, U_CELL)
        add_quad_grid(room, q, nu, nv)
    # light panel in the near arm's ceiling, far from the corridor
    lm = Mesh()
    add_quad_grid(lm, orient([(-0.5, 0.0, -0.5), (0.5, 0.0, -0.5), (0.5, 0.0, 0.5),
                              (-0.5, 0.0, 0.5)], (0, -1, 0))[0], 1, 1)
    ml = g.material("light", (0.78, 0.78, 0.78), emission=(1.0, 1.0, 1.0),
                    emission_strength=15.0)
    cams = [g.camera_node("camera_far_arm", (5.0, 1.5, 7.85), (5.0, 0.9, 0.0), 60.0),
            g.camera_node("camera_corridor", (0.3, 2.0, 7.7), (5.0, 0.8, 6.3), 70.0),
            g.camera_node("camera_near_arm", (1.0, 1.5, 7.85), (1.0, 1.0, 0.0), 60.0)]
    nodes = cams + [g.node("room", mesh=g.mesh("room", [(room, mw)])),
                    g.node("light", mesh=g.mesh("light", [(lm, ml)]),
                           translation=(1.0, U_HEIGHT - 0.01, 1.5))]
    g.scene("u_room", nodes)
    g.write_gltf(out_path, "u_room.bin")
    return {"tris": room.ntris + lm.ntris, "emissive_tris": lm.ntris}


# ------------------------------------------------------------------- main --
def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cornell-obj", required=True)
    ap.add_argument("--meshes-json")
    ap.add_argument("--only", help="write only this scene (cornell_deform.gltf needs no meshes)")
    ap.add_argument("--env-name", default="forest")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    out = a.out
    cb = Cornell(a.cornell_obj)
    for n in cb.notes:
        print("note:", n)
    stats = {}
    stats["cornell_deform.gltf"] = build_cornell(
        cb, os.path.join(out, "cornell_deform.gltf"), deform=True)
    if a.only == "cornell_deform.gltf":
        return
    if a.only or not a.meshes_json:
        raise SystemExit("--meshes-json is required (--only knows cornell_deform.gltf)")
    with open(a.meshes_json) as f:
        meshes = json.load(f)
    stats["cornell_box.gltf"] = build_cornell(cb, os.path.join(out, "cornell_box.gltf"))
    stats["cornell_box_coarse.gltf"] = build_cornell(
        cb, os.path.join(out, "cornell_box_coarse.gltf"), tessellate=False)
    stats["cornell_glossy.gltf"] = build_cornell(
        cb, os.path.join(out, "cornell_glossy.gltf"), glossy=True)
    stats["bunny_env.glb"] = build_bunny_env(meshes, a.env_name,
                                             os.path.join(out, "bunny_env.glb"))
    stats["teapot_plane.glb"] = build_teapot(meshes, a.env_name,
                                             os.path.join(out, "teapot_plane.glb"), False)
    stats["teapot_area.glb"] = build_teapot(meshes, a.env_name,
                                            os.path.join(out, "teapot_area.glb"), True)
    stats["u_room.gltf"] = build_u_room(os.path.join(out, "u_room.gltf"))
    stats["bunny_alone_env.glb"] = build_bunny_alone_env(
        meshes, a.env_name, os.path.join(out, "bunny_alone_env.glb"))
    stats["bunny_teapot_moving.glb"] = build_bunny_teapot_moving(
        meshes, a.env_name, os.path.join(out, "bunny_teapot_moving.glb"))
    pos, cells = npm_mesh(meshes["bunny"], 1.2)
    bunny = smooth_mesh(pos, cells, weld=False)
    anim = bunny_animation(cb, pos)
    print("note: cornell_moving bunny clearance %.3f" % anim["clearance"])
    stats["cornell_moving.gltf"] = build_cornell(
        cb, os.path.join(out, "cornell_moving.gltf"), bunny=bunny, anim=anim)
    print("| file | triangles | emissive triangles |")
    print("|---|---|---|")
    for k, s in stats.items():
        print("| %s | %d | %d |" % (k, s["tris"], s["emissive_tris"]))


if __name__ == "__main__":
    main()

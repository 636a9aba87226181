// AVG construction (§III-A, Fig. 2), geometry stage: the part of one
// triangle inside Z slice k = v_slice (the slab k <= z <= k + 1 in voxel
// units) is drawn into layer k of the two 3D textures with an orthographic
// projection down Z.
//
// u_mode 0 (conservative, the default): a quad covering the pixel bounding
// box of that part; the fragment stage keeps exactly the voxels the
// triangle overlaps (triangle-box test), so no surface leaves a hole.
// u_mode 1 (the paper's): the farthest vertex of a triangle nearly
// perpendicular to the view plane (|n.z| < 1 / gridwidth) moves by epsilon
// along the normal; the slice part of the triangle is drawn as a polygon,
// and where its projected area is below one voxel face a stand-in covering
// its pixel bounding box is drawn instead (the paper's "larger triangle that
// is guaranteed to be rasterised"; one quad covers every voxel it overlaps).
#include "avg_bindings.h"
#include "scene.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 5) out;

in vec3 v_grid[];
flat in uint v_material[];
flat in int v_slice[];

layout(std430, binding = AVG_SSBO_COLOURS) readonly buffer AvgColours { vec4 avg_material_colour[]; };

uniform int u_grid_n;
uniform int u_mode;
uniform float u_epsilon; // the paper's epsilon, in voxels

flat out vec3 g_normal;
flat out vec3 g_colour;
flat out vec3 g_p0;
flat out vec3 g_p1;
flat out vec3 g_p2;

vec3 poly[5];
int poly_n;

// Sutherland-Hodgman against s * z <= s * c (closed: points on the plane stay).
void clip(float c, float s)
{
    vec3 src[5];
    int n = poly_n;
    for (int i = 0; i < n; i++)
        src[i] = poly[i];
    poly_n = 0;
    for (int i = 0; i < n; i++) {
        vec3 a = src[i], b = src[(i + 1) % n];
        float da = s * (a.z - c), db = s * (b.z - c);
        if (da <= 0.0 && poly_n < 5)
            poly[poly_n++] = a;
        if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0))
            if (poly_n < 5)
                poly[poly_n++] = mix(a, b, da / (da - db));
    }
}

void emit(vec2 p)
{
    gl_Layer = v_slice[0];
    gl_Position = vec4(p / float(u_grid_n) * 2.0 - 1.0, 0.0, 1.0);
    EmitVertex();
}

void emit_box(vec2 lo, vec2 hi)
{
    lo = floor(lo);
    hi = max(ceil(hi), lo + 1.0);
    emit(vec2(lo.x, lo.y));
    emit(vec2(hi.x, lo.y));
    emit(vec2(lo.x, hi.y));
    emit(vec2(hi.x, hi.y));
    EndPrimitive();
}

void main()
{
    float k = float(v_slice[0]);
    vec3 a = v_grid[0], b = v_grid[1], c = v_grid[2];
    vec3 cr = cross(b - a, c - a);
    if (dot(cr, cr) <= 0.0)
        return;
    vec3 n = normalize(cr);
    float zmin = min(a.z, min(b.z, c.z)), zmax = max(a.z, max(b.z, c.z));
    if (zmax < k || zmin > k + 1.0)
        return;

    g_normal = n; // the stored normal is the triangle's own, before any shift
    // The material's albedo times its texture's mean colour: the paper's
    // "lowest mip-map level", so texture detail does not fill whole voxels.
    g_colour = avg_material_colour[v_material[0]].rgb;
    g_p0 = a;
    g_p1 = b;
    g_p2 = c;

    if (u_mode == 1 && abs(n.z) < 1.0 / float(u_grid_n)) {
        // The paper's fix for triangles seen edge-on: shift the farthest vertex.
        if (a.z >= b.z && a.z >= c.z)
            a += n * u_epsilon;
        else if (b.z >= c.z)
            b += n * u_epsilon;
        else
            c += n * u_epsilon;
    }
    poly[0] = a;
    poly[1] = b;
    poly[2] = c;
    poly_n = 3;
    clip(k, -1.0);       // z >= k
    clip(k + 1.0, 1.0);  // z <= k + 1
    if (poly_n == 0)
        return;
    vec2 lo = poly[0].xy, hi = poly[0].xy;
    float area2 = 0.0;
    for (int i = 0; i < poly_n; i++) {
        lo = min(lo, poly[i].xy);
        hi = max(hi, poly[i].xy);
        vec2 p = poly[i].xy, q = poly[(i + 1) % poly_n].xy;
        area2 += p.x * q.y - p.y * q.x;
    }
    if (u_mode == 0) {
        emit_box(lo - 1e-3, hi + 1e-3);
        return;
    }
    if (0.5 * abs(area2) < 1.0) {
        emit_box(lo, hi); // stand-in for a part smaller than a voxel face
        return;
    }
    // The convex polygon as a strip: 0, 1, n-1, 2, n-2, ...
    int lo_i = 1, hi_i = poly_n - 1;
    emit(poly[0].xy);
    for (int i = 1; i < poly_n; i++) {
        if ((i & 1) == 1)
            emit(poly[lo_i++].xy);
        else
            emit(poly[hi_i--].xy);
    }
    EndPrimitive();
}

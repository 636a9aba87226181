// AVG construction in a single pass (param voxeliser=single), geometry
// stage: the whole scene is drawn once; each triangle is projected along
// the axis of its normal's largest component (its projected area is then
// at least 1/sqrt(3) of its own, so no triangle is seen edge-on), as a
// quad covering its pixel bounding box on that plane (grown by 1e-3 of a
// voxel, so a wall thinner than a voxel or lying on a voxel face still
// covers every column it touches). The fragment stage then walks the
// voxels of each column the triangle's plane crosses and keeps exactly
// those the triangle overlaps (the same triangle-box test as the per-slice
// conservative voxeliser).
#include "avg_bindings.h"
#include "scene.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

in vec3 v_grid[];
flat in uint v_material[];
flat in int v_slice[];

layout(std430, binding = AVG_SSBO_COLOURS) readonly buffer AvgColours { vec4 avg_material_colour[]; };

uniform int u_grid_n;

flat out vec3 g_normal;
flat out vec3 g_colour;
flat out vec3 g_p0;
flat out vec3 g_p1;
flat out vec3 g_p2;
flat out int g_axis;

// Grid point p on the plane of axis `axis`: (u, v) are the next two axes
// in cyclic order (x: (y, z), y: (z, x), z: (x, y)).
vec2 plane(vec3 p, int axis)
{
    return axis == 0 ? p.yz : (axis == 1 ? p.zx : p.xy);
}

void emit(vec2 p)
{
    gl_Position = vec4(p / float(u_grid_n) * 2.0 - 1.0, 0.0, 1.0);
    EmitVertex();
}

void main()
{
    vec3 a = v_grid[0], b = v_grid[1], c = v_grid[2];
    vec3 cr = cross(b - a, c - a);
    if (dot(cr, cr) <= 0.0)
        return;
    vec3 n = normalize(cr);
    vec3 an = abs(n);
    int axis = (an.x >= an.y && an.x >= an.z) ? 0 : (an.y >= an.z ? 1 : 2);
    g_normal = n;
    g_colour = avg_material_colour[v_material[0]].rgb;
    g_p0 = a;
    g_p1 = b;
    g_p2 = c;
    g_axis = axis;
    vec2 pa = plane(a, axis), pb = plane(b, axis), pc = plane(c, axis);
    vec2 lo = floor(min(pa, min(pb, pc)) - 1e-3);
    vec2 hi = max(ceil(max(pa, max(pb, pc)) + 1e-3), lo + 1.0);
    emit(vec2(lo.x, lo.y));
    emit(vec2(hi.x, lo.y));
    emit(vec2(lo.x, hi.y));
    emit(vec2(hi.x, hi.y));
    EndPrimitive();
}

// AVG construction in a single pass (param voxeliser=single), fragment
// stage: pixel (u, v) of the triangle's dominant-axis plane is a column of
// voxels along that axis. The triangle's plane crosses the column between
// the depths it has at the pixel's four corners (clamped to the
// triangle's own extent on the axis); every voxel of that range, one more
// on each side, is tested against the triangle (the per-slice
// conservative voxeliser's triangle-box test, avg_grid.glsl), and each
// overlapped voxel gets the triangle's normal, colour and a count of 1
// added by integer atomics in fixed point (AVG_VOX_FIXED units; integer
// sums do not depend on the order of fragments). avg_vox_resolve.comp
// turns the sums into the two 3D textures.
#include "avg_bindings.h"
#define AVG_NO_GRID_SAMPLERS
#include "avg_grid.glsl"

flat in vec3 g_normal;
flat in vec3 g_colour;
flat in vec3 g_p0;
flat in vec3 g_p1;
flat in vec3 g_p2;
flat in int g_axis;

layout(std430, binding = AVG_SSBO_VOX_SUMS) coherent buffer AvgVoxSums { int avg_sums[]; };

uniform int u_grid_n;

// (u, v, depth) of the axis' plane and back.
vec3 to_plane(vec3 p)
{
    return g_axis == 0 ? p.yzx : (g_axis == 1 ? p.zxy : p.xyz);
}

vec3 from_plane(vec3 q)
{
    return g_axis == 0 ? q.zxy : (g_axis == 1 ? q.yzx : q.xyz);
}

void main()
{
    vec2 px = floor(gl_FragCoord.xy);
    vec3 q0 = to_plane(g_p0), q1 = to_plane(g_p1), q2 = to_plane(g_p2), m = to_plane(g_normal);
    // depth(u, v) on the triangle's plane; |m.z| >= 1 / sqrt(3) by the choice of axis
    float d00 = q0.z - (m.x * (px.x - q0.x) + m.y * (px.y - q0.y)) / m.z;
    float du = -m.x / m.z, dv = -m.y / m.z;
    float dmin = d00 + min(du, 0.0) + min(dv, 0.0), dmax = d00 + max(du, 0.0) + max(dv, 0.0);
    dmin = max(dmin, min(q0.z, min(q1.z, q2.z)));
    dmax = min(dmax, max(q0.z, max(q1.z, q2.z)));
    int k0 = max(int(floor(dmin)) - 1, 0), k1 = min(int(floor(dmax)) + 1, u_grid_n - 1);
    int n = u_grid_n;
    for (int k = k0; k <= k1; k++) {
        vec3 centre = from_plane(vec3(px + 0.5, float(k) + 0.5));
        if (!avg_triangle_box(g_p0, g_p1, g_p2, centre, vec3(0.5 + 1e-4)))
            continue;
        ivec3 v = ivec3(centre);
        int at = 8 * ((v.z * n + v.y) * n + v.x);
        atomicAdd(avg_sums[at + 0], int(round(g_normal.x * AVG_VOX_FIXED)));
        atomicAdd(avg_sums[at + 1], int(round(g_normal.y * AVG_VOX_FIXED)));
        atomicAdd(avg_sums[at + 2], int(round(g_normal.z * AVG_VOX_FIXED)));
        atomicAdd(avg_sums[at + 3], 1);
        atomicAdd(avg_sums[at + 4], int(round(g_colour.r * AVG_VOX_FIXED)));
        atomicAdd(avg_sums[at + 5], int(round(g_colour.g * AVG_VOX_FIXED)));
        atomicAdd(avg_sums[at + 6], int(round(g_colour.b * AVG_VOX_FIXED)));
    }
}

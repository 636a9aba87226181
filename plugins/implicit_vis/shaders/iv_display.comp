// Display (Sec. 4.3.1 "For final display"): the elements' irradiance,
// interpolated across each visible triangle from its three vertices, or
// with re-meshing from the three points of the triangle's k x k display
// grid around the pixel (barycentric coordinates of the pixel's world
// position), each grid point a blend of three elements (with the grid
// re-meshing the point's own element; isotropic: the corners of the
// re-meshed triangle it lies on), on the side of
// the disc the pixel's surface faces, times the pixel's albedo / pi, plus
// the emission seen directly.
#include "common.glsl"
#include "scene.glsl"
#include "gbuffer_read.glsl"
#include "iv_gpu.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = IV_SSBO_ELEM_LIGHT) readonly buffer IvLight { IvElemLight iv_light[]; };
layout(std430, binding = IV_SSBO_TRI) readonly buffer IvTri { uvec2 iv_tri[]; };   // k, first grid point
struct IvDisp {
    uvec4 elem; // three elements
    vec4 w;     // their weights
};
layout(std430, binding = IV_SSBO_GRID) readonly buffer IvGrid { IvDisp iv_grid[]; }; // grid point
layout(rgba32f, binding = GI_IMAGE_TARGET) uniform writeonly image2D u_target;

uniform ivec2 u_size;

vec3 barycentric(vec3 p, vec3 a, vec3 b, vec3 c)
{
    vec3 v0 = b - a, v1 = c - a, v2 = p - a;
    float d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1), d20 = dot(v2, v0), d21 = dot(v2, v1);
    float den = d00 * d11 - d01 * d01;
    if (abs(den) < 1e-30)
        return vec3(1.0 / 3.0);
    float v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
    vec3 bc = clamp(vec3(1.0 - v - w, v, w), 0.0, 1.0);
    return bc / max(bc.x + bc.y + bc.z, 1e-12);
}

// Grid point (i, j) of a triangle subdivided k times (iv_grid_index in iv.h).
uint iv_grid_index(uint k, int i, int j)
{
    uint ui = uint(i), uj = uint(j);
    return uj * (k + 1u) - (uj * (uj - 1u)) / 2u + ui;
}

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_size)))
        return;
    GiSurface s = gi_gbuffer_surface(px);
    vec3 L = vec3(0.0);
    if (s.hit) {
        uint tri = gi_gbuffer_ids_at(px).z;
        vec3 E = vec3(0.0);
        if (tri != GI_NO_ID) {
            vec3 p0, p1, p2;
            gi_triangle_world(tri, p0, p1, p2);
            vec3 bc = barycentric(s.position, p0, p1, p2);
            // the sub-triangle of the k x k grid holding the pixel, and the weights of its corners
            uint k = iv_tri[tri].x, base = iv_tri[tri].y;
            float x = bc.y * float(k), y = bc.z * float(k);
            int i = clamp(int(floor(x)), 0, int(k) - 1);
            int j = clamp(int(floor(y)), 0, int(k) - 1 - i);
            float fx = x - float(i), fy = y - float(j);
            uvec3 gi3;
            vec3 w;
            if (fx + fy <= 1.0) {
                gi3 = uvec3(iv_grid_index(k, i, j), iv_grid_index(k, i + 1, j), iv_grid_index(k, i, j + 1));
                w = vec3(1.0 - fx - fy, fx, fy);
            } else {
                gi3 = uvec3(iv_grid_index(k, i + 1, j + 1), iv_grid_index(k, i, j + 1), iv_grid_index(k, i + 1, j));
                w = vec3(fx + fy - 1.0, 1.0 - fx, 1.0 - fy);
            }
            w = clamp(w, 0.0, 1.0);
            w /= max(w.x + w.y + w.z, 1e-12);
            uvec3 g = uvec3(base) + gi3;
            vec3 n = vec3(0.0);
            for (int a = 0; a < 3; a++)
                for (int c = 0; c < 3; c++)
                    n += w[a] * iv_grid[g[a]].w[c] * iv_light[iv_grid[g[a]].elem[c]].normal.xyz;
            bool front = dot(n, s.normal) >= 0.0;
            for (int a = 0; a < 3; a++)
                for (int c = 0; c < 3; c++) {
                    uint e = iv_grid[g[a]].elem[c];
                    E += w[a] * iv_grid[g[a]].w[c] * (front ? iv_light[e].e_front.rgb : iv_light[e].e_back.rgb);
                }
        }
        L = s.emission + s.brdf.kd * GI_INV_PI * E;
    }
    imageStore(u_target, px, vec4(L, 1.0));
}

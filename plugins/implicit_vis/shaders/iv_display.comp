// Display (Sec. 4.3.1 "For final display"): the elements' irradiance,
// interpolated across each visible triangle from its three vertices, or
// with re-meshing from the three points of the triangle's k x k display
// grid around the pixel (barycentric coordinates of the pixel's world
// position), each grid point a blend of three elements (with the grid
// re-meshing the point's own element; isotropic: the corners of the
// re-meshed triangle it lies on), on the side of
// the disc the pixel's surface faces, times the pixel's albedo / pi, plus
// the emission seen directly; where the camera ray misses, the background
// (the environment seen directly, view.glsl), as the other methods draw it.
// With IV_GLOSSY (a scene with glossy materials, Sec. 4.3 and Fig. 11): a
// pixel of a glossy (Phong) material adds the Phong lobe of the direct
// light, the BRDF-weighted sum over the bins of its elements (blended as
// the irradiance): each light link's radiance from the direction of the
// linked node, the environment through the open bins, the punctual lights
// through their bin, each with its Eq. 5 weight, the lobe toward the eye
// evaluated with the core's BRDF. Indirect light stays diffuse, as in the
// paper's GPU version.
#include "common.glsl"
#include "scene.glsl"
#include "gbuffer_read.glsl"
#include "view.glsl"
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
#ifdef IV_TRACED
// direct=traced (README "Traced direct light"): the direct irradiance at each pixel, by shadow rays
// on the CPU; the elements then hold the indirect bounces only
layout(std430, binding = IV_SSBO_PIXEL_DIRECT) readonly buffer IvPixelDirect { vec4 iv_pixel_direct[]; };
#endif

#ifdef IV_GLOSSY
layout(std430, binding = IV_SSBO_ELEM) readonly buffer IvElems { IvElem iv_elem[]; };
layout(std430, binding = IV_SSBO_BINS) readonly buffer IvBins { IvBin iv_bin[]; };
layout(std430, binding = IV_SSBO_GEOM) readonly buffer IvGeom { IvNode iv_node[]; };
layout(std430, binding = IV_SSBO_RAD_SRC) readonly buffer IvEmit { IvRad iv_emit[]; }; // emission, pulled up
layout(std430, binding = IV_SSBO_LINKS) readonly buffer IvLinks { uvec4 iv_link[]; }; // bin, node, covered, length
layout(std430, binding = IV_SSBO_LINK_OFF) readonly buffer IvLinkOff { uvec2 iv_off[]; };
layout(std430, binding = IV_SSBO_WLINKS) readonly buffer IvWLinks { uvec2 iv_wl[]; }; // node | side << 30, weight
#include "iv_direct.glsl"

uniform uint u_bins;       // 6 n n
uniform uint u_light_base; // the light links' first record in iv_link
uniform int u_env;         // 1: the scene has an environment
uniform int u_env_share;   // as iv_gather.comp

// The glossy part of Eq. 2 for the direct light reaching element e on the
// side `front`, seen at pixel x (normal N, toward the eye wo) through the
// BRDF b: the sum over the element's bins of f(wo, wi) L(wi) times the
// bin's Eq. 5 weight (its cosine-weighted solid angle from the disc, the
// share its link covers), as iv_gather.comp gathers the direct light.
vec3 glossy_direct(uint e, bool front, gi_brdf b, vec3 x, vec3 N, vec3 wo)
{
    vec3 sum = vec3(0.0);
    uvec2 o0 = iv_off[e], o1 = iv_off[e + 1u];
    for (uint j = u_light_base + o0.y; j < u_light_base + o1.y; j++) { // the light links
        uvec2 l = iv_wl[j];
        float w = uintBitsToFloat(l.y);
        if ((w >= 0.0) != front || w == 0.0)
            continue;
        uint src = l.x & 0x3FFFFFFFu, side = l.x >> 30;
        vec3 Ls = side == IV_SIDE_BOTH ? 0.5 * (iv_emit[src].front.rgb + iv_emit[src].back.rgb)
                                       : (side == IV_SIDE_FRONT ? iv_emit[src].front.rgb : iv_emit[src].back.rgb);
        vec3 wi = normalize(iv_node[src].pos.xyz - x);
        sum += gi_brdf_eval(b, N, wo, wi) * Ls * abs(w);
    }
    vec3 n = iv_light[e].normal.xyz;
    float norm = iv_light[e].normal.w;
    if (u_env != 0) { // Sec. 4.4: the environment through what the links leave open of each bin
        uint j = o0.x;
        for (uint bn = 0u; bn < u_bins; bn++) {
            float open = 1.0;
            if (j < o1.x && iv_link[j].x == bn) { // as iv_gather.comp
                open = u_env_share != 0 ? max(1.0 - uintBitsToFloat(iv_link[j].z), 0.0) : 0.0;
                j++;
            }
            if (!(open > 0.0))
                continue;
            vec3 d = iv_bin[bn].dir.xyz;
            float w = dot(n, d) * iv_bin[bn].dir.w * norm * open;
            if ((w >= 0.0) != front || w == 0.0)
                continue;
            sum += gi_brdf_eval(b, N, wo, d) * iv_bin[bn].env.rgb * abs(w);
        }
    }
    vec3 p = iv_node[iv_elem[e].info.x].pos.xyz;
    for (uint i = 0u; i < gi_counts.y; i++) { // punctual lights, the element's bin test
        GiLight lt = gi_lights[i];
        vec3 wl;
        float scale;
        if (!iv_punctual_seen(lt.position, lt.type, lt.direction, lt.range, lt.cos_inner, lt.cos_outer, p, o0.x,
                              o1.x, wl, scale))
            continue;
        float c = dot(n, wl);
        if ((c >= 0.0) != front)
            continue;
        vec3 wi = lt.type == GI_LIGHT_TYPE_DIRECTIONAL ? wl : normalize(lt.position - x);
        sum += gi_brdf_eval(b, N, wo, wi) * abs(c) * scale * lt.intensity;
    }
    return sum;
}
#endif

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
    vec3 L = gi_background(px); // a camera ray that misses sees the environment, as every method draws it
#ifdef IV_GLOSSY
    vec3 G = vec3(0.0);
#endif
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
#ifdef IV_GLOSSY
            if (!gi_brdf_is_mirror(s.brdf) && any(greaterThan(s.brdf.ks, vec3(0.0)))) {
                gi_brdf lobe = s.brdf; // the Phong lobe only: the Lambert part is the irradiance's
                lobe.kd = vec3(0.0);
                vec3 wo = normalize(u_eye - s.position);
                for (int a = 0; a < 3; a++)
                    for (int c = 0; c < 3; c++) {
                        float wt = w[a] * iv_grid[g[a]].w[c];
                        if (wt > 0.0)
                            G += wt * glossy_direct(iv_grid[g[a]].elem[c], front, lobe, s.position, s.normal, wo);
                    }
            }
#endif
        }
#ifdef IV_TRACED
        E += iv_pixel_direct[px.y * u_size.x + px.x].rgb;
#endif
        L = s.emission + s.brdf.kd * GI_INV_PI * E;
#ifdef IV_GLOSSY
        L += G;
#endif
    }
    imageStore(u_target, px, vec4(L, 1.0));
}

// Rendering from the light field (plugins/vlf/vlf.c, paper §4): per pixel of
// the G-buffer, the diffuse part from the irradiance atlas of its face and
// the non-diffuse part from the radiance tiles of the three subfields
// around the view direction, weighted by their barycentric weights.
#include "scene.glsl"
#include "envmap.glsl"
#include "view.glsl"
#include "gbuffer_read.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// chart origin (w: the bits of the other side's face of a double-sided
// face, ~0u for none), axes (texels per unit); W, H, first element, nd
struct VlfFace { vec4 origin; vec4 t; vec4 b; uvec4 info; };
struct VlfRect { ivec4 r; uvec4 o; }; // x0, y0, w, h; offset

layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 0) readonly buffer VlfFaces { VlfFace vlf_faces[]; };
// the irradiance atlas in the storage format, then one float per element:
// the part of the texel on its face
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 1) readonly buffer VlfIrr { uint vlf_E[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 2) readonly buffer VlfOut { uint vlf_out[]; }; // tiles, storage format
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 3) readonly buffer VlfRects { VlfRect vlf_rects[]; };
// psf frames (u, v, n: 3 per fixed direction), then 3 rows of each
// triangle's inverse, then the 2l signed directions
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 4) readonly buffer VlfDirs { vec4 vlf_dirs[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 5) readonly buffer VlfTris { uvec4 vlf_tris[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 6) readonly buffer VlfTriFace { uint vlf_tri_face[]; };
layout(binding = GI_TEX_PLUGIN_FIRST) uniform usampler2D vlf_lookup; // triangle of each direction (lat-long)
layout(rgba32f, binding = GI_IMAGE_TARGET) uniform writeonly image2D vlf_target;

uniform vec3 u_centre;
uniform float u_radius;
uniform uint u_l;
uniform uint u_N;
uniform uint u_tri_count;
uniform uint u_precision; // 0: three float32, 1: RGBA16F (4 halves), 2: RGB9E5
uniform uint u_weight_offset; // first weight in vlf_E (uints)

// A value of a map in the storage format (vlf_pack in precision.c) from its
// words: three float32, RGBA16F (two words) or RGB9E5 (one word).
uint vlf_stride() { return u_precision == 1u ? 2u : u_precision == 2u ? 1u : 3u; }
vec3 vlf_decode(uint w0, uint w1, uint w2)
{
    if (u_precision == 1u)
        return vec3(unpackHalf2x16(w0), unpackHalf2x16(w1).x);
    if (u_precision == 2u)
        return vec3(w0 & 511u, (w0 >> 9u) & 511u, (w0 >> 18u) & 511u) * exp2(float(int(w0 >> 27u)) - 24.0);
    return vec3(uintBitsToFloat(w0), uintBitsToFloat(w1), uintBitsToFloat(w2));
}
vec3 vlf_irr_at(uint i)
{
    uint k = i * vlf_stride(), n = vlf_stride() - 1u;
    return vlf_decode(vlf_E[k], vlf_E[k + min(1u, n)], vlf_E[k + min(2u, n)]);
}
vec3 vlf_tile_at(uint i)
{
    uint k = i * vlf_stride(), n = vlf_stride() - 1u;
    return vlf_decode(vlf_out[k], vlf_out[k + min(1u, n)], vlf_out[k + min(2u, n)]);
}

// Irradiance of face f at world point p: bilinear over the chart's texels
// that lie on the face (the paper's texture filtering of the atlas).
vec3 vlf_irradiance(VlfFace f, vec3 p)
{
    vec3 d = p - f.origin.xyz;
    vec2 x = vec2(dot(d, f.t.xyz), dot(d, f.b.xyz)) - 0.5;
    ivec2 i0 = ivec2(floor(x));
    vec2 a = x - vec2(i0);
    ivec2 WH = ivec2(f.info.xy);
    vec4 sum = vec4(0.0);
    for (int dy = 0; dy < 2; dy++)
        for (int dx = 0; dx < 2; dx++) {
            ivec2 c = i0 + ivec2(dx, dy);
            if (any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, WH)))
                continue;
            uint e = f.info.z + uint(c.y * WH.x + c.x);
            vec3 E = vlf_irr_at(e);
            float on_face = uintBitsToFloat(vlf_E[u_weight_offset + e]);
            float w = (dx == 1 ? a.x : 1.0 - a.x) * (dy == 1 ? a.y : 1.0 - a.y) + 1e-3;
            sum += w * on_face * vec4(E, 1.0);
        }
    return sum.w > 0.0 ? sum.rgb / sum.w : vec3(0.0);
}

// The spherical triangle around w (from the lat-long lookup) and its weights.
void vlf_locate(vec3 w, out uvec3 node, out vec3 alpha)
{
    ivec2 sz = textureSize(vlf_lookup, 0);
    float phi = atan(w.y, w.x);
    float theta = acos(clamp(w.z, -1.0, 1.0));
    ivec2 t = clamp(ivec2(vec2((phi + GI_PI) / (2.0 * GI_PI), theta / GI_PI) * vec2(sz)), ivec2(0), sz - 1);
    uint tri = texelFetch(vlf_lookup, t, 0).r;
    uint base = 3u * u_l + 3u * tri;
    vec3 x = vec3(dot(vlf_dirs[base].xyz, w), dot(vlf_dirs[base + 1u].xyz, w), dot(vlf_dirs[base + 2u].xyz, w));
    x = max(x, vec3(0.0));
    float s = x.x + x.y + x.z;
    alpha = s > 0.0 ? x / s : vec3(1.0 / 3.0);
    node = vlf_tris[tri].xyz;
}

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_size)))
        return;
    GiSurface s = gi_gbuffer_surface(px);
    vec3 L;
    if (!s.hit) {
        L = gi_background(px);
    } else {
        uint tri = gi_gbuffer_ids_at(px).z;
        L = s.emission;
        vec3 p0, p1, p2;
        gi_triangle_world(tri, p0, p1, p2);
        vec3 ng = cross(p1 - p0, p2 - p0);
        vec3 wo = normalize(u_eye - s.position);
        uint fi = vlf_tri_face[tri];
        uint twin = floatBitsToUint(vlf_faces[fi].origin.w);
        if (dot(ng, wo) <= 0.0 && twin != 0xffffffffu) { // a double-sided face seen from its back: the back's values
            fi = twin;
            ng = -ng;
        }
        if (dot(ng, wo) > 0.0) { // the side facing the eye (a single-sided face's back holds nothing)
            VlfFace f = vlf_faces[fi];
            L += s.brdf.kd * vlf_irradiance(f, s.position) * GI_INV_PI;
            int nd = int(f.info.w);
            if (nd >= 0) {
                uvec3 node;
                vec3 alpha;
                vlf_locate(wo, node, alpha);
                vec3 q = (s.position - u_centre) / u_radius;
                vec3 sum = vec3(0.0);
                float wsum = 0.0;
                for (int j = 0; j < 3; j++) {
                    uint sd = node[j];
                    uint pj = sd % u_l;
                    vec3 sdir = vlf_dirs[3u * u_l + 3u * u_tri_count + sd].xyz;
                    if (dot(sdir, ng) <= 0.0)
                        continue;
                    float x = (dot(q, vlf_dirs[3u * pj].xyz) + 1.0) * 0.5 * float(u_N);
                    float y = (dot(q, vlf_dirs[3u * pj + 1u].xyz) + 1.0) * 0.5 * float(u_N);
                    VlfRect r = vlf_rects[uint(nd) * u_l + pj];
                    ivec2 c = ivec2(floor(vec2(x, y))) - r.r.xy;
                    if (c.x < 0 || c.y < 0 || c.x >= r.r.z || c.y >= r.r.w)
                        continue;
                    uint slot = r.o.x + uint(c.y * r.r.z + c.x);
                    sum += alpha[j] * vlf_tile_at(slot);
                    wsum += alpha[j];
                }
                if (wsum > 0.0)
                    L += sum / wsum;
            }
        }
    }
    imageStore(vlf_target, px, vec4(L, 1.0));
}

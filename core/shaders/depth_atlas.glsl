// Depth atlas (passes.h, gi_depth_atlas_*): the views SSBO and the lookup
// of a world point in view i's tile. A plugin binds the atlas texture to a
// sampler2D of its own and the SSBO of gi_depth_atlas_views_buffer() at
// binding GI_DEPTH_ATLAS_BINDING (default GI_SSBO_DEPTH_ATLAS; define
// it before the #include to use another binding), then:
//     float zp;
//     float zmap = gi_atlas_depth(u_atlas, i, world_point, zp);
//     bool lit = zp <= zmap + bias;   // zmap = +INF outside the footprint
// C twin: gi_depth_atlas_texel (passes.h).
#ifndef GI_DEPTH_ATLAS_GLSL
#define GI_DEPTH_ATLAS_GLSL

#include "glsl_shared.h"
#ifndef GI_DEPTH_ATLAS_BINDING
#define GI_DEPTH_ATLAS_BINDING GI_SSBO_DEPTH_ATLAS
#endif

struct GiAtlasView {
    mat4 view;   // world -> eye
    mat4 proj;   // perspective projection (unused for paraboloid)
    vec4 range;  // znear, zfar (paraboloid depth range), 0, 0
};

layout(std430, binding = GI_DEPTH_ATLAS_BINDING) readonly buffer GiDepthAtlasViews {
    uvec4 gi_atlas_info;  // tile, columns, projection (1 perspective, 2 paraboloid), metric (0 eye z, 1 radial)
    GiAtlasView gi_atlas_views[];
};

// Texel of world point p in view `view`'s tile (0..tile-1 each way, row 0
// at the bottom) and p's own depth in the atlas' metric; false outside the
// footprint (behind a perspective eye or outside its frustum's sides; in a
// paraboloid's back hemisphere).
bool gi_atlas_texel(uint view, vec3 p, out ivec2 texel, out float point_depth)
{
    uint tile = gi_atlas_info.x;
    vec3 eye = (gi_atlas_views[view].view * vec4(p, 1.0)).xyz;
    point_depth = gi_atlas_info.w == 1u ? length(eye) : -eye.z;
    vec2 ndc;
    if (gi_atlas_info.z == 2u) {
        float dist = length(eye);
        vec3 d = eye / max(dist, 1e-20);
        if (!(d.z < 0.0))
            return false;
        ndc = d.xy / (1.0 - d.z);
    } else {
        vec4 clip = gi_atlas_views[view].proj * vec4(eye, 1.0);
        if (!(clip.w > 0.0))
            return false;
        ndc = clip.xy / clip.w;
    }
    if (!(abs(ndc.x) <= 1.0 && abs(ndc.y) <= 1.0))
        return false;
    vec2 f = (ndc * 0.5 + 0.5) * float(tile);
    texel = min(ivec2(floor(f)), ivec2(int(tile) - 1));
    return true;
}

// Stored first-surface depth at p's texel in view `view`'s tile (FLT_MAX
// where the map saw nothing, +INF outside the footprint) and p's own depth
// in the same metric.
float gi_atlas_depth(sampler2D atlas, uint view, vec3 world_point, out float point_depth)
{
    ivec2 t;
    if (!gi_atlas_texel(view, world_point, t, point_depth))
        return uintBitsToFloat(0x7f800000u);
    uint columns = gi_atlas_info.y, tile = gi_atlas_info.x;
    ivec2 origin = ivec2(int((view % columns) * tile), int((view / columns) * tile));
    return texelFetch(atlas, origin + t, 0).r;
}

#endif

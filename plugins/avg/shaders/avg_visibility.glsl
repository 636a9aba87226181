// VPL visibility from the shadow-map atlas (§III-C): map j of the core's
// depth atlas (passes.h) is VPL j's low-resolution shadow map, radial depth
// about the VPL, looking along its normal (paraboloid: the hemisphere;
// perspective: a frustum of u_fov). A receiver outside a map's footprint
// is taken as visible: the map has no information there (the paper notes
// the artifact at the edges of perspective maps).
#ifndef AVG_VISIBILITY_GLSL
#define AVG_VISIBILITY_GLSL
#include "avg_bindings.h"
#define GI_DEPTH_ATLAS_BINDING AVG_SSBO_ATLAS_VIEWS
#include "depth_atlas.glsl"

layout(binding = AVG_TEX_ATLAS) uniform sampler2D u_atlas;
uniform float u_bias_abs; // world units
uniform float u_bias_rel; // fraction of the receiver's distance per unit of slope

// Receiver x with normal n, the unit direction w from x to VPL j: x moves
// along n by u_bias_abs, and the depth test allows a slope-scaled bias (a
// texel of a coarse map spans a depth range growing with tan of the angle
// between n and w).
float avg_visible(uint j, vec3 x, vec3 n, vec3 w)
{
    float zp;
    float zmap = gi_atlas_depth(u_atlas, j, x + n * u_bias_abs, zp);
    if (isinf(zmap))
        return 1.0;
    float c = clamp(dot(n, w), 0.05, 1.0);
    float slope = min(sqrt(1.0 - c * c) / c, 10.0);
    return zp <= zmap + u_bias_abs + u_bias_rel * (1.0 + slope) * zp ? 1.0 : 0.0;
}
#endif

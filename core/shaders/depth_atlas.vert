// Depth atlas, vertex stage: instance i draws the scene through view i of
// the views SSBO into tile i. The tile's placement is an affine map of clip
// x, y (exact in homogeneous coordinates, so perspective interpolation is
// unchanged) and four clip planes keep the triangle inside the tile, as
// the frustum's sides would for a map of its own. Projections as in
// depth.vert: perspective through the view's proj, or paraboloid around
// -Z (Brabec et al. 2002) with a fifth plane clipping the back hemisphere.
#include "scene.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in uint a_object;
layout(location = 3) in uint a_material;

uniform uvec2 u_grid;      // columns, rows
uniform int u_projection;  // 1 perspective, 2 paraboloid
uniform uint u_first;      // the first view of this draw (the draw may be split in batches)
// The views SSBO of depth_atlas.glsl, read as a texture buffer of vec4s
// (the info header, then 9 a view: view, proj, range): llvmpipe turns SSBO
// loads into a loop over the SIMD lanes, a texel fetch into one gather;
// this made the whole draw 3.7 times faster there.
uniform samplerBuffer u_views;

mat4 fetch_mat(int at)
{
    return mat4(texelFetch(u_views, at), texelFetch(u_views, at + 1), texelFetch(u_views, at + 2),
                texelFetch(u_views, at + 3));
}

out vec3 v_eye;
flat out uint v_single; // the one rule for sides (gi/scene.h): back faces are no surface
out float gl_ClipDistance[5];

void main()
{
    uint view = u_first + uint(gl_InstanceID);
    vec4 world = gi_objects[a_object].world_from_local * vec4(a_position, 1.0);
    int base = 1 + 9 * int(view); // vec4s: the info header, then 9 per view
    vec4 eye = fetch_mat(base) * world;
    v_eye = eye.xyz;
    v_single = gi_material_double_sided(a_material) ? 0u : 1u;
    vec4 clip;
    float hemisphere = 1.0;
    if (u_projection == 2) {
        float dist = length(eye.xyz);
        vec3 d = eye.xyz / max(dist, 1e-20);
        vec2 range = texelFetch(u_views, base + 8).xy;
        clip = vec4(d.x / (1.0 - d.z), d.y / (1.0 - d.z), (dist - range.x) / (range.y - range.x), 1.0);
        hemisphere = -d.z;
    } else {
        clip = fetch_mat(base + 4) * eye;
    }
    gl_ClipDistance[0] = clip.w + clip.x;
    gl_ClipDistance[1] = clip.w - clip.x;
    gl_ClipDistance[2] = clip.w + clip.y;
    gl_ClipDistance[3] = clip.w - clip.y;
    gl_ClipDistance[4] = hemisphere;
    // Tile (col, row): NDC x in [-1, 1] -> [-1 + 2 col / columns, -1 + 2 (col + 1) / columns].
    vec2 cell = vec2(float(view % u_grid.x), float(view / u_grid.x));
    clip.xy = (clip.xy + clip.w * (2.0 * cell + 1.0)) / vec2(u_grid) - clip.w;
    gl_Position = clip;
}

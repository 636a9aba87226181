// Depth-map pass, vertex stage: orthographic, perspective or paraboloid
// projection; linear depth (eye z or radial distance) handed to the fragment.
#include "scene.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in uint a_object;
layout(location = 3) in uint a_material;

uniform mat4 u_view;
uniform mat4 u_proj;
uniform int u_projection; // 0 ortho, 1 perspective, 2 paraboloid
uniform int u_local;      // 1: object-local space, transforms ignored
uniform vec2 u_range;     // paraboloid near, far

out vec3 v_eye;
// The one rule for sides (gi/scene.h): 1 when a back face is no surface
// (single-sided), 2 when in addition the local winding is mirrored (u_local
// draws object-local corners, so a negative determinant is not applied).
flat out uint v_cull;
out float gl_ClipDistance[1];

void main()
{
    vec4 world = u_local != 0 ? vec4(a_position, 1.0)
                              : gi_objects[a_object].world_from_local * vec4(a_position, 1.0);
    vec4 eye = u_view * world;
    v_eye = eye.xyz;
    v_cull = gi_material_double_sided(a_material) ? 0u : 1u;
    if (v_cull != 0u && u_local != 0 && determinant(mat3(gi_objects[a_object].world_from_local)) < 0.0)
        v_cull = 2u;
    gl_ClipDistance[0] = 1.0;
    if (u_projection == 2) {
        // Paraboloid around -Z (Brabec et al. 2002): the hemisphere in front.
        float dist = length(eye.xyz);
        vec3 d = eye.xyz / max(dist, 1e-20);
        gl_Position = vec4(d.x / (1.0 - d.z), d.y / (1.0 - d.z),
                           (dist - u_range.x) / (u_range.y - u_range.x), 1.0);
        gl_ClipDistance[0] = -d.z;
    } else {
        gl_Position = u_proj * eye;
    }
}

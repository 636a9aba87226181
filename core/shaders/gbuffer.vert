// G-buffer pass, vertex stage: object-local vertices placed by the object UBO.
#include "scene.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in uint a_object;
layout(location = 2) in vec3 a_normal;
layout(location = 3) in uint a_material;
layout(location = 4) in vec2 a_uv;

uniform mat4 u_view;
uniform mat4 u_proj;

out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out float v_eye_depth;
flat out uint v_object;
flat out uint v_material;

void main()
{
    vec4 world = gi_objects[a_object].world_from_local * vec4(a_position, 1.0);
    vec4 eye = u_view * world;
    v_world = world.xyz;
    v_normal = mat3(gi_objects[a_object].normal_matrix) * a_normal;
    v_uv = a_uv;
    v_eye_depth = -eye.z;
    v_object = a_object;
    v_material = a_material;
    gl_Position = u_proj * eye;
}

// AVG construction (§III-A), vertex stage: world -> grid space (voxel units,
// the grid's corner at 0). One instance per Z slice: gl_InstanceID is the
// slice the geometry stage writes (the paper's one pass per slice, drawn as
// one instanced call into a layered framebuffer, split in batches of slices
// that start at u_first_slice so that a cancel is seen between them).
#include "scene.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in uint a_object;
layout(location = 3) in uint a_material;

uniform vec3 u_grid_origin;
uniform float u_grid_h;
uniform int u_first_slice;

out vec3 v_grid;
flat out uint v_material;
flat out int v_slice;

void main()
{
    v_grid = (gi_object_point(a_object, a_position) - u_grid_origin) / u_grid_h;
    v_material = a_material;
    v_slice = u_first_slice + gl_InstanceID;
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}

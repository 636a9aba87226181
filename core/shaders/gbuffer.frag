// G-buffer pass, fragment stage: writes the layout documented in passes.h.
#include "scene.glsl"

in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in float v_eye_depth;
flat in uint v_object;
flat in uint v_material;

uniform vec3 u_eye;

layout(location = 0) out vec4 o_position;
layout(location = 1) out vec4 o_normal;
layout(location = 2) out vec4 o_albedo;
layout(location = 3) out vec4 o_phong;
layout(location = 4) out vec4 o_emission;
layout(location = 5) out uvec4 o_ids;

void main()
{
    GiMaterial m = gi_materials[v_material];
    // The one rule for sides (gi/scene.h): the back of a single-sided
    // triangle is no surface; the eye sees what lies behind it.
    int side = gi_side_of(v_material, gl_FrontFacing);
    if (side == 0)
        discard;
    // The back of a double-sided one has reversed normals; where the
    // shading normal still faces away from the eye (smooth normals at a
    // silhouette, a file whose normals disagree with its winding) the
    // triangle's geometric normal on the eye's side stands in for it, as
    // in the reference (gi_facing_normal, gi/scene.h).
    vec3 wo = u_eye - v_world;
    vec3 n = normalize(v_normal) * float(side);
    if (dot(n, wo) <= 0.0) {
        vec3 p0, p1, p2;
        gi_triangle_world(uint(gl_PrimitiveID), p0, p1, p2);
        vec3 ng = cross(p1 - p0, p2 - p0);
        float len = length(ng);
        ng = len > 0.0 ? ng / len : -n;
        n = gi_facing_normal(n, dot(ng, wo) < 0.0 ? -ng : ng, wo);
    }
    bool mirror = (m.flags & GI_MATERIAL_MIRROR) != 0u;
    // Front faces emit; back faces exist only when double-sided, and emit.
    bool emits = true;
    o_position = vec4(v_world, v_eye_depth);
    o_normal = vec4(n, 0.0);
    o_albedo = vec4(gi_material_albedo(v_material, v_uv), mirror ? 1.0 : 0.0);
    o_phong = vec4(m.ks, m.exponent);
    o_emission = vec4(emits ? m.emission : vec3(0.0), 1.0);
    o_ids = uvec4(v_object, v_material, uint(gl_PrimitiveID), 0u);
}

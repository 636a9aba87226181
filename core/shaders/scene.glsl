// The scene on the GPU: buffer layouts and fetch helpers (mirrors gpu.h).
// Binding points come from glsl_shared.h, the header the C side includes too.
#ifndef GI_SCENE_GLSL
#define GI_SCENE_GLSL
#include "common.glsl"
#include "glsl_shared.h"

struct GiVertex {
    vec3 position; uint object;
    vec3 normal; uint material;
    vec2 uv; vec2 pad;
};
struct GiMaterial {
    vec3 albedo; int texture_layer;
    vec3 ks; float exponent;
    vec3 emission; uint flags; // GI_MATERIAL_FLAG_MIRROR | GI_MATERIAL_FLAG_DOUBLE_SIDED
};
struct GiLight {
    vec3 position; uint type;  // 0 point, 1 spot, 2 directional
    vec3 direction; float range;
    vec3 intensity; float cos_inner;
    float cos_outer; float pad0, pad1, pad2;
};
struct GiEmitter {
    uint triangle; float area; float cdf; float pdf;
};
struct GiObject {
    mat4 world_from_local;
    mat4 normal_matrix;
};

layout(std430, binding = GI_SSBO_VERTICES) readonly buffer GiVertices { GiVertex gi_vertices[]; };
layout(std430, binding = GI_SSBO_INDICES) readonly buffer GiIndices { uint gi_indices[]; };
layout(std430, binding = GI_SSBO_MATERIALS) readonly buffer GiMaterials { GiMaterial gi_materials[]; };
layout(std430, binding = GI_SSBO_LIGHTS) readonly buffer GiLights { GiLight gi_lights[]; };
layout(std430, binding = GI_SSBO_EMITTERS) readonly buffer GiEmitters { GiEmitter gi_emitters[]; };
layout(std140, binding = GI_UBO_OBJECTS) uniform GiObjects { GiObject gi_objects[GI_MAX_OBJECTS]; };
layout(std140, binding = GI_UBO_FRAME) uniform GiSceneInfo {
    uvec4 gi_counts;        // triangles, punctual lights, emitters, has environment
    vec4 gi_scene_params;   // area-light power, environment power estimate, time, env rotation (rad)
    vec4 gi_bounds_min;     // world bounds at the current time
    vec4 gi_bounds_max;
};
layout(binding = GI_TEX_ALBEDO) uniform sampler2DArray gi_albedo_textures;
// envmap.glsl reads the map's rotation from here.
#define GI_ENV_ROTATION gi_scene_params.w

const uint GI_LIGHT_POINT = GI_LIGHT_TYPE_POINT;
const uint GI_LIGHT_SPOT = GI_LIGHT_TYPE_SPOT;
const uint GI_LIGHT_DIRECTIONAL = GI_LIGHT_TYPE_DIRECTIONAL;
const uint GI_MATERIAL_MIRROR = GI_MATERIAL_FLAG_MIRROR;
const uint GI_MATERIAL_DOUBLE_SIDED = GI_MATERIAL_FLAG_DOUBLE_SIDED;

uint gi_triangle_count() { return gi_counts.x; }
uint gi_light_count() { return gi_counts.y; }
uint gi_emitter_count() { return gi_counts.z; }
bool gi_has_environment() { return gi_counts.w != 0u; }

vec3 gi_object_point(uint object, vec3 p) { return (gi_objects[object].world_from_local * vec4(p, 1.0)).xyz; }
vec3 gi_object_normal(uint object, vec3 n) { return normalize(mat3(gi_objects[object].normal_matrix) * n); }

// World-space corners of triangle `tri`.
void gi_triangle_world(uint tri, out vec3 p0, out vec3 p1, out vec3 p2)
{
    uint i0 = gi_indices[3u * tri], i1 = gi_indices[3u * tri + 1u], i2 = gi_indices[3u * tri + 2u];
    uint o = gi_vertices[i0].object;
    p0 = gi_object_point(o, gi_vertices[i0].position);
    p1 = gi_object_point(o, gi_vertices[i1].position);
    p2 = gi_object_point(o, gi_vertices[i2].position);
}

// Does material m emit from both sides (glTF doubleSided)?
bool gi_material_double_sided(uint m) { return (gi_materials[m].flags & GI_MATERIAL_DOUBLE_SIDED) != 0u; }

// The one rule for sides (gi/scene.h) in a rasterised view or at a ray hit:
// 1 the front, -1 the back of a double-sided material (normals reversed
// before lighting), 0 the back of a single-sided one (no surface: discard,
// or let the ray go on). `front` is gl_FrontFacing, or dot(ng, wo) > 0.
int gi_side_of(uint m, bool front)
{
    if (front)
        return 1;
    return gi_material_double_sided(m) ? -1 : 0;
}

// The shading normal seen along wo (gi_facing_normal in gi/scene.h): n on
// the seen side where it faces wo, else the geometric normal ng on wo's side.
vec3 gi_facing_normal(vec3 n, vec3 ng, vec3 wo) { return dot(n, wo) > 0.0 ? n : ng; }

uint gi_triangle_material(uint tri) { return gi_vertices[gi_indices[3u * tri]].material; }

// Lambert albedo of a material at texture coordinate uv.
vec3 gi_material_albedo(uint m, vec2 uv)
{
    GiMaterial mat = gi_materials[m];
    if (mat.texture_layer < 0)
        return mat.albedo;
    return mat.albedo * texture(gi_albedo_textures, vec3(uv, float(mat.texture_layer))).rgb;
}

// Index of the emitter whose CDF interval holds u (binary search).
uint gi_emitter_find(float u)
{
    uint lo = 0u, hi = gi_emitter_count() - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (gi_emitters[mid].cdf > u) hi = mid; else lo = mid + 1u;
    }
    return lo;
}
#endif

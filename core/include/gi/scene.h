/* The scene: one immutable in-memory copy of a glTF 2.0 file.
 *
 * Use:
 *     gi_error err;
 *     gi_scene *s = gi_scene_load("scenes/cornell_box.gltf", &err);
 *     if (!s) { fprintf(stderr, "%s\n", err.text); ... }   // "file: /json/path: reason"
 *     ...
 *     gi_scene_free(s);
 * If gi_scene_load returns non-NULL you own the scene and must free it; the
 * scene is never modified after loading, so any number of readers may share
 * it. Time-dependent state (animated objects, lights, cameras) is computed
 * on demand by the gi_scene_*_at(t) functions.
 *
 * ==== THE ONE RULE FOR SIDES (glTF 2.0; every pass and every method) ====
 * The front face of a triangle is the one whose corners, in the file's
 * order, wind counter-clockwise in object-local space. A node whose global
 * transform has a negative determinant makes the winding clockwise (glTF),
 * so a mirrored instance keeps its front where the mesh has it. The loader
 * stores the corners of such an object in the reverse order, so in every
 * pass the front is the side where the stored world-space corners wind
 * counter-clockwise (cross(p1 - p0, p2 - p0) points out of it): test facing
 * on world-space corners.
 *  - Material not doubleSided: a triangle seen from its back DOES NOT EXIST.
 *    Camera, shadow, visibility and bounce rays and every rasterised view
 *    (G-buffer, depth/shadow/cube maps, atlases, voxelisations used for
 *    visibility) pass through it. It reflects and emits on its front only.
 *  - Material doubleSided: both sides are the same surface. Seen from the
 *    back, the geometric and shading normals are reversed before lighting;
 *    an emissive double-sided triangle emits from both sides.
 *  - A primitive without NORMAL has flat normals (the face normal).
 * The core follows it everywhere: gi_rt culls (gi/raytrace.h), the
 * G-buffer, depth maps and the depth atlas discard culled fragments, the
 * reference path tracer applies it. Methods use gi_side / gi_side_normal
 * below (C) or gi_side_of in core/shaders/scene.glsl (GLSL).
 * =========================================================================
 *
 * Conventions (fixed; see docs/scenes.md "Scene conventions"):
 *  - +Y up, right-handed, unit-free lengths. All quantities radiometric:
 *    emission is radiance, a point/spot light's intensity x colour is
 *    radiant intensity, a directional light's is irradiance.
 *  - Geometry is stored in object-local space, exactly as the glTF mesh
 *    holds it; objects[k].world_from_local (at time t) places it. One object
 *    is one glTF node carrying a mesh. Triangles of an object are contiguous.
 *  - Vertices are never shared between objects or materials, so a vertex
 *    carries its object and material index (the GPU layout relies on it).
 *  - Materials: Lambert albedo (baseColorFactor x optional baseColorTexture,
 *    linear), a normalised Phong lobe from material extras
 *    {"gibench": {"phong": {"ks": [r,g,b], "exponent": n}, "mirror": false}},
 *    emission = emissiveFactor x KHR_materials_emissive_strength.
 *    exponent >= GI_MIRROR_EXPONENT or mirror:true means an ideal mirror.
 *  - Environment: scenes[i].extras
 *    {"gibench": {"environment": {"uri": "env/x.exr", "intensity": 1.0,
 *    "rotation_deg": 0}}}, an equirectangular map (see envmap.h).
 */
#ifndef GI_SCENE_H
#define GI_SCENE_H

#include "gi/common.h"
#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GI_MIRROR_EXPONENT 10000.0f
/* Limits that validation enforces ("absurd counts or sizes"). */
#include "gi/limits.h"

/* 48 bytes; this exact layout is uploaded as an SSBO (std430, see
 * core/shaders/scene.glsl) and used as the vertex buffer. */
typedef struct gi_vertex {
    float position[3]; /* object-local */
    uint32_t object;
    float normal[3]; /* object-local, unit length */
    uint32_t material;
    float uv[2];
    float pad[2];
} gi_vertex;

typedef struct gi_material {
    char *name;
    float albedo[3];    /* Lambert reflectance, multiplied by the texture */
    int albedo_texture; /* index into gi_scene.textures, -1 if none */
    float ks[3];        /* Phong lobe reflectance */
    float exponent;     /* Phong exponent n (0 when ks is 0) */
    int mirror;         /* ideal specular reflection with reflectance ks */
    float emission[3];  /* emitted radiance; non-zero makes triangles area lights */
    int double_sided;
} gi_material;

typedef struct gi_texture {
    char *name;
    uint32_t width, height;
    float *rgba; /* linear (sRGB-decoded) RGBA, row 0 = top of the image */
} gi_texture;

/* A sampled glTF animation channel set for one node: LINEAR or STEP
 * translation/rotation/scale keyframes. Times in seconds. */
typedef struct gi_track {
    uint32_t count;
    float *times;
    float *values; /* 3 floats a key (translation, scale) or 4 (rotation xyzw) */
    int step;      /* STEP interpolation instead of LINEAR */
} gi_track;

typedef struct gi_node {
    char *name;
    int parent; /* -1 for a root */
    float translation[3], rotation[4], scale[3];
    gi_track anim_t, anim_r, anim_s; /* count 0 when not animated */
} gi_node;

typedef struct gi_object {
    char *name;
    int node; /* gi_scene.nodes index */
    uint32_t first_triangle, triangle_count;
    uint32_t first_vertex, vertex_count;
    float local_bounds[6]; /* min xyz, max xyz in object-local space; with morph
                              targets, over every weight the animation reaches */
    int animated;          /* this node or an ancestor is animated (rigid motion) */
    /* Morph targets (glTF mesh.primitives[].targets): the deforming object's
     * vertex i at weights w is position[i] + sum_k w[k] morph_positions[k][i],
     * normal normalize(normal[i] + sum_k w[k] morph_normals[k][i]). 0 targets
     * = a rigid object. Weights: node.weights, else mesh.weights, else 0,
     * animated by a "weights" channel (morph_track, morph_count floats a key,
     * LINEAR or STEP). See gi_scene_object_vertices. */
    uint32_t morph_count;
    float *morph_positions; /* morph_count x vertex_count x 3, object-local displacements */
    float *morph_normals; /* same layout; NULL when no target has NORMAL (normals not displaced) */
    float *morph_weights; /* morph_count default weights */
    /* Per triangle, 1 where the primitive had no NORMAL (flat normals): such
     * a triangle owns its three vertices, which carry its front face normal
     * (reversed in object-local space when the node's determinant is
     * negative, so that the world normal points out of the front); with
     * morph targets gi_scene_object_vertices recomputes it from the morphed
     * corners. NULL when the object has none. */
    uint8_t *flat_triangles;
    gi_track morph_track; /* count 0 when the weights are not animated */
} gi_object;

typedef enum gi_light_type {
    GI_LIGHT_POINT = GI_LIGHT_TYPE_POINT,
    GI_LIGHT_SPOT = GI_LIGHT_TYPE_SPOT,
    GI_LIGHT_DIRECTIONAL = GI_LIGHT_TYPE_DIRECTIONAL,
} gi_light_type;

/* A KHR_lights_punctual light as placed by its node. */
typedef struct gi_light {
    char *name;
    gi_light_type type;
    int node;
    float intensity[3]; /* colour x intensity: W/sr (point, spot) or W/m^2 (directional) */
    float range;        /* 0 = infinite */
    float inner_cone, outer_cone; /* spot half-angles in radians */
} gi_light;

/* The light's world-space frame at time t: position and the direction it
 * points (the node's -Z). */
typedef struct gi_light_frame {
    gi_vec3 position;
    gi_vec3 direction;
} gi_light_frame;

typedef struct gi_camera {
    char *name;
    int node;
    float yfov;        /* radians */
    float aspect;      /* 0 when the file leaves it to the viewport */
    float znear, zfar; /* zfar 0 = infinite in glTF; we substitute a bound-based far plane */
} gi_camera;

/* A camera resolved at time t: world placement and projection parameters. */
typedef struct gi_camera_frame {
    float world_from_camera[16]; /* camera looks down its -Z, +Y up */
    gi_vec3 eye, forward, up;
    float yfov, znear, zfar;
} gi_camera_frame;

typedef struct gi_environment {
    char *uri;  /* as written in the file, relative to the scene */
    char *path; /* resolved path */
    float intensity;
    float rotation_deg;
} gi_environment;

typedef struct gi_scene {
    char *path; /* the file it came from */
    gi_vertex *vertices;
    uint32_t vertex_count;
    uint32_t *indices; /* 3 per triangle, indexes into vertices */
    uint32_t triangle_count;
    gi_material *materials;
    uint32_t material_count;
    gi_texture *textures;
    uint32_t texture_count;
    gi_node *nodes;
    uint32_t node_count;
    gi_object *objects;
    uint32_t object_count;
    gi_light *lights;
    uint32_t light_count;
    gi_camera *cameras;
    uint32_t camera_count;
    /* Emissive triangles (area lights), in triangle order. */
    uint32_t *emitters;
    uint32_t emitter_count;
    int has_environment;
    gi_environment environment;
    struct gi_envmap *envmap; /* loaded map with its sampling CDF, or NULL */
    float animation_length;   /* seconds; 0 for a static scene (includes weight animations) */
    float bounds[6];          /* world bounds at t = 0 */
} gi_scene;

/* The one rule for sides at one hit (see the top of this file). */
typedef enum gi_side_kind {
    GI_SIDE_NONE = 0,  /* single-sided seen from the back: no hit, the ray goes on */
    GI_SIDE_FRONT = 1, /* the front: normals as they are */
    GI_SIDE_BACK = -1, /* the back of a double-sided triangle: normals reversed */
} gi_side_kind;

/* Which side of a triangle with front geometric normal ng (any length) is
 * seen along direction wo (from the surface towards the viewer, the
 * previous path vertex or the light; any length). */
static inline gi_side_kind gi_side(int double_sided, gi_vec3 ng, gi_vec3 wo)
{
    if (gi_v3_dot(ng, wo) > 0.0f)
        return GI_SIDE_FRONT;
    return double_sided ? GI_SIDE_BACK : GI_SIDE_NONE;
}

/* A normal (geometric or shading) as lighting must use it on that side. */
static inline gi_vec3 gi_side_normal(gi_side_kind side, gi_vec3 n)
{
    return side == GI_SIDE_BACK ? gi_v3_scale(n, -1.0f) : n;
}

/* The shading normal a surface is lit with, seen along wo (from the
 * surface towards the viewer; any length): n, the interpolated vertex
 * normal on the seen side (gi_side_normal), where it faces wo; otherwise
 * ng, the unit geometric normal on wo's side. Smooth normals face away
 * from the eye near a silhouette (and everywhere on a triangle whose file
 * normals disagree with its winding); lit with such a normal turned
 * round, the reference rendered those pixels nearly black (light from
 * the other geometric side carries nothing) while a method shading from
 * the G-buffer lit them. The reference (ref_path.c) and the G-buffer
 * (gbuffer.frag) both use this rule; GLSL twin gi_facing_normal in
 * core/shaders/scene.glsl. */
static inline gi_vec3 gi_facing_normal(gi_vec3 n, gi_vec3 ng, gi_vec3 wo)
{
    return gi_v3_dot(n, wo) > 0.0f ? n : ng;
}

/* Loads and validates a .gltf or .glb file. On failure returns NULL and
 * writes "file: /json/path: reason" into err. */
gi_scene *gi_scene_load(const char *path, gi_error *err);
/* The same from memory (the fuzz target uses this). `base_dir` resolves
 * external URIs; NULL forbids them. `name` is used in messages. */
gi_scene *gi_scene_load_memory(const void *data, size_t size, int binary, const char *base_dir,
                               const char *name, gi_error *err);
void gi_scene_free(gi_scene *scene);

/* World transform of a node / an object at time t (animations sampled and
 * composed up the parent chain). */
void gi_scene_node_transform(const gi_scene *s, int node, float t, float out[16]);
void gi_scene_object_transform(const gi_scene *s, uint32_t object, float t, float out[16]);
/* 1 when the node or one of its ancestors has an animation channel on
 * translation, rotation or scale (its world transform depends on time);
 * node -1 gives 0. */
int gi_scene_node_animated(const gi_scene *s, int node);
/* 1 when camera i (gi_scene_camera_at's index; -1, the default view, is
 * never animated) moves with time. */
int gi_scene_camera_animated(const gi_scene *s, int camera);
/* 1 when some light moves with time: a punctual light's node, or an
 * object carrying emissive triangles (rigidly animated or morphing). */
int gi_scene_lights_animated(const gi_scene *s);
/* World-space frame of punctual light i at time t. */
gi_light_frame gi_scene_light_at(const gi_scene *s, uint32_t light, float t);
/* Camera i at time t. Camera -1 is the default view (what a scene without
 * a camera renders; the loader warns once): from +Z towards -Z, aimed at
 * the centre of the bounds at t = 0, far enough that the bounding sphere fits
 * the 45-degree vertical field of view. */
gi_camera_frame gi_scene_camera_at(const gi_scene *s, int camera, float t);
/* Index of the camera named `name`, or of "#k", or -1 when none matches. */
int gi_scene_find_camera(const gi_scene *s, const char *name);
/* 1 when some object has morph targets (its vertices are a function of
 * time, or at least differ from the stored rest pose): methods must claim
 * GI_CAP_DEFORMATION for it (harness cli_caps_cover). */
int gi_scene_deforms(const gi_scene *s);
/* Morph weights of object o at time t (morph_count floats; nothing for a
 * rigid object). */
void gi_scene_morph_weights(const gi_scene *s, uint32_t object, float t, float *out);
/* The object's vertices at time t in object-local space (vertex_count
 * records, copies of scene->vertices[first_vertex ...] with morph targets
 * applied: positions blended, normals blended and renormalised). For a
 * rigid object a plain copy. This is what the GPU's vertex buffer holds
 * after gi_gpu_scene_set_time(t) and what gi_rt places at t. */
void gi_scene_object_vertices(const gi_scene *s, uint32_t object, float t, gi_vertex *out);
/* Object-local position of scene vertex v at time t (morphs applied). */
gi_vec3 gi_scene_vertex_position(const gi_scene *s, uint32_t vertex, float t);
/* World-space corners of triangle `tri` at time t (morphs applied). */
void gi_scene_triangle_world(const gi_scene *s, uint32_t tri, float t, gi_vec3 p[3]);
/* World bounds at time t (from the objects' local_bounds: conservative
 * under rotation and for morphing objects). */
void gi_scene_bounds_at(const gi_scene *s, float t, float out[6]);
/* Emitted radiance of a triangle (its material's emission). */
const float *gi_scene_triangle_emission(const gi_scene *s, uint32_t tri);
/* Albedo at a surface point: material albedo x texture(uv), bilinear. */
void gi_scene_albedo(const gi_scene *s, uint32_t material, const float uv[2], float out[3]);

#ifdef __cplusplus
}
#endif
#endif

/* Approximate Visibility Grids (Bashford-Rogers, Debattista, Harvey,
 * Chalmers): the plugin's internal interface, shared by avg.c and the tests
 * (the avg_tests program, tests/avg_test*.c, compiles the plugin's sources
 * in).
 *
 *   avg_grid   the AVG itself (§III-A): two 3D textures (summed normals and
 *              summed colours, a count in alpha), rebuilt by the rasteriser
 *              every frame (avg_grid.c, shaders/avg_vox.*).
 *   avg_vpl    one virtual point light as the tracing pass writes it (§III-B,
 *              avg_trace.comp / avg_trace_cpu.c) and the shading pass reads it.
 *   avg        the method instance (avg.c), exposed so that tests can drive
 *              create/prepare/render and then look at its G-buffer and VPLs.
 */
#ifndef AVG_H
#define AVG_H

#include "gi/kit.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

extern const gi_shader_source gi_avg_shaders[];

/* Voxelisation variants (param `voxeliser`). */
typedef enum avg_vox_mode {
    AVG_VOX_CONSERVATIVE = 0, /* bounding quad per slice + exact triangle-box test per fragment */
    AVG_VOX_PAPER = 1, /* the paper's: slice part of the triangle, epsilon shift, stand-ins */
    AVG_VOX_SINGLE =
        2, /* one draw, dominant-axis projection, the conservative test per column voxel */
} avg_vox_mode;

typedef struct avg_grid {
    uint32_t n;                   /* n x n x n voxels */
    float origin[3];              /* world position of the grid's corner (0, 0, 0) */
    float h;                      /* voxel edge length (voxels are cubes) */
    GLuint tex_normal;            /* RGBA32F 3D: sum of triangle normals, count in w */
    GLuint tex_colour;            /* RGBA32F 3D: sum of albedos, count in w */
    GLuint fbo, program[3];       /* layered FBO; programs per avg_vox_mode */
    GLuint fbo_single;            /* the single pass: no attachments, n x n */
    GLuint prog_resolve;          /* the single pass: fixed-point sums -> textures */
    GLuint ssbo_sums;             /* the single pass: 8 ints a voxel (avg_vox1.frag) */
    GLuint ssbo_colours;          /* per material: albedo x mean texture colour */
    const gi_scene *colour_scene; /* the scene ssbo_colours was made for */
    const gi_host *host;          /* polled between batches of slices (issue 32); NULL: never */
} avg_grid;

avg_grid *avg_grid_create(uint32_t n, gi_error *err);
void avg_grid_free(avg_grid *g);
/* Places the grid around `bounds` (min xyz, max xyz): a cube of the largest
 * extent plus a margin of 1.5 voxels on every side. */
void avg_grid_place(avg_grid *g, const float bounds[6]);
/* Clears and voxelises the scene at its current time (§III-A). */
gi_result avg_grid_voxelise(avg_grid *g, const gi_gpu_scene *gs, avg_vox_mode mode, gi_error *err);
/* GI_OK when this GL can hold the single-pass voxeliser's sums for an
 * n^3 grid (8 ints a voxel in one storage buffer), else a message. */
gi_result avg_grid_check_single(uint32_t n, gi_error *err);
/* Reads the normal (or colour) texture back: n^3 x 4 floats, x fastest. */
float *avg_grid_read(const avg_grid *g, int colour);
/* Binds both textures as sampler3D units (normal, colour) and sets the
 * u_grid_origin / u_grid_h / u_grid_n uniforms of `program`. */
void avg_grid_bind(const avg_grid *g, GLuint program, GLuint unit_normal, GLuint unit_colour);

/* A VPL, std430 (64 bytes), mirrored in shaders/avg_vpl.glsl. */
enum { AVG_VPL_DIFFUSE = 0, AVG_VPL_POINT = 1, AVG_VPL_SPOT = 2 };
/* kind flag: a punctual light's VPL covering the cube face whose axis is its
 * normal, not a hemisphere (avg.c, punctual_parts) */
#define AVG_VPL_FACE 0x20000u
/* kind flag: one of a punctual light's cover VPLs, shaded at every pixel
 * outside the interleaving and the filter (avg.c, punctual_parts) */
#define AVG_VPL_WHOLE 0x40000u
typedef struct avg_vpl {
    float position[3];
    uint32_t kind;   /* AVG_VPL_* | bounce << 8 | double-sided emitter << 16 | AVG_VPL_FACE |
                       punctual light's entry (1 + light) << 24 */
    float normal[3]; /* surface normal (diffuse) or spot axis */
    float cos_inner;
    float power[3]; /* diffuse: flux, radiant intensity = power cos / pi; point/spot: intensity */
    float cos_outer;
    float spot_dir[3]; /* spot lights: the cone's axis */
    float range;       /* punctual lights: glTF range (0 = none) */
} avg_vpl;

/* Tracing settings shared by the GPU and CPU tracers. */
typedef struct avg_trace_desc {
    uint32_t paths;   /* light paths; each owns bounces + 1 VPL slots */
    uint32_t bounces; /* indirect bounces B: VPLs at hits 1..B */
    float offset;     /* ray origins move this many voxels along the normal */
    uint32_t seed; /* the run's seed (gi_view.seed); 1, the default, gives the sequence of earlier
                      versions */
} avg_trace_desc;

/* Light choice of the tracers: the area lights as one group (emitter CDF
 * inside) followed by the punctual lights, by power (§III-B "weighted by the
 * power of the light source"). */
typedef struct avg_light_table {
    uint32_t count;    /* 1 + punctual lights (entry 0 = all area lights) */
    float cdf[1 + 64]; /* inclusive CDF over the entries */
    float pdf[1 + 64];
} avg_light_table;
#define AVG_MAX_PUNCTUAL 64
/* Builds the table from the scene on the GPU (punctual lights and emitter
 * power at the current time). Directional lights get no share (not supported). */
void avg_light_table_build(const gi_gpu_scene *gs, avg_light_table *t);

/* Quasi-random pair `pair` of light path i for the run's seed (C twin of
 * avg_vpl.glsl's avg_qr). */
void avg_qr(uint32_t i, uint32_t pair, uint32_t mask, uint32_t seed, float out[2]);

/* Exact tracing on the CPU with Embree (avg_trace_cpu.c): the same paths,
 * the same slots. avg_exact_trace re-places the scene at gs->time when it
 * changed and reads the emitter and light records back from the GPU. */
typedef struct avg_exact avg_exact;
avg_exact *avg_exact_create(const gi_gpu_scene *gs, gi_error *err);
void avg_exact_free(avg_exact *x);
gi_result avg_exact_trace(avg_exact *x, const gi_gpu_scene *gs, const avg_light_table *lt,
                          const avg_trace_desc *d, avg_vpl *slots, gi_error *err);

/* C twin of avg_vpl.glsl's avg_vpl_contribution (for tests): what VPL v
 * sends to a receiver at x with unit normal n without visibility, S such
 * that the Lambert receiver reflects (albedo / pi) S. */
void avg_vpl_contribution(const avg_vpl *v, const float x[3], const float n[3], float dmin2,
                          float out[3]);

/* The method instance (avg.c). */
typedef struct avg {
    gi_kit kit; /* host, scene, G-buffer, scratch textures, error text */
    /* parameters */
    int grid_n, vpls, bounces, M, tile, projection, filter, visibility, tracing, voxeliser;
    float clamp, offset, fov, shadow_lod;
    int mx; /* sqrt(M): M = mx x mx subsets */
    /* resources */
    avg_grid *grid;
    GLuint prog_trace, prog_split, prog_shade, prog_assemble, prog_final;
    GLuint ssbo_slots, ssbo_vpls, ubo_lights;
    GLuint tex_split_pos, tex_split_nrm, tex_split_out,
        tex_indirect;                  /* the kit's scratch textures 0-3 */
    GLuint tex_split_whole, tex_whole; /* 4-5: punctual lights' unfiltered part */
    uint32_t split_w, split_h;
    uint32_t slots, paths;
    avg_vpl *cpu_slots; /* readback of the slots */
    avg_vpl *cpu_vpls;  /* compacted live VPLs, in slot order */
    avg_vpl *cpu_order; /* punctual_parts' reordering (avg.c) */
    uint32_t vpl_count;
    uint32_t vpl_whole;    /* the first vpl_whole: punctual lights' covers, shaded at every pixel */
    uint32_t vpl_shaded;   /* the first vpl_shaded have power and maps; the rest repeat a cover */
    avg_exact *exact;      /* the CPU tracer (avg_trace_cpu.c), NULL for avg tracing */
    gi_depth_atlas *atlas; /* the VPLs' shadow maps when visibility is on */
    gi_depth_view *views;  /* one per VPL slot */
    struct gi_simplified *lod; /* the shadow maps' lower-detail copy (shadow_lod < 1), else NULL */
} avg;

/* The debug buffers (debug.c, plugin ABI 1.3): vpls and voxels. */
extern const gi_debug_buffer_desc avg_debug_buffers[];
gi_result avg_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out);

#ifdef __cplusplus
}
#endif
#endif

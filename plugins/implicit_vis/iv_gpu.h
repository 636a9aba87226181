/* The implicit_vis method's illumination on the GPU (Sec. 4.3.1): the
 * gather at the leaves with Eq. 5 and the area-weighted pull-up, iterated
 * for the bounces, as compute shaders over the flattened hierarchy and the
 * leaves' receiving links (iv_links_pack). The same computation as
 * iv_illuminate (illuminate.c) in single precision; the links are built on
 * the CPU.
 *
 * Use (a GL context current, the plugin's shader table registered):
 *   after iv_hier_create and iv_links_create:
 *     iv_gpu *g = iv_gpu_create(h, l, scene->envmap, &err);
 *   per frame, after iv_links_refine_push, the scene's punctual lights
 *   bound (gi_gpu_scene_bind) at the frame's time:
 *     iv_gpu_illuminate(g, l, h, bounces, light_count, &err);
 *   the result: g->ssbo_out (iv_display.comp's IvElemLight), or
 *   iv_gpu_read(g, e_out) in iv_illuminate's layout. */
#ifndef IV_GPU_H
#define IV_GPU_H

#include "iv.h"

#include <epoxy/gl.h>

typedef struct iv_gpu {
    uint32_t nodes, elems, bins, n;
    uint32_t levels; /* depth of the deepest tree */
    /* levels + 1: the first node of each depth (breadth-first order keeps them contiguous) */
    uint32_t *level_off;
    int env; /* the scene has an environment */
    GLuint prog_emit, prog_weights, prog_pull, prog_gather;
    GLuint ssbo_elem, ssbo_children, ssbo_bins; /* built once */
    GLuint ssbo_geom, ssbo_links, ssbo_off;     /* every frame */
    GLuint ssbo_wlinks;    /* per link, made on the GPU every frame: node and side, weight */
    GLuint ssbo_rad[2];    /* outgoing radiance per node, this bounce's and the previous one's */
    GLuint ssbo_out;       /* per element: irradiance on both sides, normal (IV_SSBO_ELEM_LIGHT) */
    GLuint ssbo_emit;      /* per node: the emission pulled up (bounce 0), kept when keep_emit */
    GLuint ssbo_direct;    /* per element: the traced direct irradiance (made on first use) */
    int keep_emit;         /* set by the caller: keep the emission for the glossy display */
    int links_current;     /* ssbo_geom and ssbo_links hold the links given last; the caller
                              clears it when it rebuilds them */
    float *geom;           /* staging: 8 per node */
    uint32_t *links, *off; /* staging for iv_links_pack */
    size_t links_cap;      /* words */
    size_t links_gpu;      /* bytes of ssbo_links (ssbo_wlinks: half of it) */
    size_t max_block;      /* GL_MAX_SHADER_STORAGE_BLOCK_SIZE */
} iv_gpu;

iv_gpu *iv_gpu_create(const iv_hier *h, const iv_links *l, const gi_envmap *env, gi_error *err);
void iv_gpu_free(iv_gpu *g);
/* Uploads the frame's node positions, normals and areas and the links,
 * then runs the passes: emission, the links' weights, pull-up, and
 * bounces + 1 gathers each followed by a pull-up (the last one needs none). punctual: the number of
 * the scene's punctual lights (bound at GI_SSBO_LIGHTS). direct: NULL for the paper's direct
 * light along the links, else iv_lights.direct's traced irradiance (6 per element), which then
 * replaces the first gather and is left out of ssbo_out (iv_illuminate's rule). */
gi_result iv_gpu_illuminate(iv_gpu *g, const iv_links *l, const iv_hier *h, uint32_t bounces,
                            uint32_t punctual, const float *direct, gi_error *err);
/* Binds what the glossy display reads of the frame's direct light (after
 * iv_gpu_illuminate with keep_emit): the elements, bins, node geometry,
 * receiving links, their offsets and weights, and the pulled-up emission
 * at IV_SSBO_RAD_SRC. */
void iv_gpu_bind_direct(const iv_gpu *g);
/* Reads the result back: 6 floats per element as iv_illuminate writes them. */
void iv_gpu_read(const iv_gpu *g, float *e_out);

#endif

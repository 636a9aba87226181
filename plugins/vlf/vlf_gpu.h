/* Propagation of the vlf light field on the GPU (paper §3.2-§3.4): the
 * sweeps through every subfield's sorted fragments, the non-diffuse
 * scattering and the shooting iterations run as GL 4.5 compute passes
 * (shaders/vlf_propagate.comp) on the depth order the CPU's sort stage
 * built, giving the maps the CPU's vlf_field_propagate gives (within
 * float rounding; tests: vlf_storage_tests gpu). Needs a current GL 4.5
 * context and the plugin's shaders registered. */
#ifndef VLF_GPU_H
#define VLF_GPU_H

#include <stddef.h>

#include <epoxy/gl.h>

#include "vlf_field.h"

enum { VLF_GPU_PASSES = 5, VLF_GPU_BUFFERS = 20 };

/* The rasterised sweeps (propagate = raster, vlf_raster.c): the faces of a
 * subfield drawn in depth order into its radiance interface, a tile of
 * an atlas holding a batch of directions. */
typedef struct vlf_raster {
    GLuint draw, escape, init;  /* programs: the faces; the escape count; the sky */
    GLuint fbo, tex[2], vao;    /* interfaces (RGB) and per-ray counters, RGBA32F */
    GLuint dirs, signed_dirs;   /* buffers: per direction its order; per signed one t, dW, sky */
    uint32_t NS, TX, TY, batch; /* a tile's side, tiles across and down, directions a batch */
    uint32_t *order_first, *order_count, *extra_first; /* per fixed direction */
    int barrier; /* 1: GL 4.5 core, the order in layers and glTextureBarrier (vlf_layers.c);
                  * 0: GL_EXT_shader_framebuffer_fetch */
    uint32_t *layer_first; /* per fixed direction: its first entry of layer_start */
    uint32_t *layer_start; /* per direction its layers' first entries in its order, and the end */
    uint32_t max_layers;   /* the most layers of a direction */
    uint64_t layer_total;  /* layers over all directions */
} vlf_raster;

/* How the raster path orders each pixel's read-modify-write (parameter
 * raster_sync): the fetch extension where the GL has it, else barriers. */
enum { VLF_SYNC_AUTO = 0, VLF_SYNC_FETCH = 1, VLF_SYNC_BARRIER = 2 };

typedef struct vlf_gpu {
    GLuint prog[VLF_GPU_PASSES]; /* sweep, gather, scatter, finish, settle */
    GLuint buf[VLF_GPU_BUFFERS];
    int raster; /* 1: the sweeps by the rasteriser (vlf_raster.c), no fragment lists */
    vlf_raster ras;
    /* per fixed direction: first cell_start entry and fragment, gather
     * entries (elements then tile cells), scatter jobs and their cells */
    uint32_t *start_base, *frag_base, *g_first, *g_elem, *g_count, *j_first, *j_count, *j_cells;
    double setup_s, readback_s; /* the upload of the depth order and the read-back of the maps */
} vlf_gpu;

/* Builds the passes' programs; raster = 1 for the rasterised sweeps
 * (propagate = raster; fails with a one-line reason where the GL lacks
 * what they need). */
gi_result vlf_gpu_init(vlf_gpu *g, int raster, int sync, gi_error *err);
/* Uploads field f's depth order, gather lists, tiles and scatter jobs
 * (the paper keeps them on the GPU for the iterations). */
gi_result vlf_gpu_setup(vlf_gpu *g, const vlf_field *f, gi_error *err);
/* Propagates f for f->prm.iterations iterations on the GPU (after
 * vlf_gpu_setup on the same field) and reads the maps back into f (the
 * same arrays and counters as vlf_field_propagate). `cancelled` (may be
 * NULL) is polled between directions; returns GI_ERR_CANCELLED then. */
gi_result vlf_gpu_propagate(vlf_gpu *g, vlf_field *f, int (*cancelled)(void *), void *user,
                            gi_error *err);
void vlf_gpu_free(vlf_gpu *g);

/* ---- The rasterised sweeps (vlf_raster.c) ---------------------------------- */

/* Checks the GL's extensions and builds the draw programs. */
gi_result vlf_raster_init(vlf_raster *r, int sync, gi_error *err);
/* The barrier variant's layers (vlf_layers.c): each direction's entries of
 * f->psf[i].rorder sorted by layer into order + r->order_first[i], the
 * layers' bounds into r->layer_first / layer_start. */
gi_result vlf_raster_layers(vlf_raster *r, const vlf_field *f, uint32_t *order, gi_error *err);
/* Uploads f's triangles, face charts and every subfield's face order
 * (vlf_psf.rorder; f built with vlf_settings.raster) into buf (the buffers
 * of vlf_gpu), and makes the interface's render target. */
gi_result vlf_raster_setup(vlf_raster *r, GLuint *buf, const vlf_field *f, gi_error *err);
/* The sweeps of every fixed direction of one iteration (along +w_i front
 * to back, along -w_i back to front), a batch of directions a draw:
 * receivers' flux into the accumulators (buffer 6), senders' radiance on
 * the interfaces. `cancelled` is polled between batches. */
gi_result vlf_raster_iteration(vlf_raster *r, const vlf_field *f, int first_iteration,
                               int (*cancelled)(void *), void *user, gi_error *err);
void vlf_raster_constants(vlf_raster *r, const vlf_field *f, float cell_area);
/* Clears the per-ray counters (start of a propagation). */
void vlf_raster_clear_counters(vlf_raster *r);
/* The counters summed into f's flux statistics. */
gi_result vlf_raster_counters(vlf_raster *r, vlf_field *f, gi_error *err);
void vlf_raster_free(vlf_raster *r);

#endif

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

enum { VLF_GPU_PASSES = 4, VLF_GPU_BUFFERS = 16 };

typedef struct vlf_gpu {
    GLuint prog[VLF_GPU_PASSES]; /* sweep, gather, scatter, finish */
    GLuint buf[VLF_GPU_BUFFERS];
    /* per fixed direction: first cell_start entry and fragment, gather
     * entries (elements then tile cells), scatter jobs and their cells */
    uint32_t *start_base, *frag_base, *g_first, *g_elem, *g_count, *j_first, *j_count, *j_cells;
    double setup_s, readback_s; /* the upload of the depth order and the read-back of the maps */
} vlf_gpu;

/* Builds the passes' programs. */
gi_result vlf_gpu_init(vlf_gpu *g, gi_error *err);
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

#endif

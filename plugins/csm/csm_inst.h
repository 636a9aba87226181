/* The csm instance, shared by csm.c (the method) and debug.c (its debug
 * buffers). */
#ifndef CSM_INST_H
#define CSM_INST_H

#include "csm_local.h"

#include "gi/kit.h"

enum {
    B_OBJECTS = 8,
    B_OFFSETS = 9,
    B_ZAVG = 10,
    B_IEND = 11,
    B_CELLS = 12,
    B_PATTERNS = 13,
    B_LIGHTS = 14,
    B_PAIRS = 15,
    B_LIGHT_CELLS = 16,
    B_COUNT = 17
};

enum { LIGHTS_LOCAL = 0, LIGHTS_SEMILOCAL = 1 };
enum { RECEIVERS_NONE = 0, RECEIVERS_PLANAR = 1 };

typedef struct csm {
    gi_kit kit; /* host, scene, G-buffer, accumulation, error text */
    int N, M, S, z3, filter, mode, open_surfaces;
    gi_csm_order order;
    float bias, normal_offset, normal_offset_local, shell_thickness;
    int lights_mode, n_local, m_local, receivers, distant, warned_moved, local_motion;
    int dilate_local;  /* occluders=dilated: README "Sub-texel occluders" */
    uint32_t rebuilds; /* local-light precomputations redone in update() (local_motion=rebuild) */
    float *prepare_transforms; /* 16 per object: world_from_local at prepare time */
    gi_csm_order light_order;
    float linear_aspect;
    uint32_t object_count, light_count;
    unsigned char *casts; /* per object: 1 if it has CSMs (not receiver-only) */
    csm_light *lights;
    csm_gpu_object *objects;
    GLuint
        ssbo[9]; /* objects, offsets, z_avg, i_end, cells, patterns, lights, pairs, light cells */
    GLuint program, count; /* count: samples taken this frame */
} csm;

/* The shading pass's program in use with its buffers and uniforms (§5;
 * u_debug 0: the image). */
void csm_bind_pass(csm *c, const gi_view *view, const gi_target *target);

/* The debug buffers (debug.c): visibility and segments. */
extern const gi_debug_buffer_desc csm_debug_buffers[];
gi_result csm_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out);

#endif

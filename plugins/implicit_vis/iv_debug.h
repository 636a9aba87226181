/* The implicit_vis method's debug buffers (debug.c, plugin ABI 1.3): links
 * and gathered; debug.c reaches the instance through iv_debug_state
 * (implicit_vis.c). */
#ifndef IV_DEBUG_H
#define IV_DEBUG_H

#include "iv.h"

#include "gi/kit.h"

/* What the debug buffers read of a live instance. */
typedef struct iv_debug {
    gi_kit *kit;
    const iv_hier *hier;   /* NULL before prepare */
    const iv_links *links; /* after refine_push: leaf_off */
    GLuint elem_light;     /* 12 floats per element: e_front, e_back, normal (vec4 each) */
} iv_debug;

void iv_debug_state(void *inst, iv_debug *out);

extern const gi_debug_buffer_desc iv_debug_buffers[];
gi_result iv_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out);

#endif

/* The vlf method's debug buffers (debug.c, plugin ABI 1.3): direction and
 * diffuse; debug.c reaches the instance's field and kit through
 * vlf_debug_field (vlf.c). */
#ifndef VLF_DEBUG_H
#define VLF_DEBUG_H

#include "vlf_field.h"

#include "gi/kit.h"

extern const gi_debug_buffer_desc vlf_debug_buffers[];
gi_result vlf_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out);
/* The instance's light field (NULL before prepare) and its kit. */
const vlf_field *vlf_debug_field(void *inst, gi_kit **kit);

#endif

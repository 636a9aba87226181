/* Debug buffers of a live method instance (plugin ABI 1.3, issue 33): the
 * named intermediate images a plugin declares in gi_method.debug_buffers,
 * fetched after a render() as float RGB images. Shared by gibench render
 * --buffer (harness/cli/cmd_render.c), gibench view and the Python API. */
#ifndef GIBENCH_DEBUG_BUFFER_H
#define GIBENCH_DEBUG_BUFFER_H

#include "gi/image.h"
#include "gi/method.h"

#include <stddef.h>

/* "a, b, c": the names of m's debug buffers into buf ("none" when it
 * declares none, or was built before ABI 1.3). */
void debug_buffer_names(const gi_method *m, char *buf, size_t size);

/* GI_OK when m declares a buffer `name`; else GI_ERR_INVALID_ARGUMENT and
 * the one-line "csm: no debug buffer 'x' (buffers: visibility, maps)". */
gi_result debug_buffer_check(const gi_method *m, const char *name, gi_error *err);

/* Buffer `name` of instance `inst` of method m, after a render() that was
 * given `view`: a new image (free it with gi_image_free), row 0 the top
 * row, RGB with alpha 1, view->width x view->height for a screen-space
 * buffer, its own size otherwise. NULL with a one-line err on an unknown
 * name (debug_buffer_check's), on the method's failure ("M: debug buffer
 * 'x' failed (RESULT): its last_error"), on a screen-space buffer of the
 * wrong size, or on a buffer holding NaN or infinite values. */
gi_image *debug_buffer_fetch(const gi_method *m, void *inst, const gi_view *view, const char *name,
                             gi_error *err);

#endif

/* Debug buffers of a live method instance (debug_buffer.h). */
#include "debug_buffer.h"

#include "gi/passes.h"
#include "gi/plugin.h"

#include <stdio.h>
#include <string.h>

void debug_buffer_names(const gi_method *m, char *buf, size_t size)
{
    if (!size)
        return;
    buf[0] = '\0';
    const gi_debug_buffer_desc *d = gi_method_debug_buffers(m);
    for (size_t used = 0; d && d->name; d++) {
        snprintf(buf + used, size - used, "%s%s", used ? ", " : "", d->name);
        used = strlen(buf);
    }
    if (!buf[0])
        snprintf(buf, size, "none");
}

gi_result debug_buffer_check(const gi_method *m, const char *name, gi_error *err)
{
    if (gi_method_debug_buffer(m, name))
        return GI_OK;
    char names[512];
    debug_buffer_names(m, names, sizeof names);
    return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: no debug buffer '%s' (buffers: %s)",
                        m->id, name ? name : "", names);
}

gi_image *debug_buffer_fetch(const gi_method *m, void *inst, const gi_view *view, const char *name,
                             gi_error *err)
{
    if (debug_buffer_check(m, name, err) != GI_OK)
        return NULL;
    const gi_debug_buffer_desc *d = gi_method_debug_buffer(m, name);
    gi_image *img = NULL;
    gi_result r = m->debug_buffer(inst, name, view, &img);
    if (r != GI_OK || !img) {
        const char *why = m->last_error(inst);
        gi_image_free(img);
        /* GI_OK without an image: gi_image_create ran out of memory */
        gi_result res = r != GI_OK ? r : GI_ERR_OUT_OF_MEMORY;
        gi_error_set(err, res, "%s: debug buffer '%s' failed (%s)%s%s", m->id, name,
                     gi_result_name(res), why && *why ? ": " : "", why ? why : "");
        return NULL;
    }
    gi_error gerr;
    if (gi_gl_check("after debug_buffer", &gerr) != GI_OK) {
        gi_image_free(img);
        gi_error_set(err, GI_ERR_GL, "%s: debug buffer '%s': %s", m->id, name, gerr.text);
        return NULL;
    }
    if (d->space == GI_DEBUG_SCREEN && (img->width != view->width || img->height != view->height)) {
        gi_error_set(err, GI_ERR_UNSUPPORTED,
                     "%s: debug buffer '%s' is %ux%u, a screen-space buffer must be %ux%u", m->id,
                     name, img->width, img->height, view->width, view->height);
        gi_image_free(img);
        return NULL;
    }
    for (size_t i = 0; i < (size_t)img->width * img->height; i++)
        img->rgba[4 * i + 3] = 1.0f;
    uint64_t bad = gi_image_count_nonfinite(img);
    if (bad) {
        gi_error_set(err, GI_ERR_UNSUPPORTED,
                     "%s: debug buffer '%s' has %llu NaN or infinite pixels", m->id, name,
                     (unsigned long long)bad);
        gi_image_free(img);
        return NULL;
    }
    return img;
}

/* gibench view: the method's debug buffers (named intermediate images, the
 * "Buffers" combo of the panels and the viewport's source "buffer"). The
 * method ABI's optional list of named images and the harness function that
 * fetches one as a float RGB image come with the debug-buffer work (branch
 * s7-dbg); until it is merged, GIBENCH_VIEW_DEBUG_BUFFERS is 0 and the list
 * is empty: the combo shows "(none)" and the source shows black. */
#include "view.h"

#include "gi/image.h"

#ifndef GIBENCH_VIEW_DEBUG_BUFFERS
#define GIBENCH_VIEW_DEBUG_BUFFERS 0
#endif

#if GIBENCH_VIEW_DEBUG_BUFFERS
#error                                                                                             \
    "wire view_buffer_count, view_buffer_name and view_buffer_fetch to the method ABI's debug buffers (s7-dbg)"
#else
/* No debug buffers yet: an empty list. */
uint32_t view_buffer_count(const viewer *v)
{
    (void)v;
    return 0;
}

const char *view_buffer_name(const viewer *v, uint32_t i)
{
    (void)v;
    (void)i;
    return NULL;
}

gi_image *view_buffer_fetch(viewer *v, uint32_t i)
{
    (void)v;
    (void)i;
    return NULL;
}
#endif

void view_buffer_upload(viewer *v)
{
    gi_image *img = NULL;
    if (v->method_index >= 0 && v->inst && (uint32_t)v->buffer_sel < view_buffer_count(v))
        img = view_buffer_fetch(v, (uint32_t)v->buffer_sel);
    if (v->buf_tex)
        glDeleteTextures(1, &v->buf_tex);
    uint32_t w = img ? img->width : 1, h = img ? img->height : 1;
    glCreateTextures(GL_TEXTURE_2D, 1, &v->buf_tex);
    glTextureStorage2D(v->buf_tex, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
    glTextureParameteri(v->buf_tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(v->buf_tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    const float black[4] = {0, 0, 0, 1};
    glClearTexImage(v->buf_tex, 0, GL_RGBA, GL_FLOAT, black);
    if (img)
        glTextureSubImage2D(v->buf_tex, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_FLOAT,
                            img->rgba);
    gi_image_free(img);
}

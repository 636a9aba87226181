/* gibench view: the method's debug buffers (named intermediate images, the
 * "Buffers" combo of the panels and the viewport's source "buffer"): the
 * plugin ABI 1.3 list gi_method.debug_buffers, fetched after each frame by
 * the harness's debug_buffer_fetch (harness/run/debug_buffer.h), the same
 * function as `gibench render --buffer`. */
#include "view.h"

#include "debug_buffer.h"
#include "gi/image.h"
#include "gi/log.h"
#include "gi/plugin.h"

/* The buffers the method shown declares (none before plugin ABI 1.3). */
static const gi_debug_buffer_desc *buffers(const viewer *v)
{
    return v->m ? gi_method_debug_buffers(v->m) : NULL;
}

uint32_t view_buffer_count(const viewer *v)
{
    const gi_debug_buffer_desc *d = buffers(v);
    uint32_t n = 0;
    while (d && d[n].name)
        n++;
    return n;
}

const char *view_buffer_name(const viewer *v, uint32_t i)
{
    return i < view_buffer_count(v) ? buffers(v)[i].name : NULL;
}

/* Buffer i of the instance shown, after its last render(); NULL (black, and
 * the one-line reason logged) when the method fails to give it. */
gi_image *view_buffer_fetch(viewer *v, uint32_t i)
{
    const char *name = view_buffer_name(v, i);
    if (!name || !v->inst)
        return NULL;
    gi_error err = {{0}};
    gi_image *img = debug_buffer_fetch(v->m, v->inst, &v->last_view, name, &err);
    if (!img)
        gi_log(GI_LOG_WARN, "view: %s", err.text);
    return img;
}

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

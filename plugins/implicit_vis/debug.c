/* The implicit_vis method's debug buffers (plugin ABI 1.3, issue 33): the
 * links that replace visibility and what the elements gather along them
 * (Dong, Kautz, Theobalt, Seidel, PG 2007).
 *
 *   links     per pixel, the receiving links of the element its surface
 *             point belongs to (Sec. 4.2: the hierarchical links after
 *             refinement and push-down, one per non-empty bin of the
 *             6 N^2, each the nearest node in its direction): the implicit
 *             visibility itself; few where little is in view (a corner,
 *             open sky), many on a surface facing the whole scene.
 *   gathered  per pixel, the radiance its element reflects from the
 *             irradiance it gathered along those links (Sec. 4.3, Eq. 5,
 *             every bounce: albedo E / pi + emission); with direct=traced
 *             the elements hold the indirect bounces only (the traced direct
 *             light is added per pixel). The image interpolates this over
 *             three elements and adds the glossy lobe.
 *
 * The element of a pixel is the one nearest its G-buffer position among
 * those the display blends on its triangle (iv_hier's display grid). */
#include "iv_debug.h"

#include <stdlib.h>
#include <string.h>

const gi_debug_buffer_desc iv_debug_buffers[] = {
    {"links", "receiving links (non-empty bins, Sec. 4.2) of the element the pixel sees",
     GI_DEBUG_SCREEN},
    {"gathered",
     "the pixel's element's radiance from what it gathered along its links: albedo E / pi + "
     "emission (Sec. 4.3)",
     GI_DEBUG_SCREEN},
    {NULL, NULL, 0},
};

/* The element nearest P among those the display blends on triangle tri;
 * -1 when it has none. */
static int32_t pixel_element(const iv_hier *h, uint32_t tri, const float P[3])
{
    int32_t best = -1;
    float best_d = 0;
    for (uint32_t g = h->tri_grid[tri]; g < h->tri_grid[tri + 1]; g++)
        for (int k = 0; k < 3; k++) {
            uint32_t e = h->disp_elem[3 * g + (uint32_t)k];
            const float *q = &h->pos[3 * (size_t)h->elem_node[e]];
            float d = (q[0] - P[0]) * (q[0] - P[0]) + (q[1] - P[1]) * (q[1] - P[1]) +
                      (q[2] - P[2]) * (q[2] - P[2]);
            if (best < 0 || d < best_d)
                best = (int32_t)e, best_d = d;
        }
    return best;
}

/* Element e's value for buffer `links` (is_links) or `gathered`, seen from
 * eye at P. */
static void element_value(const iv_debug *d, const float *light, uint32_t e, int is_links,
                          const float P[3], gi_vec3 eye, float out[3])
{
    const iv_hier *h = d->hier;
    if (is_links) {
        out[0] = out[1] = out[2] = (float)(d->links->leaf_off[e + 1] - d->links->leaf_off[e]);
        return;
    }
    const float *n = &light[12 * (size_t)e + 8];
    float facing = n[0] * (eye.x - P[0]) + n[1] * (eye.y - P[1]) + n[2] * (eye.z - P[2]);
    const float *E = &light[12 * (size_t)e + (facing >= 0 ? 0 : 4)];
    int emits = facing >= 0 || h->elem_two_sided_emit[e];
    for (int k = 0; k < 3; k++)
        out[k] = h->elem_albedo[3 * (size_t)e + k] / (float)GI_PI * E[k] +
                 (emits ? h->elem_emit[3 * (size_t)e + k] : 0.0f);
}

static gi_image *pixel_image(const iv_debug *d, const gi_view *view, int is_links)
{
    const iv_hier *h = d->hier;
    const uint32_t w = view->width, hh = view->height;
    size_t n = (size_t)w * hh;
    float *pos = malloc(4 * n * sizeof *pos);
    uint32_t *ids = malloc(4 * n * sizeof *ids);
    float *light = malloc(12 * (size_t)h->elem_count * sizeof *light);
    gi_image *img = pos && ids && light ? gi_image_create(w, hh) : NULL;
    if (img) {
        glGetTextureImage(d->kit->gbuffer->tex_position, 0, GL_RGBA, GL_FLOAT,
                          (GLsizei)(4 * n * sizeof *pos), pos);
        glGetTextureImage(d->kit->gbuffer->tex_ids, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                          (GLsizei)(4 * n * sizeof *ids), ids);
        glGetNamedBufferSubData(d->elem_light, 0,
                                (GLsizeiptr)(12 * (size_t)h->elem_count * sizeof *light), light);
    }
    const gi_scene *s = d->kit->scene->scene;
    for (size_t p = 0; img && p < n; p++) {
        uint32_t tri = ids[4 * p + 2];
        int32_t e =
            pos[4 * p + 3] > 0 && tri < s->triangle_count ? pixel_element(h, tri, &pos[4 * p]) : -1;
        size_t y = hh - 1 - p / w, x = p % w; /* G-buffer row 0 at the bottom */
        if (e >= 0)
            element_value(d, light, (uint32_t)e, is_links, &pos[4 * p], view->eye,
                          &img->rgba[4 * (y * w + x)]);
    }
    free(pos);
    free(ids);
    free(light);
    return img;
}

gi_result iv_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out)
{
    iv_debug d;
    iv_debug_state(inst, &d);
    *out = NULL;
    if (!d.hier || !d.links || !d.links->leaf_off || !d.kit->gbuffer ||
        d.kit->width != view->width || d.kit->height != view->height)
        return gi_kit_fail(d.kit, GI_ERR_INVALID_ARGUMENT,
                           "implicit_vis: debug buffer '%s' needs a render() of this view first",
                           name);
    *out = pixel_image(&d, view, !strcmp(name, "links"));
    if (!*out)
        return gi_kit_fail(d.kit, GI_ERR_OUT_OF_MEMORY,
                           "implicit_vis: out of memory for a debug buffer");
    return GI_OK;
}

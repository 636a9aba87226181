/* The cssm_hrc method's debug buffers (plugin ABI 1.3, issue 33): the two
 * things that explain CSSM + hierarchical radiosity (Ritschel et al. 2008).
 *
 *   atlas     the illumination atlas (§3.2.3, §4.1): atlas x atlas texels,
 *             each the radiance its surface sample sends (emission plus the
 *             reflected light of every bounce, texel_L), black where no
 *             chart covers the texel; surface samples of curved meshes have
 *             no place in it and are not shown.
 *   indirect  the gathered indirect light (§4.4): per pixel, the reflected
 *             light of the atlas (light set 2) that the hierarchy's cut
 *             brings to the pixel, through the CSSM visibility, before the
 *             receiver's BRDF adds its own direct light; no jitter.
 *
 * Both read what render() keeps on the CPU: the atlas' lighting and the
 * G-buffer it read back. */
#include "cssm_hrc.h"

#include <string.h>

const gi_debug_buffer_desc cssm_debug_buffers[] = {
    {"atlas", "radiance of each atlas texel: emission + reflected light of all bounces (Sec. 4.1)",
     GI_DEBUG_OWN_SIZE},
    {"indirect", "reflected light of the atlas gathered at the pixel by the hierarchy (Sec. 4.4)",
     GI_DEBUG_SCREEN},
    {NULL, NULL, 0},
};

static gi_image *atlas_image(const cssm_hrc *c)
{
    const cssm_atlas *a = &c->atlas;
    gi_image *img = gi_image_create(a->R, a->R);
    for (size_t i = 0; img && i < (size_t)a->R * a->R; i++) {
        int32_t t = a->grid[i];
        if (t >= 0)
            memcpy(&img->rgba[4 * i], &c->texel_L[3 * (size_t)t], 3 * sizeof(float));
    }
    return img;
}

/* Row 0 of the image at the top; the G-buffer read back has it at the
 * bottom. */
static gi_image *indirect_image(const cssm_hrc *c, const gi_view *view)
{
    const uint32_t w = view->width, h = view->height;
    gi_image *img = gi_image_create(w, h);
    for (uint32_t y = 0; img && y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            size_t p = (size_t)y * w + x;
            if (c->gb[0][4 * p + 3] > 0.0f)
                cssm_pixel_reflected(c, view, p, &img->rgba[4 * ((size_t)(h - 1 - y) * w + x)]);
        }
    return img;
}

gi_result cssm_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out)
{
    cssm_hrc *c = inst;
    *out = NULL;
    /* gather=gpu keeps the G-buffer on the GPU: read the last frame's back */
    if (c->prepared && c->gpu_on && c->kit.frames > 0 && c->kit.width == view->width &&
        c->kit.height == view->height) {
        gi_result r = cssm_read_gbuffer(c, view->width, view->height);
        if (r != GI_OK)
            return r;
    }
    if (!c->prepared || !c->gb[0] || c->acc_w != view->width || c->acc_h != view->height)
        return gi_kit_fail(&c->kit, GI_ERR_INVALID_ARGUMENT,
                           "cssm_hrc: debug buffer '%s' needs a render() of this view first", name);
    *out = !strcmp(name, "atlas") ? atlas_image(c) : indirect_image(c, view);
    if (!*out)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for a debug buffer");
    return GI_OK;
}

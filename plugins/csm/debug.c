/* The csm method's debug buffers (plugin ABI 1.3, issue 33): the two
 * quantities that explain Coherent Shadow Maps (Ritschel et al. 2007).
 *
 *   visibility  the shadow term: per pixel, the direct light the CSM
 *               queries let through divided by the same light unshadowed
 *               (§3.2 tests, §5 sampling), in [0, 1]; 0 where no light
 *               reaches the pixel even unshadowed (or it shows background).
 *   segments    the compression the method rests on (§3.1-3.2): the mean
 *               length of the CSM texel lists (segments of coherent depth
 *               over the N maps) that the pixel's queries read; 1 where one
 *               depth serves every map, more along silhouettes.
 *
 * Both come from one extra dispatch of the shading pass (u_debug in
 * shaders/csm.comp) into a scratch texture, on the G-buffer of the last
 * render(); the running average the next frame continues is untouched. */
#include "csm_inst.h"

#include "gi/passes.h"

#include <string.h>

const gi_debug_buffer_desc csm_debug_buffers[] = {
    {"visibility",
     "shadow term: shadowed / unshadowed direct light of one frame's samples, in [0, 1] (Sec. 3.2)",
     GI_DEBUG_SCREEN},
    {"segments",
     "mean CSM segments per texel list the pixel's shadow queries read (Sec. 3.1 compression)",
     GI_DEBUG_SCREEN},
    {NULL, NULL, 0},
};

/* One dispatch of the shading pass with u_debug = mode, read back. */
static gi_image *debug_pass(csm *c, const gi_view *view, int mode)
{
    csm_bind_pass(c, view, NULL);
    gi_kit_debug_target(&c->kit, c->program, 0, view->width, view->height);
    glUniform1i(glGetUniformLocation(c->program, "u_debug"), mode);
    gi_kit_dispatch_8x8(view->width, view->height);
    glUseProgram(0);
    return gi_gpu_read_texture(c->kit.scratch[0].texture, view->width, view->height);
}

static float lum(const float *p)
{
    return 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
}

gi_result csm_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out)
{
    csm *c = inst;
    *out = NULL;
    if (!c->program || !c->kit.gbuffer || c->kit.width != view->width ||
        c->kit.height != view->height)
        return gi_kit_fail(&c->kit, GI_ERR_INVALID_ARGUMENT,
                           "csm: debug buffer '%s' needs a render() of this view first", name);
    if (!strcmp(name, "segments")) {
        *out = debug_pass(c, view, 3);
    } else {
        gi_image *lit = debug_pass(c, view, 1);
        gi_image *open = debug_pass(c, view, 2);
        if (lit && open)
            for (size_t i = 0; i < (size_t)view->width * view->height; i++) {
                float u = lum(open->rgba + 4 * i), v = u > 1e-12f ? lum(lit->rgba + 4 * i) / u : 0;
                v = v < 0 ? 0 : v > 1 ? 1 : v;
                lit->rgba[4 * i] = lit->rgba[4 * i + 1] = lit->rgba[4 * i + 2] = v;
            }
        gi_image_free(open);
        *out = open ? lit : NULL;
        if (!open)
            gi_image_free(lit);
    }
    if (!*out)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY, "csm: out of memory for a debug buffer");
    gi_error err;
    if (gi_gl_check("csm: debug buffer", &err) != GI_OK) {
        gi_image_free(*out);
        *out = NULL;
        return gi_kit_fail_with(&c->kit, GI_ERR_GL, &err);
    }
    return GI_OK;
}

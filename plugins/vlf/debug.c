/* The vlf method's debug buffers (plugin ABI 1.3, issue 33): the light
 * field itself and what it gives the image (Mortensen, Khanna, Slater,
 * Afrigraph 2007).
 *
 *   direction  the radiance of one direction of the light field (§3.1-3.2):
 *              the stored direction closest to the way the camera looks,
 *              seen along it as an orthographic (N S) x (N S) image of its
 *              radiance interface: each ray's fragments swept front to back
 *              as propagation sweeps them, the last front-facing element's
 *              diffuse radiance (kd E / pi + emission) what leaves; the sky
 *              where nothing is met.
 *   diffuse    the diffuse term the field gives each pixel (§4): the element
 *              the pixel's surface falls in, its irradiance E (all bounces
 *              the propagation carried, direct light included) times kd /
 *              pi, plus emission; the image is this plus the non-diffuse
 *              tiles' light, so on a diffuse scene the two agree.
 *
 * Both are computed on the CPU from the field prepare() keeps (E_tot, the
 * subfields' fragment lists) and the G-buffer of the last render(). */
#include "vlf_debug.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const gi_debug_buffer_desc vlf_debug_buffers[] = {
    {"direction",
     "radiance of the stored direction nearest the view, seen along it (Sec. 3.1, (N S)^2 rays)",
     GI_DEBUG_OWN_SIZE},
    {"diffuse", "the field's diffuse radiance at the pixel: kd E / pi + emission (Sec. 4)",
     GI_DEBUG_SCREEN},
    {NULL, NULL, 0},
};

/* Radiance element el sends (its diffuse part). */
static void element_radiance(const vlf_field *f, uint32_t el, float out[3])
{
    const vlf_face *fc = &f->faces[f->elem_face[el]];
    for (int q = 0; q < 3; q++)
        out[q] = f->elem_kd[3 * (size_t)el + q] / (float)GI_PI * f->E_tot[3 * (size_t)el + q] +
                 fc->emission[q];
}

static gi_image *direction_image(const vlf_field *f, const gi_view *view)
{
    uint32_t l = f->prm.l, S = f->prm.S, N = f->prm.N * S;
    /* toward the camera: the opposite of the way it looks */
    gi_vec3 back = gi_v3_normalize(gi_v3(view->view[2], view->view[6], view->view[10]));
    uint32_t best = 0;
    for (uint32_t sd = 1; sd < 2 * l; sd++)
        if (gi_v3_dot(f->dirs.signed_dirs[sd], back) > gi_v3_dot(f->dirs.signed_dirs[best], back))
            best = sd;
    uint32_t i = best < l ? best : best - l;
    int sign = best < l ? 1 : -1;
    gi_vec3 t = f->dirs.signed_dirs[best];
    const vlf_psf *p = &f->psf[i];
    float sky[3];
    vlf_sweep_sky(f, i, sign, 0, sky);
    gi_image *img = gi_image_create(N, N);
    for (uint32_t c = 0; img && c < N * N; c++) {
        float L[3] = {sky[0], sky[1], sky[2]};
        int32_t a = (int32_t)p->cell_start[c], e = (int32_t)p->cell_start[c + 1];
        int32_t k = sign > 0 ? a : e - 1, end = sign > 0 ? e : a - 1;
        for (; k != end; k += sign) {
            uint32_t el = p->frag[k];
            if (gi_v3_dot(f->faces[f->elem_face[el]].n, t) > 0.0f)
                element_radiance(f, el, L); /* a sender: its front faces along t */
        }
        /* interface row 0 at the bottom, the image's at the top */
        uint32_t x = c % N, y = N - 1 - c / N;
        memcpy(&img->rgba[4 * ((size_t)y * N + x)], L, sizeof L);
    }
    return img;
}

static gi_image *diffuse_image(const vlf_field *f, const gi_kit *k, const gi_view *view)
{
    const uint32_t w = view->width, h = view->height;
    size_t n = (size_t)w * h;
    float *pos = malloc(4 * n * sizeof *pos);
    uint32_t *ids = malloc(4 * n * sizeof *ids);
    gi_image *img = pos && ids ? gi_image_create(w, h) : NULL;
    if (img) {
        glGetTextureImage(k->gbuffer->tex_position, 0, GL_RGBA, GL_FLOAT,
                          (GLsizei)(4 * n * sizeof *pos), pos);
        glGetTextureImage(k->gbuffer->tex_ids, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                          (GLsizei)(4 * n * sizeof *ids), ids);
    }
    for (size_t px = 0; img && px < n; px++) {
        uint32_t tri = ids[4 * px + 2];
        if (pos[4 * px + 3] <= 0.0f || (uint64_t)tri * f->tri_sub >= f->tri_count)
            continue;
        gi_vec3 P = gi_v3(pos[4 * px], pos[4 * px + 1], pos[4 * px + 2]);
        int32_t fi = (int32_t)f->tri_face[tri * f->tri_sub];
        /* a double-sided face seen from its back: the other side's elements */
        if (f->faces[fi].twin >= 0 && gi_v3_dot(f->faces[fi].n, gi_v3_sub(view->eye, P)) < 0.0f)
            fi = f->faces[fi].twin;
        uint32_t el = vlf_element_at(f, &f->faces[fi], vlf_to_vlf(f, P));
        size_t y = h - 1 - px / w, x = px % w; /* G-buffer row 0 at the bottom */
        element_radiance(f, el, &img->rgba[4 * (y * w + x)]);
    }
    free(pos);
    free(ids);
    return img;
}

gi_result vlf_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out)
{
    gi_kit *k;
    const vlf_field *f = vlf_debug_field(inst, &k);
    *out = NULL;
    if (!f || !k->gbuffer || k->width != view->width || k->height != view->height)
        return gi_kit_fail(k, GI_ERR_INVALID_ARGUMENT,
                           "vlf: debug buffer '%s' needs a render() of this view first", name);
    *out = !strcmp(name, "direction") ? direction_image(f, view) : diffuse_image(f, k, view);
    if (!*out)
        return gi_kit_fail(k, GI_ERR_OUT_OF_MEMORY, "vlf: out of memory for a debug buffer");
    return GI_OK;
}

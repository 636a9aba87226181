/* The light field of the vlf method built for a scene (paper §2.1,
 * §3.1, §3.2): the settings checked, the scene scaled into the unit
 * sphere, its lights, faces and elements, every subfield's depth order,
 * the tile storage of the non-diffuse faces and the memory it takes; and
 * the field freed. */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi/raytrace.h"

gi_result vlf_build_out_of_memory(const vlf_field *f, gi_error *err)
{
    return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                        "vlf: out of memory building the light field (N = %u, l = %u)", f->prm.N,
                        f->prm.l);
}

/* The settings a field can be built with (the parameter table's bounds
 * leave some combinations out of reach of the storage). */
static gi_result check_settings(const vlf_settings *p, gi_error *err)
{
    if (p->precision > VLF_PREC_RGB9E5)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "vlf: storage precision %u unknown",
                            p->precision);
    if (p->S < 1 || p->S > 8)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "vlf: supersampling S = %u outside 1..8",
                            p->S);
    if (p->N < 4 || p->m < 1 || p->N % p->m != 0)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "vlf: N = %u must be a multiple of the tile size m = %u", p->N, p->m);
    double ray_bytes =
        (double)p->l * (double)(p->N * p->S) * (double)(p->N * p->S) * sizeof(uint32_t);
    if (ray_bytes > 2.0 * 1024 * 1024 * 1024)
        return gi_error_set(
            err, GI_ERR_INVALID_ARGUMENT,
            "vlf: l (N S)^2 = %.3g rays need %.1f GB of depth lists alone; lower l, N or S",
            ray_bytes / sizeof(uint32_t), ray_bytes / (1024.0 * 1024 * 1024));
    return GI_OK;
}

/* The VLF coordinates of scene s at time t: its bounds' centre and half
 * diagonal (a little more) make the unit sphere. */
static gi_result place_scene(vlf_field *f, const gi_scene *s, float t, gi_error *err)
{
    if (s->triangle_count == 0)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "vlf: the scene has no triangles");
    float b[6];
    gi_scene_bounds_at(s, t, b);
    f->centre = gi_v3(0.5f * (b[0] + b[3]), 0.5f * (b[1] + b[4]), 0.5f * (b[2] + b[5]));
    f->radius = 0.5f * sqrtf((b[3] - b[0]) * (b[3] - b[0]) + (b[4] - b[1]) * (b[4] - b[1]) +
                             (b[5] - b[2]) * (b[5] - b[2]));
    f->radius *= 1.001f;
    if (!(f->radius > 0.0f) || !isfinite(f->radius))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "vlf: the scene's bounds are empty or not finite");
    f->env = s->envmap;
    return GI_OK;
}

/* Each face's first element in the atlas, its index among the non-diffuse
 * faces and its emission normaliser; the per-element maps, the subfields
 * and the tile rectangles allocated. */
static gi_result lay_out_elements(vlf_field *f)
{
    uint32_t elems = 0, l = f->prm.l;
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        vlf_face *fc = &f->faces[fi];
        fc->first_elem = elems;
        elems += fc->W * fc->H;
        fc->nd = (fc->ks[0] > 0.0f || fc->ks[1] > 0.0f || fc->ks[2] > 0.0f) ? (int32_t)f->nd_count++
                                                                            : -1;
        /* Diffuse emission normalised so that the discrete directions carry
         * exactly pi L per unit area out of the face. */
        double sum = 0.0;
        for (uint32_t sd = 0; sd < 2 * l; sd++) {
            float c2 = gi_v3_dot(fc->n, f->dirs.signed_dirs[sd]);
            if (c2 > 0.0f)
                sum += c2 * f->dirs.solid_angle[sd];
        }
        fc->send_scale = sum > 0.0 ? (float)(GI_PI / sum) : 1.0f;
    }
    f->elem_count = elems;
    f->elem_face = malloc((size_t)elems * sizeof *f->elem_face);
    f->elem_area = calloc((size_t)elems, sizeof *f->elem_area);
    f->elem_c = calloc((size_t)elems * 2 + 2, sizeof *f->elem_c);
    f->E_tot = calloc((size_t)elems * 3, sizeof(float));
    f->E_next = calloc((size_t)elems * 3, sizeof(float));
    f->L_cur = calloc((size_t)elems * 3, sizeof(float));
    f->psf = calloc(l, sizeof *f->psf);
    f->rects = calloc((size_t)f->nd_count * l + 1, sizeof *f->rects);
    if (!f->elem_face || !f->elem_area || !f->elem_c || !f->E_tot || !f->E_next || !f->L_cur ||
        !f->psf || !f->rects)
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        vlf_face *fc = &f->faces[fi];
        for (uint32_t e = 0; e < fc->W * fc->H; e++)
            f->elem_face[fc->first_elem + e] = fi;
    }
    f->elem_kd = calloc((size_t)elems * 3 + 3, sizeof *f->elem_kd);
    return f->elem_kd ? GI_OK : GI_ERR_OUT_OF_MEMORY;
}

/* Each element's area on its face, the centroid of its part of the face
 * and its albedo (§3.1). */
static void element_values(vlf_field *f, const gi_scene *s)
{
    uint32_t elems = f->elem_count;
    vlf_element_areas(f, s);
    /* a back side's elements are its front's texels: the same areas,
     * centroids and (textured) albedo sums */
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        const vlf_face *fc = &f->faces[fi];
        if (!fc->back)
            continue;
        const vlf_face *fr = &f->faces[fc->twin];
        for (uint32_t e = 0; e < fc->W * fc->H; e++) {
            size_t d = fc->first_elem + e, o = fr->first_elem + e;
            f->elem_area[d] = f->elem_area[o];
            memcpy(f->elem_c + 2 * d, f->elem_c + 2 * o, 2 * sizeof *f->elem_c);
            memcpy(f->elem_kd + 3 * d, f->elem_kd + 3 * o, 3 * sizeof *f->elem_kd);
        }
    }
    /* each element's albedo: the material's, or on textured faces the
     * texture averaged over the element's part of the face */
    for (uint32_t e = 0; e < elems; e++) {
        const vlf_face *fc = &f->faces[f->elem_face[e]];
        for (int c = 0; c < 3; c++) {
            float *kd = &f->elem_kd[3 * (size_t)e + (size_t)c];
            *kd = fc->textured && f->elem_area[e] > 0.0f ? *kd / f->elem_area[e] : fc->kd[c];
        }
    }
    for (uint32_t e = 0; e < elems; e++) {
        if (f->elem_area[e] > 0.0f) {
            f->elem_c[2 * (size_t)e] /= f->elem_area[e];
            f->elem_c[2 * (size_t)e + 1] /= f->elem_area[e];
        }
    }
}

/* Tile storage offsets of the rectangles the sort recorded, then the
 * non-diffuse maps allocated. */
static gi_result allocate_tiles(vlf_field *f, gi_error *err)
{
    const vlf_settings *p = &f->prm;
    size_t cells = 0;
    uint32_t tiles = 0;
    for (size_t r = 0; r < (size_t)f->nd_count * p->l; r++) {
        f->rects[r].offset = (uint32_t)cells;
        cells += (size_t)f->rects[r].w * f->rects[r].h;
        tiles += f->rects[r].w * f->rects[r].h / (p->m * p->m);
    }
    if (cells > 0x7fffffffu)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "vlf: %zu non-diffuse cells do not fit (lower N or l)", cells);
    f->nd_cells = (uint32_t)cells;
    f->st.tiles = tiles;
    size_t nc = cells ? cells : 1;
    f->nd_cover = calloc(nc, 1);
    f->out_cur = calloc(nc * 3, sizeof(float));
    f->out_next = calloc(nc * 3, sizeof(float));
    f->out_tot = calloc(nc * 3, sizeof(float));
    f->in = calloc(nc * 3, sizeof(float));
    if (!f->nd_cover || !f->out_cur || !f->out_next || !f->out_tot || !f->in)
        return vlf_build_out_of_memory(f, err);
    return GI_OK;
}

/* Coverage of each stored tile cell: the cells some ray of the subfield
 * meets the face in. */
static void mark_coverage(vlf_field *f)
{
    const vlf_settings *p = &f->prm;
    for (uint32_t i = 0; i < p->l; i++) {
        const vlf_psf *ps = &f->psf[i];
        uint32_t NS = p->N * p->S;
        for (uint32_t c = 0; c < NS * NS; c++)
            for (uint32_t k = ps->cell_start[c]; k < ps->cell_start[c + 1]; k++) {
                const vlf_face *fc = &f->faces[f->elem_face[ps->frag[k]]];
                if (fc->nd >= 0)
                    f->nd_cover[vlf_rect_slot(&f->rects[(size_t)fc->nd * p->l + i], (c % NS) / p->S,
                                              (c / NS) / p->S)] = 1;
            }
    }
    uint32_t ndel = 0;
    for (size_t c = 0; c < f->nd_cells; c++)
        ndel += f->nd_cover[c];
    f->st.nondiffuse_elements = ndel;
}

/* Memory as the paper counts it: current, next and total ir/radiance
 * maps in the storage format for both kinds (and the incoming tiles),
 * plus the depth order; rendering keeps the totals and the tile index
 * only (vlf.c uploads exactly these maps). */
static void count_memory(vlf_field *f)
{
    const vlf_settings *p = &f->prm;
    size_t elems = f->elem_count, cells = f->nd_cells, frags = 0;
    for (uint32_t i = 0; i < p->l; i++)
        frags += f->psf[i].frag_count;
    f->st.diffuse_elements = f->elem_count;
    size_t bpv = vlf_precision_bytes(p->precision);
    f->st.bytes_maps_render = (elems + cells) * bpv;
    f->st.bytes_propagate =
        elems * bpv * 3 + cells * bpv * 4 + cells + frags * sizeof(uint32_t) +
        (size_t)p->l * ((size_t)p->N * p->S * p->N * p->S + 1) * sizeof(uint32_t);
    f->st.bytes_render = f->st.bytes_maps_render + (size_t)f->nd_count * p->l * sizeof(vlf_rect);
}

/* Whether the caller asked to stop (vlf_settings.cancelled). */
static int build_cancelled(const vlf_field *f)
{
    return f->prm.cancelled && f->prm.cancelled(f->prm.cancel_user);
}

gi_result vlf_field_build(vlf_field *f, const gi_scene *s, float t, const vlf_settings *p,
                          gi_error *err)
{
    memset(f, 0, sizeof *f);
    f->prm = *p;
    double t0 = vlf_now_s();
    gi_result rc = check_settings(p, err);
    if (rc == GI_OK)
        rc = vlf_dirs_build(&f->dirs, p->l, err);
    if (rc == GI_OK)
        rc = place_scene(f, s, t, err);
    if (rc == GI_OK)
        rc = vlf_add_lights(f, s, t, err);
    if (rc != GI_OK)
        return rc;
    if (build_cancelled(f))
        return gi_error_set(err, GI_ERR_CANCELLED, "vlf: build cancelled");
    rc = vlf_group_faces(f, s, t);
    if (rc == GI_ERR_CANCELLED)
        return gi_error_set(err, GI_ERR_CANCELLED, "vlf: build cancelled");
    if (rc != GI_OK || lay_out_elements(f) != GI_OK)
        return vlf_build_out_of_memory(f, err);
    if (build_cancelled(f))
        return gi_error_set(err, GI_ERR_CANCELLED, "vlf: build cancelled");
    element_values(f, s);
    if ((uint64_t)s->triangle_count * p->subdivide * p->subdivide > 50000000u)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "vlf: %u triangles cut into %u^2 each are too many", s->triangle_count,
                            p->subdivide);
    if (vlf_subdivide_triangles(f, p->subdivide < 1 ? 1 : p->subdivide) != GI_OK ||
        vlf_merge_faces(f) != GI_OK || vlf_build_subfields(f) != GI_OK)
        return build_cancelled(f) ? gi_error_set(err, GI_ERR_CANCELLED, "vlf: build cancelled")
                                  : vlf_build_out_of_memory(f, err);
    rc = allocate_tiles(f, err);
    if (rc != GI_OK)
        return rc;
    mark_coverage(f);
    count_memory(f);
    f->st.sort_s = vlf_now_s() - t0;
    return GI_OK;
}

void vlf_field_free(vlf_field *f)
{
    if (f->psf)
        for (uint32_t i = 0; i < f->prm.l; i++) {
            free(f->psf[i].cell_start);
            free(f->psf[i].frag);
            free(f->psf[i].rorder);
            free(f->psf[i].rextra);
        }
    free(f->psf);
    vlf_dirs_free(&f->dirs);
    free(f->faces);
    free(f->tri_face);
    if (f->sort_p != f->tri_p) {
        free(f->sort_p);
        free(f->sort_face);
        free(f->sort_group);
    }
    free(f->tri_group);
    free(f->tri_p);
    free(f->elem_face);
    free(f->elem_area);
    free(f->elem_kd);
    free(f->rects);
    free(f->nd_cover);
    free(f->E_tot);
    free(f->E_next);
    free(f->L_cur);
    free(f->out_cur);
    free(f->out_next);
    free(f->out_tot);
    free(f->in);
    free(f->sun);
    free(f->punctual);
    free(f->elem_c);
    if (f->rt)
        gi_rt_free(f->rt);
    memset(f, 0, sizeof *f);
}

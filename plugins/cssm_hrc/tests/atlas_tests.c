/* cssm_tests' parts on the illumination atlas of cssm_hrc (§3.2.3):
 *   traversal  every traversal visits every texel exactly once; zig-zag
 *              and spiral steps stay between neighbouring texels of a
 *              chart except at a stated few jumps
 *   texture    the textured albedo of the atlas texels */
#include "cssm_tests.h"

#include "check.h"

#include "gi/rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static void check_traversals(const cssm_atlas *a, const char *what)
{
    for (int how = 0; how < 3; how++) {
        uint32_t *order = cssm_traverse(a, (cssm_traversal)how);
        CHECK_MSG(order != NULL, "traverse");
        if (!order)
            return;
        unsigned char *seen = calloc(a->count, 1);
        uint32_t twice = 0, jumps = 0, chart_changes = 0;
        for (uint32_t k = 0; k < a->count; k++) {
            CHECK_MSG(order[k] < a->count, "texel index %u out of range", order[k]);
            if (order[k] >= a->count)
                break;
            twice += seen[order[k]];
            seen[order[k]] = 1;
            if (k == 0)
                continue;
            const cssm_texel *p = &a->texels[order[k - 1]], *q = &a->texels[order[k]];
            if (p->chart != q->chart) {
                chart_changes++;
                continue;
            }
            if (p->chart < 0)
                continue;
            int dx = abs((int)p->x - (int)q->x), dy = abs((int)p->y - (int)q->y);
            jumps += dx + dy != 1;
        }
        uint32_t missed = 0;
        for (uint32_t i = 0; i < a->count; i++)
            missed += !seen[i];
        CHECK_MSG(!twice && !missed, "%s %s: %u visited twice, %u missed", what,
                  cssm_traversal_name((cssm_traversal)how), twice, missed);
        printf("%s %-7s: %u texels, each once; %u steps leave the chart, %u in-chart steps are not "
               "to a "
               "4-neighbour\n",
               what, cssm_traversal_name((cssm_traversal)how), a->count, chart_changes, jumps);
        /* charts are visited one after the other: each is entered once */
        if (how != CSSM_GREEDY)
            CHECK_MSG(chart_changes <= a->chart_count, "%s: %u chart changes for %u charts", what,
                      chart_changes, a->chart_count);
        /* zig-zag jumps once per row at most (a row broken by a hole); spiral
         * only after stepping back */
        if (how == CSSM_ZIGZAG) {
            uint32_t rows = 0;
            for (uint32_t c = 0; c < a->chart_count; c++)
                rows += a->charts[c].h;
            CHECK_MSG(jumps <= rows, "zig-zag: %u jumps for %u rows", jumps, rows);
        }
        if (how == CSSM_SPIRAL)
            CHECK_MSG(jumps * 10 <= a->chart_texels,
                      "spiral: %u jumps for %u chart texels (more than 10 %%)", jumps,
                      a->chart_texels);
        free(seen);
        free(order);
    }
}

int cssm_test_traversal(void)
{
    const char *scenes[2] = {"scenes/cornell_box.gltf", "tests/data/conformance/furnace_050.gltf"};
    for (int k = 0; k < 2; k++) {
        gi_scene *s = cssm_test_load(scenes[k]);
        if (!s)
            return 1;
        for (uint32_t R = 16; R <= 64; R *= 2) {
            cssm_atlas a;
            gi_error err;
            gi_result r = cssm_atlas_build(s, 0.0f, R, 0, &a, &err);
            CHECK_MSG(r == GI_OK, "atlas: %s", err.text);
            if (r != GI_OK)
                continue;
            double texel_area = 0;
            for (uint32_t i = 0; i < a.count; i++)
                texel_area += a.texels[i].area;
            printf("%s atlas %u^2: %u texels (%u in %u charts, %u surface samples), coverage %.3f, "
                   "texel area / "
                   "surface area %.4f\n",
                   scenes[k], R, a.count, a.chart_texels, a.chart_count, a.count - a.chart_texels,
                   a.covered_area / a.surface_area, texel_area / a.surface_area);
            CHECK_MSG(fabs(texel_area / a.surface_area - 1.0) < 0.01,
                      "texel areas sum to %.4f of the surface", texel_area / a.surface_area);
            if (k == 0 && R >= 32)
                CHECK_MSG(a.chart_count >= 5 && a.chart_texels * 3 > 2 * a.count,
                          "Cornell box: %u charts, %u of %u texels", a.chart_count, a.chart_texels,
                          a.count);
            char what[64];
            snprintf(what, sizeof what, "%s %u^2", k ? "sphere" : "cornell", R);
            check_traversals(&a, what);
            cssm_atlas_free(&a);
            if (k == 0 && R == 32 && cssm_atlas_build(s, 0.0f, R, 1, &a, &err) == GI_OK) {
                /* no parametrisation: surface samples at the charts' density (the paper's greedy
                 * case) */
                printf("%s atlas %u^2, samples only: %u texels\n", scenes[k], R, a.count);
                CHECK_MSG(a.chart_count == 0 && a.count > 300, "samples only: %u charts, %u texels",
                          a.chart_count, a.count);
                check_traversals(&a, "cornell samples");
                cssm_atlas_free(&a);
            }
        }
        gi_scene_free(s);
    }
    return 0;
}

/* Textured albedo in the atlas: the checker ground of
 * scenes/teapot_plane.glb. Its texels carry the texture (both checker
 * colours appear), and their area-weighted mean albedo matches the mean
 * of the textured albedo at 20 000 random points of the same triangles
 * (uvs interpolated here) within 5 %, where the untextured factor is off
 * by more than 50 %. */
int cssm_test_texture(void)
{
    gi_scene *s = cssm_test_load("scenes/teapot_plane.glb");
    if (!s)
        return 1;
    gi_error err;
    cssm_atlas a;
    if (cssm_atlas_build(s, 0.0f, 32, 0, &a, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    double sum = 0.0, area = 0.0, factor = 0.0;
    float lo = 1e9f, hi = -1e9f;
    uint32_t textured = 0;
    for (uint32_t i = 0; i < a.count; i++) {
        const cssm_texel *x = &a.texels[i];
        const gi_material *m = &s->materials[s->vertices[s->indices[3 * x->triangle]].material];
        if (m->albedo_texture < 0)
            continue;
        textured++;
        sum += x->area * x->albedo[1];
        area += x->area;
        factor = m->albedo[1];
        lo = fminf(lo, x->albedo[1]), hi = fmaxf(hi, x->albedo[1]);
    }
    /* the same mean at random points of the textured triangles, by area */
    double ref = 0.0, ref_area = 0.0;
    uint32_t rng = gi_rng_init(5, 0, 0x7e7u);
    for (uint32_t tri = 0; tri < s->triangle_count; tri++) {
        const uint32_t *idx = &s->indices[3 * tri];
        const gi_material *m = &s->materials[s->vertices[idx[0]].material];
        if (m->albedo_texture < 0)
            continue;
        gi_vec3 p[3];
        gi_scene_triangle_world(s, tri, 0.0f, p);
        float A = 0.5f * gi_v3_length(gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0])));
        const int n = 20000 / 2; /* the ground is two triangles or more: points per triangle */
        double acc = 0.0;
        for (int k = 0; k < n; k++) {
            float u = gi_rng_next_float(&rng), v = gi_rng_next_float(&rng);
            if (u + v > 1.0f)
                u = 1.0f - u, v = 1.0f - v;
            float uv[2], al[3];
            for (int c = 0; c < 2; c++)
                uv[c] = (1.0f - u - v) * s->vertices[idx[0]].uv[c] + u * s->vertices[idx[1]].uv[c] +
                        v * s->vertices[idx[2]].uv[c];
            gi_scene_albedo(s, s->vertices[idx[0]].material, uv, al);
            acc += al[1];
        }
        ref += A * acc / n;
        ref_area += A;
    }
    double mean = area > 0 ? sum / area : 0.0, want = ref_area > 0 ? ref / ref_area : 0.0;
    printf("texture: %u textured texels, albedo (green) %.3f .. %.3f, area mean %.4f; random "
           "points %.4f (%+.2f %%); "
           "the untextured factor %.3f (%+.1f %%)\n",
           textured, lo, hi, mean, want, 100.0 * (mean / want - 1.0), factor,
           100.0 * (factor / want - 1.0));
    CHECK_MSG(textured >= 100, "only %u textured texels", textured);
    CHECK_MSG(hi > lo + 0.2f, "the checker does not show in the atlas (%.3f .. %.3f)", lo, hi);
    CHECK_MSG(fabs(mean / want - 1.0) <= 0.05, "mean textured albedo %.4f, random points %.4f",
              mean, want);
    CHECK_MSG(fabs(factor / want - 1.0) > 0.5,
              "the test cannot tell: the factor is near the textured mean");
    cssm_atlas_free(&a);
    gi_scene_free(s);
    return 0;
}

/* Independent CPU evaluation of unshadowed direct light, to check the
 * `direct` plugin end to end.
 *
 * Primary visibility by brute-force ray casting through pixel centres (no
 * rasteriser), and direct light from each emissive triangle by Lambert's
 * closed-form polygon irradiance, E = L/2 sum_i theta_i (gamma_i . N), with
 * the triangle clipped to the receiver's upper hemisphere. No sampling, so
 * the only thing shared with the GPU path is the scene file. Lambertian
 * scenes only (a Phong lobe has no closed form here).
 *
 *   direct_reference SCENE WIDTH HEIGHT IMAGE.exr TOLERANCE
 * compares the mean RGB of IMAGE (rendered by gibench at that size) with
 * the reference mean and exits 1 when a channel differs by more than
 * TOLERANCE (relative). */
#include "gi/image.h"
#include "gi/scene.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct world_tri {
    gi_vec3 p[3], n[3];
    float uv[3][2];
    uint32_t material;
    gi_vec3 ng; /* unit geometric normal, CCW */
} world_tri;

static int intersect(const world_tri *t, gi_vec3 o, gi_vec3 d, float *dist, float *bu, float *bv)
{
    gi_vec3 e1 = gi_v3_sub(t->p[1], t->p[0]), e2 = gi_v3_sub(t->p[2], t->p[0]);
    gi_vec3 pv = gi_v3_cross(d, e2);
    float det = gi_v3_dot(e1, pv);
    if (fabsf(det) < 1e-12f)
        return 0;
    float inv = 1.0f / det;
    gi_vec3 tv = gi_v3_sub(o, t->p[0]);
    float u = gi_v3_dot(tv, pv) * inv;
    if (u < 0.0f || u > 1.0f)
        return 0;
    gi_vec3 qv = gi_v3_cross(tv, e1);
    float v = gi_v3_dot(d, qv) * inv;
    if (v < 0.0f || u + v > 1.0f)
        return 0;
    float h = gi_v3_dot(e2, qv) * inv;
    if (h <= 1e-6f || h >= *dist)
        return 0;
    *dist = h;
    *bu = u;
    *bv = v;
    return 1;
}

/* Irradiance at x (normal N) from a polygon of unit radiance: Lambert's
 * formula over the polygon clipped to the plane through x with normal N. */
static double polygon_irradiance(gi_vec3 x, gi_vec3 N, const gi_vec3 *poly, int n)
{
    gi_vec3 v[8];
    int m = 0;
    for (int i = 0; i < n; i++) { /* Sutherland-Hodgman against N.(p - x) >= 0 */
        gi_vec3 a = gi_v3_sub(poly[i], x), b = gi_v3_sub(poly[(i + 1) % n], x);
        float da = gi_v3_dot(a, N), db = gi_v3_dot(b, N);
        if (da >= 0)
            v[m++] = a;
        if ((da >= 0) != (db >= 0)) {
            float t = da / (da - db);
            v[m++] = gi_v3_add(a, gi_v3_scale(gi_v3_sub(b, a), t));
        }
    }
    if (m < 3)
        return 0.0;
    double sum = 0.0;
    for (int i = 0; i < m; i++) {
        gi_vec3 a = gi_v3_normalize(v[i]), b = gi_v3_normalize(v[(i + 1) % m]);
        double c = gi_v3_dot(a, b);
        c = c > 1 ? 1 : (c < -1 ? -1 : c);
        gi_vec3 g = gi_v3_cross(a, b);
        float gl = gi_v3_length(g);
        if (gl < 1e-12f)
            continue;
        sum += acos(c) * gi_v3_dot(gi_v3_scale(g, 1.0f / gl), N);
    }
    return 0.5 * fabs(sum);
}

int main(int argc, char **argv)
{
    if (argc != 6) {
        fprintf(stderr, "usage: direct_reference SCENE WIDTH HEIGHT IMAGE.exr TOLERANCE\n");
        return 2;
    }
    gi_error err;
    gi_scene *s = gi_scene_load(argv[1], &err);
    if (!s) {
        fprintf(stderr, "%s\n", err.text);
        return 2;
    }
    uint32_t W = (uint32_t)atoi(argv[2]), H = (uint32_t)atoi(argv[3]);
    double tol = atof(argv[5]);
    for (uint32_t i = 0; i < s->material_count; i++)
        if (s->materials[i].ks[0] + s->materials[i].ks[1] + s->materials[i].ks[2] > 0 &&
            !s->materials[i].mirror) {
            fprintf(stderr, "direct_reference: material %u is glossy; Lambertian scenes only\n", i);
            return 2;
        }
    world_tri *tris = calloc(s->triangle_count, sizeof *tris);
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const gi_vertex *v0 = &s->vertices[s->indices[3 * t]];
        float m[16], nm[16], inv[16];
        gi_scene_object_transform(s, v0->object, 0.0f, m);
        gi_mat4_invert(inv, m);
        gi_mat4_transpose(nm, inv);
        for (int k = 0; k < 3; k++) {
            const gi_vertex *v = &s->vertices[s->indices[3 * t + (uint32_t)k]];
            tris[t].p[k] = gi_mat4_point(m, gi_v3_load(v->position));
            tris[t].n[k] = gi_v3_normalize(gi_mat4_dir(nm, gi_v3_load(v->normal)));
            memcpy(tris[t].uv[k], v->uv, sizeof v->uv);
        }
        tris[t].material = v0->material;
        tris[t].ng = gi_v3_normalize(gi_v3_cross(gi_v3_sub(tris[t].p[1], tris[t].p[0]),
                                                 gi_v3_sub(tris[t].p[2], tris[t].p[0])));
    }
    gi_camera_frame cam = gi_scene_camera_at(s, s->camera_count ? 0 : -1, 0.0f);
    float aspect = (float)W / (float)H, th = tanf(cam.yfov * 0.5f);
    gi_vec3 right = gi_v3_normalize(gi_v3_cross(cam.forward, cam.up));
    gi_vec3 up = gi_v3_cross(right, cam.forward);
    double sum[3] = {0, 0, 0};
    for (uint32_t row = 0; row < H; row++)
        for (uint32_t col = 0; col < W; col++) {
            /* Image row 0 is the top of the picture. */
            float sx = ((col + 0.5f) / W * 2.0f - 1.0f) * th * aspect;
            float sy = (1.0f - (row + 0.5f) / H * 2.0f) * th;
            gi_vec3 d = gi_v3_normalize(
                gi_v3_add(cam.forward, gi_v3_add(gi_v3_scale(right, sx), gi_v3_scale(up, sy))));
            float best = FLT_MAX, bu = 0, bv = 0, u, v;
            int hit = -1;
            for (uint32_t t = 0; t < s->triangle_count; t++)
                if (intersect(&tris[t], cam.eye, d, &best, &u, &v)) {
                    hit = (int)t;
                    bu = u;
                    bv = v;
                }
            if (hit < 0)
                continue;
            const world_tri *t = &tris[hit];
            const gi_material *mat = &s->materials[t->material];
            gi_vec3 x = gi_v3_add(cam.eye, gi_v3_scale(d, best));
            float bw = 1.0f - bu - bv;
            gi_vec3 N = gi_v3_normalize(
                gi_v3_add(gi_v3_scale(t->n[0], bw),
                          gi_v3_add(gi_v3_scale(t->n[1], bu), gi_v3_scale(t->n[2], bv))));
            if (gi_v3_dot(N, d) > 0)
                N = gi_v3_scale(N, -1.0f);
            float L[3] = {0, 0, 0};
            if (mat->double_sided || gi_v3_dot(t->ng, d) < 0)
                memcpy(L, mat->emission, sizeof L);
            float uv[2] = {bw * t->uv[0][0] + bu * t->uv[1][0] + bv * t->uv[2][0],
                           bw * t->uv[0][1] + bu * t->uv[1][1] + bv * t->uv[2][1]};
            float albedo[3];
            gi_scene_albedo(s, t->material, uv, albedo);
            if (mat->mirror)
                albedo[0] = albedo[1] = albedo[2] = 0.0f;
            for (uint32_t e = 0; e < s->emitter_count; e++) {
                const world_tri *lt = &tris[s->emitters[e]];
                const gi_material *lm = &s->materials[lt->material];
                /* One-sided emitters light only what lies in front of them. */
                if (!lm->double_sided && gi_v3_dot(lt->ng, gi_v3_sub(x, lt->p[0])) <= 0)
                    continue;
                double E = polygon_irradiance(x, N, lt->p, 3);
                for (int c = 0; c < 3; c++)
                    L[c] += (float)(albedo[c] * GI_INV_PI * lm->emission[c] * E);
            }
            for (int c = 0; c < 3; c++)
                sum[c] += L[c];
        }
    double ref[3];
    for (int c = 0; c < 3; c++)
        ref[c] = sum[c] / ((double)W * H);
    gi_image *img = gi_image_read(argv[4], &err);
    if (!img) {
        fprintf(stderr, "%s\n", err.text);
        return 2;
    }
    int fail = img->width != W || img->height != H || gi_image_count_nonfinite(img) != 0;
    double mean[4];
    gi_image_mean(img, mean);
    for (int c = 0; c < 3; c++) {
        double rel = fabs(mean[c] - ref[c]) / ref[c];
        printf("channel %d: gibench %.6f reference %.6f relative difference %.4f%%\n", c, mean[c],
               ref[c], 100.0 * rel);
        fail |= !(rel <= tol);
    }
    gi_image_free(img);
    free(tris);
    gi_scene_free(s);
    printf("%s\n", fail ? "FAIL" : "ok");
    return fail;
}

/* The csm plugin's CPU side against exact ray casting on the bunny:
 *  - precompute the bunny's CSM (N = 8 x 8 directions, M = 64) on the GL
 *    context with the plugin's own code (plugins/csm/precompute.c);
 *  - lossless on real maps: re-render maps and check z1 <= z_avg < z2 for
 *    every texel (z_avg == z1 on degenerate texels);
 *  - visibility of random point-direction pairs around the bunny (points
 *    inside the mesh left out): the nearest-filter CSM query against brute
 *    force ray casting along the query direction w, and along the snapped
 *    map direction (which isolates the depth/codec path from the angular
 *    discretisation of §4.5). */
#include "../../plugins/csm/csm_cpu.h"

#include "gi/mesh.h"
#include "gi/rng.h"
#include "gi/sampling.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures;
#define EXPECT(cond, ...)                                                                                              \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            failures++;                                                                                                \
            fprintf(stderr, "%s:%d: failed: %s: ", __FILE__, __LINE__, #cond);                                       \
            fprintf(stderr, __VA_ARGS__);                                                                              \
            fputc('\n', stderr);                                                                                       \
        }                                                                                                              \
    } while (0)

/* Number of hits of the ray o + h d, h > 0, with object k (local space). */
static int hits(const gi_scene *s, uint32_t k, gi_vec3 o, gi_vec3 d)
{
    const gi_object *ob = &s->objects[k];
    int n = 0;
    for (uint32_t t = ob->first_triangle; t < ob->first_triangle + ob->triangle_count; t++) {
        const float *q0 = s->vertices[s->indices[3 * t]].position, *q1 = s->vertices[s->indices[3 * t + 1]].position,
                    *q2 = s->vertices[s->indices[3 * t + 2]].position;
        gi_vec3 p0 = gi_v3(q0[0], q0[1], q0[2]);
        gi_vec3 e1 = gi_v3_sub(gi_v3(q1[0], q1[1], q1[2]), p0), e2 = gi_v3_sub(gi_v3(q2[0], q2[1], q2[2]), p0);
        gi_vec3 pv = gi_v3_cross(d, e2);
        float det = gi_v3_dot(e1, pv);
        if (fabsf(det) < 1e-14f)
            continue;
        gi_vec3 tv = gi_v3_sub(o, p0);
        float u = gi_v3_dot(tv, pv) / det;
        gi_vec3 qv = gi_v3_cross(tv, e1);
        float v = gi_v3_dot(d, qv) / det;
        float h = gi_v3_dot(e2, qv) / det;
        n += u >= 0 && v >= 0 && u + v <= 1 && h > 0;
    }
    return n;
}

int main(void)
{
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    if (!gpu) {
        fprintf(stderr, "no GL: %s\n", err.text);
        return 1;
    }
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/bunny_env.glb", &err);
    if (!s) {
        fprintf(stderr, "%s\n", err.text);
        return 1;
    }
    gi_gpu_scene *gs = gi_gpu_scene_upload(gpu, s, &err);
    uint32_t k = 0;
    while (k < s->object_count && strcmp(s->objects[k].name, "bunny") != 0)
        k++;
    if (!gs || k == s->object_count) {
        fprintf(stderr, "no bunny object / upload failed\n");
        return 1;
    }
    float sphere[4];
    gi_mesh_object_sphere(s, k, sphere);
    const uint32_t N = 8, M = 64;
    csm_build_desc desc = {.M = M, .n_theta = N, .n_phi = N, .order = GI_CSM_ORDER_HILBERT, .z3 = 0, .batch = 16};
    gi_csm_data data;
    EXPECT(csm_build_object(gs, k, sphere, &desc, NULL, 0, 1, &data, &err) == GI_OK, "%s", err.text);
    printf("bunny: R = %.4f, %u maps of %u^2: %.2f segments per texel, %.2f : 1\n", (double)sphere[3], N * N, M,
           (double)data.segment_count / (M * M), (double)data.bytes_uncompressed / (double)data.bytes_compressed);

    /* Lossless on real maps. */
    gi_depth_desc dd = {.size = M, .surfaces = 2, .metric = GI_DEPTH_EYE_Z, .object = (int)k, .local = 1};
    gi_depth_renderer *dr = gi_depth_renderer_create(&dd, &err);
    GLuint tex = gi_depth_texture_create(dr, 1);
    uint64_t bad = 0, checked = 0, degenerate = 0;
    for (uint32_t i = 0; i < N * N; i += 3) {
        uint32_t a, b;
        float theta, phi;
        gi_csm_order_cell(desc.order, N, N, i, &a, &b);
        csm_cell_angles(N, N, a, b, &theta, &phi);
        gi_depth_view v;
        csm_map_view(sphere, theta, phi, &v);
        EXPECT(gi_depth_render(dr, gs, &v, 1, tex, 0, &err) == GI_OK, "%s", err.text);
        float *map = gi_depth_read_layer(tex, M, 0);
        for (uint32_t t = 0; t < M * M; t++) {
            float z1 = map[4 * t], z2 = map[4 * t + 1], z = gi_csm_lookup(&data, t, i);
            int deg = z1 == z2 && z1 < FLT_MAX;
            degenerate += deg;
            int ok = z >= z1 && (z2 >= FLT_MAX || z < z2 || (deg && z == z1));
            bad += !ok;
            checked++;
        }
        free(map);
    }
    printf("lossless: %llu of %llu texels violate z1 <= z_avg < z2 (%llu degenerate)\n", (unsigned long long)bad,
           (unsigned long long)checked, (unsigned long long)degenerate);
    EXPECT(bad == 0, "%llu texels", (unsigned long long)bad);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);

    /* Visibility against ray casting. */
    uint32_t rng = gi_rng_init(7, 0, 1);
    gi_vec3 c = gi_v3(sphere[0], sphere[1], sphere[2]);
    float R = sphere[3], bias = 0.01f * R;
    int pairs = 0, agree = 0, agree_snapped = 0, shadowed = 0, inside = 0;
    while (pairs < 2000) {
        gi_vec3 x = gi_v3_add(c, gi_v3_scale(gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng)),
                                             1.5f * R * cbrtf(gi_rng_next_float(&rng))));
        gi_vec3 w = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
        int hw = hits(s, k, x, w);
        if ((hw & 1) && (hits(s, k, x, gi_v3_scale(w, -1)) & 1)) {
            inside++;
            continue;
        }
        pairs++;
        int exact = hw == 0;
        int lit = csm_visible_nearest(&data, sphere, N, N, desc.order, x, w, bias);
        float u, v, theta, phi;
        csm_grid_coords(w, N, N, &u, &v);
        int bi = (int)floorf(v + 0.5f);
        csm_cell_angles(N, N, (uint32_t)floorf(u + 0.5f) % N, (uint32_t)(bi < 0 ? 0 : bi >= (int)N ? (int)N - 1 : bi),
                        &theta, &phi);
        int exact_snapped = hits(s, k, x, csm_dir(theta, phi)) == 0;
        shadowed += !exact;
        agree += lit == exact;
        agree_snapped += lit == exact_snapped;
    }
    printf("visibility, %d pairs (%d shadowed, %d inside points skipped): %.1f%% agree with rays along w, "
           "%.1f%% with rays along the snapped map direction\n",
           pairs, shadowed, inside, 100.0 * agree / pairs, 100.0 * agree_snapped / pairs);
    EXPECT(agree >= pairs * 90 / 100, "%d of %d", agree, pairs);
    EXPECT(agree_snapped >= pairs * 97 / 100, "%d of %d", agree_snapped, pairs);
    EXPECT(shadowed > pairs / 20, "too few shadowed pairs to mean anything: %d", shadowed);

    gi_csm_data_free(&data);
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
    printf("%s\n", failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}

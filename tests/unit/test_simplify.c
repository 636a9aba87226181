/* Lower-detail copies of the scene (gi/algo/simplify.h, meshoptimizer):
 *   - ratio 1 copies the scene's triangles unchanged;
 *   - the bunny (one closed object) drops to the target triangle count
 *     within 10 % at ratios 0.5, 0.25 and 0.1 (a generous error bound, so
 *     the count alone decides), keeps its bounding box within twice the
 *     reported relative error of its extent, and keeps its surface area
 *     within 5 %;
 *   - the tessellated Cornell box (flat 32 x 32 walls) loses most of its
 *     triangles at a tight error bound (1e-3) with its area kept within 1 %
 *     and its bounds exact;
 *   - every index stays inside its object's vertices, no triangle is
 *     degenerate in index terms;
 *   - the deforming box: vertices merged only where their morph
 *     displacements agree too, so the simplified short block at t = 2
 *     still spans the deformed block's bounds;
 *   - bad ratios and error bounds are refused with a message;
 *   - on the GPU, a depth atlas drawn from the ratio-1 copy equals the one
 *     drawn from the scene, texel for texel; perspective maps drawn from
 *     the ratio-0.25 copy differ in few texels (< 2 %), paraboloid maps in
 *     many (their warp bends the copy's long edges). */
#include "check.h"
#include "gpu_fixture.h"

#include "gi/mesh.h"
#include "gi/passes.h"
#include "gi/algo/simplify.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

static gi_scene *load(const char *path)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    return s;
}

/* World bounds and area at time t of object o's triangles in m (or the
 * scene's own when m is NULL). */
static double object_measure(const gi_scene *s, const gi_simplified *m, uint32_t o, float t,
                             float box[6])
{
    const gi_object *ob = &s->objects[o];
    gi_vertex *v = malloc((size_t)ob->vertex_count * sizeof *v);
    gi_scene_object_vertices(s, o, t, v);
    for (int a = 0; a < 3; a++) {
        box[a] = FLT_MAX;
        box[3 + a] = -FLT_MAX;
    }
    uint32_t first = m ? m->object_first[o] : ob->first_triangle,
             count = m ? m->object_count[o] : ob->triangle_count;
    const uint32_t *idx = m ? m->indices : s->indices;
    double area = 0.0;
    for (uint32_t tri = first; tri < first + count; tri++) {
        gi_vec3 p[3];
        for (int k = 0; k < 3; k++) {
            p[k] = gi_v3_load(v[idx[3 * (size_t)tri + k] - ob->first_vertex].position);
            for (int a = 0; a < 3; a++) {
                box[a] = fminf(box[a], (&p[k].x)[a]);
                box[3 + a] = fmaxf(box[3 + a], (&p[k].x)[a]);
            }
        }
        area += 0.5 * gi_v3_length(gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0])));
    }
    free(v);
    return area;
}

/* Every index of object o's simplified triangles lies in its vertex range,
 * and no triangle repeats an index. */
static int indices_valid(const gi_scene *s, const gi_simplified *m)
{
    int bad = 0;
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *ob = &s->objects[o];
        for (uint32_t tri = m->object_first[o]; tri < m->object_first[o] + m->object_count[o];
             tri++) {
            const uint32_t *t = &m->indices[3 * (size_t)tri];
            for (int k = 0; k < 3; k++)
                bad += t[k] < ob->first_vertex || t[k] >= ob->first_vertex + ob->vertex_count;
            bad += t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
        }
    }
    return bad == 0;
}

static void test_identity(const gi_scene *s)
{
    gi_error err;
    gi_simplified *m = gi_simplify_scene(s, 1.0f, 0.0f, &err);
    CHECK_MSG(m != NULL, "%s", err.text);
    if (!m)
        return;
    CHECK(m->triangle_count == s->triangle_count);
    CHECK(memcmp(m->indices, s->indices, (size_t)s->triangle_count * 3 * sizeof *m->indices) == 0);
    gi_simplified_free(m);
}

static void test_bunny(void)
{
    gi_scene *s = load(GI_SOURCE_DIR "/scenes/bunny_alone_env.glb");
    if (!s)
        return;
    CHECK(s->object_count == 1);
    test_identity(s);
    float box0[6];
    double area0 = object_measure(s, NULL, 0, 0.0f, box0);
    float ext = fmaxf(box0[3] - box0[0], fmaxf(box0[4] - box0[1], box0[5] - box0[2]));
    const float ratios[] = {0.5f, 0.25f, 0.1f};
    for (int i = 0; i < 3; i++) {
        gi_error err;
        gi_simplified *m = gi_simplify_scene(s, ratios[i], 1.0f, &err);
        CHECK_MSG(m != NULL, "%s", err.text);
        if (!m)
            continue;
        double target = ceil((double)ratios[i] * s->triangle_count);
        float box[6];
        double area = object_measure(s, m, 0, 0.0f, box);
        float worst = 0.0f;
        for (int a = 0; a < 6; a++)
            worst = fmaxf(worst, fabsf(box[a] - box0[a]));
        printf("bunny ratio %.2f: %u of %u triangles (target %.0f), meshopt error %.4f, bounds "
               "moved by %.4f of "
               "the extent, area %.4f of the original\n",
               (double)ratios[i], m->triangle_count, s->triangle_count, target,
               (double)m->max_error, (double)(worst / ext), area / area0);
        CHECK_MSG(m->triangle_count <= target && m->triangle_count >= 0.9 * target,
                  "%u triangles, target %.0f", m->triangle_count, target);
        CHECK_MSG(worst <= 2.0f * m->max_error * ext + 1e-6f * ext,
                  "bounds moved by %g, error %g x extent %g", (double)worst, (double)m->max_error,
                  (double)ext);
        CHECK_MSG(fabs(area / area0 - 1.0) < 0.05, "area ratio %.4f", area / area0);
        CHECK(indices_valid(s, m));
        gi_simplified_free(m);
    }
    gi_scene_free(s);
}

static void test_cornell(void)
{
    gi_scene *s = load(GI_SOURCE_DIR "/scenes/cornell_box.gltf");
    if (!s)
        return;
    test_identity(s);
    gi_error err;
    gi_simplified *m = gi_simplify_scene(s, 0.01f, 1e-3f, &err);
    CHECK_MSG(m != NULL, "%s", err.text);
    if (m) {
        double a0 = 0.0, a1 = 0.0;
        float worst = 0.0f;
        for (uint32_t o = 0; o < s->object_count; o++) {
            float b0[6], b1[6];
            a0 += object_measure(s, NULL, o, 0.0f, b0);
            a1 += object_measure(s, m, o, 0.0f, b1);
            for (int a = 0; a < 6; a++)
                worst = fmaxf(worst, fabsf(b1[a] - b0[a]));
        }
        printf("cornell ratio 0.01, error 1e-3: %u of %u triangles, meshopt error %.2g, area %.5f "
               "of the original, "
               "bounds moved by %g\n",
               m->triangle_count, s->triangle_count, (double)m->max_error, a1 / a0, (double)worst);
        CHECK_MSG(m->triangle_count * 4 < s->triangle_count, "only down to %u of %u",
                  m->triangle_count, s->triangle_count);
        CHECK_MSG(fabs(a1 / a0 - 1.0) < 0.01, "area ratio %.5f", a1 / a0);
        CHECK(worst < 1e-5f);
        CHECK(m->max_error <= 1e-3f);
        CHECK(indices_valid(s, m));
        gi_simplified_free(m);
    }
    /* Refusals. */
    CHECK(gi_simplify_scene(s, 0.0f, 0.01f, &err) == NULL && strstr(err.text, "ratio") != NULL);
    CHECK(gi_simplify_scene(s, 1.5f, 0.01f, &err) == NULL);
    CHECK(gi_simplify_scene(s, NAN, 0.01f, &err) == NULL);
    CHECK(gi_simplify_scene(s, 0.5f, -1.0f, &err) == NULL);
    gi_scene_free(s);
}

/* The short block of cornell_deform morphs: its simplified copy, evaluated
 * at t = 2 through the same vertices, spans the deformed block. */
static void test_deform(void)
{
    gi_scene *s = load(GI_SOURCE_DIR "/scenes/cornell_deform.gltf");
    if (!s)
        return;
    gi_error err;
    gi_simplified *m = gi_simplify_scene(s, 0.25f, 0.01f, &err);
    CHECK_MSG(m != NULL, "%s", err.text);
    int morphing = 0;
    for (uint32_t o = 0; m && o < s->object_count; o++) {
        if (!s->objects[o].morph_count)
            continue;
        morphing++;
        float b0[6], b1[6];
        object_measure(s, NULL, o, 2.0f, b0);
        object_measure(s, m, o, 2.0f, b1);
        float ext = fmaxf(b0[3] - b0[0], fmaxf(b0[4] - b0[1], b0[5] - b0[2])), worst = 0.0f;
        for (int a = 0; a < 6; a++)
            worst = fmaxf(worst, fabsf(b1[a] - b0[a]));
        printf(
            "deform object %u at t = 2: %u of %u triangles, bounds moved by %.4f of the extent\n",
            o, m->object_count[o], s->objects[o].triangle_count, (double)(worst / ext));
        CHECK(m->object_count[o] < s->objects[o].triangle_count);
        CHECK_MSG(worst <= 0.02f * ext, "bounds moved by %g of %g", (double)worst, (double)ext);
    }
    CHECK(morphing > 0);
    if (m)
        CHECK(indices_valid(s, m));
    gi_simplified_free(m);
    gi_scene_free(s);
}

/* GPU: depth atlases drawn from a copy, four maps each. The paraboloid
 * warp bends straight edges, so the large triangles of a simplified copy
 * are drawn wrongly there (the paper's reason for perspective maps with
 * large triangles, Sec. IV): that is measured and must be large, and the
 * perspective maps of the copy must be close to the scene's. */
static void atlas_case(gi_gpu_scene *gs, gi_projection proj, const gi_simplified *full,
                       const gi_simplified *low, size_t *differ_full, size_t *differ_low)
{
    gi_error err;
    gi_depth_atlas_desc d = {32, 4, proj, GI_DEPTH_RADIAL, 0, 0};
    gi_depth_atlas *a = gi_depth_atlas_create(&d, &err);
    CHECK_MSG(a != NULL, "%s", err.text);
    if (!a)
        return;
    gi_depth_view views[4];
    const float eyes[4][3] = {{0, 1.9f, 0}, {0.5f, 1, 0.5f}, {-0.9f, 0.2f, 0}, {0, 0.1f, 0.9f}};
    const float dirs[4][3] = {{0, -1, 0}, {-1, 0, 0}, {1, 0, 0}, {0, 0, -1}};
    for (int i = 0; i < 4; i++) {
        gi_vec3 eye = gi_v3_load(eyes[i]), n = gi_v3_load(dirs[i]);
        gi_vec3 up = fabsf(n.y) < 0.9f ? gi_v3(0, 1, 0) : gi_v3(1, 0, 0);
        gi_mat4_look_at(views[i].view, eye, gi_v3_add(eye, n), up);
        gi_mat4_perspective(views[i].proj, 120.0f * GI_PI / 180.0f, 1.0f, 1e-3f, 10.0f);
        views[i].projection = proj;
        views[i].znear = 0.0f;
        views[i].zfar = 10.0f;
    }
    float *tiles[3][4] = {{NULL}};
    const gi_simplified *geo[3] = {NULL, full, low};
    for (int g = 0; g < 3; g++) {
        gi_depth_atlas_set_geometry(a, geo[g] ? geo[g]->ibo : 0,
                                    geo[g] ? geo[g]->triangle_count : 0);
        CHECK_MSG(gi_depth_atlas_render(a, gs, views, 4, &err) == GI_OK, "%s", err.text);
        for (int i = 0; i < 4; i++)
            tiles[g][i] = gi_depth_atlas_read_tile(a, (uint32_t)i);
    }
    *differ_full = *differ_low = 0;
    for (int i = 0; i < 4; i++)
        for (int t = 0; t < 32 * 32; t++) {
            *differ_full += tiles[0][i][t] != tiles[1][i][t];
            *differ_low +=
                fabsf(tiles[0][i][t] - tiles[2][i][t]) > 0.02f * fmaxf(1.0f, tiles[0][i][t]);
        }
    for (int g = 0; g < 3; g++)
        for (int i = 0; i < 4; i++)
            free(tiles[g][i]);
    gi_depth_atlas_free(a);
}

static void test_atlas(void)
{
    gi_gpu *gpu;
    gi_scene *s;
    gi_gpu_scene *gs;
    if (!gpu_fixture_load(GI_SOURCE_DIR "/scenes/cornell_moving.gltf", &gpu, &s, &gs) || !gs) {
        CHECK_MSG(0, "no GL context or scene");
        return;
    }
    gi_error err;
    gi_simplified *full = gi_simplify_scene(s, 1.0f, 0.0f, &err),
                  *low = gi_simplify_scene(s, 0.25f, 0.01f, &err);
    CHECK(full && low);
    if (full && low && gi_simplified_upload(full, &err) == GI_OK &&
        gi_simplified_upload(low, &err) == GI_OK) {
        size_t texels = 4 * 32 * 32, pf, pl, qf, ql;
        atlas_case(gs, GI_PROJ_PERSPECTIVE, full, low, &pf, &pl);
        atlas_case(gs, GI_PROJ_PARABOLOID, full, low, &qf, &ql);
        printf("atlas (%u of %u triangles at ratio 0.25), texels of %zu differing by more than 2 "
               "%%: perspective "
               "ratio 1 %zu, ratio 0.25 %zu; paraboloid ratio 1 %zu, ratio 0.25 %zu\n",
               low->triangle_count, s->triangle_count, texels, pf, pl, qf, ql);
        CHECK(pf == 0 && qf == 0);
        CHECK_MSG(pl * 50 < texels, "perspective: %zu of %zu texels differ", pl, texels);
        CHECK_MSG(ql > 2 * pl, "paraboloid: %zu texels differ, perspective %zu", ql, pl);
    }
    gi_simplified_free(full);
    gi_simplified_free(low);
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
}

int main(void)
{
    test_bunny();
    test_cornell();
    test_deform();
    test_atlas();
    return gi_test_finish();
}

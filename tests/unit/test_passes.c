/* The core's passes against CPU ray casting on the same scene: G-buffer
 * (ids, depth, normal, albedo) and peeled depth maps (orthographic,
 * perspective cube faces, paraboloid; first, second and third surface). */
#include "check.h"
#include "gpu_fixture.h"
#include "gi/gpu.h"
#include "gi/passes.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* All hit distances along a ray, sorted, up to max: the surfaces the one
 * rule for sides leaves (single-sided triangles seen from the front). */
static int cast_all(const gi_scene *s, gi_vec3 o, gi_vec3 d, float *out, int max,
                    uint32_t *first_tri)
{
    int n = 0;
    float best = FLT_MAX;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        gi_vec3 p[3];
        gi_scene_triangle_world(s, t, 0.0f, p);
        gi_vec3 e1 = gi_v3_sub(p[1], p[0]), e2 = gi_v3_sub(p[2], p[0]);
        gi_vec3 pv = gi_v3_cross(d, e2);
        float det = gi_v3_dot(e1, pv);
        if (fabsf(det) < 1e-12f)
            continue;
        /* The one rule for sides (gi/scene.h): det > 0 is the front (d
         * against cross(e1, e2)); a single-sided back face is no surface. */
        if (det < 0.0f && !s->materials[s->vertices[s->indices[3 * t]].material].double_sided)
            continue;
        gi_vec3 tv = gi_v3_sub(o, p[0]);
        float u = gi_v3_dot(tv, pv) / det;
        gi_vec3 qv = gi_v3_cross(tv, e1);
        float v = gi_v3_dot(d, qv) / det;
        float h = gi_v3_dot(e2, qv) / det;
        if (u < 0 || v < 0 || u + v > 1 || h <= 0)
            continue;
        if (h < best) {
            best = h;
            if (first_tri)
                *first_tri = t;
        }
        /* insert sorted, dropping near-duplicates (shared edges) */
        int dup = 0;
        for (int i = 0; i < n; i++)
            dup |= fabsf(out[i] - h) < 1e-4f * (1 + h);
        if (dup || n == max)
            continue;
        int i = n++;
        while (i > 0 && out[i - 1] > h) {
            out[i] = out[i - 1];
            i--;
        }
        out[i] = h;
    }
    return n;
}

/* Compares depth-map texels with CPU casts; returns the fraction that agree
 * within tol (relative). Texels near silhouettes may legitimately differ. */
static float compare_map(const gi_scene *s, const float *map, uint32_t size, int surfaces,
                         const float view[16], int projection, const float proj_inv_scale[2],
                         float tol, int metric_radial)
{
    float inv[16];
    gi_mat4_invert(inv, view);
    int agree = 0, total = 0;
    for (uint32_t y = 2; y < size; y += 5)
        for (uint32_t x = 2; x < size; x += 5) {
            float sx = (x + 0.5f) / size * 2 - 1, sy = (y + 0.5f) / size * 2 - 1;
            gi_vec3 o, d;
            if (projection == GI_PROJ_ORTHOGRAPHIC) {
                o = gi_mat4_point(inv, gi_v3(sx * proj_inv_scale[0], sy * proj_inv_scale[1], 0));
                d = gi_v3_normalize(gi_mat4_dir(inv, gi_v3(0, 0, -1)));
            } else if (projection == GI_PROJ_PERSPECTIVE) {
                o = gi_mat4_point(inv, gi_v3(0, 0, 0));
                d = gi_v3_normalize(
                    gi_mat4_dir(inv, gi_v3(sx * proj_inv_scale[0], sy * proj_inv_scale[1], -1)));
            } else { /* paraboloid: (sx, sy) -> direction around -Z */
                float r2 = sx * sx + sy * sy;
                if (r2 > 0.95f)
                    continue;
                gi_vec3 e = gi_v3(2 * sx / (1 + r2), 2 * sy / (1 + r2), -(1 - r2) / (1 + r2));
                o = gi_mat4_point(inv, gi_v3(0, 0, 0));
                d = gi_v3_normalize(gi_mat4_dir(inv, e));
            }
            float hits[4];
            int n = cast_all(s, o, d, hits, 4, NULL);
            const float *texel = map + ((size_t)y * size + x) * 4;
            int ok = 1;
            for (int k = 0; k < surfaces; k++) {
                float want = FLT_MAX;
                if (k < n) {
                    /* eye z = distance x cos(angle to the axis) for non-radial maps */
                    gi_vec3 axis = gi_v3_normalize(gi_mat4_dir(inv, gi_v3(0, 0, -1)));
                    want = metric_radial ? hits[k] : hits[k] * gi_v3_dot(d, axis);
                }
                if (want == FLT_MAX)
                    ok &= texel[k] == FLT_MAX;
                else
                    ok &= fabsf(texel[k] - want) <= tol * want;
            }
            if (!ok && getenv("GI_DEBUG"))
                printf("texel %u %u: map %g %g expected %g %g (n %d)\n", x, y, texel[0], texel[1],
                       n > 0 ? hits[0] : -1.0, n > 1 ? hits[1] : -1.0, n);
            agree += ok;
            total++;
        }
    return total ? (float)agree / total : 0.0f;
}

/* Frustum culling of the depth pass (passes.c): the views rendered with
 * culling on and off must give the same bits, and culling must have left
 * triangles out. Cube faces around `eye` and, where `ortho_half` > 0, an
 * orthographic view down onto it; each with `desc` (objects skipped or
 * drawn alone, local space). Returns the share of triangles drawn. */
static double culled_equals_whole(const gi_gpu_scene *gs, gi_depth_desc desc, gi_vec3 eye,
                                  float ortho_half, const char *what)
{
    gi_error err;
    const uint32_t S = 32;
    gi_depth_view v[7];
    gi_depth_cube_views(eye, 0.01f, 50.0f, v);
    uint32_t nv = 6;
    if (ortho_half > 0.0f) {
        memset(&v[6], 0, sizeof v[6]);
        gi_mat4_look_at(v[6].view, gi_v3(eye.x, eye.y + 2.0f, eye.z), eye, gi_v3(0, 0, -1));
        gi_mat4_ortho(v[6].proj, -ortho_half, ortho_half, -ortho_half, ortho_half, 0.01f, 20.0f);
        v[6].projection = GI_PROJ_ORTHOGRAPHIC;
        nv = 7;
    }
    gi_depth_renderer *on = gi_depth_renderer_create(&desc, &err);
    gi_depth_renderer *off = on ? gi_depth_renderer_create(&desc, &err) : NULL;
    CHECK_MSG(on && off, "%s", err.text);
    if (!on || !off) {
        gi_depth_renderer_free(on);
        return 1.0;
    }
    gi_depth_renderer_set_culling(off, 0);
    GLuint ta = gi_depth_texture_create(on, nv), tb = gi_depth_texture_create(off, nv);
    CHECK(gi_depth_render(on, gs, v, nv, ta, 0, &err) == GI_OK);
    CHECK(gi_depth_render(off, gs, v, nv, tb, 0, &err) == GI_OK);
    uint32_t differ = 0;
    for (uint32_t k = 0; k < nv; k++) {
        float *a = gi_depth_read_layer(ta, S, k), *b = gi_depth_read_layer(tb, S, k);
        CHECK(a && b);
        if (a && b)
            differ += memcmp(a, b, (size_t)S * S * 4 * sizeof(float)) != 0;
        free(a);
        free(b);
    }
    uint64_t drawn = 0, total = 0, d2 = 0, t2 = 0;
    gi_depth_renderer_drawn(on, &drawn, &total);
    gi_depth_renderer_drawn(off, &d2, &t2);
    double share = total ? (double)drawn / (double)total : 1.0;
    printf("culling, %s: %u of %u views differ from drawing everything; %.1f%% of %llu triangles "
           "drawn\n",
           what, differ, nv, 100.0 * share, (unsigned long long)total);
    CHECK_MSG(differ == 0, "%s: %u views differ with culling", what, differ);
    CHECK_MSG(total > 0 && drawn < total, "%s: culling left nothing out (%llu of %llu)", what,
              (unsigned long long)drawn, (unsigned long long)total);
    CHECK_MSG(d2 == 0 && t2 == 0, "%s: the renderer without culling counted triangles", what);
    glDeleteTextures(1, &ta);
    glDeleteTextures(1, &tb);
    gi_depth_renderer_free(on);
    gi_depth_renderer_free(off);
    return share;
}

/* The same on scenes whose objects move (rigid animation at t = 0.7 s) and
 * deform (morph targets), where the runs' boxes must follow the transforms
 * and the weights. */
static void culling_moved(gi_gpu *gpu, const char *name, float t)
{
    gi_error err;
    char path[512];
    snprintf(path, sizeof path, "%s/scenes/%s", GI_SOURCE_DIR, name);
    gi_scene *s = gi_scene_load(path, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    gi_gpu_scene *gs = s ? gi_gpu_scene_upload(gpu, s, &err) : NULL;
    CHECK_MSG(gs != NULL, "%s", err.text);
    if (gs) {
        gi_gpu_scene_set_time(gs, t);
        gi_depth_desc desc = {.size = 32, .surfaces = 2, .metric = GI_DEPTH_RADIAL};
        gi_vec3 mid =
            gi_v3(0.5f * (s->bounds[0] + s->bounds[3]), 0.5f * (s->bounds[1] + s->bounds[4]),
                  0.5f * (s->bounds[2] + s->bounds[5]));
        culled_equals_whole(gs, desc, mid, 0.0f, name);
    }
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
}

int main(void)
{
    gi_error err;
    gi_gpu *gpu;
    gi_scene *s;
    gi_gpu_scene *gs;
    if (!gpu_fixture_load(GI_SOURCE_DIR "/scenes/cornell_box.gltf", &gpu, &s, &gs))
        return gi_test_finish();

    /* ---- G-buffer from the scene camera ---- */
    const uint32_t W = 48, H = 48;
    gi_gbuffer *gb = gi_gbuffer_create(W, H, &err);
    CHECK_MSG(gb != NULL, "%s", err.text);
    gi_camera_frame cam = gi_scene_camera_at(s, 0, 0.0f);
    float view[16], proj[16];
    gi_mat4_invert(view, cam.world_from_camera);
    gi_mat4_perspective(proj, cam.yfov, 1.0f, cam.znear, cam.zfar);
    CHECK(gi_gbuffer_render(gb, gs, view, proj, &err) == GI_OK);
    float *pos = malloc(W * H * 4 * sizeof(float)), *nrm = malloc(W * H * 4 * sizeof(float));
    float *alb = malloc(W * H * 4 * sizeof(float));
    uint32_t *ids = malloc(W * H * 4 * sizeof(uint32_t));
    glGetTextureImage(gb->tex_position, 0, GL_RGBA, GL_FLOAT, W * H * 16, pos);
    glGetTextureImage(gb->tex_normal, 0, GL_RGBA, GL_FLOAT, W * H * 16, nrm);
    glGetTextureImage(gb->tex_albedo, 0, GL_RGBA, GL_FLOAT, W * H * 16, alb);
    glGetTextureImage(gb->tex_ids, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, W * H * 16, ids);
    int id_ok = 0, depth_ok = 0, normal_ok = 0, albedo_ok = 0, n = 0;
    float th = tanf(cam.yfov * 0.5f);
    gi_vec3 right = gi_v3_normalize(gi_v3_cross(cam.forward, cam.up)),
            up = gi_v3_cross(right, cam.forward);
    for (uint32_t y = 1; y < H; y += 3)
        for (uint32_t x = 1; x < W; x += 3) {
            float sx = ((x + 0.5f) / W * 2 - 1) * th,
                  sy = ((y + 0.5f) / H * 2 - 1) * th; /* GL row 0 = bottom */
            gi_vec3 d = gi_v3_normalize(
                gi_v3_add(cam.forward, gi_v3_add(gi_v3_scale(right, sx), gi_v3_scale(up, sy))));
            float hits[4];
            uint32_t tri = 0xFFFFFFFFu;
            int k = cast_all(s, cam.eye, d, hits, 4, &tri);
            size_t i = ((size_t)y * W + x) * 4;
            n++;
            if (k == 0) {
                id_ok += ids[i] == 0xFFFFFFFFu && pos[i + 3] == 0.0f;
                depth_ok++, normal_ok++, albedo_ok++;
                continue;
            }
            uint32_t mat = s->vertices[s->indices[3 * tri]].material;
            id_ok += ids[i + 2] == tri && ids[i + 1] == mat;
            depth_ok += fabsf(pos[i + 3] - hits[0] * gi_v3_dot(d, cam.forward)) < 1e-3f * hits[0];
            float nl = sqrtf(nrm[i] * nrm[i] + nrm[i + 1] * nrm[i + 1] + nrm[i + 2] * nrm[i + 2]);
            normal_ok +=
                fabsf(nl - 1) < 1e-2f && (nrm[i] * d.x + nrm[i + 1] * d.y + nrm[i + 2] * d.z) <= 0;
            albedo_ok += fabsf(alb[i] - s->materials[mat].albedo[0]) < 2e-3f;
        }
    printf("G-buffer vs ray casting: ids %d/%d, depth %d/%d, normals %d/%d, albedo %d/%d\n", id_ok,
           n, depth_ok, n, normal_ok, n, albedo_ok, n);
    /* A few texel centres may sit exactly on a triangle edge. */
    CHECK(id_ok >= n * 97 / 100);
    CHECK(depth_ok >= n * 97 / 100);
    CHECK(normal_ok == n);
    CHECK(albedo_ok >= n * 97 / 100);
    free(pos), free(nrm), free(alb), free(ids);
    gi_gbuffer_free(gb);

    /* ---- peeled depth maps ---- */
    const uint32_t S = 64;
    float cx = 0.5f * (s->bounds[0] + s->bounds[3]), cz = 0.5f * (s->bounds[2] + s->bounds[5]);
    float top = s->bounds[4] + 1.0f, half = 0.55f * (s->bounds[3] - s->bounds[0]);
    gi_depth_desc desc = {.size = S, .surfaces = 3, .metric = GI_DEPTH_EYE_Z};
    gi_depth_renderer *dr = gi_depth_renderer_create(&desc, &err);
    CHECK_MSG(dr != NULL, "%s", err.text);
    GLuint tex = gi_depth_texture_create(dr, 8);
    gi_depth_view ortho;
    memset(&ortho, 0, sizeof ortho);
    gi_mat4_look_at(ortho.view, gi_v3(cx, top, cz), gi_v3(cx, 0, cz), gi_v3(0, 0, -1));
    gi_mat4_ortho(ortho.proj, -half, half, -half, half, 0.01f, 20.0f);
    ortho.projection = GI_PROJ_ORTHOGRAPHIC;
    CHECK(gi_depth_render(dr, gs, &ortho, 1, tex, 0, &err) == GI_OK);
    float *map = gi_depth_read_layer(tex, S, 0);
    float scale[2] = {half, half};
    float agree = compare_map(s, map, S, 3, ortho.view, GI_PROJ_ORTHOGRAPHIC, scale, 1e-4f, 0);
    printf("orthographic, 3 surfaces: %.1f%% of texels agree with ray casting\n", 100 * agree);
    CHECK(agree >= 0.97f);
    free(map);
    gi_depth_renderer_free(dr);

    /* Cube faces (radial depth) from a point inside the box, dual depth. */
    desc.surfaces = 2;
    desc.metric = GI_DEPTH_RADIAL;
    dr = gi_depth_renderer_create(&desc, &err);
    gi_depth_view cube[6];
    gi_vec3 inside = gi_v3(cx, 0.5f * (s->bounds[1] + s->bounds[4]), cz);
    gi_depth_cube_views(inside, 0.01f, 50.0f, cube);
    CHECK(gi_depth_render(dr, gs, cube, 6, tex, 1, &err) == GI_OK);
    float one[2] = {1, 1};
    for (int f = 0; f < 6; f++) {
        map = gi_depth_read_layer(tex, S, 1 + (uint32_t)f);
        agree = compare_map(s, map, S, 2, cube[f].view, GI_PROJ_PERSPECTIVE, one, 1e-4f, 1);
        printf("cube face %d, 2 surfaces: %.1f%% agree\n", f, 100 * agree);
        CHECK(agree >= 0.97f);
        free(map);
    }
    gi_depth_view para;
    memset(&para, 0, sizeof para);
    /* Paraboloid looking down from below the ceiling, away from the blocks:
     * surfaces far compared with the triangle size, as for a VPL map. */
    gi_vec3 high = gi_v3(cx + 0.3f, s->bounds[1] + 0.85f * (s->bounds[4] - s->bounds[1]), cz);
    gi_mat4_look_at(para.view, high, gi_v3(high.x, 0, high.z), gi_v3(0, 0, -1));
    para.projection = GI_PROJ_PARABOLOID;
    para.znear = 0.01f;
    para.zfar = 50.0f;
    CHECK(gi_depth_render(dr, gs, &para, 1, tex, 7, &err) == GI_OK);
    map = gi_depth_read_layer(tex, S, 7);
    /* Paraboloid rasterisation is linear in screen space between vertices,
     * so triangles bend slightly; the tessellated box keeps that small. */
    agree = compare_map(s, map, S, 1, para.view, GI_PROJ_PARABOLOID, one, 0.01f, 1);
    printf("paraboloid: %.1f%% agree within 1%%\n", 100 * agree);
    CHECK(agree >= 0.9f);
    free(map);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);

    /* ---- frustum culling: the same bits as drawing everything ---- */
    gi_depth_desc cd = {.size = 32, .surfaces = 2, .metric = GI_DEPTH_RADIAL};
    double share = culled_equals_whole(gs, cd, inside, half, "Cornell box, cube and ortho");
    CHECK_MSG(share < 0.6, "culling drew %.0f%% of the triangles from the box's centre",
              100.0 * share);
    cd.skip_object = 1;
    culled_equals_whole(gs, cd, inside, half, "first object skipped");
    cd.skip_object = 0;
    cd.only_object = s->object_count;
    culled_equals_whole(gs, cd, inside, half, "last object alone");
    cd.local = 1;
    culled_equals_whole(gs, cd, inside, half, "last object alone, local space");
    culling_moved(gpu, "cornell_moving.gltf", 0.7f);
    culling_moved(gpu, "cornell_deform.gltf", 0.7f);
    CHECK(gi_gl_check("passes", &err) == GI_OK);
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
    return gi_test_finish();
}

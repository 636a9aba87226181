/* The depth atlas (passes.h, gi_depth_atlas_*) on the Cornell box:
 *  - every tile equals the per-view gi_depth_render map (surfaces = 1) of
 *    the same view on every texel, for perspective (eye z and radial, with
 *    and without back-face culling) and paraboloid views at mixed positions
 *    inside and outside the box; a texel may differ only on a silhouette
 *    (a depth jump of more than 2 % within its 3 x 3 neighbourhood in the
 *    per-view map), and such texels are counted, reported and bounded;
 *  - tiles past the views drawn hold FLT_MAX, also after a render with
 *    fewer views than the one before;
 *  - depth_atlas.glsl in a compute shader on random world points: the same
 *    footprint, texel, stored depth and point depth as the C twin
 *    gi_depth_atlas_texel reading the tile on the CPU (a different texel
 *    only for a point within 1e-3 texel of a texel edge);
 *  - the depth the lookup returns is the first surface along the texel's
 *    centre ray by exact ray casting (gi/raytrace.h): 99 % of points for
 *    perspective (1e-3), 90 % for paraboloid (1 %: paraboloid rasterisation
 *    bends triangles, as in test_passes.c);
 *  - bad descs, capacity overflow, a mismatched projection and a bad
 *    paraboloid range are errors.
 * With --bench [maps] [tile]: times `maps` maps (default 1024 of 32^2) drawn
 * instanced into the atlas against the same views drawn one by one with
 * gi_depth_render, side by side in one run with the core timer. */
#include "check.h"
#include "gpu_fixture.h"

#include "gi/gpu.h"
#include "gi/passes.h"
#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/shader.h"
#include "gi/timer.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static float urand(uint32_t *rng)
{
    return gi_rng_next_float(rng);
}

/* Random view inside (or, one in four, outside) the box looking in a random
 * direction; perspective fov 50..110 degrees. */
static void random_view(const gi_scene *s, gi_projection proj, uint32_t *rng, gi_depth_view *v)
{
    const float *b = s->bounds;
    memset(v, 0, sizeof *v);
    gi_vec3 eye;
    float *e = &eye.x;
    int outside = urand(rng) < 0.25f;
    for (int k = 0; k < 3; k++) {
        float ext = b[3 + k] - b[k];
        e[k] = outside ? b[k] - 0.5f * ext + 2.0f * ext * urand(rng)
                       : b[k] + ext * (0.05f + 0.9f * urand(rng));
    }
    gi_vec3 c = gi_v3(0.5f * (b[0] + b[3]), 0.5f * (b[1] + b[4]), 0.5f * (b[2] + b[5]));
    gi_vec3 dir = outside ? gi_v3_normalize(gi_v3_sub(c, eye))
                          : gi_sample_uniform_sphere(urand(rng), urand(rng));
    gi_vec3 up = fabsf(dir.y) > 0.9f ? gi_v3(1, 0, 0) : gi_v3(0, 1, 0);
    gi_mat4_look_at(v->view, eye, gi_v3_add(eye, dir), up);
    v->projection = proj;
    v->znear = 0.02f;
    v->zfar = 60.0f;
    if (proj == GI_PROJ_PERSPECTIVE)
        gi_mat4_perspective(v->proj, (50.0f + 60.0f * urand(rng)) * (float)GI_PI / 180.0f, 1.0f,
                            v->znear, v->zfar);
}

typedef struct tile_stats {
    uint64_t texels, exact, close, silhouette, bad, empty;
    double worst_rel; /* over non-silhouette texels */
} tile_stats;

static int near_jump(const float *m, uint32_t n, uint32_t x, uint32_t y)
{
    float c = m[y * n + x];
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            int xx = (int)x + dx, yy = (int)y + dy;
            if (xx < 0 || yy < 0 || xx >= (int)n || yy >= (int)n)
                continue;
            float o = m[yy * n + xx];
            if ((o >= FLT_MAX) != (c >= FLT_MAX) || fabsf(o - c) > 0.02f * fminf(o, c))
                return 1;
        }
    return 0;
}

/* Atlas tiles against per-view maps of the same views. */
static void compare_with_per_view(gi_gpu_scene *gs, const gi_scene *s, const char *name,
                                  gi_projection proj, gi_depth_metric metric, int cull,
                                  uint32_t tile, uint32_t nviews, uint32_t seed)
{
    gi_error err;
    uint32_t rng = gi_rng_init(seed, 0, 1);
    gi_depth_view *views = malloc(nviews * sizeof *views);
    for (uint32_t i = 0; i < nviews; i++)
        random_view(s, proj, &rng, &views[i]);
    gi_depth_atlas_desc ad = {
        .tile = tile, .capacity = nviews + 3, .projection = proj, .metric = metric, .cull = cull};
    gi_depth_atlas *a = gi_depth_atlas_create(&ad, &err);
    CHECK_MSG(a != NULL, "%s", err.text);
    gi_depth_desc dd = {.size = tile, .surfaces = 1, .metric = metric, .cull = cull};
    gi_depth_renderer *dr = gi_depth_renderer_create(&dd, &err);
    CHECK_MSG(dr != NULL, "%s", err.text);
    if (!a || !dr) {
        gi_depth_atlas_free(a);
        gi_depth_renderer_free(dr);
        free(views);
        return;
    }
    GLuint arr = gi_depth_texture_create(dr, nviews);
    CHECK(gi_depth_render(dr, gs, views, nviews, arr, 0, &err) == GI_OK);
    CHECK_MSG(gi_depth_atlas_render(a, gs, views, nviews, &err) == GI_OK, "%s", err.text);
    tile_stats st = {0};
    for (uint32_t i = 0; i < nviews; i++) {
        float *ref4 = gi_depth_read_layer(arr, tile, i), *t = gi_depth_atlas_read_tile(a, i);
        float *ref = malloc((size_t)tile * tile * sizeof *ref);
        for (uint32_t k = 0; k < tile * tile; k++)
            ref[k] = ref4[4 * k];
        for (uint32_t y = 0; y < tile; y++)
            for (uint32_t x = 0; x < tile; x++) {
                float r = ref[y * tile + x], v = t[y * tile + x];
                st.texels++;
                st.empty += r >= FLT_MAX;
                if (r == v) {
                    st.exact++;
                    continue;
                }
                double rel =
                    (r >= FLT_MAX || v >= FLT_MAX) ? INFINITY : fabs((double)r - v) / fmin(r, v);
                if (rel <= 1e-5) {
                    st.close++;
                    st.worst_rel = fmax(st.worst_rel, rel);
                } else if (near_jump(ref, tile, x, y)) {
                    st.silhouette++;
                } else {
                    st.bad++;
                    st.worst_rel = fmax(st.worst_rel, rel);
                    if (st.bad <= 3)
                        fprintf(stderr, "%s: view %u texel %u,%u: atlas %g, per view %g\n", name, i,
                                x, y, (double)v, (double)r);
                }
            }
        free(ref4);
        free(t);
        free(ref);
    }
    /* The three spare tiles were never drawn. */
    int spare_ok = 1;
    for (uint32_t i = nviews; i < nviews + 3; i++) {
        float *t = gi_depth_atlas_read_tile(a, i);
        for (uint32_t k = 0; k < tile * tile; k++)
            spare_ok &= t[k] == FLT_MAX;
        free(t);
    }
    CHECK(spare_ok);
    printf("%s: %u views of %u^2 (atlas %u x %u tiles): %llu texels, %.3f%% bit-equal, %.3f%% "
           "within 1e-5 "
           "(worst %.2g), %.3f%% differ on silhouettes, %llu elsewhere; %.1f%% empty\n",
           name, nviews, tile, gi_depth_atlas_columns(a), gi_depth_atlas_rows(a),
           (unsigned long long)st.texels, 100.0 * st.exact / st.texels,
           100.0 * st.close / st.texels, st.worst_rel, 100.0 * st.silhouette / st.texels,
           (unsigned long long)st.bad, 100.0 * st.empty / st.texels);
    CHECK(st.bad == 0);
    CHECK_MSG(st.silhouette * 200 <= st.texels, "%llu silhouette texels",
              (unsigned long long)st.silhouette);
    CHECK(st.empty < st.texels); /* something was drawn */
    glDeleteTextures(1, &arr);
    gi_depth_renderer_free(dr);
    gi_depth_atlas_free(a);
    free(views);
}

/* The GLSL lookup on random points: per point, in: xyz + view; out:
 * stored depth, point depth, texel x, texel y (-1 outside). */
static const char *lookup_comp =
    "#include \"depth_atlas.glsl\"\n"
    "layout(local_size_x = 64) in;\n"
    "layout(std430, binding = 8) readonly buffer In { vec4 pts[]; };\n"
    "layout(std430, binding = 9) writeonly buffer Out { vec4 res[]; };\n"
    "layout(binding = 0) uniform sampler2D u_atlas;\n"
    "uniform uint u_count;\n"
    "void main() {\n"
    "    uint i = gl_GlobalInvocationID.x;\n"
    "    if (i >= u_count) return;\n"
    "    uint view = floatBitsToUint(pts[i].w);\n"
    "    float pd, pd2;\n"
    "    float z = gi_atlas_depth(u_atlas, view, pts[i].xyz, pd);\n"
    "    ivec2 t;\n"
    "    bool in_fp = gi_atlas_texel(view, pts[i].xyz, t, pd2);\n"
    "    res[i] = vec4(z, pd, in_fp ? float(t.x) : -1.0, in_fp ? float(t.y) : -1.0);\n"
    "}\n";

/* Distance of coordinate f (in texels) to the nearest texel edge. */
static float edge_dist(float f)
{
    return fabsf(f - roundf(f));
}

static void test_lookup(gi_gpu_scene *gs, const gi_scene *s, gi_projection proj,
                        gi_depth_metric metric)
{
    gi_error err;
    const uint32_t tile = 32, nviews = 20, N = 4096;
    uint32_t rng = gi_rng_init(proj == GI_PROJ_PARABOLOID ? 31u : 32u, 0, 1);
    gi_depth_view views[20];
    for (uint32_t i = 0; i < nviews; i++)
        random_view(s, proj, &rng, &views[i]);
    gi_depth_atlas_desc ad = {
        .tile = tile, .capacity = nviews, .projection = proj, .metric = metric};
    gi_depth_atlas *a = gi_depth_atlas_create(&ad, &err);
    CHECK_MSG(a != NULL, "%s", err.text);
    GLuint prog = gi_program_build_compute_text("tests/unit/depth_atlas_lookup.comp", lookup_comp,
                                                NULL, &err);
    CHECK_MSG(prog != 0, "%s", err.text);
    gi_rt *rt = NULL;
    CHECK_MSG(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK, "%s", err.text);
    if (!a || !prog || !rt) {
        gi_depth_atlas_free(a);
        gi_rt_free(rt);
        return;
    }
    CHECK(gi_depth_atlas_render(a, gs, views, nviews, &err) == GI_OK);
    /* Half the points anywhere in (and around) the box, half on surfaces. */
    float *pts = malloc((size_t)N * 4 * sizeof *pts);
    const float *b = s->bounds;
    for (uint32_t i = 0; i < N; i++) {
        gi_vec3 p;
        if (i % 2 == 0) {
            p = gi_v3(b[0] + (b[3] - b[0]) * (1.2f * urand(&rng) - 0.1f),
                      b[1] + (b[4] - b[1]) * (1.2f * urand(&rng) - 0.1f),
                      b[2] + (b[5] - b[2]) * (1.2f * urand(&rng) - 0.1f));
        } else {
            uint32_t t = (uint32_t)(urand(&rng) * (float)s->triangle_count) % s->triangle_count;
            gi_vec3 q[3];
            gi_scene_triangle_world(s, t, 0.0f, q);
            float u = urand(&rng), v = urand(&rng);
            if (u + v > 1.0f)
                u = 1.0f - u, v = 1.0f - v;
            p = gi_v3_add(q[0], gi_v3_add(gi_v3_scale(gi_v3_sub(q[1], q[0]), u),
                                          gi_v3_scale(gi_v3_sub(q[2], q[0]), v)));
        }
        uint32_t view = (uint32_t)(urand(&rng) * nviews) % nviews;
        pts[4 * i] = p.x, pts[4 * i + 1] = p.y, pts[4 * i + 2] = p.z;
        memcpy(&pts[4 * i + 3], &view, sizeof view);
    }
    GLuint bufs[2];
    glCreateBuffers(2, bufs);
    glNamedBufferStorage(bufs[0], (GLsizeiptr)N * 16, pts, 0);
    glNamedBufferStorage(bufs[1], (GLsizeiptr)N * 16, NULL, 0);
    glUseProgram(prog);
    glUniform1ui(glGetUniformLocation(prog, "u_count"), N);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, bufs[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, bufs[1]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_DEPTH_ATLAS, gi_depth_atlas_views_buffer(a));
    glBindTextureUnit(0, gi_depth_atlas_texture(a));
    glDispatchCompute((N + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    float *res = malloc((size_t)N * 16);
    glGetNamedBufferSubData(bufs[1], 0, (GLsizeiptr)N * 16, res);
    CHECK(gi_gl_check("atlas lookup", &err) == GI_OK);
    float **tiles = calloc(nviews, sizeof *tiles);
    for (uint32_t i = 0; i < nviews; i++)
        tiles[i] = gi_depth_atlas_read_tile(a, i);
    int inside = 0, same = 0, edge_excused = 0, bad = 0, ray_n = 0, ray_agree = 0, texel_ok = 0;
    for (uint32_t i = 0; i < N; i++) {
        gi_vec3 p = gi_v3(pts[4 * i], pts[4 * i + 1], pts[4 * i + 2]);
        uint32_t view;
        memcpy(&view, &pts[4 * i + 3], sizeof view);
        uint32_t tx = 0, ty = 0;
        float pd;
        int in = gi_depth_atlas_texel(&views[view], proj, metric, tile, p, &tx, &ty, &pd);
        const float *r = res + 4 * i;
        int gin = r[2] >= 0.0f;
        int pd_ok = fabsf(r[1] - pd) <= 1e-5f * fabsf(pd) + 1e-6f;
        /* the C side's position in texels, to excuse rounding at texel edges */
        float near_edge = 1.0f, nx = 0.0f, ny = 0.0f;
        {
            const float *m = views[view].view;
            gi_vec3 e = gi_v3(m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12],
                              m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
                              m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]);
            if (proj == GI_PROJ_PARABOLOID) {
                gi_vec3 d = gi_v3_normalize(e);
                nx = d.x / (1 - d.z), ny = d.y / (1 - d.z);
                near_edge = fabsf(d.z) * tile; /* the hemisphere's rim */
            } else {
                const float *q = views[view].proj;
                float w = q[3] * e.x + q[7] * e.y + q[11] * e.z + q[15];
                nx = (q[0] * e.x + q[4] * e.y + q[8] * e.z + q[12]) / w;
                ny = (q[1] * e.x + q[5] * e.y + q[9] * e.z + q[13]) / w;
            }
            near_edge = fminf(near_edge, fminf(edge_dist((nx * 0.5f + 0.5f) * tile),
                                               edge_dist((ny * 0.5f + 0.5f) * tile)));
        }
        if (in != gin || (in && (r[2] != (float)tx || r[3] != (float)ty))) {
            if (near_edge < 1e-3f)
                edge_excused++;
            else {
                bad++;
                if (bad <= 3)
                    fprintf(stderr, "point %u view %u: C in %d texel %u %u, GLSL %g %g\n", i, view,
                            in, tx, ty, (double)r[2], (double)r[3]);
            }
            continue;
        }
        if (!in) {
            bad += !(isinf(r[0]) && r[0] > 0) || !pd_ok;
            continue;
        }
        inside++;
        float stored = tiles[view][ty * tile + tx];
        int ok = stored == r[0] && pd_ok;
        same += ok;
        bad += !ok;
        /* The stored depth is the first surface along the texel's centre
         * ray (exact ray casting, gi/raytrace.h): checks the tile layout and
         * orientation the C twin and the GLSL share. */
        {
            float inv[16];
            gi_mat4_invert(inv, views[view].view);
            float sx = ((float)tx + 0.5f) / (float)tile * 2.0f - 1.0f,
                  sy = ((float)ty + 0.5f) / (float)tile * 2.0f - 1.0f;
            /* p's own projection lies in that texel (row 0 at the bottom) */
            texel_ok += fabsf(nx - sx) <= 1.0f / (float)tile + 1e-5f &&
                        fabsf(ny - sy) <= 1.0f / (float)tile + 1e-5f;
            gi_vec3 de;
            if (proj == GI_PROJ_PARABOLOID) {
                float r2 = sx * sx + sy * sy;
                de = gi_v3(2 * sx / (1 + r2), 2 * sy / (1 + r2), -(1 - r2) / (1 + r2));
            } else {
                de = gi_v3_normalize(
                    gi_v3(sx / views[view].proj[0], sy / views[view].proj[5], -1.0f));
            }
            gi_vec3 eye = gi_mat4_point(inv, gi_v3(0, 0, 0)),
                    d = gi_v3_normalize(gi_mat4_dir(inv, de));
            gi_rt_hit h;
            int hit = gi_rt_intersect(rt, eye, d, 0.0f, INFINITY, &h);
            float want = !hit ? FLT_MAX : metric == GI_DEPTH_RADIAL ? h.t : h.t * -de.z;
            float tol = proj == GI_PROJ_PARABOLOID
                            ? 0.01f
                            : 1e-3f; /* paraboloid: triangles bend (test_passes.c) */
            ray_n++;
            ray_agree += stored >= FLT_MAX ? want >= FLT_MAX : fabsf(stored - want) <= tol * want;
        }
    }
    printf("lookup (%s, %s): %u points, %d in a footprint: %d equal the C twin, %d differ at texel "
           "edges "
           "(< 1e-3 texel), %d wrong; the stored depth equals a ray cast through the texel centre "
           "for %.1f%%\n",
           proj == GI_PROJ_PARABOLOID ? "paraboloid" : "perspective",
           metric == GI_DEPTH_RADIAL ? "radial" : "eye z", N, inside, same, edge_excused, bad,
           100.0 * ray_agree / (ray_n ? ray_n : 1));
    CHECK(bad == 0);
    CHECK(edge_excused * 100 <= (int)N);
    CHECK(inside > (int)N / 10);
    CHECK_MSG(texel_ok == inside, "%d of %d points in their texel", texel_ok, inside);
    CHECK(ray_n == inside && ray_agree >= ray_n * (proj == GI_PROJ_PARABOLOID ? 90 : 99) / 100);
    for (uint32_t i = 0; i < nviews; i++)
        free(tiles[i]);
    free(tiles);
    free(res);
    free(pts);
    glDeleteBuffers(2, bufs);
    glDeleteProgram(prog);
    gi_rt_free(rt);
    gi_depth_atlas_free(a);
}

static void test_errors(gi_gpu_scene *gs, const gi_scene *s)
{
    gi_error err;
    gi_depth_atlas_desc ad = {
        .tile = 16, .capacity = 5, .projection = GI_PROJ_PERSPECTIVE, .metric = GI_DEPTH_EYE_Z};
    gi_depth_atlas_desc bad = ad;
    bad.tile = 0;
    CHECK(gi_depth_atlas_create(&bad, &err) == NULL);
    printf("tile 0: %s\n", err.text);
    bad = ad;
    bad.capacity = 0;
    CHECK(gi_depth_atlas_create(&bad, &err) == NULL);
    bad = ad;
    bad.projection = GI_PROJ_ORTHOGRAPHIC;
    CHECK(gi_depth_atlas_create(&bad, &err) == NULL);
    bad = ad;
    bad.tile = 4096;
    bad.capacity = 1u << 20;
    CHECK(gi_depth_atlas_create(&bad, &err) == NULL);
    printf("too big: %s\n", err.text);
    CHECK(gi_depth_atlas_create(NULL, &err) == NULL);
    gi_depth_atlas *a = gi_depth_atlas_create(&ad, &err);
    CHECK_MSG(a != NULL, "%s", err.text);
    if (!a)
        return;
    CHECK(gi_depth_atlas_columns(a) == 3 && gi_depth_atlas_rows(a) == 2);
    uint32_t rng = gi_rng_init(3, 0, 1);
    gi_depth_view v[6];
    for (int i = 0; i < 6; i++)
        random_view(s, GI_PROJ_PERSPECTIVE, &rng, &v[i]);
    CHECK(gi_depth_atlas_render(a, gs, v, 6, &err) == GI_ERR_INVALID_ARGUMENT);
    printf("overflow: %s\n", err.text);
    CHECK(strstr(err.text, "capacity") != NULL);
    CHECK(gi_depth_atlas_render(a, gs, v, 5, &err) == GI_OK && gi_depth_atlas_count(a) == 5);
    /* Fewer views clear the tiles drawn before. */
    CHECK(gi_depth_atlas_render(a, gs, v, 2, &err) == GI_OK);
    float *t = gi_depth_atlas_read_tile(a, 4);
    int cleared = 1;
    for (uint32_t k = 0; k < 16 * 16; k++)
        cleared &= t[k] == FLT_MAX;
    free(t);
    CHECK(cleared);
    CHECK(gi_depth_atlas_read_tile(a, 5) == NULL);
    v[1].projection = GI_PROJ_PARABOLOID;
    CHECK(gi_depth_atlas_render(a, gs, v, 2, &err) == GI_ERR_INVALID_ARGUMENT);
    printf("mismatch: %s\n", err.text);
    CHECK(gi_depth_atlas_render(a, NULL, v, 2, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_depth_atlas_render(a, gs, NULL, 2, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_depth_atlas_render(a, gs, NULL, 0, &err) == GI_OK);
    gi_depth_atlas_free(a);
    ad.projection = GI_PROJ_PARABOLOID;
    a = gi_depth_atlas_create(&ad, &err);
    random_view(s, GI_PROJ_PARABOLOID, &rng, &v[0]);
    v[0].zfar = v[0].znear;
    CHECK(a && gi_depth_atlas_render(a, gs, v, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    printf("range: %s\n", err.text);
    gi_depth_atlas_free(a);
    gi_depth_atlas_free(NULL);
    CHECK(gi_gl_check("atlas errors", &err) == GI_OK);
}

/* Instanced atlas against per-view rendering, side by side. */
static int bench(gi_gpu *gpu, gi_gpu_scene *gs, const gi_scene *s, uint32_t maps, uint32_t tile,
                 gi_projection proj)
{
    gi_error err;
    uint32_t rng = gi_rng_init(77, 0, 1);
    gi_depth_view *views = malloc(maps * sizeof *views);
    for (uint32_t i = 0; i < maps; i++)
        random_view(s, proj, &rng, &views[i]);
    gi_depth_metric metric = proj == GI_PROJ_PARABOLOID ? GI_DEPTH_RADIAL : GI_DEPTH_EYE_Z;
    gi_depth_atlas_desc ad = {.tile = tile, .capacity = maps, .projection = proj, .metric = metric};
    gi_depth_atlas *a = gi_depth_atlas_create(&ad, &err);
    gi_depth_desc dd = {.size = tile, .surfaces = 1, .metric = metric};
    gi_depth_renderer *dr = gi_depth_renderer_create(&dd, &err);
    if (!a || !dr) {
        fprintf(stderr, "%s\n", err.text);
        return 1;
    }
    GLuint arr = gi_depth_texture_create(dr, maps);
    gi_timer *t = gi_timer_create(gi_timer_mode_for(gi_gpu_is_software(gpu)), 1);
    const int frames = 8;
    for (int f = 0; f < frames; f++) {
        gi_timer_frame_begin(t);
        /* alternate the order so neither always runs first */
        for (int k = 0; k < 2; k++) {
            if ((k + f) % 2 == 0) {
                gi_timer_begin(t, "instanced");
                gi_depth_atlas_render(a, gs, views, maps, &err);
                gi_timer_end(t, "instanced");
            } else {
                gi_timer_begin(t, "per_view");
                gi_depth_render(dr, gs, views, maps, arr, 0, &err);
                gi_timer_end(t, "per_view");
            }
        }
        gi_timer_frame_end(t);
    }
    gi_stage_stats st[GI_TIMER_MAX_STAGES];
    uint32_t n = gi_timer_stats(t, st, GI_TIMER_MAX_STAGES);
    double inst = 0, per = 0;
    for (uint32_t i = 0; i < n && i < GI_TIMER_MAX_STAGES; i++) {
        if (strcmp(st[i].name, "instanced") == 0)
            inst = st[i].median_ms;
        if (strcmp(st[i].name, "per_view") == 0)
            per = st[i].median_ms;
    }
    printf("bench (%s, timer %s): %u %s maps of %u^2 of %s (%u triangles), median of %d frames: "
           "instanced atlas %.1f ms, per-view gi_depth_render %.1f ms, ratio per-view / instanced "
           "= %.2f\n",
           gi_gpu_renderer(gpu), gi_timer_mode_name(gi_timer_get_mode(t)), maps,
           proj == GI_PROJ_PARABOLOID ? "paraboloid" : "perspective", tile, s->path,
           s->triangle_count, frames - 1, inst, per, per / inst);
    gi_timer_free(t);
    glDeleteTextures(1, &arr);
    gi_depth_renderer_free(dr);
    gi_depth_atlas_free(a);
    free(views);
    return 0;
}

int main(int argc, char **argv)
{
    gi_error err;
    gi_gpu *gpu;
    gi_scene *s;
    gi_gpu_scene *gs;
    if (!gpu_fixture_load(GI_SOURCE_DIR "/scenes/cornell_box.gltf", &gpu, &s, &gs) || !gs)
        return gi_test_finish();
    if (argc > 1 && strcmp(argv[1], "--bench") == 0) {
        uint32_t maps = argc > 2 ? (uint32_t)strtoul(argv[2], NULL, 10) : 1024;
        uint32_t tile = argc > 3 ? (uint32_t)strtoul(argv[3], NULL, 10) : 32;
        int r = bench(gpu, gs, s, maps, tile, GI_PROJ_PARABOLOID) |
                bench(gpu, gs, s, maps, tile, GI_PROJ_PERSPECTIVE);
        gi_gpu_scene_free(gs);
        gi_scene_free(s);
        gi_gpu_destroy(gpu);
        return r;
    }
    compare_with_per_view(gs, s, "perspective, eye z", GI_PROJ_PERSPECTIVE, GI_DEPTH_EYE_Z, 0, 32,
                          24, 1);
    compare_with_per_view(gs, s, "perspective, radial, back faces culled", GI_PROJ_PERSPECTIVE,
                          GI_DEPTH_RADIAL, 1, 24, 16, 2);
    compare_with_per_view(gs, s, "paraboloid, radial", GI_PROJ_PARABOLOID, GI_DEPTH_RADIAL, 0, 32,
                          24, 3);
    compare_with_per_view(gs, s, "paraboloid, 64 maps of 16^2", GI_PROJ_PARABOLOID, GI_DEPTH_RADIAL,
                          0, 16, 64, 4);
    test_lookup(gs, s, GI_PROJ_PERSPECTIVE, GI_DEPTH_EYE_Z);
    test_lookup(gs, s, GI_PROJ_PARABOLOID, GI_DEPTH_RADIAL);
    test_errors(gs, s);
    CHECK(gi_gl_check("depth atlas", &err) == GI_OK);
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
    return gi_test_finish();
}

/* The avg plugin's parts against independent computations (the plugin's
 * sources are compiled in; see plugins/avg/README.md "Tests"):
 *
 *   avg_tests voxel   the GPU voxelisation (all three voxelisers) against a
 *                     CPU triangle-box overlap voxelisation of the same
 *                     scene (Cornell box at t = 0, Cornell moving at
 *                     t = 1.3): every overlapped voxel filled, false
 *                     positives and per-voxel triangle counts reported; the
 *                     single-pass voxeliser also against the per-slice
 *                     conservative one: equal counts in every voxel, sums
 *                     within its fixed-point rounding;
 *   avg_tests march   rays marched through the grid on the GPU against
 *                     Embree rays (gi/raytrace.h) in the same scene: the AVG
 *                     hit voxel lies within one voxel of the real hit;
 *   avg_tests vpls    the VPL set of two frames of a static scene is
 *                     identical; it changes when the scene moves and comes
 *                     back when the scene does; the light VPLs of AVG and
 *                     exact tracing agree (same quasi-random numbers);
 *   avg_tests visibility  the light VPLs' shadow maps (core depth atlas,
 *                     paraboloid and perspective; and the maps of the
 *                     shadow_lod=0.1 copy on the Cornell box and Cornell
 *                     moving) against Embree shadow rays through the full
 *                     scene for every receiver pixel (the VPLs at hits lie
 *                     inside voxels, behind their surface, by design, and
 *                     are not comparable with exact rays);
 *   avg_tests shade   interleaved shading with M = 1 equals the plain sum
 *                     over all VPLs computed on the CPU from the G-buffer
 *                     (no visibility), and M = 16 without the filter equals
 *                     M times the sum over each pixel's own subset. */
#include "avg.h"
#include "shaders/avg_bindings.h"

#include "gi/image.h"
#include "gi/lights.h"
#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/algo/simplify.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed. */
#include "check.h"
#define EXPECT CHECK_MSG
#include "vis_score.h"

/* ---- a minimal host for driving the method in-process ---- */

static void host_log(const gi_host *h, int level, const char *fmt, ...)
{
    (void)h;
    (void)level;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}
static void host_progress(const gi_host *h, const char *task, float f)
{
    (void)h, (void)task, (void)f;
}
static void host_stage(const gi_host *h, const char *name)
{
    (void)h, (void)name;
}
static void host_stat(const gi_host *h, const char *name, double v)
{
    (void)h, (void)name, (void)v;
}
static int host_cancelled(const gi_host *h)
{
    (void)h;
    return 0;
}

static gi_host make_host(const gi_gpu_scene *gs)
{
    gi_host h;
    memset(&h, 0, sizeof h);
    h.struct_size = sizeof h;
    h.abi_version = GI_ABI_VERSION;
    h.log = host_log;
    h.progress = host_progress;
    h.stage_begin = host_stage;
    h.stage_end = host_stage;
    h.stat = host_stat;
    h.cancelled = host_cancelled;
    h.gpu_scene = gs;
    return h;
}

static void make_view(const gi_scene *s, float t, uint32_t w, uint32_t h, gi_view *v)
{
    gi_camera_frame cf = gi_scene_camera_at(s, s->camera_count ? 0 : -1, t);
    gi_view_from_camera(&cf, w, h, t, v);
    v->seed = 1;
}

/* Creates and prepares an avg instance with "k=v" parameters. */
static avg *make_avg(const gi_host *host, const gi_gpu_scene *gs, const char *const *kv, uint32_t n)
{
    const gi_method *m = gi_method_entry(GI_ABI_VERSION);
    gi_error err;
    gi_params *p = gi_params_parse("avg", m->params, kv, n, &err);
    if (!p) {
        fprintf(stderr, "%s\n", err.text);
        return NULL;
    }
    void *inst = NULL;
    gi_result r = m->create(host, p, &inst);
    gi_params_free(p);
    if (r != GI_OK)
        return NULL;
    if (m->prepare(inst, gs) != GI_OK) {
        fprintf(stderr, "prepare: %s\n", m->last_error(inst));
        m->destroy(inst);
        return NULL;
    }
    return inst;
}

typedef struct target {
    GLuint tex, fbo;
    uint32_t w, h;
} target;

static target make_target(uint32_t w, uint32_t h)
{
    target t = {0, 0, w, h};
    glCreateTextures(GL_TEXTURE_2D, 1, &t.tex);
    glTextureStorage2D(t.tex, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
    glCreateFramebuffers(1, &t.fbo);
    glNamedFramebufferTexture(t.fbo, GL_COLOR_ATTACHMENT0, t.tex, 0);
    return t;
}

static int render(avg *a, const gi_view *v, const target *t)
{
    const gi_method *m = gi_method_entry(GI_ABI_VERSION);
    gi_target gt = {t->tex, t->fbo, t->w, t->h};
    if (m->render(a, v, &gt) != GI_OK) {
        fprintf(stderr, "render: %s\n", m->last_error(a));
        return 0;
    }
    return 1;
}

/* A scene loaded and uploaded at t = 0, with a host around it. */
typedef struct fixture {
    gi_scene *s;
    gi_gpu_scene *gs;
    gi_host host;
} fixture;

static int load_fixture(gi_gpu *gpu, const char *scene_path, fixture *f)
{
    gi_error err;
    f->s = gi_scene_load(scene_path, &err);
    if (!f->s) {
        EXPECT(0, "%s", err.text);
        return 0;
    }
    f->gs = gi_gpu_scene_upload(gpu, f->s, &err);
    if (!f->gs) {
        EXPECT(0, "set-up failed: upload of %s: %s", scene_path, err.text);
        gi_scene_free(f->s);
        return 0;
    }
    gi_gpu_scene_set_time(f->gs, 0.0f);
    f->host = make_host(f->gs);
    return 1;
}

static void free_fixture(fixture *f)
{
    gi_gpu_scene_free(f->gs);
    gi_scene_free(f->s);
}

/* Renders one w x h frame of `a` at t = 0 into a new target. */
static target render_frame(avg *a, const gi_scene *s, uint32_t w, uint32_t h)
{
    target t = make_target(w, h);
    gi_view v;
    make_view(s, 0.0f, w, h, &v);
    EXPECT(render(a, &v, &t), "render");
    return t;
}

/* The G-buffer of the last frame of `a`, read back. */
typedef struct gbuffer_images {
    gi_image *pos, *nrm, *alb, *emi;
} gbuffer_images;

static gbuffer_images read_gbuffer(const avg *a, uint32_t w, uint32_t h)
{
    gbuffer_images g = {gi_gpu_read_texture(a->kit.gbuffer->tex_position, w, h),
                        gi_gpu_read_texture(a->kit.gbuffer->tex_normal, w, h),
                        gi_gpu_read_texture(a->kit.gbuffer->tex_albedo, w, h),
                        gi_gpu_read_texture(a->kit.gbuffer->tex_emission, w, h)};
    return g;
}

static void free_gbuffer_images(gbuffer_images *g)
{
    gi_image_free(g->pos);
    gi_image_free(g->nrm);
    gi_image_free(g->alb);
    gi_image_free(g->emi);
}

/* ---- voxel: CPU triangle-box overlap by clipping ---- */

/* Does triangle p (grid space) meet the box [lo, hi]? Clips the triangle
 * against the box's six planes (Sutherland-Hodgman); anything left means
 * overlap. Independent of the GPU's separating-axis test. */
static int tri_box_clip(const gi_vec3 p[3], gi_vec3 lo, gi_vec3 hi)
{
    gi_vec3 a[16], b[16];
    int n = 3;
    for (int i = 0; i < 3; i++)
        a[i] = p[i];
    for (int plane = 0; plane < 6 && n > 0; plane++) {
        int axis = plane / 2;
        float s = plane % 2 ? -1.0f : 1.0f; /* keep s * x <= s * c */
        float c = plane % 2 ? (&lo.x)[axis] : (&hi.x)[axis];
        int m = 0;
        for (int i = 0; i < n; i++) {
            gi_vec3 u = a[i], w = a[(i + 1) % n];
            float du = s * ((&u.x)[axis] - c), dw = s * ((&w.x)[axis] - c);
            if (du <= 0.0f)
                b[m++] = u;
            if ((du < 0.0f && dw > 0.0f) || (du > 0.0f && dw < 0.0f)) {
                float t = du / (du - dw);
                b[m++] = gi_v3_add(u, gi_v3_scale(gi_v3_sub(w, u), t));
            }
        }
        n = m;
        memcpy(a, b, sizeof(gi_vec3) * (size_t)n);
    }
    return n > 0;
}

/* CPU counts of triangles overlapping each voxel, boxes grown by `grow`;
 * with `colour`, also the sum of the overlapping triangles' material
 * albedos (the test scenes have no textures). */
static uint32_t *cpu_voxelise(const gi_scene *s, float t, const avg_grid *g, float grow,
                              float *colour)
{
    uint32_t n = g->n;
    uint32_t *count = calloc((size_t)n * n * n, sizeof *count);
    for (uint32_t tri = 0; tri < s->triangle_count; tri++) {
        gi_vec3 w[3], p[3];
        gi_scene_triangle_world(s, tri, t, w);
        gi_vec3 lo = gi_v3(FLT_MAX, FLT_MAX, FLT_MAX), hi = gi_v3(-FLT_MAX, -FLT_MAX, -FLT_MAX);
        for (int i = 0; i < 3; i++) {
            p[i] = gi_v3_scale(gi_v3_sub(w[i], gi_v3_load(g->origin)), 1.0f / g->h);
            lo = gi_v3(fminf(lo.x, p[i].x), fminf(lo.y, p[i].y), fminf(lo.z, p[i].z));
            hi = gi_v3(fmaxf(hi.x, p[i].x), fmaxf(hi.y, p[i].y), fmaxf(hi.z, p[i].z));
        }
        gi_vec3 e1 = gi_v3_sub(p[1], p[0]), e2 = gi_v3_sub(p[2], p[0]);
        if (gi_v3_length(gi_v3_cross(e1, e2)) == 0.0f)
            continue; /* degenerate: the rasteriser draws nothing either */
        int i0[3], i1[3];
        for (int a = 0; a < 3; a++) {
            i0[a] = (int)floorf((&lo.x)[a] - grow) - 1;
            i1[a] = (int)floorf((&hi.x)[a] + grow) + 1;
            i0[a] = i0[a] < 0 ? 0 : i0[a];
            i1[a] = i1[a] > (int)n - 1 ? (int)n - 1 : i1[a];
        }
        for (int z = i0[2]; z <= i1[2]; z++)
            for (int y = i0[1]; y <= i1[1]; y++)
                for (int x = i0[0]; x <= i1[0]; x++) {
                    gi_vec3 blo = gi_v3((float)x - grow, (float)y - grow, (float)z - grow);
                    gi_vec3 bhi =
                        gi_v3((float)x + 1 + grow, (float)y + 1 + grow, (float)z + 1 + grow);
                    if (tri_box_clip(p, blo, bhi)) {
                        size_t v = ((size_t)z * n + y) * n + x;
                        count[v]++;
                        if (colour)
                            for (int c = 0; c < 3; c++)
                                colour[3 * v + c] +=
                                    s->materials[s->vertices[s->indices[3 * tri]].material]
                                        .albedo[c];
                    }
                }
    }
    return count;
}

/* The GPU grid at each time of `ts` in turn (one scene upload and one grid,
 * as frames of an animation: moved and morphed vertices come from
 * gi_gpu_scene_set_time) against the CPU voxelisation of the scene at that
 * time (gi_scene_triangle_world: transforms and morph targets applied). */
static void voxel_case(gi_gpu *gpu, const char *scene_path, const float *ts, int nt, uint32_t n)
{
    gi_error err;
    fixture fx;
    if (!load_fixture(gpu, scene_path, &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    avg_grid *g = avg_grid_create(n, &err);
    if (!g) {
        EXPECT(0, "%s", err.text);
        return;
    }
    for (int ti = 0; ti < nt; ti++) {
        float t = ts[ti];
        gi_gpu_scene_set_time(gs, t);
        avg_grid_place(g, gs->bounds);
        float *colour = calloc((size_t)n * n * n * 3, sizeof *colour);
        uint32_t *inner = cpu_voxelise(s, t, g, -1e-3f, NULL),
                 *exact = cpu_voxelise(s, t, g, 0.0f, colour),
                 *outer = cpu_voxelise(s, t, g, 1e-3f, NULL);
        size_t total = (size_t)n * n * n, filled_cpu = 0;
        for (size_t i = 0; i < total; i++)
            filled_cpu += exact[i] > 0;
        float *slices_nrm = NULL, *slices_col = NULL;
        static const char *mode_names[] = {"conservative", "paper", "single"};
        for (int mode = 0; mode < 3; mode++) {
            EXPECT(avg_grid_voxelise(g, gs, (avg_vox_mode)mode, &err) == GI_OK, "%s", err.text);
            float *nrm = avg_grid_read(g, 0), *col = avg_grid_read(g, 1);
            size_t misses = 0, fp = 0, filled = 0, count_equal = 0, colour_bad = 0, ambiguous = 0;
            for (size_t i = 0; i < total; i++) {
                float c = nrm[4 * i + 3];
                filled += c > 0.0f;
                misses += inner[i] > 0 && c == 0.0f;
                fp += outer[i] == 0 && c > 0.0f;
                /* The count equals the CPU's; a triangle that only touches the
                 * voxel within 1e-3 voxel edges of its faces may count either way. */
                count_equal += (uint32_t)c >= inner[i] && (uint32_t)c <= outer[i];
                ambiguous += inner[i] != outer[i];
                if (c > 0.0f && fabsf(col[4 * i + 3] - c) > 0.0f)
                    colour_bad++;
                /* Where the overlap is unambiguous, the colour sums agree too. */
                if (mode != AVG_VOX_PAPER && inner[i] == outer[i] && (uint32_t)c == exact[i])
                    for (int k = 0; k < 3; k++)
                        if (fabsf(col[4 * i + k] - colour[3 * i + k]) > 1e-4f * (1.0f + c))
                            colour_bad++;
            }
            printf("voxel %s t=%.2f n=%u %-12s: %zu filled (CPU %zu), %zu missed, %zu false "
                   "positives (%.3f %%), "
                   "triangle count different from the CPU's in %zu of %zu voxels (%zu voxels with "
                   "a triangle within "
                   "1e-3 of a face, counted either way)\n",
                   strrchr(scene_path, '/') + 1, t, n, mode_names[mode], filled, filled_cpu, misses,
                   fp, 100.0 * (double)fp / (double)(filled ? filled : 1), total - count_equal,
                   total, ambiguous);
            EXPECT(colour_bad == 0, "%zu voxels with different counts or colour sums", colour_bad);
            if (mode != AVG_VOX_PAPER) {
                EXPECT(misses == 0, "%s voxeliser missed %zu overlapped voxels", mode_names[mode],
                       misses);
                EXPECT(fp == 0, "%s voxeliser filled %zu voxels no triangle overlaps",
                       mode_names[mode], fp);
                EXPECT(count_equal == total, "triangle counts differ in %zu voxels",
                       total - count_equal);
            }
            if (mode == AVG_VOX_SINGLE && slices_nrm) {
                /* The single pass against the per-slice conservative pass:
                 * the same count in every voxel, the sums within the fixed
                 * point's rounding (count / (2 AVG_VOX_FIXED) per component)
                 * plus float summation error. */
                size_t count_diff = 0, sum_bad = 0;
                double worst = 0.0;
                for (size_t i = 0; i < total; i++) {
                    float c = slices_nrm[4 * i + 3];
                    count_diff += nrm[4 * i + 3] != c;
                    double bound = c / (2.0 * AVG_VOX_FIXED) + 1e-6 * (1.0 + c);
                    for (int k = 0; k < 3; k++) {
                        double dn = fabs(nrm[4 * i + k] - slices_nrm[4 * i + k]);
                        double dc = fabs(col[4 * i + k] - slices_col[4 * i + k]);
                        worst = fmax(worst, fmax(dn, dc));
                        sum_bad += dn > bound || dc > bound;
                    }
                }
                printf("voxel %s t=%.2f n=%u single vs conservative: counts differ in %zu of %zu "
                       "voxels, largest sum "
                       "difference %.3g (bound per voxel count / %.0f)\n",
                       strrchr(scene_path, '/') + 1, t, n, count_diff, total, worst,
                       2.0 * AVG_VOX_FIXED);
                EXPECT(count_diff == 0,
                       "single-pass counts differ from the per-slice ones in %zu voxels",
                       count_diff);
                EXPECT(sum_bad == 0, "%zu sums beyond the fixed-point bound", sum_bad);
            }
            if (mode == AVG_VOX_PAPER) {
                /* The paper's voxeliser is not conservative at partly covered
                 * voxels; it must still fill most of the surface voxels. */
                EXPECT(misses * 10 < filled_cpu, "paper voxeliser missed %zu of %zu voxels", misses,
                       filled_cpu);
            }
            if (mode == AVG_VOX_CONSERVATIVE) {
                slices_nrm = nrm;
                slices_col = col;
            } else {
                free(nrm);
                free(col);
            }
        }
        free(slices_nrm);
        free(slices_col);
        free(inner);
        free(exact);
        free(outer);
        free(colour);
    }
    avg_grid_free(g);
    free_fixture(&fx);
}

/* ---- deform: the grid follows morph targets ---- */

static void deform_case(gi_gpu *gpu)
{
    static const float ts[] = {0.0f, 1.0f, 2.0f, 2.5f, 3.0f, 0.0f};
    voxel_case(gpu, GI_SOURCE_DIR "/scenes/cornell_deform.gltf", ts,
               (int)(sizeof ts / sizeof ts[0]), 32);
    /* The poses differ in the grid (else the comparison above says nothing):
     * the CPU voxelisations at t = 0 and t = 2 differ in many voxels. */
    gi_error err;
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/cornell_deform.gltf", &err);
    avg_grid *g = avg_grid_create(32, &err);
    if (!s || !g) {
        EXPECT(0, "%s", err.text);
        return;
    }
    avg_grid_place(g, s->bounds);
    uint32_t *a = cpu_voxelise(s, 0.0f, g, 0.0f, NULL), *b = cpu_voxelise(s, 2.0f, g, 0.0f, NULL);
    size_t differ = 0;
    for (size_t i = 0; i < (size_t)32 * 32 * 32; i++)
        differ += (a[i] > 0) != (b[i] > 0);
    printf("deform: %zu voxels filled at one pose and empty at the other (t = 0, 2)\n", differ);
    EXPECT(differ > 100, "only %zu voxels differ between the poses", differ);
    free(a);
    free(b);
    avg_grid_free(g);
    gi_scene_free(s);
}

/* ---- march: GPU ray marching against Embree ---- */

/* Closest point on triangle abc to p (Ericson, Real-Time Collision
 * Detection 5.1.5). */
static gi_vec3 closest_on_triangle(gi_vec3 p, gi_vec3 a, gi_vec3 b, gi_vec3 c)
{
    gi_vec3 ab = gi_v3_sub(b, a), ac = gi_v3_sub(c, a), ap = gi_v3_sub(p, a);
    float d1 = gi_v3_dot(ab, ap), d2 = gi_v3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return a;
    gi_vec3 bp = gi_v3_sub(p, b);
    float d3 = gi_v3_dot(ab, bp), d4 = gi_v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return b;
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return gi_v3_add(a, gi_v3_scale(ab, d1 / (d1 - d3)));
    gi_vec3 cp = gi_v3_sub(p, c);
    float d5 = gi_v3_dot(ab, cp), d6 = gi_v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return c;
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return gi_v3_add(a, gi_v3_scale(ac, d2 / (d2 - d6)));
    float va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return gi_v3_add(b, gi_v3_scale(gi_v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    float denom = 1.0f / (va + vb + vc);
    return gi_v3_add(a, gi_v3_add(gi_v3_scale(ab, vb * denom), gi_v3_scale(ac, vc * denom)));
}

/* Distance from p to the nearest triangle of the scene at t = 0. */
static float scene_distance(const gi_scene *s, gi_vec3 p)
{
    float best = FLT_MAX;
    for (uint32_t tri = 0; tri < s->triangle_count; tri++) {
        gi_vec3 w[3];
        gi_scene_triangle_world(s, tri, 0.0f, w);
        gi_vec3 q = closest_on_triangle(p, w[0], w[1], w[2]);
        best = fminf(best, gi_v3_length(gi_v3_sub(p, q)));
    }
    return best;
}

static const char *march_src =
    "#define AVG_UNIT_NORMAL 8\n"
    "#define AVG_UNIT_COLOUR 9\n"
    "#include \"avg_grid.glsl\"\n"
    "layout(local_size_x = 64) in;\n"
    "layout(std430, binding = 8) readonly buffer Rays { vec4 rays[]; };\n"
    "layout(std430, binding = 9) writeonly buffer Hits { vec4 hits[]; };\n"
    "uniform uint u_count;\n"
    "void main() {\n"
    "  uint i = gl_GlobalInvocationID.x;\n"
    "  if (i >= u_count) return;\n"
    "  vec3 o = avg_to_grid(rays[2u * i].xyz), d = rays[2u * i + 1u].xyz;\n"
    "  ivec3 c; float t0, t1;\n"
    "  if (avg_march(o, d, c, t0, t1)) hits[i] = vec4(vec3(c), t0 * u_grid_h);\n"
    "  else hits[i] = vec4(-1.0);\n"
    "}\n";

static void march_case(gi_gpu *gpu, const char *scene_path, uint32_t n, uint32_t rays)
{
    gi_error err;
    fixture fx;
    if (!load_fixture(gpu, scene_path, &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    avg_grid *g = avg_grid_create(n, &err);
    gi_rt *rt = NULL;
    if (!g || gi_rt_create(s, 0.0f, &rt, &err) != GI_OK) {
        EXPECT(0, "%s", err.text);
        return;
    }
    avg_grid_place(g, gs->bounds);
    EXPECT(avg_grid_voxelise(g, gs, AVG_VOX_CONSERVATIVE, &err) == GI_OK, "%s", err.text);
    float *grid = avg_grid_read(g, 0);
    /* Ray origins: random points in the scene's bounds whose own voxel and
     * its neighbours are empty (rays start in free space); directions
     * uniform on the sphere. */
    float *ray = calloc((size_t)rays * 8, sizeof *ray);
    uint32_t rng = gi_rng_init(7, 0, 1), made = 0;
    while (made < rays) {
        gi_vec3 o;
        for (int a = 0; a < 3; a++)
            (&o.x)[a] =
                gs->bounds[a] + (gs->bounds[3 + a] - gs->bounds[a]) * gi_rng_next_float(&rng);
        int cx = (int)floorf((o.x - g->origin[0]) / g->h),
            cy = (int)floorf((o.y - g->origin[1]) / g->h),
            cz = (int)floorf((o.z - g->origin[2]) / g->h), free_space = 1;
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++)
                    free_space &= grid[4 * (((size_t)(cz + dz) * n + (size_t)(cy + dy)) * n +
                                            (size_t)(cx + dx)) +
                                       3] == 0.0f;
        if (!free_space)
            continue;
        gi_vec3 d = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
        float *r = &ray[8 * (size_t)made++];
        r[0] = o.x, r[1] = o.y, r[2] = o.z, r[4] = d.x, r[5] = d.y, r[6] = d.z;
    }
    GLuint prog = gi_program_build_compute_text("avg_tests march", march_src, NULL, &err);
    EXPECT(prog != 0, "%s", err.text);
    GLuint buf[2];
    glCreateBuffers(2, buf);
    glNamedBufferStorage(buf[0], (GLsizeiptr)(rays * 8 * sizeof(float)), ray, 0);
    glNamedBufferStorage(buf[1], (GLsizeiptr)(rays * 4 * sizeof(float)), NULL,
                         GL_DYNAMIC_STORAGE_BIT);
    glUseProgram(prog);
    avg_grid_bind(g, prog, 8, 9);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, buf[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, buf[1]);
    glUniform1ui(glGetUniformLocation(prog, "u_count"), rays);
    glDispatchCompute((rays + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    float *hit = malloc((size_t)rays * 4 * sizeof *hit);
    glGetNamedBufferSubData(buf[1], 0, (GLsizeiptr)(rays * 4 * sizeof(float)), hit);

    uint32_t both = 0, near = 0, avg_only = 0, embree_only = 0, neither = 0, late = 0, steep = 0,
             steep_near = 0, phantom = 0;
    for (uint32_t i = 0; i < rays; i++) {
        const float *r = &ray[8 * (size_t)i];
        gi_rt_hit h;
        int eh = gi_rt_intersect(rt, gi_v3(r[0], r[1], r[2]), gi_v3(r[4], r[5], r[6]), 0.0f,
                                 INFINITY, &h);
        int ah = hit[4 * i + 3] >= 0.0f;
        if (ah) {
            /* The grid never stops a ray in empty space: some surface lies
             * within two voxel diagonals of where the ray enters the hit voxel. */
            gi_vec3 p = gi_v3(r[0] + r[4] * hit[4 * i + 3], r[1] + r[5] * hit[4 * i + 3],
                              r[2] + r[6] * hit[4 * i + 3]);
            int near_surface = 0;
            for (int k = 0; k < 27 && !near_surface; k++) {
                gi_vec3 dir =
                    gi_v3((float)(k % 3) - 1.0f, (float)(k / 3 % 3) - 1.0f, (float)(k / 9) - 1.0f);
                if (k == 13)
                    continue;
                near_surface =
                    gi_rt_occluded(rt, p, gi_v3_normalize(dir), 0.0f, 2.0f * sqrtf(3.0f) * g->h);
            }
            if (!near_surface) /* probes can pass beside an edge: measure exactly */
                near_surface = scene_distance(s, p) <= 2.0f * sqrtf(3.0f) * g->h;
            phantom += !near_surface;
        }
        if (eh && ah) {
            both++;
            int c[3] = {(int)floorf((h.position.x - g->origin[0]) / g->h),
                        (int)floorf((h.position.y - g->origin[1]) / g->h),
                        (int)floorf((h.position.z - g->origin[2]) / g->h)};
            int cheb = 0;
            for (int a = 0; a < 3; a++) {
                int dd = abs(c[a] - (int)hit[4 * i + a]);
                cheb = dd > cheb ? dd : cheb;
            }
            near += cheb <= 1;
            /* A ray grazing a surface runs through its layer of voxels for
             * about h / tan(angle) before it reaches the surface itself; at
             * angles over 15 degrees the hit voxel must be a neighbour. */
            if (fabsf(gi_v3_dot(h.ng, gi_v3(r[4], r[5], r[6]))) > 0.26f) {
                steep++;
                steep_near += cheb <= 1;
            }
            /* The AVG voxel is entered no later than one voxel diagonal past the real hit. */
            late += hit[4 * i + 3] > h.t + sqrtf(3.0f) * g->h;
        } else if (ah) {
            avg_only++;
        } else if (eh) {
            embree_only++;
        } else {
            neither++;
        }
    }
    printf("march %s n=%u: %u rays: %u hit both (%u = %.2f %% within one voxel; of the %u not "
           "grazing (> 15 deg), "
           "%.2f %%; %u entered late), %u AVG only, %u Embree only (leaks), %u neither; %u AVG "
           "hits far from any surface\n",
           strrchr(scene_path, '/') + 1, n, rays, both, near, 100.0 * near / (both ? both : 1),
           steep, 100.0 * steep_near / (steep ? steep : 1), late, avg_only, embree_only, neither,
           phantom);
    EXPECT(embree_only == 0, "%u rays went through the AVG where Embree hits a surface",
           embree_only);
    /* The rest of the non-grazing hits are rays passing within a voxel of an
     * edge, caught by its conservative voxels (counted, not failed). */
    EXPECT(steep_near >= steep - steep / 10,
           "only %u of %u non-grazing hits within one voxel of the real hit", steep_near, steep);
    EXPECT(phantom == 0, "%u AVG hits with no surface within two voxel diagonals", phantom);
    EXPECT(late == 0, "%u AVG hits lie more than a voxel diagonal behind the real surface", late);
    EXPECT(both > rays / 2, "too few hits (%u) for the test to mean anything", both);
    glDeleteBuffers(2, buf);
    glDeleteProgram(prog);
    free(ray);
    free(hit);
    free(grid);
    gi_rt_free(rt);
    avg_grid_free(g);
    free_fixture(&fx);
}

/* ---- vpls: determinism and the two tracers ---- */

static void vpls_case(gi_gpu *gpu)
{
    fixture fx;
    if (!load_fixture(gpu, GI_SOURCE_DIR "/scenes/cornell_moving.gltf", &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    const char *kv[] = {"vpls=512", "grid=32", "M=4"};
    avg *a = make_avg(&fx.host, gs, kv, 3);
    const char *kx[] = {"vpls=512", "grid=32", "M=4", "tracing=exact"};
    avg *x = make_avg(&fx.host, gs, kx, 4);
    if (!a || !x) {
        EXPECT(0, "cannot make the avg instances");
        return;
    }
    target t = make_target(32, 32);
    gi_view v;
    make_view(s, 0.0f, 32, 32, &v);
    size_t bytes = a->slots * sizeof(avg_vpl);
    avg_vpl *first = malloc(bytes), *moved = malloc(bytes);
    EXPECT(render(a, &v, &t), "frame 1");
    memcpy(first, a->cpu_slots, bytes);
    uint32_t live = a->vpl_count;
    EXPECT(render(a, &v, &t), "frame 2");
    EXPECT(memcmp(first, a->cpu_slots, bytes) == 0,
           "the VPL slots differ between two frames of a still scene");
    EXPECT(a->vpl_count == live && live > a->paths, "live VPLs %u then %u (paths %u)", live,
           a->vpl_count, a->paths);
    /* The bunny moves: the VPLs that hit it move too; back at t = 0 they return. */
    gi_gpu_scene_set_time(gs, 1.3f);
    gi_changes ch = {GI_CHANGED_TRANSFORMS, 1.3f, ~0ull};
    gi_method_entry(GI_ABI_VERSION)->update(a, gs, &ch);
    make_view(s, 1.3f, 32, 32, &v);
    EXPECT(render(a, &v, &t), "moved frame");
    memcpy(moved, a->cpu_slots, bytes);
    EXPECT(memcmp(first, moved, bytes) != 0, "the VPLs did not change when the bunny moved");
    gi_gpu_scene_set_time(gs, 0.0f);
    make_view(s, 0.0f, 32, 32, &v);
    EXPECT(render(a, &v, &t), "frame back at t = 0");
    EXPECT(memcmp(first, a->cpu_slots, bytes) == 0,
           "the VPLs at t = 0 differ after the scene moved and came back");

    /* AVG and exact tracing share the light VPLs (slot 0 of every path):
     * same light choice, same quasi-random numbers, same emitter records. */
    EXPECT(render(x, &v, &t), "exact frame");
    uint32_t stride = (uint32_t)a->bounces + 1, same = 0, hits_a = 0, hits_x = 0;
    double pow_a = 0, pow_x = 0;
    for (uint32_t i = 0; i < a->paths; i++) {
        const avg_vpl *va = &first[i * stride], *vx = &x->cpu_slots[i * stride];
        float dmax = 0.0f;
        for (int c = 0; c < 3; c++) {
            dmax = fmaxf(dmax, fabsf(va->position[c] - vx->position[c]));
            dmax = fmaxf(dmax, fabsf(va->power[c] - vx->power[c]) /
                                   fmaxf(fabsf(vx->power[c]), 1e-6f) * 1e-2f);
        }
        same += dmax < 1e-4f && va->kind == vx->kind;
        for (uint32_t k = 1; k < stride; k++) {
            hits_a += first[i * stride + k].power[0] > 0.0f;
            hits_x += x->cpu_slots[i * stride + k].power[0] > 0.0f;
            pow_a += gi_luminance(first[i * stride + k].power);
            pow_x += gi_luminance(x->cpu_slots[i * stride + k].power);
        }
    }
    printf("vpls: %u slots, %u live; light VPLs equal in AVG and exact tracing: %u of %u; bounce "
           "VPLs %u (AVG) vs "
           "%u (exact), their total power %.4g vs %.4g (%+.1f %%)\n",
           a->slots, live, same, a->paths, hits_a, hits_x, pow_a, pow_x,
           100.0 * (pow_a - pow_x) / pow_x);
    EXPECT(same == a->paths, "only %u of %u light VPLs agree between AVG and exact tracing", same,
           a->paths);
    EXPECT(fabs(pow_a - pow_x) < 0.25 * pow_x, "bounce VPL power differs by more than 25 %%");
    const gi_method *m = gi_method_entry(GI_ABI_VERSION);
    m->destroy(a);
    m->destroy(x);
    free(first);
    free(moved);
    free_fixture(&fx);
}

/* ---- shade: interleaved shading against the plain sum ---- */

static void shade_case(gi_gpu *gpu, int M, int filter)
{
    fixture fx;
    if (!load_fixture(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    char m_kv[16], f_kv[16];
    snprintf(m_kv, sizeof m_kv, "M=%d", M);
    snprintf(f_kv, sizeof f_kv, "filter=%d", filter);
    const char *kv[] = {"vpls=256", "grid=32", m_kv, f_kv, "visibility=false"};
    avg *a = make_avg(&fx.host, gs, kv, 5);
    if (!a) {
        EXPECT(0, "cannot make the avg instance");
        return;
    }
    uint32_t w = 30, h = 26; /* not multiples of 4: partial sub-images */
    target t = render_frame(a, s, w, h);
    gi_image *img = gi_gpu_read_texture(t.tex, w, h);
    gbuffer_images gb = read_gbuffer(a, w, h);
    const gi_image *pos = gb.pos, *nrm = gb.nrm, *alb = gb.alb, *emi = gb.emi;
    float dmin = a->clamp * a->grid->h;
    double worst = 0.0;
    uint32_t lit = 0;
    for (uint32_t row = 0; row < h; row++) {
        uint32_t gl_row = h - 1 - row; /* images are top row first; subsets follow GL rows */
        for (uint32_t col = 0; col < w; col++) {
            size_t i = 4 * ((size_t)row * w + col);
            if (pos->rgba[i + 3] <= 0.0f)
                continue;
            uint32_t m = (gl_row % (uint32_t)a->mx) * (uint32_t)a->mx + col % (uint32_t)a->mx;
            float n[3] = {nrm->rgba[i], nrm->rgba[i + 1], nrm->rgba[i + 2]};
            float ln = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int c = 0; c < 3; c++)
                n[c] /= ln;
            double S[3] = {0, 0, 0};
            for (uint32_t j = M == 1 ? 0 : m; j < a->vpl_count; j += (uint32_t)M) {
                float c3[3];
                avg_vpl_contribution(&a->cpu_vpls[j], &pos->rgba[i], n, dmin * dmin, c3);
                for (int c = 0; c < 3; c++)
                    S[c] += c3[c];
            }
            for (int c = 0; c < 3; c++) {
                double expect = emi->rgba[i + c] + alb->rgba[i + c] / GI_PI * S[c] * M;
                double got = img->rgba[i + c];
                double rel = fabs(got - expect) / (fabs(expect) + 1e-3);
                worst = rel > worst ? rel : worst;
            }
            lit++;
        }
    }
    printf("shade M=%d filter=%d: %u pixels, %u VPLs, largest relative difference to the CPU sum "
           "%.2e\n",
           M, filter, lit, a->vpl_count, worst);
    EXPECT(lit > w * h / 2, "only %u pixels hit the scene", lit);
    EXPECT(worst < 1e-3, "GPU shading differs from the CPU sum by %.3g (relative)", worst);
    gi_image_free(img);
    free_gbuffer_images(&gb);
    gi_method_entry(GI_ABI_VERSION)->destroy(a);
    free_fixture(&fx);
}

/* ---- visibility: the VPL shadow maps against Embree ---- */

/* The shadow-map test of avg_visibility.glsl on the CPU (same offsets and
 * biases as avg.c), given the atlas tiles read back: 1 visible, 0 shadowed. */
static int map_visible(const avg *a, const float *tiles, uint32_t j, gi_vec3 x, gi_vec3 n,
                       float bias_abs, float bias_rel)
{
    const gi_depth_atlas_desc *d = gi_depth_atlas_get_desc(a->atlas);
    uint32_t tx, ty;
    float zp;
    gi_vec3 xo = gi_v3_add(x, gi_v3_scale(n, bias_abs));
    if (!gi_depth_atlas_texel(&a->views[j], d->projection, d->metric, d->tile, xo, &tx, &ty, &zp))
        return 1;
    float zmap = tiles[(size_t)j * d->tile * d->tile + (size_t)ty * d->tile + tx];
    gi_vec3 w = gi_v3_normalize(gi_v3_sub(gi_v3_load(a->cpu_vpls[j].position), x));
    float c = fminf(fmaxf(gi_v3_dot(n, w), 0.05f), 1.0f);
    float slope = fminf(sqrtf(1.0f - c * c) / c, 10.0f);
    return zp <= zmap + bias_abs + bias_rel * (1.0f + slope) * zp;
}

static void visibility_case(gi_gpu *gpu, const char *scene, const char *projection, const char *lod)
{
    gi_error err;
    fixture fx;
    if (!load_fixture(gpu, scene, &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    char pkv[64], lkv[64];
    snprintf(pkv, sizeof pkv, "projection=%s", projection);
    snprintf(lkv, sizeof lkv, "shadow_lod=%s", lod);
    const char *kv[] = {"vpls=256", "grid=32", pkv, lkv};
    avg *a = make_avg(&fx.host, gs, kv, 4);
    gi_rt *rt = NULL;
    if (!a || gi_rt_create(s, 0.0f, &rt, &err) != GI_OK) {
        EXPECT(0, "cannot make the avg instance or the ray caster");
        return;
    }
    uint32_t w = 32, h = 32;
    render_frame(a, s, w, h);
    const gi_depth_atlas_desc *d = gi_depth_atlas_get_desc(a->atlas);
    float *tiles = malloc((size_t)a->vpl_count * d->tile * d->tile * sizeof *tiles);
    for (uint32_t j = 0; j < a->vpl_count; j++) {
        float *tile = gi_depth_atlas_read_tile(a->atlas, j);
        memcpy(tiles + (size_t)j * d->tile * d->tile, tile,
               (size_t)d->tile * d->tile * sizeof *tiles);
        free(tile);
    }
    gbuffer_images gb = read_gbuffer(a, w, h);
    const gi_image *pos = gb.pos, *nrm = gb.nrm;
    uint32_t pairs = 0, agree = 0, false_shadow = 0, false_light = 0;
    vis_score score = {0};
    float bias_abs = 0.5f * a->grid->h, bias_rel = 1.0f / (float)a->tile; /* AVG_BIAS_* in avg.c */
    for (size_t i = 0; i < (size_t)w * h; i++) {
        if (pos->rgba[4 * i + 3] <= 0.0f)
            continue;
        gi_vec3 x = gi_v3_load(&pos->rgba[4 * i]),
                n = gi_v3_normalize(gi_v3_load(&nrm->rgba[4 * i]));
        for (uint32_t j = 0; j < a->vpl_count; j++) {
            float c3[3];
            avg_vpl_contribution(&a->cpu_vpls[j], &pos->rgba[4 * i], &nrm->rgba[4 * i], 0.0f, c3);
            if (c3[0] + c3[1] + c3[2] <= 0.0f || (a->cpu_vpls[j].kind >> 8 & 0xFFu) != 0)
                continue;
            gi_vec3 y = gi_v3_load(a->cpu_vpls[j].position);
            gi_vec3 dir = gi_v3_sub(y, x);
            float dist = gi_v3_length(dir);
            /* Ray from just off the receiver to just short of the VPL. */
            int blocked = gi_rt_occluded(rt, gi_v3_add(x, gi_v3_scale(n, 1e-3f)),
                                         gi_v3_scale(dir, 1.0f / dist), 0.0f, dist - 1e-2f);
            int vis = map_visible(a, tiles, j, x, n, bias_abs, bias_rel);
            pairs++;
            agree += vis == !blocked;
            vis_add(&score, !blocked, vis);
            false_shadow += !vis && !blocked;
            false_light += vis && blocked;
        }
    }
    const char *used = gi_depth_atlas_get_desc(a->atlas)->projection == GI_PROJ_PARABOLOID
                           ? "paraboloid"
                           : "perspective";
    printf("visibility %s %s (%s maps) shadow_lod=%s (%u triangles a map): %u receiver-VPL pairs, "
           "shadow maps agree "
           "with Embree on %.2f %% (%u falsely shadowed, %u falsely lit)\n",
           strrchr(scene, '/') + 1, projection, used, lod,
           a->lod ? a->lod->triangle_count : s->triangle_count, pairs,
           100.0 * agree / (pairs ? pairs : 1), false_shadow, false_light);
    EXPECT(agree >= pairs - pairs / 20, "shadow maps agree with ray casting on only %u of %u pairs",
           agree, pairs);
    EXPECT(pairs > 10000, "too few pairs (%u)", pairs);
    char what[96];
    snprintf(what, sizeof what, "visibility %s shadow_lod=%s, light-VPL shadow maps vs Embree",
             projection, lod);
    gi_test_failed += vis_check(&score, what, VIS_MARGIN, 1000);
    free(tiles);
    free_gbuffer_images(&gb);
    gi_rt_free(rt);
    gi_method_entry(GI_ABI_VERSION)->destroy(a);
    free_fixture(&fx);
}

/* ---- punctual: point and spot lights through their VPLs ---- */

/* tests/data/valid/lights.gltf (an emissive quad, a point, a spot and a
 * directional light over a floor) with direct light only, no visibility,
 * M = 1: the image must equal emission + albedo/pi x (the area-light VPLs'
 * sum + the exact point and spot light irradiance). The point light's VPLs
 * each cover one hemisphere at twice the intensity and the paths are split
 * among the lights by power, so this holds the split and the hemispheres
 * to the closed form (up to the rounding of path counts: 4096 paths). The
 * directional light is ignored by the method and by this sum. */
static void punctual_case(gi_gpu *gpu)
{
    fixture fx;
    if (!load_fixture(gpu, GI_SOURCE_DIR "/tests/data/valid/lights.gltf", &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    const char *kv[] = {"vpls=4096", "bounces=0",    "grid=16",
                        "M=1",       "filter=false", "visibility=false"};
    avg *a = make_avg(&fx.host, gs, kv, 6);
    if (!a) {
        EXPECT(0, "cannot make the avg instance");
        return;
    }
    uint32_t w = 48, h = 48;
    target t = render_frame(a, s, w, h);
    gi_image *img = gi_gpu_read_texture(t.tex, w, h);
    gbuffer_images gb = read_gbuffer(a, w, h);
    const gi_image *pos = gb.pos, *nrm = gb.nrm, *alb = gb.alb, *emi = gb.emi;
    float dmin2 = a->clamp * a->grid->h * a->clamp * a->grid->h;
    double worst = 0.0, sum_got = 0.0, sum_expect = 0.0, punctual_share = 0.0;
    uint32_t lit = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) {
        /* Receivers only: the lamp seen directly is exact either way. */
        if (pos->rgba[4 * i + 3] <= 0.0f ||
            emi->rgba[4 * i] + emi->rgba[4 * i + 1] + emi->rgba[4 * i + 2] > 0.0f)
            continue;
        gi_vec3 x = gi_v3_load(&pos->rgba[4 * i]),
                n = gi_v3_normalize(gi_v3_load(&nrm->rgba[4 * i]));
        double S[3] = {0, 0, 0}, P[3] = {0, 0, 0};
        for (uint32_t j = 0; j < a->vpl_count; j++) {
            if ((a->cpu_vpls[j].kind & 0xFFu) != AVG_VPL_DIFFUSE)
                continue;
            float c3[3], nn[3] = {n.x, n.y, n.z};
            avg_vpl_contribution(&a->cpu_vpls[j], &pos->rgba[4 * i], nn, dmin2, c3);
            for (int c = 0; c < 3; c++)
                S[c] += c3[c];
        }
        for (uint32_t l = 0; l < s->light_count; l++) {
            const gi_light *L = &s->lights[l];
            if (L->type == GI_LIGHT_DIRECTIONAL)
                continue;
            gi_light_frame f = gi_scene_light_at(s, l, 0.0f);
            gi_vec3 d = gi_v3_sub(f.position, x);
            float d2 = gi_v3_dot(d, d), dist = sqrtf(d2);
            gi_vec3 wl = gi_v3_scale(d, 1.0f / dist);
            float cx = gi_v3_dot(n, wl);
            if (cx <= 0.0f)
                continue;
            float g = cx / fmaxf(d2, dmin2) * gi_range_window(dist, L->range);
            if (L->type == GI_LIGHT_SPOT)
                g *= gi_spot_falloff(-gi_v3_dot(wl, f.direction), cosf(L->inner_cone),
                                     cosf(L->outer_cone));
            for (int c = 0; c < 3; c++)
                P[c] += L->intensity[c] * g;
        }
        for (int c = 0; c < 3; c++) {
            double expect = emi->rgba[4 * i + c] + alb->rgba[4 * i + c] / GI_PI * (S[c] + P[c]);
            double got = img->rgba[4 * i + c];
            sum_got += got;
            sum_expect += expect;
            punctual_share += alb->rgba[4 * i + c] / GI_PI * P[c];
            double rel = fabs(got - expect) / (fabs(expect) + 1e-3);
            worst = rel > worst ? rel : worst;
        }
        lit++;
    }
    printf("punctual: %u receiver pixels, %u VPLs, point and spot lights %.0f %% of their light; "
           "image sum %.5g against the "
           "closed form %.5g (%+.3f %%), largest pixel difference %.2f %%\n",
           lit, a->vpl_count, 100.0 * punctual_share / sum_expect, sum_got, sum_expect,
           100.0 * (sum_got - sum_expect) / sum_expect, 100.0 * worst);
    EXPECT(punctual_share > 0.2 * sum_expect,
           "the punctual lights carry too little of the light to test them");
    EXPECT(fabs(sum_got - sum_expect) < 0.01 * sum_expect, "image sum off by more than 1 %%");
    EXPECT(worst < 0.03, "a pixel differs by %.3g (relative)", worst);
    gi_image_free(img);
    free_gbuffer_images(&gb);
    gi_method_entry(GI_ABI_VERSION)->destroy(a);
    free_fixture(&fx);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: avg_tests voxel|deform|march|vpls|shade|visibility|punctual\n");
        return 2;
    }
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    if (!gpu) {
        fprintf(stderr, "no GL: %s\n", err.text);
        return 1;
    }
    if (gi_shader_register(gi_avg_shaders, &err) != GI_OK) {
        fprintf(stderr, "shaders: %s\n", err.text);
        return 1;
    }
    if (!strcmp(argv[1], "voxel")) {
        voxel_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", (const float[]){0.0f}, 1, 32);
        voxel_case(gpu, GI_SOURCE_DIR "/scenes/cornell_moving.gltf", (const float[]){1.3f}, 1, 40);
    } else if (!strcmp(argv[1], "deform")) {
        /* The short block morphing: rest, stretched, stretched and bulged,
         * half way back, bulged only; then the rest pose again. */
        deform_case(gpu);
    } else if (!strcmp(argv[1], "march")) {
        march_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", 32, 4096);
        march_case(gpu, GI_SOURCE_DIR "/scenes/u_room.gltf", 48, 4096);
    } else if (!strcmp(argv[1], "vpls")) {
        vpls_case(gpu);
    } else if (!strcmp(argv[1], "shade")) {
        shade_case(gpu, 1, 1);
        shade_case(gpu, 16, 0);
        shade_case(gpu, 9, 0);
    } else if (!strcmp(argv[1], "punctual")) {
        punctual_case(gpu);
    } else if (!strcmp(argv[1], "visibility")) {
        visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", "paraboloid", "1");
        visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", "perspective", "1");
        /* Maps of the lower-detail copy (the auto rule then picks
         * perspective maps) against rays through the full scene. */
        visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", "auto", "0.1");
        visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_moving.gltf", "auto", "0.1");
    } else {
        fprintf(stderr, "unknown test '%s'\n", argv[1]);
        return 2;
    }
    gi_gpu_destroy(gpu);
    if (gi_test_failed)
        fprintf(stderr, "%d failure(s)\n", gi_test_failed);
    return gi_test_failed ? 1 : 0;
}

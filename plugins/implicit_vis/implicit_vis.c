/* The `implicit_vis` method: Interactive Global Illumination Using Implicit
 * Visibility (Dong, Kautz, Theobalt, Seidel, PG 2007).
 *
 * prepare(): surface elements and the geometric hierarchy (Algorithm 1,
 * lines 1-2; elements.c, hierarchy.c). Every frame (lines 3-11), each a
 * stage timer named as the paper's Table 1:
 *   update_elements  positions, normals, areas at the frame's time, bottom-up;
 *   create_links     the hierarchical links in world-aligned 6 x N x N bins,
 *                    the shortest per bin (implicit visibility);
 *   refine_push      refinement and push-down to unidirectional leaf links;
 *   illumination     direct light along the light links, the environment
 *                    through empty bins, punctual lights through their bin,
 *                    then `bounces` gathers and pull-ups: compute shaders
 *                    over the flattened links (iv_gpu.c, Sec. 4.3.1), or
 *                    with `illum=cpu` the same on one CPU thread
 *                    (illuminate.c);
 *   display          the G-buffer and the per-vertex irradiance
 *                    interpolated per pixel (shaders/iv_display.comp), plus,
 *                    on glossy materials, the BRDF-weighted sum of the
 *                    direct light over the elements' bins (Sec. 4.3).
 * The hierarchy and the links are built on the CPU (hierarchy.c,
 * links.c; the links on `threads` threads, links_threads.c); the
 * gathering and pull-up and the display run on the GPU. */
#define _POSIX_C_SOURCE 200809L
#include "iv.h"
#include "iv_debug.h"
#include "iv_gpu.h"
#include "iv_traced.h"
#include "shaders/iv_bindings.h"

#include "gi/kit.h"
#include "gi/shader.h"
#include "gi/log.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Bins x nodes x 8 bytes (link, distance; 12 with the coverage where read) above this are
 * refused with a message. */
#define IV_MAX_LINK_BYTES (3ull << 30)
/* Brute force compares every two leaves: refused above this many. */
#define IV_MAX_BRUTE_ELEMENTS 40000u

extern const gi_shader_source gi_implicit_vis_shaders[];

static const gi_param_desc iv_params[] = {
    {"N", GI_PARAM_INT, 12, 1, 32,
     GI_QUALITY_NONE(
         "the error need not fall with N: under Eq. 5 as printed (the default) a bin "
         "counts only its nearest node (README \"Weights\"); at the held-out remedy it "
         "rises along a room's edges where a lamp is flush under the ceiling (seed 1 "
         "ceiling, 32^2: 0.0033 at N 12, 0.0058 at 32; README \"Traced direct light\")"),
     "N (Sec. 4.2.2, 6 x N x N bins; Table 1: 8, 12, 16)",
     "bins per cube-map side of every node (more = finer bins; the error does not always fall: "
     "README \"Weights\", \"Traced direct light\"; furnace -35/-27/-17/-3 % at N 8/12/16/24 "
     "under Eq. 5 as printed, weight=surface converges there)"},
    {"bounces", GI_PARAM_INT, 3, 0, 3, NULL, "light bounces (Algorithm 1, line 8)",
     "indirect bounces after the direct light (Table 1: 1)"},
    {"subdiv", GI_PARAM_FLOAT, 1.0, 0.01, 100.0, GI_QUALITY_DOWN(2), "Sec. 4.2.2",
     "a node is subdivided while its solid angle seen from the other end exceeds this many bins' "
     "solid angle"},
    {"links", GI_PARAM_ENUM, 0, 0, 0, "hierarchical|brute", "Sec. 4.2 / 3.1 (Fig. 10 b, c)",
     "hierarchical links, or every leaf against every leaf"},
    {"remesh", GI_PARAM_FLOAT, 0.0, 0.0, 1.0, NULL, "Sec. 5.1 (re-meshing)",
     "target edge length as a fraction of the scene's largest extent (re-meshed by `remesher`); 0 "
     "= the model's own vertices"},
    {"remesher", GI_PARAM_ENUM, 0, 0, 0, "isotropic|grid", "Sec. 5.1 (re-meshing)",
     "isotropic: CGAL's isotropic re-meshing, each new vertex on an original triangle; grid: each "
     "triangle subdivided into a k x k grid"},
    {"bilinear", GI_PARAM_BOOL, 0, 0, 1, NULL, "Sec. 4.2.2 (deviation)",
     "a link goes into the four bins around its direction, each with its share of the node's solid "
     "angle (README \"Deviations\")"},
    {"coverage", GI_PARAM_FLOAT, 0.0, 0.0, 1.0, NULL, "Eq. 4 / Eq. 5 (deviation)",
     "a bin whose links' solid angles sum to less than this share of it passes light through that "
     "share only; 0: Eq. 5 (the nearest covers the bin)"},
    {"weight", GI_PARAM_ENUM, 0, 0, 0, "eq5|bin|surface", "Eq. 5 / Eq. 4 (README \"Weights\")",
     "a link's weight in its bin: eq5 the linked node's own solid angle (as printed); bin the "
     "bin's solid angle (nearest covers it); surface every node of the nearest surface in the bin"},
    {"splat", GI_PARAM_BOOL, 0, 0, 1, NULL, "Sec. 3 (an element covers its bin)",
     "a disc nearer than its size covers every bin it spans, not only its centre's (README "
     "\"Deviations\")"},
    {"threads", GI_PARAM_INT, 0, 0, 256, NULL, "Table 1 (create_links on the CPU)",
     "threads that create the hierarchical links (the same links as on one); 0 = every online "
     "core"},
    {"keep_pairs", GI_PARAM_BOOL, 1, 0, 1, NULL, "Algorithm 1, line 5 (the same links)",
     "the pairs Sec. 4.2.2 links between two segments of which neither moved since the last "
     "build are taken from it, not tested anew; every pair is still written into the bins, the "
     "links are the same; not with relink=always (README \"Pairs of still segments\")"},
    {"glossy", GI_PARAM_BOOL, 1, 0, 1, NULL, "Sec. 4.3 (glossy direct light, Fig. 11)",
     "glossy (Phong) materials reflect the direct light through their lobe, the BRDF-weighted sum "
     "over each element's bins; false: diffuse only"},
    {"illum", GI_PARAM_ENUM, 0, 0, 0, "gpu|cpu", "Sec. 4.3.1 (GPU implementation)",
     "where the gathering and pull-up run: compute shaders over the flattened links, or one CPU "
     "thread"},
    {"direct", GI_PARAM_ENUM, 0, 0, 0, "links|traced", "Sec. 4.3 (traced: deviation, issue 28)",
     "the direct light: links, along the light links with implicit visibility (the paper); "
     "traced, by shadow rays at every element and every pixel, the bounces still along the links "
     "(README \"Traced direct light\")"},
    {"direct_samples", GI_PARAM_INT, 64, 1, 4096, GI_QUALITY_UP(2), "(direct=traced only)",
     "shadow rays per element and per pixel for the area lights, as many for the environment "
     "(direct=traced)"},
    {"relink", GI_PARAM_ENUM, 0, 0, 0, "moved|always", "Algorithm 1, lines 3-6",
     "when the elements are updated and the links created and pushed down: moved, on a frame "
     "where something moved or changed (the same image; a still frame reuses them); always, "
     "every frame as Algorithm 1 (the timing of Table 1)"},
    {0},
};

typedef struct implicit_vis {
    gi_kit kit;
    int N, bounces, brute, splat, bilinear, cpu_illum, remesher, threads, keep_pairs;
    int weight; /* IV_WEIGHT_* */
    int glossy; /* the display adds the glossy direct light (a glossy material, glossy=true) */
    int traced; /* direct=traced: the direct light by shadow rays (iv_traced.h) */
    int direct_samples;
    int warned_cpu;    /* the links outgrew one GL storage block once: warned */
    int relink_always; /* relink=always: Algorithm 1 lines 3-6 on every frame */
    int scene_static;  /* nothing in the scene moves with time */
    int links_valid;   /* the links were made for links_time and nothing changed since */
    float links_time;
    int light_valid;  /* the elements' light of the last frame still holds (relink=moved) */
    int light_on_cpu; /* where that light is (illuminate's on_cpu) */
    float subdiv, remesh, coverage;
    iv_hier *hier;
    iv_links *links;
    iv_gpu *gpu;              /* the GPU illumination (illum=gpu) */
    iv_traced *traced_direct; /* direct=traced */
    float *irr;               /* 6 per element */
    float *elem_light;        /* 12 per element: e_front, e_back, normal (vec4 each) */
    GLuint ssbo_light, ssbo_tri, ssbo_grid;
    GLuint prog_display;
} implicit_vis;

static gi_result iv_create(const gi_host *host, const gi_params *params, void **out)
{
    implicit_vis *m = calloc(1, sizeof *m);
    if (!m)
        return GI_ERR_OUT_OF_MEMORY;
    if (gi_kit_init(&m->kit, host, gi_implicit_vis_shaders) != GI_OK) {
        free(m);
        return GI_ERR_INVALID_ARGUMENT;
    }
    m->N = gi_params_int(params, "N");
    m->bounces = gi_params_int(params, "bounces");
    m->subdiv = gi_params_float(params, "subdiv");
    m->remesh = gi_params_float(params, "remesh");
    m->remesher = gi_params_enum(params, "remesher") == 1 ? IV_REMESH_GRID : IV_REMESH_ISOTROPIC;
    m->brute = gi_params_enum(params, "links") == 1;
    m->splat = gi_params_bool(params, "splat");
    m->weight = gi_params_enum(params, "weight");
    m->bilinear = gi_params_bool(params, "bilinear");
    m->keep_pairs = gi_params_bool(params, "keep_pairs");
    m->coverage = gi_params_float(params, "coverage");
    m->cpu_illum = gi_params_enum(params, "illum") == 1;
    m->threads = gi_params_int(params, "threads");
    m->glossy = gi_params_bool(params, "glossy");
    m->traced = gi_params_enum(params, "direct") == 1;
    m->direct_samples = gi_params_int(params, "direct_samples");
    m->relink_always = gi_params_enum(params, "relink") == 1;
    if (m->threads == 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        m->threads = n > 0 ? (n > 256 ? 256 : (int)n) : 1;
    }
    *out = m;
    return GI_OK;
}

/* Whether nothing in the scene moves with time: then links made at one
 * time hold at every other. */
static int scene_is_static(const gi_gpu_scene *gs)
{
    const gi_scene *s = gs->scene;
    if (gs->deforming || gi_scene_lights_animated(s))
        return 0;
    for (uint32_t k = 0; k < s->object_count; k++)
        if (s->objects[k].animated || s->objects[k].morph_track.count)
            return 0;
    return 1;
}

static void release_prepared(implicit_vis *m)
{
    iv_gpu_free(m->gpu);
    iv_traced_free(m->traced_direct);
    m->traced_direct = NULL;
    iv_links_free(m->links);
    iv_hier_free(m->hier);
    free(m->irr);
    free(m->elem_light);
    GLuint bufs[3] = {m->ssbo_light, m->ssbo_tri, m->ssbo_grid};
    for (int i = 0; i < 3; i++)
        if (bufs[i])
            glDeleteBuffers(1, &bufs[i]);
    if (m->prog_display)
        glDeleteProgram(m->prog_display);
    m->gpu = NULL;
    m->links = NULL;
    m->hier = NULL;
    m->irr = m->elem_light = NULL;
    m->ssbo_light = m->ssbo_tri = m->ssbo_grid = m->prog_display = 0;
}

/* The links' memory (bins x nodes x 12 bytes) and brute force's element
 * count, refused above their limits. */
static gi_result check_limits(implicit_vis *m)
{
    /* a cell (link and length), and the coverage where the modes read it */
    unsigned long long cell =
        sizeof(iv_cell) + (m->coverage > 0.0f || m->weight == IV_WEIGHT_SURFACE ? 4ull : 0ull);
    unsigned long long bytes =
        6ull * (unsigned long long)m->N * (unsigned long long)m->N * m->hier->node_count * cell;
    if (bytes > IV_MAX_LINK_BYTES)
        return gi_kit_fail(&m->kit, GI_ERR_UNSUPPORTED,
                           "implicit_vis: %u nodes x 6 x %d x %d bins need %.1f GiB of links "
                           "(limit 3 GiB): lower N",
                           m->hier->node_count, m->N, m->N, (double)bytes / (1u << 30));
    if (m->brute && m->hier->elem_count > IV_MAX_BRUTE_ELEMENTS)
        return gi_kit_fail(&m->kit, GI_ERR_UNSUPPORTED,
                           "implicit_vis: links=brute compares every two of %u elements (limit "
                           "%u): use links=hierarchical",
                           m->hier->elem_count, IV_MAX_BRUTE_ELEMENTS);
    return GI_OK;
}

/* The display's look-up: triangle -> (k, first grid point), grid point
 * -> three elements and their weights (uvec4, vec4), filled into tri and
 * grid (freed here) and uploaded. */
static void upload_display_grid(implicit_vis *m, const gi_scene *s, uint32_t *tri, uint32_t *grid)
{
    const iv_hier *h = m->hier;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        tri[2 * t] = h->tri_k[t];
        tri[2 * t + 1] = h->tri_grid[t];
    }
    for (uint32_t d = 0; d < h->disp_count; d++) {
        memcpy(&grid[8 * (size_t)d], &h->disp_elem[3 * (size_t)d], 3 * sizeof(uint32_t));
        grid[8 * (size_t)d + 3] = 0;
        memcpy(&grid[8 * (size_t)d + 4], &h->disp_w[3 * (size_t)d], 3 * sizeof(float));
        grid[8 * (size_t)d + 7] = 0;
    }
    glCreateBuffers(1, &m->ssbo_tri);
    glNamedBufferStorage(m->ssbo_tri,
                         (GLsizeiptr)((size_t)s->triangle_count * 2 * sizeof(uint32_t)), tri, 0);
    glCreateBuffers(1, &m->ssbo_grid);
    glNamedBufferStorage(m->ssbo_grid, (GLsizeiptr)((size_t)h->disp_count * 8 * sizeof(uint32_t)),
                         grid, 0);
    free(tri), free(grid);
}

/* Whether the scene has a glossy material: a Phong lobe (a mirror's delta
 * lobe is not handled: no GI_CAP_MIRROR). */
static int scene_glossy(const gi_scene *s)
{
    int glossy = 0;
    for (uint32_t i = 0; i < s->material_count; i++) {
        const gi_material *mat = &s->materials[i];
        glossy |= mat->ks[0] + mat->ks[1] + mat->ks[2] > 0.0f && !mat->mirror &&
                  mat->exponent < GI_MIRROR_EXPONENT;
    }
    return glossy;
}

/* The hierarchy's sizes and the surface's edge lengths, as stats. */
static void report_hierarchy(const implicit_vis *m, const gi_scene *s)
{
    const gi_host *host = m->kit.host;
    host->stat(host, "elements", (double)m->hier->elem_count);
    host->stat(host, "nodes", (double)m->hier->node_count);
    host->stat(host, "segments", (double)m->hier->segment_count);
    host->stat(host, "link_threads", (double)m->threads);
    host->stat(host, "surface_points", (double)m->hier->sample_count);
    host->stat(host, "surface_triangles", (double)m->hier->surf_count);
    double edge_mean, edge_cv;
    iv_hier_edge_stats(m->hier, s, &edge_mean, &edge_cv);
    host->stat(host, "edge_mean", edge_mean);
    host->stat(host, "edge_cv", edge_cv);
}

static gi_result iv_prepare(void *inst, const gi_gpu_scene *gs)
{
    implicit_vis *m = inst;
    gi_error err;
    release_prepared(m);
    gi_kit_prepare(&m->kit, gs);
    const gi_scene *s = gs->scene;
    const gi_host *host = m->kit.host;
    host->stage_begin(host, "hierarchy");
    float ext = 0.0f;
    for (int c = 0; c < 3; c++)
        ext = fmaxf(ext, s->bounds[3 + c] - s->bounds[c]);
    m->hier = iv_hier_create(s, m->remesh * ext, m->remesher, &err);
    host->stage_end(host, "hierarchy");
    if (!m->hier)
        return gi_kit_fail_with(&m->kit, GI_ERR_INVALID_ARGUMENT, &err);
    gi_result r = check_limits(m);
    if (r != GI_OK)
        return r;
    m->links = iv_links_create(m->hier, (uint32_t)m->N);
    if (m->links) {
        m->links->bilinear = m->bilinear;
        m->links->coverage = m->coverage;
        m->links->weight = m->weight;
        m->links->threads = (uint32_t)m->threads;
        /* relink=always is Algorithm 1 as printed, every pair tested every
         * frame (the stage times of Table 1): nothing kept */
        m->links->keep_pairs = m->keep_pairs && !m->relink_always;
        m->links->host = host; /* link creation stops on a cancel (issue 32) */
    }
    m->irr = calloc((size_t)m->hier->elem_count * 6, sizeof(float));
    m->elem_light = calloc((size_t)m->hier->elem_count * 12, sizeof(float));
    uint32_t *tri = malloc(((size_t)s->triangle_count * 2 + 1) * sizeof(uint32_t));
    uint32_t *grid = malloc(((size_t)m->hier->disp_count * 8 + 1) * sizeof(uint32_t));
    if (!m->links || !m->irr || !m->elem_light || !tri || !grid) {
        free(tri), free(grid);
        return gi_kit_fail(&m->kit, GI_ERR_OUT_OF_MEMORY,
                           "implicit_vis: out of memory for the links of %u nodes",
                           m->hier->node_count);
    }
    upload_display_grid(m, s, tri, grid);
    glCreateBuffers(1, &m->ssbo_light);
    glNamedBufferStorage(m->ssbo_light,
                         (GLsizeiptr)((size_t)m->hier->elem_count * 12 * sizeof(float)), NULL,
                         GL_DYNAMIC_STORAGE_BIT);
    m->glossy = m->glossy != 0 && scene_glossy(s);
    if (m->glossy && m->cpu_illum)
        return gi_kit_fail(&m->kit, GI_ERR_UNSUPPORTED,
                           "implicit_vis: glossy materials need illum=gpu (the display reads the "
                           "GPU's links); use "
                           "illum=gpu or glossy=false");
    char defines[64];
    snprintf(defines, sizeof defines, "%s%s", m->glossy ? "#define IV_GLOSSY 1\n" : "",
             m->traced ? "#define IV_TRACED 1\n" : "");
    m->prog_display =
        gi_program_build_compute("iv_display.comp", defines[0] ? defines : NULL, &err);
    if (!m->prog_display)
        return gi_kit_fail_with(&m->kit, GI_ERR_GL, &err);
    if (!m->cpu_illum) {
        m->gpu = iv_gpu_create(m->hier, m->links, s->envmap, &err);
        if (!m->gpu)
            return gi_kit_fail_with(&m->kit, GI_ERR_GL, &err);
        m->gpu->keep_emit = m->glossy;
    }
    if (m->traced) {
        m->traced_direct =
            iv_traced_create(s, gs->time, m->hier->elem_count, (uint32_t)m->direct_samples,
                             (uint32_t)m->threads, &err);
        if (!m->traced_direct)
            return gi_kit_fail_with(&m->kit, GI_ERR_INVALID_ARGUMENT, &err);
    }
    m->scene_static = scene_is_static(gs);
    m->links_valid = m->light_valid = 0;
    report_hierarchy(m, s);
    if (gi_gl_check("implicit_vis: prepare", &err) != GI_OK)
        return gi_kit_fail_with(&m->kit, GI_ERR_GL, &err);
    return GI_OK;
}

static gi_result iv_update(void *inst, const gi_gpu_scene *gs, const gi_changes *changes)
{
    /* Algorithm 1 rebuilds everything but the hierarchy every frame; the
     * links depend only on where the elements and emitters are, so a change
     * of anything but the camera makes them stale (iv_render rebuilds). */
    implicit_vis *m = inst;
    if (changes->flags & ~(uint32_t)GI_CHANGED_CAMERA)
        m->links_valid = 0;
    gi_kit_update(&m->kit, gs, changes);
    return GI_OK;
}

/* Algorithm 1, lines 3-6: the elements at the frame's time, the
 * hierarchical links and their push-down, each a stage of Table 1. With
 * relink=moved they are kept from the last frame when nothing moved since
 * (stat links_reused); the stages are still recorded, near zero. */
static gi_result update_links(implicit_vis *m, const gi_gpu_scene *gs)
{
    const gi_host *host = m->kit.host;
    int reuse =
        !m->relink_always && m->links_valid && (m->scene_static || m->links_time == gs->time);
    host->stage_begin(host, "update_elements");
    if (!reuse)
        iv_hier_update(m->hier, gs->scene, gs->time);
    host->stage_end(host, "update_elements");

    host->stage_begin(host, "create_links");
    if (!reuse)
        iv_links_build(m->links, m->hier, m->subdiv, m->brute, m->splat);
    host->stage_end(host, "create_links");
    if (m->links->oom) {
        m->links_valid = 0;
        return gi_kit_fail(&m->kit, GI_ERR_OUT_OF_MEMORY,
                           "implicit_vis: out of memory for the links' coverage");
    }
    if (m->links->stopped) {
        m->links_valid = 0;
        return gi_kit_fail(&m->kit, GI_ERR_CANCELLED, "implicit_vis: link creation cancelled");
    }
    host->stage_begin(host, "refine_push");
    if (!reuse)
        iv_links_refine_push(m->links, m->hier);
    host->stage_end(host, "refine_push");
    if (!reuse && m->gpu)
        m->gpu->links_current = 0;
    if (!reuse)
        m->light_valid = 0;
    m->links_valid = 1;
    m->links_time = gs->time;
    host->stat(host, "links_reused", reuse ? 1.0 : 0.0);
    return GI_OK;
}

/* Each element's irradiance (both sides) and normal, for the display. */
static void upload_elem_light(implicit_vis *m)
{
    const iv_hier *h = m->hier;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        float *o = &m->elem_light[12 * (size_t)e];
        memcpy(o, &m->irr[6 * e], 3 * sizeof(float));
        memcpy(o + 4, &m->irr[6 * e + 3], 3 * sizeof(float));
        memcpy(o + 8, &h->nrm[3 * h->elem_node[e]], 3 * sizeof(float));
        o[3] = o[7] = o[11] = 0.0f;
    }
    glNamedBufferSubData(m->ssbo_light, 0, (GLsizeiptr)((size_t)h->elem_count * 12 * sizeof(float)),
                         m->elem_light);
}

/* The frame's light at the elements (Algorithm 1, lines 7-10): with
 * direct=traced first the elements' direct light by shadow rays (stage
 * traced_direct), then the gathers and pull-ups on the GPU (Sec. 4.3.1) or
 * the CPU; *on_cpu says where the result is (ssbo_light, or the GPU's
 * ssbo_out). */
static gi_result illuminate(implicit_vis *m, const gi_gpu_scene *gs, int *on_cpu, gi_error *err)
{
    const gi_host *host = m->kit.host;
    const gi_scene *s = gs->scene;
    const float *direct = NULL;
    gi_result r = GI_OK;
    if (m->traced_direct) { /* README "Traced direct light" */
        host->stage_begin(host, "traced_direct");
        r = iv_traced_elements(m->traced_direct, m->hier, gs->time, err);
        host->stage_end(host, "traced_direct");
        if (r != GI_OK)
            return r;
        direct = m->traced_direct->elem;
    }
    host->stage_begin(host, "illumination");
    *on_cpu = m->gpu == NULL;
    if (m->gpu) { /* Sec. 4.3.1: the punctual lights at the frame's time come from the scene's
                     buffer */
        gi_gpu_scene_bind(gs);
        r = iv_gpu_illuminate(m->gpu, m->links, m->hier, (uint32_t)m->bounces, s->light_count,
                              direct, err);
        if (r == GI_ERR_UNSUPPORTED && !m->glossy) { /* more links than one GL storage block holds
                                                        (llvmpipe: 128 MiB): the same gather on
                                                        the CPU */
            if (!m->warned_cpu)
                gi_log(GI_LOG_WARN, "%s; gathering on the CPU (illum=cpu) instead", err->text);
            m->warned_cpu = 1;
            *on_cpu = 1;
            r = GI_OK;
        }
    }
    if (*on_cpu && r == GI_OK) {
        iv_lights li = {s, gs->time, s->envmap, direct};
        iv_illuminate(m->links, m->hier, &li, (uint32_t)m->bounces, m->irr);
        upload_elem_light(m);
    }
    host->stage_end(host, "illumination");
    return r;
}

static gi_result iv_render(void *inst, const gi_view *view, const gi_target *target)
{
    implicit_vis *m = inst;
    const gi_host *host = m->kit.host;
    const gi_gpu_scene *gs = m->kit.scene;
    gi_error err;
    gi_result r = gi_kit_frame_begin(&m->kit, view, GI_KIT_GBUFFER);
    if (r != GI_OK)
        return r;

    r = update_links(m, gs);
    if (r != GI_OK)
        return r;
    if (host->cancelled && host->cancelled(host)) /* before the gathers (issue 32) */
        return gi_kit_fail(&m->kit, GI_ERR_CANCELLED, "implicit_vis: cancelled");

    /* With the links kept and the direct light along them (deterministic),
     * the elements' light is the last frame's: only the display runs. */
    int on_cpu = m->light_on_cpu;
    if (m->light_valid) {
        host->stage_begin(host, "illumination");
        host->stage_end(host, "illumination");
    } else {
        r = illuminate(m, gs, &on_cpu, &err);
        if (r != GI_OK)
            return gi_kit_fail_with(&m->kit, r, &err);
        m->light_valid = !m->traced && !m->relink_always;
        m->light_on_cpu = on_cpu;
    }

    host->stage_begin(host, "display");
    r = gi_kit_render_gbuffer(&m->kit, view, NULL);
    if (r == GI_OK && m->traced_direct)
        r = iv_traced_pixels(m->traced_direct, m->kit.gbuffer, &err);
    if (r == GI_OK) {
        GLuint p = m->prog_display;
        glUseProgram(p);
        gi_kit_bind(&m->kit, p, view, target);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_ELEM_LIGHT,
                         on_cpu ? m->ssbo_light : m->gpu->ssbo_out);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_TRI, m->ssbo_tri);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_GRID, m->ssbo_grid);
        if (m->traced_direct)
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, IV_SSBO_PIXEL_DIRECT,
                             m->traced_direct->ssbo_pixel);
        if (m->glossy) { /* Sec. 4.3: the glossy lobe over the elements' direct-light bins */
            iv_gpu_bind_direct(m->gpu);
            glUniform1ui(glGetUniformLocation(p, "u_n"), m->gpu->n);
            glUniform1ui(glGetUniformLocation(p, "u_bins"), m->gpu->bins);
            glUniform1ui(glGetUniformLocation(p, "u_light_base"),
                         m->links->leaf_off[m->hier->elem_count]);
            glUniform1i(glGetUniformLocation(p, "u_env"), m->gpu->env);
            glUniform1i(glGetUniformLocation(p, "u_env_share"), iv_env_partial(m->links));
        }
        GLint size[2] = {(GLint)view->width, (GLint)view->height};
        glUniform2iv(glGetUniformLocation(p, "u_size"), 1, size);
        gi_kit_dispatch_8x8(view->width, view->height);
        glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
        glUseProgram(0);
        r = gi_gl_check("implicit_vis: display", &err);
    }
    host->stage_end(host, "display");
    if (r != GI_OK)
        return gi_kit_fail_with(&m->kit, r, &err);
    gi_kit_frame_end(&m->kit);

    host->stat(host, "link_tries", (double)m->links->tries);
    host->stat(host, "link_tries_kept", (double)m->links->kept_tries);
    host->stat(host, "links_created", (double)m->links->created);
    host->stat(host, "leaf_links", (double)m->links->receiving);
    host->stat(host, "light_links", (double)m->links->light_off[m->hier->elem_count]);
    /* Kept for rendering: the per-node bins (linked node, distance and, with
     * coverage, the covered solid angle) and each leaf's receiving and light
     * links (bin + source). The hierarchy's own arrays are not counted. */
    const iv_links *L = m->links;
    double bin_bytes = (double)L->nodes * (double)L->bins *
                       (double)(sizeof(iv_cell) + (L->cover ? sizeof(float) : 0));
    double leaf_bytes =
        2.0 * sizeof(uint32_t) *
        ((double)L->leaf_off[m->hier->elem_count] + (double)L->light_off[m->hier->elem_count]);
    host->stat(host, "data_bytes_links", bin_bytes + leaf_bytes);
    host->stat(host, "data_bytes", bin_bytes + leaf_bytes);
    return GI_OK;
}

static void iv_destroy(void *inst)
{
    implicit_vis *m = inst;
    if (!m)
        return;
    gi_kit_free(&m->kit);
    release_prepared(m);
    free(m);
}

static const char *iv_last_error(void *inst)
{
    return inst ? gi_kit_last_error(&((implicit_vis *)inst)->kit) : "";
}

/* Where the paper's method, at its defaults, is known to fail a conformance
 * check (gi_departure): Eq. 5 as printed (Sec. 4.2.2) weights a bin by its
 * nearest node alone, so a closed surface split into many nodes per bin
 * loses the rest of them; weight=surface (Eq. 4 over the nearest surface,
 * README "Weights") is the remedy the suite checks instead. */
static const gi_departure iv_departures[] = {
    {"furnace",
     "Eq. 5 as printed counts only a bin's nearest node, so closed surfaces lose energy (furnace, "
     "32^2, N 12: -27 % at rho 0.5, -45 % at rho 0.8; README \"Weights\")",
     "weight=surface"},
    {"held_out",
     "the direct light along implicit-visibility links misses small and flush emitters, and "
     "elements at mesh vertices cannot draw shadows between them (held-out family: relMSE 1.9 to "
     "4.9 times the limit on every variant but the furnaces; README \"Held-out family\")",
     "direct=traced weight=surface remesh=0.03 splat=true"},
    {NULL, NULL, NULL},
};

/* For the debug buffers (debug.c): the elements, their links and the
 * buffer the display reads their light from. */
void iv_debug_state(void *inst, iv_debug *out)
{
    implicit_vis *m = inst;
    *out = (iv_debug){&m->kit, m->links_valid ? m->hier : NULL, m->links,
                      m->light_on_cpu || !m->gpu ? m->ssbo_light : m->gpu->ssbo_out};
}

GI_METHOD_EXPORT(iv, .id = "implicit_vis",
                 .title = "Interactive Global Illumination Using Implicit Visibility",
                 .citation = "Dong, Kautz, Theobalt, Seidel. Pacific Graphics 2007",
                 .version = "0.1",
                 .caps = GI_CAP_DIRECT | GI_CAP_INDIRECT | GI_CAP_GLOSSY | GI_CAP_AREA_LIGHTS |
                         GI_CAP_POINT_LIGHTS | GI_CAP_DIRECTIONAL | GI_CAP_ENVIRONMENT |
                         GI_CAP_RIGID_MOTION | GI_CAP_DEFORMATION | GI_CAP_VISIBILITY |
                         GI_CAP_TEXTURES,
                 .max_bounces = 3, .params = iv_params, .departures = iv_departures,
                 .debug_buffers = iv_debug_buffers, .debug_buffer = iv_debug_buffer);

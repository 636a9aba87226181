/* The `vlf` method: Light Field Propagation and Rendering on the GPU
 * (Mortensen, Khanna, Slater, Afrigraph 2007), the GPU Virtual Light Field.
 *
 * prepare(): the light field is built on the CPU (field.c: stage
 * `sort`), propagated on the CPU or, with propagate = gpu, by compute
 * passes (vlf_gpu.c; stage `propagate`), then uploaded (`gpu_init`);
 * render(): the G-buffer and one compute pass reading the irradiance atlas
 * and the non-diffuse tiles (shaders/vlf_render.comp, stage `render`).
 * See plugins/vlf/README.md for what follows the paper and what does not. */
#define _POSIX_C_SOURCE 200809L
#include "gi/kit.h"
#include "gi/log.h"

#include <math.h>
#include <time.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vlf_debug.h"
#include "vlf_field.h"
#include "vlf_gpu.h"

extern const gi_shader_source gi_vlf_shaders[];

enum { VLF_LOOKUP_W = 512, VLF_LOOKUP_H = 256, VLF_BUFFERS = 7 };

typedef struct vlf {
    gi_kit kit;
    vlf_settings prm;
    vlf_field field;
    int have_field;
    int gpu_propagate; /* propagate = gpu or raster: vlf_gpu.c (raster: vlf_raster.c) */
    int prop_auto;     /* propagate = auto, decided at prepare() from GL_RENDERER */
    int raster_sync;   /* VLF_SYNC_* */
    vlf_gpu gpu;
    int have_gpu;
    GLuint program;
    GLuint buf[VLF_BUFFERS];
    GLuint lookup;
    size_t gpu_map_bytes; /* bytes of the light-field maps uploaded for rendering */
} vlf;

static const gi_param_desc vlf_params[] = {
    {"l", GI_PARAM_INT, 512, 8, 1024, GI_QUALITY_UP(2), "l (Sec. 2.1)",
     "bi-directional directions spread over the hemisphere"},
    {"N", GI_PARAM_INT, 64, 8, 256, GI_QUALITY_UP(2), "N (Sec. 2.1)",
     "rays per side of each parallel subfield (N x N)"},
    {"m", GI_PARAM_INT, 8, 1, 64, NULL, "m (Sec. 2.1)",
     "cells per side of a tile of non-diffuse storage; N must be a multiple"},
    {"S", GI_PARAM_INT, 2, 1, 8, NULL, "RI super-sampling (Sec. 3.3)",
     "radiance interface cells per subfield cell and side: transport on (N S)^2 rays"},
    {"density", GI_PARAM_FLOAT, 12, 1, 64, GI_QUALITY_UP(1.5), "texel density",
     "diffuse elements per unit length, the scene scaled into the unit sphere (faces get k x k "
     "elements, k <= 64)"},
    {"iterations", GI_PARAM_INT, 8, 1, 64, NULL, "iterations (Sec. 6)",
     "shooting iterations; k iterations carry k bounces (max_bounces = 7 describes the default 8)"},
    {"perturbed", GI_PARAM_INT, 0, 0, 36, NULL, "perturbed samples (Sec. 3.5)",
     "perturbed virtual directions per fixed direction, used only for transport (0: the fixed "
     "direction itself; "
     "the paper's high quality uses 36)"},
    {"seed", GI_PARAM_INT, 1, 0, 1000000, NULL, NULL, "seed of the perturbed directions"},
    {"order", GI_PARAM_ENUM, 0, 0, 0, "faces|rays", "Sec. 3.2",
     "depth order of a subfield: faces: the faces sorted front to back (Newell's painter's "
     "ordering, faces split "
     "where they overlap in a cycle, BSP cuts orthogonal to the direction), rasterised in that "
     "order; rays: each "
     "ray's fragments sorted by depth"},
    {"precision", GI_PARAM_ENUM, 0, 0, 0, "32f|16f|rgb9e5", "storage (Sec. 3.1, 6)",
     "format of the ir/radiance maps, during propagation (every pass writes in it) and for "
     "rendering: 32f: three "
     "float32 (12 bytes); 16f: RGBA16F, the paper's 64-bit format (8 bytes); rgb9e5: shared "
     "exponent (4 bytes)"},
    {"subdivide", GI_PARAM_INT, 1, 1, 16, NULL, NULL,
     "each scene triangle cut into subdivide^2 triangles before sorting and transport: the same "
     "surfaces as more "
     "faces (the tessellation sweep of propagation time against faces)"},
    {"propagate", GI_PARAM_ENUM, 3, 0, 0, "cpu|gpu|raster|auto", "propagation (Sec. 3.2-3.4)",
     "where propagation runs: cpu: the sweeps in C over per-ray fragment lists (propagate.c); "
     "gpu: compute passes over those lists (vlf_gpu.c), needs perturbed = 0; raster: the sorted "
     "faces drawn by the rasteriser into the radiance interface (vlf_raster.c, the paper's way), "
     "with perturbed > 0 or order = rays the CPU's sweeps; auto: raster on a hardware GL, cpu on "
     "a software rasteriser (llvmpipe, softpipe, swrast: there raster costs more CPU)"},
    {"raster_sync", GI_PARAM_ENUM, 0, 0, 0, "auto|barrier", "raster ordering (Sec. 3.3)",
     "how propagate = raster keeps each ray's faces in depth order: auto: "
     "GL_EXT_shader_framebuffer_fetch where the GL has it, else barrier; barrier: GL 4.5 core "
     "only, the order in layers of faces that do not overlap, a texture barrier between "
     "(vlf_layers.c)"},
    {"hier_min", GI_PARAM_INT, 0, 0, 1000000, NULL, "hierarchical sort (Sec. 3.2)",
     "objects (glTF nodes) of at least this many triangles whose bounding box in a direction's "
     "frame no other "
     "triangle reaches into are sorted on their own and spliced in at their box's place; 0: off"},
    {"threads", GI_PARAM_INT, 4, 1, 64, NULL, "sort threads (Sec. 6)",
     "CPU threads of the sort stage, one subfield at a time each (the field is the same for any "
     "count)"},
    {"bsp_levels", GI_PARAM_INT, 2, 0, 8, NULL, "BSP levels (Sec. 3.2, 6)",
     "cuts of the face list orthogonal to the direction at its centre of mass, levels (paper: 2)"},
    {"bsp_min", GI_PARAM_INT, 4096, 2, 1000000, NULL, "BSP threshold (Sec. 3.2)",
     "a face list is cut only with at least this many faces (paper: 4K)"},
    {0},
};

static gi_result vlf_create(const gi_host *host, const gi_params *params, void **out)
{
    vlf *v = calloc(1, sizeof *v);
    if (!v)
        return GI_ERR_OUT_OF_MEMORY;
    if (gi_kit_init(&v->kit, host, gi_vlf_shaders) != GI_OK) {
        free(v);
        return GI_ERR_INVALID_ARGUMENT;
    }
    v->prm.l = (uint32_t)gi_params_int(params, "l");
    v->prm.N = (uint32_t)gi_params_int(params, "N");
    v->prm.m = (uint32_t)gi_params_int(params, "m");
    v->prm.S = (uint32_t)gi_params_int(params, "S");
    v->prm.perturbed = (uint32_t)gi_params_int(params, "perturbed");
    v->prm.seed = (uint32_t)gi_params_int(params, "seed");
    v->prm.density = gi_params_float(params, "density");
    v->prm.iterations = (uint32_t)gi_params_int(params, "iterations");
    v->prm.order = gi_params_enum(params, "order") == 1 ? VLF_ORDER_RAYS : VLF_ORDER_FACES;
    v->prm.threads = (uint32_t)gi_params_int(params, "threads");
    v->prm.precision = (uint32_t)gi_params_enum(params, "precision");
    v->prm.subdivide = (uint32_t)gi_params_int(params, "subdivide");
    v->prm.bsp_levels = (uint32_t)gi_params_int(params, "bsp_levels");
    v->prm.bsp_min = (uint32_t)gi_params_int(params, "bsp_min");
    v->prm.hier_min = (uint32_t)gi_params_int(params, "hier_min");
    int prop = gi_params_enum(params, "propagate");
    v->raster_sync = gi_params_enum(params, "raster_sync") == 1 ? VLF_SYNC_BARRIER : VLF_SYNC_AUTO;
    v->prop_auto = prop == 3;
    if (v->prop_auto && (v->prm.perturbed > 0 || v->prm.order == VLF_ORDER_RAYS))
        prop = 0, v->prop_auto = 0; /* nothing to draw: the CPU's sweeps (below) */
    if (v->prop_auto)
        prop = 2; /* until prepare() sees the renderer */
    v->gpu_propagate = prop != 0;
    /* the rasteriser draws the fixed directions' face order: the perturbed
     * directions (sorted beside the sweeps) and the per-ray order have no
     * such draw, so they take the CPU's sweeps (said once in the log) */
    if (prop == 2 && (v->prm.perturbed > 0 || v->prm.order == VLF_ORDER_RAYS)) {
        host->log(host, GI_LOG_WARN,
                  "propagate = raster draws the fixed directions' face order; with %s it "
                  "propagates on the CPU",
                  v->prm.perturbed > 0 ? "perturbed > 0" : "order = rays");
        v->gpu_propagate = 0;
    }
    v->prm.raster = v->gpu_propagate && prop == 2;
    if (v->gpu_propagate && v->prm.perturbed > 0) {
        host->log(host, GI_LOG_ERROR,
                  "vlf: propagate = gpu runs the fixed directions only; set perturbed = 0");
        gi_kit_free(&v->kit);
        free(v);
        return GI_ERR_INVALID_ARGUMENT;
    }
    if (v->prm.N % v->prm.m != 0) {
        host->log(host, GI_LOG_ERROR, "vlf: N = %u is not a multiple of the tile size m = %u",
                  v->prm.N, v->prm.m);
        gi_kit_free(&v->kit);
        free(v);
        return GI_ERR_INVALID_ARGUMENT;
    }
    *out = v;
    return GI_OK;
}

static int vlf_cancelled(void *user)
{
    const gi_host *h = user;
    return h->cancelled && h->cancelled(h);
}

static void upload(GLuint b, const void *data, size_t bytes)
{
    static const float zero[4] = {0, 0, 0, 0};
    glNamedBufferData(b, (GLsizeiptr)(bytes ? bytes : sizeof zero), bytes ? data : zero,
                      GL_STATIC_DRAW);
}

/* Per face: chart origin and the back side's face, axes scaled to texels,
 * then W, H, first element, nd (16 words). */
static void pack_faces(const vlf_field *f, float *faces)
{
    for (uint32_t i = 0; i < f->face_count; i++) {
        const vlf_face *fc = &f->faces[i];
        gi_vec3 o = gi_v3_add(f->centre, gi_v3_scale(fc->origin, f->radius));
        gi_vec3 t = gi_v3_scale(fc->t, f->prm.density / f->radius),
                b = gi_v3_scale(fc->b, f->prm.density / f->radius);
        float *F = faces + 16 * (size_t)i;
        memcpy(F, &o, 3 * sizeof(float));
        memcpy(F + 4, &t, 3 * sizeof(float));
        memcpy(F + 8, &b, 3 * sizeof(float));
        uint32_t info[4] = {fc->W, fc->H, fc->first_elem, (uint32_t)fc->nd};
        memcpy(F + 12, info, sizeof info);
        uint32_t twin =
            (uint32_t)fc->twin; /* the other side of a double-sided face, ~0u for none */
        memcpy(F + 3, &twin, sizeof twin);
    }
}

/* The irradiance atlas in the storage format, then per element the part
 * of the texel that lies on its face (the filter's weight, so that
 * slivers at a face's border, hit by few rays, count little); the tiles in
 * the storage format. */
static void pack_maps(const vlf_field *f, uint32_t *irr, size_t e_words, void *tiles)
{
    uint32_t prec = f->prm.precision;
    float texel = 1.0f / (f->prm.density * f->prm.density);
    vlf_pack(prec, f->E_tot, f->elem_count, irr);
    for (uint32_t e = 0; e < f->elem_count; e++) {
        float w = fminf(1.0f, f->elem_area[e] / texel);
        memcpy(irr + e_words + e, &w, sizeof w);
    }
    vlf_pack(prec, f->out_tot, f->nd_cells, tiles);
}

/* The subfield frames (the WC -> PSF matrices' rows), the inverse vertex
 * matrices of the spherical triangles and the signed directions, 4 floats
 * each, into dirs; the triangles' nodes into tris. */
static void pack_directions(const vlf_field *f, float *dirs, uint32_t *tris)
{
    uint32_t l = f->prm.l, T = f->dirs.tri_count;
    for (uint32_t i = 0; i < l; i++) {
        const vlf_psf *p = &f->psf[i];
        gi_vec3 fr[3] = {p->u, p->v, p->n};
        for (int k = 0; k < 3; k++)
            memcpy(dirs + 4 * (3 * i + (uint32_t)k), &fr[k], 3 * sizeof(float));
    }
    for (uint32_t t = 0; t < T; t++) {
        for (int k = 0; k < 3; k++)
            memcpy(dirs + 4 * (3 * l + 3 * t + (uint32_t)k), f->dirs.tri_inv + 9 * t + 3 * k,
                   3 * sizeof(float));
        memcpy(tris + 4 * t, f->dirs.tris + 3 * t, 3 * sizeof(uint32_t));
    }
    for (uint32_t s = 0; s < 2 * l; s++)
        memcpy(dirs + 4 * (3 * l + 3 * T + s), &f->dirs.signed_dirs[s], 3 * sizeof(float));
}

/* The tile index: per (face, direction) its rectangle (8 words). */
static void pack_rects(const vlf_field *f, int32_t *rects)
{
    for (size_t r = 0; r < (size_t)f->nd_count * f->prm.l; r++) {
        const vlf_rect *R = &f->rects[r];
        rects[8 * r] = R->x0;
        rects[8 * r + 1] = R->y0;
        rects[8 * r + 2] = (int32_t)R->w;
        rects[8 * r + 3] = (int32_t)R->h;
        rects[8 * r + 4] = (int32_t)R->offset;
    }
}

/* The lat-long lookup: the spherical triangle of each texel's direction. */
static void fill_lookup(const vlf_field *f, uint32_t *lut)
{
    for (uint32_t y = 0; y < VLF_LOOKUP_H; y++)
        for (uint32_t x = 0; x < VLF_LOOKUP_W; x++) {
            float phi = ((float)x + 0.5f) / VLF_LOOKUP_W * 2.0f * GI_PI - GI_PI;
            float theta = ((float)y + 0.5f) / VLF_LOOKUP_H * GI_PI;
            gi_vec3 w = gi_v3(sinf(theta) * cosf(phi), sinf(theta) * sinf(phi), cosf(theta));
            uint32_t node[3];
            float al[3];
            lut[y * VLF_LOOKUP_W + x] = vlf_dirs_locate(&f->dirs, w, node, al);
        }
}

/* The face of each scene triangle (the G-buffer's ids) into buffer b. 1,
 * or 0 out of memory. */
static int upload_scene_faces(const vlf_field *f, GLuint b)
{
    uint32_t scene_tris = f->tri_count / f->tri_sub;
    uint32_t *scene_face = malloc((size_t)scene_tris * sizeof *scene_face + 4);
    if (!scene_face)
        return 0;
    for (uint32_t t = 0; t < scene_tris; t++)
        scene_face[t] = f->tri_face[(size_t)t * f->tri_sub];
    upload(b, scene_face, (size_t)scene_tris * sizeof *scene_face);
    free(scene_face);
    return 1;
}

/* Uploads the propagated field: faces, irradiance atlas, tiles, their
 * index, the subfield frames (the WC -> PSF matrices' rows) and the
 * triangulation with its lat-long lookup ("gpu_init"). */
static gi_result vlf_upload(vlf *v)
{
    vlf_field *f = &v->field;
    uint32_t l = f->prm.l, T = f->dirs.tri_count;
    if (!v->buf[0])
        glCreateBuffers(VLF_BUFFERS, v->buf);
    float *faces = calloc((size_t)f->face_count * 16, sizeof *faces);
    size_t bpv = vlf_precision_bytes(f->prm.precision), e_words = (size_t)f->elem_count * bpv / 4;
    uint32_t *irr = calloc(e_words + f->elem_count + 4, sizeof *irr);
    void *tiles = calloc((size_t)f->nd_cells * bpv + 4, 1);
    float *dirs = calloc(((size_t)3 * l + 3 * T + 2 * l) * 4, sizeof *dirs);
    int32_t *rects = calloc((size_t)f->nd_count * l * 8 + 8, sizeof *rects);
    uint32_t *tris = calloc((size_t)T * 4, sizeof *tris);
    uint32_t *lut = calloc((size_t)VLF_LOOKUP_W * VLF_LOOKUP_H, sizeof *lut);
    int ok = faces && irr && tiles && dirs && rects && tris && lut;
    if (ok) {
        pack_faces(f, faces);
        pack_maps(f, irr, e_words, tiles);
        pack_directions(f, dirs, tris);
        pack_rects(f, rects);
        fill_lookup(f, lut);
        upload(v->buf[0], faces, (size_t)f->face_count * 16 * sizeof *faces);
        upload(v->buf[1], irr, (e_words + f->elem_count) * sizeof *irr);
        ok = upload_scene_faces(f, v->buf[6]);
    }
    if (ok) {
        upload(v->buf[2], tiles, (size_t)f->nd_cells * bpv);
        v->gpu_map_bytes = e_words * sizeof *irr + (size_t)f->nd_cells * bpv;
        upload(v->buf[3], rects, (size_t)f->nd_count * l * 8 * sizeof *rects);
        upload(v->buf[4], dirs, ((size_t)3 * l + 3 * T + 2 * l) * 4 * sizeof *dirs);
        upload(v->buf[5], tris, (size_t)T * 4 * sizeof *tris);
        if (!v->lookup)
            v->lookup = gi_gpu_texture_2d(GL_R32UI, VLF_LOOKUP_W, VLF_LOOKUP_H);
        glTextureSubImage2D(v->lookup, 0, 0, 0, VLF_LOOKUP_W, VLF_LOOKUP_H, GL_RED_INTEGER,
                            GL_UNSIGNED_INT, lut);
    }
    free(faces), free(irr), free(tiles), free(dirs), free(rects), free(tris), free(lut);
    if (!ok)
        return gi_kit_fail(&v->kit, GI_ERR_OUT_OF_MEMORY,
                           "vlf: out of memory uploading the light field");
    gi_error err;
    if (gi_gl_check("vlf: upload", &err) != GI_OK)
        return gi_kit_fail_with(&v->kit, GI_ERR_GL, &err);
    return GI_OK;
}

/* CPU seconds of the calling thread and of the whole process (llvmpipe's
 * threads included): the main-thread share of a stage. */
static void cpu_times(double *thread, double *process)
{
    struct timespec a, b;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
    *thread = (double)a.tv_sec + 1e-9 * (double)a.tv_nsec;
    *process = (double)b.tv_sec + 1e-9 * (double)b.tv_nsec;
}

/* The "propagate" stage: on the CPU, by the compute passes or by the
 * rasteriser; its CPU time and the main thread's share of it as stats. */
static gi_result vlf_propagate_stage(vlf *v)
{
    const gi_host *host = v->kit.host;
    gi_error err;
    gi_result rc;
    double th0, pr0, th1, pr1;
    cpu_times(&th0, &pr0);
    host->stage_begin(host, "propagate");
    if (v->gpu_propagate) {
        /* the depth order and the gather lists uploaded (propagate_setup),
         * then the passes; the maps read back for the upload below */
        host->stage_begin(host, "propagate_setup");
        rc = vlf_gpu_setup(&v->gpu, &v->field, &err);
        host->stage_end(host, "propagate_setup");
        if (rc == GI_OK)
            rc = vlf_gpu_propagate(&v->gpu, &v->field, vlf_cancelled, (void *)host, &err);
        host->stage_end(host, "propagate");
        if (rc != GI_OK)
            rc = gi_kit_fail_with(
                &v->kit, host->cancelled && host->cancelled(host) ? GI_ERR_CANCELLED : GI_ERR_GL,
                &err);
    } else {
        /* any failure here has been reported as a cancellation */
        rc = vlf_field_propagate(&v->field, vlf_cancelled, (void *)host, NULL);
        host->stage_end(host, "propagate");
        if (rc != GI_OK)
            rc = gi_kit_fail(&v->kit, GI_ERR_CANCELLED, "vlf: propagation cancelled");
    }
    glFinish();
    cpu_times(&th1, &pr1);
    host->stat(host, "propagate_cpu_s", pr1 - pr0);
    host->stat(host, "propagate_main_share", pr1 > pr0 ? (th1 - th0) / (pr1 - pr0) : 1.0);
    return rc;
}

/* Builds, propagates and uploads the light field of the scene at its
 * current time. */
static gi_result vlf_build(vlf *v, const gi_gpu_scene *gs)
{
    const gi_host *host = v->kit.host;
    if (v->have_field)
        vlf_field_free(&v->field);
    v->have_field = 0;
    gi_error err;
    v->prm.cancelled = vlf_cancelled; /* polled in the build's long loops */
    v->prm.cancel_user = (void *)host;
    host->stage_begin(host, "sort");
    gi_result rc = vlf_field_build(&v->field, gs->scene, gs->time, &v->prm, &err);
    host->stage_end(host, "sort");
    if (rc != GI_OK) {
        vlf_field_free(&v->field);
        return gi_kit_fail_with(
            &v->kit, rc == GI_ERR_CANCELLED ? GI_ERR_CANCELLED : GI_ERR_INVALID_ARGUMENT, &err);
    }
    v->have_field = 1;
    rc = vlf_propagate_stage(v);
    if (rc != GI_OK)
        return rc;
    host->stage_begin(host, "gpu_init");
    gi_result r = vlf_upload(v);
    glFinish();
    host->stage_end(host, "gpu_init");
    const vlf_stats *s = &v->field.st;
    host->stat(host, "faces", v->field.face_count);
    /* where propagation ran: 0 cpu, 1 gpu (compute over lists), 2 raster */
    host->stat(host, "propagate_path", v->prm.raster ? 2 : v->gpu_propagate ? 1 : 0);
    /* how the raster path ordered each ray's faces: 1 fetch, 2 barrier
     * (then its layers: the most of a direction, the mean) */
    int ras = v->prm.raster && v->have_gpu;
    host->stat(host, "raster_sync", ras ? (v->gpu.ras.barrier ? 2 : 1) : 0);
    if (ras && v->gpu.ras.barrier) {
        host->stat(host, "raster_layers_max", (double)v->gpu.ras.max_layers);
        host->stat(host, "raster_layers_mean", (double)v->gpu.ras.layer_total / v->prm.l);
    }
    host->stat(host, "triangles", v->field.tri_count);
    host->stat(host, "sort_triangles", v->field.sort_count); /* drawn: merged faces (merge.c) */
    host->stat(host, "diffuse_elements", s->diffuse_elements);
    host->stat(host, "nondiffuse_elements", s->nondiffuse_elements);
    host->stat(host, "tiles", s->tiles);
    host->stat(host, "bytes_propagate", (double)s->bytes_propagate);
    host->stat(host, "bytes_render", (double)s->bytes_render);
    host->stat(host, "data_bytes",
               (double)s->bytes_render); /* what rendering keeps after propagation */
    host->stat(host, "bytes_maps_render", (double)s->bytes_maps_render);
    host->stat(host, "gpu_bytes_maps", (double)v->gpu_map_bytes);
    host->stat(host, "samples_transported", (double)s->samples);
    host->stat(host, "samples_per_s",
               s->propagate_s > 0 ? (double)s->samples / s->propagate_s : 0.0);
    host->stat(host, "sort_pieces", (double)s->sort_pieces);
    host->stat(host, "sort_splits", (double)s->sort_splits);
    host->stat(host, "sort_bsp_cuts", (double)s->sort_bsp_cuts);
    host->stat(host, "sort_unresolved", (double)s->sort_unresolved);
    host->stat(host, "sort_tests", (double)s->sort_tests);
    host->stat(host, "sort_groups", (double)s->sort_groups);
    host->stat(host, "sort_hier_fallbacks", (double)s->sort_hier_fallbacks);
    host->stat(host, "flux_emitted", s->flux_emitted);
    host->stat(host, "flux_received", s->flux_received);
    host->stat(host, "flux_escaped", s->flux_escaped);
    return r;
}

/* propagate = auto: the rasteriser (the paper's propagation, §3.2) on a
 * hardware GL; on a software one (Mesa's llvmpipe, softpipe, swrast) the C
 * sweeps, which there cost a fraction of its CPU time (plugins/vlf/README.md
 * "Where each stage runs"). Decided once, said in the log. */
static void choose_path(vlf *v)
{
    const char *rd = (const char *)glGetString(GL_RENDERER);
    int soft = !rd || strstr(rd, "llvmpipe") || strstr(rd, "softpipe") || strstr(rd, "swrast");
    v->prop_auto = 0;
    v->gpu_propagate = !soft;
    v->prm.raster = (uint32_t)!soft;
    v->kit.host->log(v->kit.host, GI_LOG_INFO, "propagate = auto: %s on %s",
                     soft ? "cpu (a software rasteriser)" : "raster", rd ? rd : "an unnamed GL");
}

static gi_result vlf_prepare(void *inst, const gi_gpu_scene *gs)
{
    vlf *v = inst;
    gi_kit_prepare(&v->kit, gs);
    if (!v->program) {
        gi_error err;
        v->program = gi_program_build_compute("vlf_render.comp", NULL, &err);
        if (!v->program)
            return gi_kit_fail_with(&v->kit, GI_ERR_GL, &err);
    }
    if (v->prop_auto)
        choose_path(v);
    if (v->gpu_propagate && !v->have_gpu) {
        gi_error err;
        if (vlf_gpu_init(&v->gpu, (int)v->prm.raster, v->raster_sync, &err) != GI_OK)
            return gi_kit_fail_with(&v->kit, GI_ERR_GL, &err);
        v->have_gpu = 1;
    }
    return vlf_build(v, gs);
}

/* A static method: any change of the scene propagates the field again;
 * a moved camera needs nothing. */
static gi_result vlf_update(void *inst, const gi_gpu_scene *gs, const gi_changes *changes)
{
    vlf *v = inst;
    gi_kit_update(&v->kit, gs, changes);
    if (changes->flags & ~(uint32_t)GI_CHANGED_CAMERA)
        return vlf_build(v, gs);
    return GI_OK;
}

static gi_result vlf_render(void *inst, const gi_view *view, const gi_target *target)
{
    vlf *v = inst;
    gi_kit *k = &v->kit;
    const gi_host *host = k->host;
    if (!v->have_field)
        return gi_kit_fail(k, GI_ERR_INVALID_ARGUMENT, "vlf: render before prepare");
    host->stage_begin(host, "render");
    gi_result r = gi_kit_frame_begin(k, view, GI_KIT_GBUFFER);
    if (r == GI_OK)
        r = gi_kit_render_gbuffer(k, view, NULL);
    if (r != GI_OK) {
        host->stage_end(host, "render");
        return r;
    }
    GLuint p = v->program;
    glUseProgram(p);
    gi_kit_bind(k, p, view, target);
    for (int b = 0; b < VLF_BUFFERS; b++)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_PLUGIN_FIRST + (GLuint)b, v->buf[b]);
    glBindTextureUnit(GI_TEX_PLUGIN_FIRST, v->lookup);
    glBindImageTexture(GI_IMAGE_TARGET, target->texture, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    const vlf_field *f = &v->field;
    glUniform3f(glGetUniformLocation(p, "u_centre"), f->centre.x, f->centre.y, f->centre.z);
    glUniform1f(glGetUniformLocation(p, "u_radius"), f->radius);
    glUniform1ui(glGetUniformLocation(p, "u_l"), f->prm.l);
    glUniform1ui(glGetUniformLocation(p, "u_N"), f->prm.N);
    glUniform1ui(glGetUniformLocation(p, "u_tri_count"), f->dirs.tri_count);
    glUniform1ui(glGetUniformLocation(p, "u_precision"), f->prm.precision);
    glUniform1ui(glGetUniformLocation(p, "u_weight_offset"),
                 (uint32_t)((size_t)f->elem_count * vlf_precision_bytes(f->prm.precision) / 4));
    gi_kit_dispatch_8x8(view->width, view->height);
    glUseProgram(0);
    host->stage_end(host, "render");
    gi_kit_frame_end(k);
    gi_error err;
    if (gi_gl_check("vlf: render pass", &err) != GI_OK)
        return gi_kit_fail_with(k, GI_ERR_GL, &err);
    return GI_OK;
}

static void vlf_destroy(void *inst)
{
    vlf *v = inst;
    if (!v)
        return;
    gi_kit_free(&v->kit);
    if (v->have_field)
        vlf_field_free(&v->field);
    if (v->program)
        glDeleteProgram(v->program);
    if (v->buf[0])
        glDeleteBuffers(VLF_BUFFERS, v->buf);
    if (v->lookup)
        glDeleteTextures(1, &v->lookup);
    if (v->have_gpu)
        vlf_gpu_free(&v->gpu);
    free(v);
}

static const char *vlf_last_error(void *inst)
{
    return inst ? gi_kit_last_error(&((vlf *)inst)->kit) : "";
}

/* For the debug buffers (debug.c): the light field (NULL before prepare)
 * and the kit (its G-buffer, its error). */
const vlf_field *vlf_debug_field(void *inst, gi_kit **kit)
{
    vlf *v = inst;
    *kit = &v->kit;
    return v->have_field ? &v->field : NULL;
}

GI_METHOD_EXPORT(
    vlf, .id = "vlf",
    .title = "Light Field Propagation and Rendering on the GPU (GPU Virtual Light Field)",
    .citation = "Mortensen, Khanna, Slater. Afrigraph 2007", .version = "0.1",
    .caps = GI_CAP_DIRECT | GI_CAP_INDIRECT | GI_CAP_GLOSSY | GI_CAP_MIRROR | GI_CAP_AREA_LIGHTS |
            GI_CAP_POINT_LIGHTS | GI_CAP_DIRECTIONAL | GI_CAP_ENVIRONMENT | GI_CAP_RIGID_MOTION |
            GI_CAP_PRECOMPUTE | GI_CAP_VISIBILITY | GI_CAP_TEXTURES,
    .max_bounces = 7, .params = vlf_params, .debug_buffers = vlf_debug_buffers,
    .debug_buffer = vlf_debug_buffer);

/* The `csm` method: Coherent Shadow Maps (Ritschel, Grosch, Kautz, Mueller,
 * EGSR 2007) for distant light from the scene's environment map.
 *
 * prepare(): per object (every object casts; see README.md), N_theta x N_phi
 * orthographic dual-depth maps around its local bounding sphere on a
 * lat-long grid of directions (§4.1), enumerated in scan-line, zig-zag or
 * Hilbert order (§4.4) and compressed losslessly by the core's codec (§3.1);
 * cached on disk by a hash of the mesh and the parameters.
 * render(): G-buffer, then S environment samples per pixel with visibility
 * from all objects' CSMs (§3.2, §4.5 filters, §4.6 rigid motion through the
 * inverse object transform), averaged progressively over frames (§5). */
#include "csm_cpu.h"

#include "gi/cache.h"
#include "gi/log.h"
#include "gi/mesh.h"
#include "gi/rng.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gi_shader_source gi_csm_shaders[];

#define CSM_FORMAT_VERSION 2u
#define CSM_PATTERNS 256u

enum { B_OBJECTS = 8, B_OFFSETS = 9, B_ZAVG = 10, B_IEND = 11, B_CELLS = 12, B_PATTERNS = 13, B_COUNT = 14 };

typedef struct csm {
    const gi_host *host;
    int N, M, S, z3, filter, mode;
    gi_csm_order order;
    float bias, normal_offset;
    uint32_t object_count;
    csm_gpu_object *objects;
    GLuint ssbo[6]; /* objects, offsets, z_avg, i_end, cells, patterns */
    gi_gbuffer *gbuffer;
    GLuint program, accum, count; /* count: samples taken this frame */
    uint32_t width, height, frames;
    float last_view_proj[16];
    const gi_gpu_scene *scene;
    char error[GI_ERROR_MAX];
} csm;

static const gi_param_desc csm_params[] = {
    {"N", GI_PARAM_INT, 16, 2, 256, NULL, "N (Sec. 4.1)",
     "directions per dimension of the lat-long grid: N_theta = N_phi = N, N^2 maps per object"},
    {"M", GI_PARAM_INT, 128, 8, 1024, NULL, "M (Sec. 3)", "depth map size M x M"},
    {"enumeration", GI_PARAM_ENUM, 2, 0, 0, "scanline|zigzag|hilbert", "Sec. 4.4", "order of the maps in the codec"},
    {"depth", GI_PARAM_ENUM, 0, 0, 0, "z2|z3", "Sec. 3.1",
     "second depth of a segment: z2, or z3 (closed-manifold option)"},
    {"filter", GI_PARAM_ENUM, 0, 0, 0, "nearest|pcf|rr", "Sec. 4.5",
     "nearest map and texel; generalised PCF (4 maps x 4 texels); Russian roulette over those 16"},
    {"S", GI_PARAM_INT, 16, 1, 1024, NULL, "S (Sec. 5.1)", "environment samples per pixel and frame"},
    {"bias", GI_PARAM_FLOAT, 0.01, 0, 1, NULL, "bias (Sec. 6)", "depth bias as a fraction of the bounding-sphere radius"},
    {"normal_offset", GI_PARAM_FLOAT, 1, 0, 16, NULL, NULL,
     "receivers move along their normal by this many texels of each object's map (against shadow acne)"},
    {"mode", GI_PARAM_ENUM, 0, 0, 0, "shade|random|coherent", "Table 2",
     "shade: the image; random/coherent: Table 2's benchmark, S shadow tests per pixel in uniform directions, "
     "per-pixel patterns (random) or one direction per sample for all pixels (coherent); image = visible fraction"},
    {0},
};

static gi_result fail(csm *c, gi_result r, const char *msg)
{
    snprintf(c->error, sizeof c->error, "%s", msg);
    return r;
}

static gi_result csm_create(const gi_host *host, const gi_params *params, void **out)
{
    csm *c = calloc(1, sizeof *c);
    if (!c)
        return GI_ERR_OUT_OF_MEMORY;
    c->host = host;
    c->N = gi_params_int(params, "N");
    c->M = gi_params_int(params, "M");
    c->order = (gi_csm_order)gi_params_enum(params, "enumeration");
    c->z3 = gi_params_enum(params, "depth");
    c->filter = gi_params_enum(params, "filter");
    c->S = gi_params_int(params, "S");
    c->bias = gi_params_float(params, "bias");
    c->normal_offset = gi_params_float(params, "normal_offset");
    c->mode = gi_params_enum(params, "mode");
    gi_shader_register(gi_csm_shaders);
    *out = c;
    return GI_OK;
}

/* Cache file name: hash of the format version, the object's mesh, its
 * sphere and every parameter that changes the data. */
static void cache_name(const csm *c, const gi_scene *s, uint32_t k, const float sphere[4], char *name, size_t size)
{
    uint32_t key[12] = {CSM_FORMAT_VERSION, (uint32_t)c->M, (uint32_t)c->N, (uint32_t)c->N, (uint32_t)c->order,
                        (uint32_t)c->z3, 0, 0, 0, 0, 0, 0};
    memcpy(&key[6], sphere, 4 * sizeof(float));
    uint64_t h = gi_hash64("gibench-csm", 11, gi_scene_object_hash(s, k));
    h = gi_hash64(key, sizeof key, h);
    snprintf(name, size, "csm-%016llx.bin", (unsigned long long)h);
}

static gi_result load_or_build(csm *c, const gi_gpu_scene *gs, uint32_t k, const float sphere[4], gi_csm_data *data,
                               int *hit)
{
    const gi_host *host = c->host;
    char name[64];
    cache_name(c, gs->scene, k, sphere, name, sizeof name);
    char *path = host->cache_dir ? gi_cache_path(host->cache_dir, name) : NULL;
    gi_error err;
    *hit = 0;
    if (path) {
        size_t size = 0;
        void *bytes = gi_file_read_all(path, &size);
        if (bytes) {
            if (gi_csm_data_read(bytes, size, data, &err) == GI_OK && data->M == (uint32_t)c->M &&
                data->N == (uint32_t)(c->N * c->N))
                *hit = 1;
            else {
                host->log(host, GI_LOG_WARN, "%s: unusable cache file (%s); recomputing", path,
                          data->M ? "wrong size" : err.text);
                gi_csm_data_free(data);
            }
            free(bytes);
        }
    }
    if (*hit) {
        free(path);
        return GI_OK;
    }
    csm_build_desc desc = {.M = (uint32_t)c->M,
                           .n_theta = (uint32_t)c->N,
                           .n_phi = (uint32_t)c->N,
                           .order = c->order,
                           .z3 = c->z3,
                           .batch = 16};
    /* keep one batch of RGBA32F layers under 64 MiB */
    uint64_t layer = (uint64_t)c->M * (uint64_t)c->M * 16u;
    if (layer * desc.batch > (64u << 20))
        desc.batch = (uint32_t)((64u << 20) / layer) > 0 ? (uint32_t)((64u << 20) / layer) : 1u;
    float p0 = (float)k / (float)c->object_count, p1 = 1.0f / (float)c->object_count;
    gi_result r = csm_build_object(gs, k, sphere, &desc, host, p0, p1, data, &err);
    if (r != GI_OK) {
        free(path);
        return fail(c, r, err.text);
    }
    if (path) {
        void *bytes = NULL;
        size_t size = 0;
        if (gi_csm_data_write(data, &bytes, &size, &err) != GI_OK ||
            gi_file_write_atomic(path, bytes, size, &err) != GI_OK)
            host->log(host, GI_LOG_WARN, "csm: not cached: %s", err.text);
        free(bytes);
    }
    free(path);
    return GI_OK;
}

/* §5.1: 256 stratified patterns of S points: jittered strata of a
 * sqrt(S) x sqrt(S) grid when S is a square, else a Latin hypercube (one
 * point per row and per column of an S x S grid). Fixed seed. */
static float *make_patterns(int S)
{
    float *p = malloc((size_t)CSM_PATTERNS * (size_t)S * 2 * sizeof *p);
    int *perm = malloc((size_t)S * sizeof *perm);
    if (!p || !perm) {
        free(p);
        free(perm);
        return NULL;
    }
    int root = (int)lroundf(sqrtf((float)S));
    for (uint32_t k = 0; k < CSM_PATTERNS; k++) {
        uint32_t rng = gi_rng_init(k, 0, 0x05eed5u);
        float *q = p + (size_t)k * (size_t)S * 2;
        for (int i = 0; i < S; i++)
            perm[i] = i;
        for (int i = S - 1; i > 0; i--) {
            int j = (int)(gi_rng_next_u32(&rng) % (uint32_t)(i + 1));
            int t = perm[i];
            perm[i] = perm[j];
            perm[j] = t;
        }
        for (int s = 0; s < S; s++) {
            float u1 = gi_rng_next_float(&rng), u2 = gi_rng_next_float(&rng);
            if (root * root == S) {
                int cell = perm[s];
                q[2 * s] = ((float)(cell % root) + u1) / (float)root;
                q[2 * s + 1] = ((float)(cell / root) + u2) / (float)root;
            } else {
                q[2 * s] = ((float)s + u1) / (float)S;
                q[2 * s + 1] = ((float)perm[s] + u2) / (float)S;
            }
        }
    }
    free(perm);
    return p;
}

static gi_result csm_prepare(void *inst, const gi_gpu_scene *gs)
{
    csm *c = inst;
    const gi_host *host = c->host;
    const gi_scene *s = gs->scene;
    gi_error err;
    c->scene = gs;
    c->program = gi_program_build_compute("csm.comp", NULL, &err);
    if (!c->program)
        return fail(c, GI_ERR_GL, err.text);
    c->object_count = s->object_count;
    uint32_t n = s->object_count ? s->object_count : 1u;
    c->objects = calloc(n, sizeof *c->objects);
    gi_csm_data *data = calloc(n, sizeof *data);
    if (!c->objects || !data) {
        free(data);
        return fail(c, GI_ERR_OUT_OF_MEMORY, "csm: out of memory");
    }
    gi_result r = GI_OK;
    int hits = 0;
    uint64_t offsets_total = 0, segments_total = 0, bytes_u = 0, bytes_c = 0;
    for (uint32_t k = 0; k < c->object_count && r == GI_OK; k++) {
        float sphere[4];
        gi_mesh_object_sphere(s, k, sphere);
        if (!(sphere[3] > 0.0f))
            sphere[3] = 1e-6f; /* a degenerate object: a point; its maps are empty */
        int hit = 0;
        r = load_or_build(c, gs, k, sphere, &data[k], &hit);
        if (r != GI_OK)
            break;
        hits += hit;
        csm_gpu_object *o = &c->objects[k];
        memcpy(o->sphere, sphere, sizeof sphere);
        o->M = (uint32_t)c->M;
        o->offsets_base = (uint32_t)offsets_total;
        o->segments_base = (uint32_t)segments_total;
        float b = c->bias * sphere[3];
        memcpy(&o->bias_bits, &b, sizeof b);
        offsets_total += (uint64_t)c->M * (uint64_t)c->M + 1u;
        segments_total += data[k].segment_count;
        bytes_u += data[k].bytes_uncompressed;
        bytes_c += data[k].bytes_compressed;
    }
    if (r == GI_OK && (offsets_total > UINT32_MAX || segments_total > UINT32_MAX))
        r = fail(c, GI_ERR_UNSUPPORTED, "csm: more than 2^32 segments in all");
    if (r == GI_OK) {
        host->stage_begin(host, "upload");
        uint32_t *offsets = malloc((offsets_total ? offsets_total : 1) * sizeof *offsets);
        float *z = malloc((segments_total ? segments_total : 1) * sizeof *z);
        uint32_t *iend = malloc((segments_total ? segments_total : 1) * sizeof *iend);
        uint32_t cells_n = (uint32_t)(c->N * c->N);
        uint32_t *cells = malloc(cells_n * sizeof *cells);
        float *patterns = make_patterns(c->S);
        if (!offsets || !z || !iend || !cells || !patterns)
            r = fail(c, GI_ERR_OUT_OF_MEMORY, "csm: out of memory for the upload");
        for (uint32_t k = 0; r == GI_OK && k < c->object_count; k++) {
            size_t m2 = (size_t)c->M * (size_t)c->M + 1u;
            memcpy(offsets + c->objects[k].offsets_base, data[k].offsets, m2 * sizeof *offsets);
            memcpy(z + c->objects[k].segments_base, data[k].z_avg, data[k].segment_count * sizeof *z);
            memcpy(iend + c->objects[k].segments_base, data[k].i_end, data[k].segment_count * sizeof *iend);
        }
        for (uint32_t b = 0; r == GI_OK && b < (uint32_t)c->N; b++)
            for (uint32_t a = 0; a < (uint32_t)c->N; a++)
                cells[b * (uint32_t)c->N + a] = gi_csm_order_index(c->order, (uint32_t)c->N, (uint32_t)c->N, a, b);
        if (r == GI_OK) {
            glCreateBuffers(6, c->ssbo);
            glCreateBuffers(1, &c->count);
            glNamedBufferStorage(c->count, 4, NULL, GL_DYNAMIC_STORAGE_BIT);
            glNamedBufferStorage(c->ssbo[0], (GLsizeiptr)(n * sizeof *c->objects), c->objects,
                                 GL_DYNAMIC_STORAGE_BIT);
            glNamedBufferStorage(c->ssbo[1], (GLsizeiptr)((offsets_total ? offsets_total : 1) * 4), offsets, 0);
            glNamedBufferStorage(c->ssbo[2], (GLsizeiptr)((segments_total ? segments_total : 1) * 4), z, 0);
            glNamedBufferStorage(c->ssbo[3], (GLsizeiptr)((segments_total ? segments_total : 1) * 4), iend, 0);
            glNamedBufferStorage(c->ssbo[4], (GLsizeiptr)(cells_n * 4), cells, 0);
            glNamedBufferStorage(c->ssbo[5], (GLsizeiptr)(CSM_PATTERNS * (size_t)c->S * 8), patterns, 0);
            if (gi_gl_check("csm: upload", &err) != GI_OK)
                r = fail(c, GI_ERR_GL, err.text);
        }
        free(offsets);
        free(z);
        free(iend);
        free(cells);
        free(patterns);
        host->stage_end(host, "upload");
    }
    for (uint32_t k = 0; k < c->object_count; k++)
        gi_csm_data_free(&data[k]);
    free(data);
    if (r != GI_OK)
        return r;
    double texels = (double)c->object_count * (double)c->M * (double)c->M;
    host->stat(host, "bytes_uncompressed", (double)bytes_u);
    host->stat(host, "bytes_compressed", (double)bytes_c);
    host->stat(host, "ratio", bytes_c ? (double)bytes_u / (double)bytes_c : 0.0);
    host->stat(host, "segments_per_texel", texels > 0 ? (double)segments_total / texels : 0.0);
    host->stat(host, "maps", (double)c->object_count * c->N * c->N);
    host->stat(host, "cache_hit", c->object_count > 0 && hits == (int)c->object_count ? 1.0 : 0.0);
    return GI_OK;
}

static gi_result csm_update(void *inst, const gi_gpu_scene *scene, const gi_changes *changes)
{
    csm *c = inst;
    c->scene = scene;
    if (changes->flags)
        c->frames = 0;
    return GI_OK;
}

static gi_result ensure_size(csm *c, uint32_t w, uint32_t h)
{
    if (c->gbuffer && c->width == w && c->height == h)
        return GI_OK;
    gi_gbuffer_free(c->gbuffer);
    glDeleteTextures(1, &c->accum);
    gi_error err;
    c->gbuffer = gi_gbuffer_create(w, h, &err);
    if (!c->gbuffer)
        return fail(c, GI_ERR_GL, err.text);
    glCreateTextures(GL_TEXTURE_2D, 1, &c->accum);
    glTextureStorage2D(c->accum, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
    c->width = w;
    c->height = h;
    c->frames = 0;
    return GI_OK;
}

static gi_result csm_render(void *inst, const gi_view *view, const gi_target *target)
{
    csm *c = inst;
    gi_error err;
    gi_result r = ensure_size(c, view->width, view->height);
    if (r != GI_OK)
        return r;
    if (view->frame_index == 0 || memcmp(c->last_view_proj, view->view_proj, sizeof c->last_view_proj))
        c->frames = 0;
    memcpy(c->last_view_proj, view->view_proj, sizeof c->last_view_proj);

    /* §4.6: queries in object-local space through the inverse transform. */
    for (uint32_t k = 0; k < c->object_count; k++) {
        csm_gpu_object *o = &c->objects[k];
        memcpy(o->world_from_local, c->scene->world_from_local[k], sizeof o->world_from_local);
        if (!gi_mat4_invert(o->local_from_world, o->world_from_local))
            gi_mat4_identity(o->local_from_world);
    }
    if (c->object_count)
        glNamedBufferSubData(c->ssbo[0], 0, (GLsizeiptr)(c->object_count * sizeof *c->objects), c->objects);

    c->host->stage_begin(c->host, "gbuffer");
    r = gi_gbuffer_render(c->gbuffer, c->scene, view->view, view->proj, &err);
    c->host->stage_end(c->host, "gbuffer");
    if (r != GI_OK)
        return fail(c, r, err.text);

    c->host->stage_begin(c->host, "render");
    GLuint p = c->program;
    glUseProgram(p);
    gi_gpu_scene_bind(c->scene);
    gi_gbuffer_bind(c->gbuffer, GI_BINDING_PLUGIN_FIRST);
    static const GLuint bindings[6] = {B_OBJECTS, B_OFFSETS, B_ZAVG, B_IEND, B_CELLS, B_PATTERNS};
    for (int i = 0; i < 6; i++)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, bindings[i], c->ssbo[i]);
    glBindImageTexture(0, c->accum, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(1, target->texture, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform3f(glGetUniformLocation(p, "u_eye"), view->eye.x, view->eye.y, view->eye.z);
    glUniformMatrix4fv(glGetUniformLocation(p, "u_inv_view_proj"), 1, GL_FALSE, view->inv_view_proj);
    glUniform2i(glGetUniformLocation(p, "u_size"), (GLint)view->width, (GLint)view->height);
    glUniform1ui(glGetUniformLocation(p, "u_frame"), c->frames);
    glUniform1ui(glGetUniformLocation(p, "u_seed"), view->seed);
    glUniform1i(glGetUniformLocation(p, "u_S"), c->S);
    glUniform1i(glGetUniformLocation(p, "u_mode"), c->mode);
    const GLuint zero = 0;
    glNamedBufferSubData(c->count, 0, 4, &zero);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, B_COUNT, c->count);
    glUniform1ui(glGetUniformLocation(p, "csm_n_theta"), (GLuint)c->N);
    glUniform1ui(glGetUniformLocation(p, "csm_n_phi"), (GLuint)c->N);
    glUniform1ui(glGetUniformLocation(p, "csm_object_count"), c->object_count);
    glUniform1f(glGetUniformLocation(p, "csm_normal_offset"), c->normal_offset);
    glUniform1i(glGetUniformLocation(p, "csm_filter"), c->filter);
    glDispatchCompute((view->width + 7) / 8, (view->height + 7) / 8, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                    GL_FRAMEBUFFER_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    glUseProgram(0);
    c->host->stage_end(c->host, "render");
    c->frames++;
    c->host->stat(c->host, "samples_per_pixel_env", (double)c->frames * c->S);
    /* read after the timed stage: S per surface pixel (Table 2's "samples") */
    GLuint taken = 0;
    glGetNamedBufferSubData(c->count, 0, 4, &taken);
    c->host->stat(c->host, "samples_per_frame", (double)taken);
    if (gi_gl_check("csm: shading pass", &err) != GI_OK)
        return fail(c, GI_ERR_GL, err.text);
    return GI_OK;
}

static void csm_destroy(void *inst)
{
    csm *c = inst;
    if (!c)
        return;
    gi_gbuffer_free(c->gbuffer);
    if (c->accum)
        glDeleteTextures(1, &c->accum);
    if (c->ssbo[0])
        glDeleteBuffers(6, c->ssbo);
    if (c->count)
        glDeleteBuffers(1, &c->count);
    if (c->program)
        glDeleteProgram(c->program);
    free(c->objects);
    free(c);
}

static const char *csm_last_error(void *inst)
{
    return inst ? ((csm *)inst)->error : "";
}

static const gi_method csm_method = {
    .struct_size = sizeof(gi_method),
    .abi_version = GI_ABI_VERSION,
    .id = "csm",
    .title = "Coherent Shadow Maps (distant light)",
    .citation = "Ritschel, Grosch, Kautz, Mueller. Interactive Illumination with Coherent Shadow Maps. EGSR 2007",
    .version = "0.1",
    .caps = GI_CAP_DIRECT | GI_CAP_ENVIRONMENT | GI_CAP_GLOSSY | GI_CAP_VISIBILITY | GI_CAP_PROGRESSIVE |
            GI_CAP_PRECOMPUTE | GI_CAP_RIGID_MOTION | GI_CAP_TEXTURES,
    .max_bounces = 0,
    .params = csm_params,
    .create = csm_create,
    .prepare = csm_prepare,
    .update = csm_update,
    .render = csm_render,
    .destroy = csm_destroy,
    .last_error = csm_last_error,
};

GI_EXPORT const gi_method *gi_method_entry(uint32_t host_abi_version)
{
    if (GI_ABI_VERSION_MAJOR(host_abi_version) != GI_ABI_MAJOR)
        return NULL;
    return &csm_method;
}

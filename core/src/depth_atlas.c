/* Depth atlas (passes.h): many small first-surface depth maps in one R32F
 * texture, drawn with one instanced draw (depth_atlas.vert/.frag), and the
 * C twin of the GLSL lookup (depth_atlas.glsl). */
#include "gi/passes.h"

#include "gi/method.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define ATLAS_MAX_TILE 4096u
#define ATLAS_VIEWS_UNIT GI_TEX_CORE_ATLAS_VIEWS /* the views' texture buffer while drawing */

/* std430 layout of depth_atlas.glsl's GiDepthAtlasViews. */
typedef struct atlas_view_gpu {
    float view[16];
    float proj[16];
    float range[4];
} atlas_view_gpu;

typedef struct atlas_info_gpu {
    uint32_t tile, columns, projection, metric;
} atlas_info_gpu;

struct gi_depth_atlas {
    gi_depth_atlas_desc desc;
    uint32_t columns, rows, width, height, count;
    GLuint program, fbo, tex, depth_rb, ssbo, ssbo_tex;
    GLint loc_grid, loc_views, loc_projection, loc_metric, loc_receiver_side, loc_first;
    atlas_view_gpu *staging; /* capacity entries */
    GLuint geometry_ibo;     /* indices drawn instead of the scene's triangles when not 0 */
    uint32_t geometry_count; /* their triangles */
    const gi_host *host;     /* polled for cancellation between batches of views; NULL: never */
};

/* Triangles (times views) one batch of the draw holds when a host is set:
 * about a tenth of a second on llvmpipe, so that a cancel is seen soon
 * while a draw of a few thousand views is still only a few calls. */
#define ATLAS_BATCH_TRIANGLES (1u << 20)

/* Rejects a desc the atlas cannot draw. */
static gi_result check_desc(const gi_depth_atlas_desc *d, gi_error *err)
{
    if (!d)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "depth atlas: the desc is NULL");
    if (d->tile == 0 || d->tile > ATLAS_MAX_TILE || d->capacity == 0)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "depth atlas: tile %u (1..%u) or capacity %u (>= 1) invalid", d->tile,
                            ATLAS_MAX_TILE, d->capacity);
    if (d->projection != GI_PROJ_PERSPECTIVE && d->projection != GI_PROJ_PARABOLOID)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "depth atlas: projection %d is not perspective or paraboloid",
                            (int)d->projection);
    if (d->metric != GI_DEPTH_EYE_Z && d->metric != GI_DEPTH_RADIAL)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "depth atlas: metric %d invalid",
                            (int)d->metric);
    if (d->cull < 0 || d->cull > 2)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "depth atlas: cull %d is not 0, 1 or 2",
                            d->cull);
    if ((int)d->receiver_side != GI_SIDES_EYE && (int)d->receiver_side != GI_SIDES_RECEIVERS)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "depth atlas: receiver_side %d is not 0 (eye) or 1 (receivers)",
                            (int)d->receiver_side);
    return GI_OK;
}

/* The grid of tiles: the smallest square number of columns that holds
 * capacity tiles, as many rows as they fill; refused when the texture
 * would exceed this GL's limits. */
static gi_result atlas_grid(const gi_depth_atlas_desc *d, uint32_t *columns_out, uint32_t *rows_out,
                            gi_error *err)
{
    uint32_t columns = (uint32_t)ceil(sqrt((double)d->capacity));
    while ((uint64_t)columns * columns < d->capacity) /* guard sqrt rounding */
        columns++;
    while (columns > 1 && (uint64_t)(columns - 1) * (columns - 1) >= d->capacity)
        columns--;
    uint32_t rows = (d->capacity + columns - 1) / columns;
    GLint max_tex = 0, max_rb = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
    uint64_t limit = (uint64_t)(max_tex < max_rb ? max_tex : max_rb);
    if ((uint64_t)columns * d->tile > limit || (uint64_t)rows * d->tile > limit)
        return gi_error_set(
            err, GI_ERR_INVALID_ARGUMENT,
            "depth atlas: %u maps of %u^2 need a %llu x %llu texture, more than this GL "
            "allows (%llu)",
            d->capacity, d->tile, (unsigned long long)columns * d->tile,
            (unsigned long long)rows * d->tile, (unsigned long long)limit);
    *columns_out = columns;
    *rows_out = rows;
    return GI_OK;
}

/* The texture, its depth buffer and framebuffer, and the views' buffer
 * (the info header, then capacity views), bound as a texture buffer too. */
static void create_targets(gi_depth_atlas *a)
{
    const gi_depth_atlas_desc *d = &a->desc;
    a->tex = gi_gpu_texture_2d(GL_R32F, a->width, a->height);
    glCreateRenderbuffers(1, &a->depth_rb);
    glNamedRenderbufferStorage(a->depth_rb, GL_DEPTH_COMPONENT32F, (GLsizei)a->width,
                               (GLsizei)a->height);
    glCreateFramebuffers(1, &a->fbo);
    glNamedFramebufferTexture(a->fbo, GL_COLOR_ATTACHMENT0, a->tex, 0);
    glNamedFramebufferRenderbuffer(a->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, a->depth_rb);
    glNamedFramebufferDrawBuffer(a->fbo, GL_COLOR_ATTACHMENT0);
    /* The SSBO: the info header, then capacity views. */
    atlas_info_gpu info = {d->tile, a->columns, (uint32_t)d->projection, (uint32_t)d->metric};
    GLsizeiptr size = (GLsizeiptr)(sizeof info + (size_t)d->capacity * sizeof(atlas_view_gpu));
    glCreateBuffers(1, &a->ssbo);
    glNamedBufferStorage(a->ssbo, size, NULL, GL_DYNAMIC_STORAGE_BIT);
    glNamedBufferSubData(a->ssbo, 0, sizeof info, &info);
    /* The vertex stage reads the same buffer as a texture buffer (see depth_atlas.vert). */
    glCreateTextures(GL_TEXTURE_BUFFER, 1, &a->ssbo_tex);
    glTextureBuffer(a->ssbo_tex, GL_RGBA32F, a->ssbo);
}

gi_depth_atlas *gi_depth_atlas_create(const gi_depth_atlas_desc *d, gi_error *err)
{
    uint32_t columns = 0, rows = 0;
    if (check_desc(d, err) != GI_OK || atlas_grid(d, &columns, &rows, err) != GI_OK)
        return NULL;
    gi_depth_atlas *a = calloc(1, sizeof *a);
    if (a)
        a->staging = malloc((size_t)d->capacity * sizeof *a->staging);
    if (!a || !a->staging) {
        free(a);
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "depth atlas: out of memory");
        return NULL;
    }
    a->desc = *d;
    a->columns = columns;
    a->rows = rows;
    a->width = columns * d->tile;
    a->height = rows * d->tile;
    a->program = gi_program_build("depth_atlas.vert", NULL, "depth_atlas.frag", NULL, err);
    if (!a->program) {
        free(a->staging);
        free(a);
        return NULL;
    }
    a->loc_grid = glGetUniformLocation(a->program, "u_grid");
    a->loc_views = glGetUniformLocation(a->program, "u_views");
    a->loc_projection = glGetUniformLocation(a->program, "u_projection");
    a->loc_metric = glGetUniformLocation(a->program, "u_metric");
    a->loc_receiver_side = glGetUniformLocation(a->program, "u_receiver_side");
    a->loc_first = glGetUniformLocation(a->program, "u_first");
    create_targets(a);
    if (glCheckNamedFramebufferStatus(a->fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        gi_error_set(err, GI_ERR_GL, "depth atlas: the %ux%u framebuffer is incomplete", a->width,
                     a->height);
        gi_depth_atlas_free(a);
        return NULL;
    }
    /* Every tile starts empty. */
    const float far_value[4] = {FLT_MAX, FLT_MAX, FLT_MAX, FLT_MAX};
    glClearNamedFramebufferfv(a->fbo, GL_COLOR, 0, far_value);
    if (gi_gl_check("depth atlas: create", err) != GI_OK) {
        gi_depth_atlas_free(a);
        return NULL;
    }
    return a;
}

void gi_depth_atlas_free(gi_depth_atlas *a)
{
    if (!a)
        return;
    glDeleteProgram(a->program);
    glDeleteFramebuffers(1, &a->fbo);
    glDeleteRenderbuffers(1, &a->depth_rb);
    glDeleteTextures(1, &a->tex);
    glDeleteTextures(1, &a->ssbo_tex);
    glDeleteBuffers(1, &a->ssbo);
    free(a->staging);
    free(a);
}

/* The instanced draw of views 0..count-1 (u_first + gl_InstanceID is the
 * view): in one call without a host, else in batches of about
 * ATLAS_BATCH_TRIANGLES with host->cancelled() asked before each (llvmpipe
 * runs a draw's vertex work inside the call, so a batch is the longest a
 * cancel waits). */
static gi_result draw_batches(gi_depth_atlas *a, const gi_gpu_scene *gs, uint32_t count,
                              gi_error *err)
{
    uint32_t tris = a->geometry_ibo ? a->geometry_count : gs->scene->triangle_count;
    uint32_t step = count;
    if (a->host && a->host->cancelled) {
        step = ATLAS_BATCH_TRIANGLES / (tris ? tris : 1);
        step = step ? step : 1;
    }
    for (uint32_t first = 0; first < count; first += step) {
        if (a->host && a->host->cancelled && a->host->cancelled(a->host))
            return gi_error_set(err, GI_ERR_CANCELLED, "depth atlas: cancelled");
        uint32_t n = count - first < step ? count - first : step;
        glUniform1ui(a->loc_first, first);
        if (a->geometry_ibo)
            gi_gpu_scene_draw_indices(gs, a->geometry_ibo, a->geometry_count * 3, (GLsizei)n);
        else
            gi_gpu_scene_draw(gs, -1, (GLsizei)n);
    }
    return GI_OK;
}

gi_result gi_depth_atlas_render(gi_depth_atlas *a, const gi_gpu_scene *gs,
                                const gi_depth_view *views, uint32_t count, gi_error *err)
{
    if (!a || !gs || (count > 0 && !views))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "depth atlas: %s is NULL",
                            !a    ? "the atlas"
                            : !gs ? "the GPU scene"
                                  : "the view array");
    const gi_depth_atlas_desc *d = &a->desc;
    if (count > d->capacity)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "depth atlas: %u views exceed its capacity of %u maps", count,
                            d->capacity);
    for (uint32_t i = 0; i < count; i++) {
        const gi_depth_view *v = &views[i];
        if (v->projection != d->projection)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "depth atlas: view %u has projection %d, the atlas %d", i,
                                (int)v->projection, (int)d->projection);
        if (d->projection == GI_PROJ_PARABOLOID &&
            !(v->znear >= 0.0f && v->zfar > v->znear && isfinite(v->zfar)))
            return gi_error_set(
                err, GI_ERR_INVALID_ARGUMENT,
                "depth atlas: view %u: paraboloid range %g..%g is not 0 <= znear < zfar", i,
                (double)v->znear, (double)v->zfar);
        atlas_view_gpu *g = &a->staging[i];
        memcpy(g->view, v->view, sizeof g->view);
        memcpy(g->proj, v->proj, sizeof g->proj);
        g->range[0] = v->znear;
        g->range[1] = v->zfar;
        g->range[2] = g->range[3] = 0.0f;
    }
    if (count > 0)
        glNamedBufferSubData(a->ssbo, sizeof(atlas_info_gpu),
                             (GLsizeiptr)(count * sizeof(atlas_view_gpu)), a->staging);
    glBindFramebuffer(GL_FRAMEBUFFER, a->fbo);
    glViewport(0, 0, (GLsizei)a->width, (GLsizei)a->height);
    const float far_value[4] = {FLT_MAX, FLT_MAX, FLT_MAX, FLT_MAX};
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
    glClearBufferfv(GL_COLOR, 0, far_value);
    glClear(GL_DEPTH_BUFFER_BIT);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_DEPTH_ATLAS, a->ssbo);
    if (count > 0) {
        glUseProgram(a->program);
        gi_gpu_scene_bind(gs);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDisable(GL_BLEND);
        if (d->cull) {
            glEnable(GL_CULL_FACE);
            glCullFace(d->cull == 1 ? GL_BACK : GL_FRONT);
        } else {
            glDisable(GL_CULL_FACE);
        }
        for (GLenum k = 0; k < 5; k++)
            glEnable(GL_CLIP_DISTANCE0 + k);
        glUniform2ui(a->loc_grid, a->columns, a->rows);
        glUniform1i(a->loc_views, ATLAS_VIEWS_UNIT);
        glUniform1i(a->loc_projection, (GLint)d->projection);
        glUniform1i(a->loc_metric, (GLint)d->metric);
        glUniform1i(a->loc_receiver_side, (GLint)d->receiver_side);
        glBindTextureUnit(ATLAS_VIEWS_UNIT, a->ssbo_tex);
        gi_result r = draw_batches(a, gs, count, err);
        for (GLenum k = 0; k < 5; k++)
            glDisable(GL_CLIP_DISTANCE0 + k);
        glDisable(GL_CULL_FACE);
        glBindTextureUnit(ATLAS_VIEWS_UNIT, 0);
        glUseProgram(0);
        if (r != GI_OK) { /* cancelled: the atlas holds no complete set of views */
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
            a->count = 0;
            return r;
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    a->count = count;
    return gi_gl_check("depth atlas: render", err);
}

void gi_depth_atlas_set_host(gi_depth_atlas *a, const gi_host *host)
{
    a->host = host;
}

void gi_depth_atlas_set_geometry(gi_depth_atlas *a, GLuint ibo, uint32_t triangle_count)
{
    a->geometry_ibo = ibo;
    a->geometry_count = ibo ? triangle_count : 0;
}

GLuint gi_depth_atlas_texture(const gi_depth_atlas *a)
{
    return a->tex;
}

GLuint gi_depth_atlas_views_buffer(const gi_depth_atlas *a)
{
    return a->ssbo;
}

uint32_t gi_depth_atlas_columns(const gi_depth_atlas *a)
{
    return a->columns;
}

uint32_t gi_depth_atlas_rows(const gi_depth_atlas *a)
{
    return a->rows;
}

uint32_t gi_depth_atlas_count(const gi_depth_atlas *a)
{
    return a->count;
}

const gi_depth_atlas_desc *gi_depth_atlas_get_desc(const gi_depth_atlas *a)
{
    return &a->desc;
}

uint64_t gi_depth_atlas_bytes(const gi_depth_atlas *a)
{
    return (uint64_t)a->width * a->height * (sizeof(float) + sizeof(float));
}

float *gi_depth_atlas_read_tile(const gi_depth_atlas *a, uint32_t tile)
{
    if (!a || tile >= a->desc.capacity)
        return NULL;
    uint32_t n = a->desc.tile;
    float *out = malloc((size_t)n * n * sizeof *out);
    if (!out)
        return NULL;
    GLint x = (GLint)((tile % a->columns) * n), y = (GLint)((tile / a->columns) * n);
    glGetTextureSubImage(a->tex, 0, x, y, 0, (GLsizei)n, (GLsizei)n, 1, GL_RED, GL_FLOAT,
                         (GLsizei)((size_t)n * n * sizeof *out), out);
    return out;
}

int gi_depth_atlas_texel(const gi_depth_view *v, gi_projection projection, gi_depth_metric metric,
                         uint32_t tile, gi_vec3 p, uint32_t *tx, uint32_t *ty, float *point_depth)
{
    const float *m = v->view;
    gi_vec3 eye = gi_v3(m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12],
                        m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
                        m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]);
    *point_depth = metric == GI_DEPTH_RADIAL ? gi_v3_length(eye) : -eye.z;
    float nx, ny;
    if (projection == GI_PROJ_PARABOLOID) {
        float dist = gi_v3_length(eye);
        gi_vec3 d = gi_v3_scale(eye, 1.0f / fmaxf(dist, 1e-20f));
        if (!(d.z < 0.0f))
            return 0;
        nx = d.x / (1.0f - d.z);
        ny = d.y / (1.0f - d.z);
    } else {
        const float *q = v->proj;
        float cx = q[0] * eye.x + q[4] * eye.y + q[8] * eye.z + q[12];
        float cy = q[1] * eye.x + q[5] * eye.y + q[9] * eye.z + q[13];
        float cw = q[3] * eye.x + q[7] * eye.y + q[11] * eye.z + q[15];
        if (!(cw > 0.0f))
            return 0;
        nx = cx / cw;
        ny = cy / cw;
    }
    if (!(fabsf(nx) <= 1.0f && fabsf(ny) <= 1.0f))
        return 0;
    float fx = floorf((nx * 0.5f + 0.5f) * (float)tile),
          fy = floorf((ny * 0.5f + 0.5f) * (float)tile);
    *tx = fx >= (float)tile ? tile - 1 : (uint32_t)fx;
    *ty = fy >= (float)tile ? tile - 1 : (uint32_t)fy;
    return 1;
}

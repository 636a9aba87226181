/* Shared render passes: G-buffer and (peeled) depth maps; see passes.h. */
#include "gi/passes.h"
#include "gi/image.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

gi_gbuffer *gi_gbuffer_create(uint32_t width, uint32_t height, gi_error *err)
{
    if (width == 0 || height == 0 || width > 16384 || height > 16384) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "G-buffer size %ux%u is not in 1..16384", width,
                     height);
        return NULL;
    }
    gi_gbuffer *gb = calloc(1, sizeof *gb);
    if (!gb) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
        return NULL;
    }
    gb->width = width;
    gb->height = height;
    gb->program = gi_program_build("gbuffer.vert", NULL, "gbuffer.frag", NULL, err);
    if (!gb->program) {
        free(gb);
        return NULL;
    }
    gb->tex_position = gi_gpu_texture_2d(GL_RGBA32F, width, height);
    gb->tex_normal = gi_gpu_texture_2d(GL_RGBA16F, width, height);
    gb->tex_albedo = gi_gpu_texture_2d(GL_RGBA16F, width, height);
    gb->tex_phong = gi_gpu_texture_2d(GL_RGBA16F, width, height);
    gb->tex_emission = gi_gpu_texture_2d(GL_RGBA16F, width, height);
    gb->tex_ids = gi_gpu_texture_2d(GL_RGBA32UI, width, height);
    gb->tex_depth = gi_gpu_texture_2d(GL_DEPTH_COMPONENT32F, width, height);
    glCreateFramebuffers(1, &gb->fbo);
    GLuint color[6] = {gb->tex_position, gb->tex_normal,   gb->tex_albedo,
                       gb->tex_phong,    gb->tex_emission, gb->tex_ids};
    GLenum bufs[6];
    for (int i = 0; i < 6; i++) {
        glNamedFramebufferTexture(gb->fbo, GL_COLOR_ATTACHMENT0 + (GLenum)i, color[i], 0);
        bufs[i] = GL_COLOR_ATTACHMENT0 + (GLenum)i;
    }
    glNamedFramebufferTexture(gb->fbo, GL_DEPTH_ATTACHMENT, gb->tex_depth, 0);
    glNamedFramebufferDrawBuffers(gb->fbo, 6, bufs);
    if (glCheckNamedFramebufferStatus(gb->fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        gi_error_set(err, GI_ERR_GL, "G-buffer framebuffer incomplete");
        gi_gbuffer_free(gb);
        return NULL;
    }
    return gb;
}

void gi_gbuffer_free(gi_gbuffer *gb)
{
    if (!gb)
        return;
    GLuint t[7] = {gb->tex_position, gb->tex_normal, gb->tex_albedo, gb->tex_phong,
                   gb->tex_emission, gb->tex_ids,    gb->tex_depth};
    glDeleteTextures(7, t);
    glDeleteFramebuffers(1, &gb->fbo);
    glDeleteProgram(gb->program);
    free(gb);
}

gi_result gi_gbuffer_render(gi_gbuffer *gb, const gi_gpu_scene *gs, const float view[16],
                            const float proj[16], gi_error *err)
{
    float inv[16];
    if (!gi_mat4_invert(inv, view))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "G-buffer: singular view matrix");
    glBindFramebuffer(GL_FRAMEBUFFER, gb->fbo);
    glViewport(0, 0, (GLsizei)gb->width, (GLsizei)gb->height);
    const float zero[4] = {0, 0, 0, 0};
    const GLuint none[4] = {0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu, 0};
    for (int i = 0; i < 5; i++)
        glClearBufferfv(GL_COLOR, i, zero);
    glClearBufferuiv(GL_COLOR, 5, none);
    glClearBufferfi(GL_DEPTH_STENCIL, 0, 1.0f, 0);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glUseProgram(gb->program);
    glUniformMatrix4fv(glGetUniformLocation(gb->program, "u_view"), 1, GL_FALSE, view);
    glUniformMatrix4fv(glGetUniformLocation(gb->program, "u_proj"), 1, GL_FALSE, proj);
    glUniform3f(glGetUniformLocation(gb->program, "u_eye"), inv[12], inv[13], inv[14]);
    gi_gpu_scene_bind(gs);
    gi_gpu_scene_draw(gs, -1, 1);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return gi_gl_check("G-buffer pass", err);
}

void gi_gbuffer_bind(const gi_gbuffer *gb, GLuint first_unit)
{
    GLuint t[6] = {gb->tex_position, gb->tex_normal,   gb->tex_albedo,
                   gb->tex_phong,    gb->tex_emission, gb->tex_ids};
    for (GLuint i = 0; i < 6; i++)
        glBindTextureUnit(first_unit + i, t[i]);
}

/* ---- depth maps ---- */

/* Frustum culling of the depth pass. The triangles an object draws are
 * taken in runs of DEPTH_RUN (in the index buffer's order, never across
 * objects), each with its box; a view draws only the runs whose box is not
 * wholly outside one of its six clip planes. A triangle in such a box lies
 * outside the view volume, where the rasteriser would clip it whole, so
 * the maps are the same bits as drawing everything (tests/unit/
 * test_passes.c compares them), with fewer vertices shaded and set up: a
 * cube map's face sees about a sixth of the directions around its eye. */
enum { DEPTH_RUN = 128 };

typedef struct depth_run {
    uint32_t first, count; /* indices into the scene's index buffer */
    float box[8][4];       /* the box's corners, as drawn (world or local space) */
} depth_run;

struct gi_depth_renderer {
    gi_depth_desc desc;
    GLuint program, fbo, depth_rb;
    GLuint peel[2]; /* R32F ping-pong of the previous surface */
    int cull_views; /* frustum culling on (the default) */
    depth_run *runs;
    uint32_t nruns, cap_runs;
    GLsizei *counts;       /* per draw: the visible runs merged where adjacent */
    const void **offsets;  /* nruns each */
    uint64_t drawn, total; /* triangles drawn and offered, over the views so far */
};

static int object_drawn(const gi_depth_desc *d, const gi_scene *s, uint32_t o)
{
    if (d->only_object) /* one past the objects draws them all, as gi_gpu_scene_draw does */
        return d->only_object > s->object_count || o + 1 == d->only_object;
    return o + 1 != d->skip_object && !(d->skip_objects && d->skip_objects[o]);
}

/* The runs of every drawn object with their boxes now: from the CPU copy of
 * the vertices (kept in step with the GPU's by the caller of
 * gi_gpu_scene_update_vertices), placed by the objects' current transforms;
 * an object with morph targets is one run with its local bounds, which
 * cover every weight. 0 when out of memory. */
static int depth_runs_build(gi_depth_renderer *r, const gi_gpu_scene *gs)
{
    const gi_scene *s = gs->scene;
    r->nruns = 0;
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *obj = &s->objects[o];
        if (!object_drawn(&r->desc, s, o) || !obj->triangle_count)
            continue;
        uint32_t per = obj->morph_count ? obj->triangle_count : DEPTH_RUN;
        for (uint32_t t0 = 0; t0 < obj->triangle_count; t0 += per) {
            uint32_t n = obj->triangle_count - t0 < per ? obj->triangle_count - t0 : per;
            if (r->nruns == r->cap_runs) {
                uint32_t cap = r->cap_runs ? 2 * r->cap_runs : 64;
                depth_run *nr = realloc(r->runs, cap * sizeof *nr);
                GLsizei *nc = realloc(r->counts, cap * sizeof *nc);
                if (nr)
                    r->runs = nr;
                if (nc)
                    r->counts = nc;
                const void **no = realloc(r->offsets, cap * sizeof *no);
                if (no)
                    r->offsets = no;
                if (!nr || !nc || !no)
                    return 0;
                r->cap_runs = cap;
            }
            depth_run *run = &r->runs[r->nruns++];
            run->first = 3 * (obj->first_triangle + t0);
            run->count = 3 * n;
            float lo[3], hi[3];
            if (obj->morph_count) {
                memcpy(lo, obj->local_bounds, sizeof lo);
                memcpy(hi, obj->local_bounds + 3, sizeof hi);
            } else {
                lo[0] = lo[1] = lo[2] = FLT_MAX;
                hi[0] = hi[1] = hi[2] = -FLT_MAX;
                for (uint32_t i = run->first; i < run->first + run->count; i++) {
                    const float *x = s->vertices[s->indices[i]].position;
                    for (int k = 0; k < 3; k++)
                        lo[k] = x[k] < lo[k] ? x[k] : lo[k], hi[k] = x[k] > hi[k] ? x[k] : hi[k];
                }
            }
            for (int c = 0; c < 8; c++) {
                gi_vec3 p = {c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]};
                if (!r->desc.local)
                    p = gi_mat4_point(gs->world_from_local[o], p);
                run->box[c][0] = p.x, run->box[c][1] = p.y, run->box[c][2] = p.z,
                run->box[c][3] = 1.0f;
            }
        }
    }
    return 1;
}

/* 1 when every corner of the box lies outside one clip plane of clip =
 * proj x view (-w <= x, y, z <= w), with a margin for the GPU's rounding. */
static int depth_box_outside(const float clip[16], const float box[8][4])
{
    double c[8][4];
    for (int k = 0; k < 8; k++)
        for (int i = 0; i < 4; i++)
            c[k][i] = (double)clip[i] * box[k][0] + (double)clip[4 + i] * box[k][1] +
                      (double)clip[8 + i] * box[k][2] + (double)clip[12 + i];
    for (int axis = 0; axis < 3; axis++)
        for (int sign = -1; sign <= 1; sign += 2) {
            int out = 0;
            for (int k = 0; k < 8; k++) {
                double v = sign * c[k][axis], w = c[k][3];
                out += v - w > 1e-4 * (fabs(v) + fabs(w)) + 1e-12;
            }
            if (out == 8)
                return 1;
        }
    return 0;
}

/* The draws of what view dv can see of the runs, in the scene's order: the
 * runs inside its volume, adjacent ones merged, into r->counts and
 * r->offsets; returns how many. Found once per view, drawn once per peeled
 * surface. */
static GLsizei depth_cull_view(gi_depth_renderer *r, const gi_depth_view *dv)
{
    float clip[16];
    gi_mat4_mul(clip, dv->proj, dv->view);
    GLsizei n = 0;
    uint32_t end = UINT32_MAX;
    for (uint32_t k = 0; k < r->nruns; k++) {
        const depth_run *run = &r->runs[k];
        r->total += run->count / 3;
        if (depth_box_outside(clip, run->box))
            continue;
        r->drawn += run->count / 3;
        if (n > 0 && run->first == end) {
            r->counts[n - 1] += (GLsizei)run->count;
        } else {
            r->counts[n] = (GLsizei)run->count;
            r->offsets[n] = (const void *)((size_t)run->first * sizeof(uint32_t));
            n++;
        }
        end = run->first + run->count;
    }
    return n;
}

void gi_depth_renderer_set_culling(gi_depth_renderer *r, int on)
{
    r->cull_views = on;
}

void gi_depth_renderer_drawn(const gi_depth_renderer *r, uint64_t *drawn, uint64_t *total)
{
    *drawn = r->drawn;
    *total = r->total;
}

gi_depth_renderer *gi_depth_renderer_create(const gi_depth_desc *desc, gi_error *err)
{
    gi_depth_desc d = *desc;
    if (d.surfaces == 0)
        d.surfaces = 1;
    if (d.size == 0 || d.size > 16384 || d.surfaces > 4) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "depth maps: size %u (1..16384) or surfaces %u (1..4) invalid", d.size,
                     d.surfaces);
        return NULL;
    }
    if ((int)d.receiver_side < GI_SIDES_EYE || (int)d.receiver_side > GI_SIDES_ANY_THEN_RECEIVERS) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "depth maps: receiver_side %d is not a gi_sides",
                     (int)d.receiver_side);
        return NULL;
    }
    gi_depth_renderer *r = calloc(1, sizeof *r);
    if (!r) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
        return NULL;
    }
    r->desc = d;
    r->cull_views = 1;
    r->program = gi_program_build("depth.vert", NULL, "depth.frag", NULL, err);
    if (!r->program) {
        free(r);
        return NULL;
    }
    glCreateFramebuffers(1, &r->fbo);
    glCreateRenderbuffers(1, &r->depth_rb);
    glNamedRenderbufferStorage(r->depth_rb, GL_DEPTH_COMPONENT32F, (GLsizei)desc->size,
                               (GLsizei)desc->size);
    glNamedFramebufferRenderbuffer(r->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, r->depth_rb);
    r->peel[0] = gi_gpu_texture_2d(GL_R32F, desc->size, desc->size);
    r->peel[1] = gi_gpu_texture_2d(GL_R32F, desc->size, desc->size);
    return r;
}

void gi_depth_renderer_free(gi_depth_renderer *r)
{
    if (!r)
        return;
    glDeleteProgram(r->program);
    glDeleteFramebuffers(1, &r->fbo);
    glDeleteRenderbuffers(1, &r->depth_rb);
    glDeleteTextures(2, r->peel);
    free(r->runs);
    free(r->counts);
    free(r->offsets);
    free(r);
}

GLuint gi_depth_texture_create(const gi_depth_renderer *r, uint32_t layers)
{
    GLuint t;
    glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &t);
    glTextureStorage3D(t, 1, GL_RGBA32F, (GLsizei)r->desc.size, (GLsizei)r->desc.size,
                       (GLsizei)(layers ? layers : 1));
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

void gi_depth_cube_view(gi_vec3 eye, float znear, float zfar, int face, gi_depth_view *out)
{
    gi_mat4_cube_face_view(out->view, eye, face);
    gi_mat4_perspective(out->proj, GI_PI * 0.5f, 1.0f, znear, zfar);
    out->projection = GI_PROJ_PERSPECTIVE;
    out->znear = znear;
    out->zfar = zfar;
}

void gi_depth_cube_views(gi_vec3 eye, float znear, float zfar, gi_depth_view out[6])
{
    for (int f = 0; f < 6; f++)
        gi_depth_cube_view(eye, znear, zfar, f, &out[f]);
}

gi_result gi_depth_render(gi_depth_renderer *r, const gi_gpu_scene *gs, const gi_depth_view *views,
                          uint32_t count, GLuint array_tex, uint32_t first_layer, gi_error *err)
{
    const gi_depth_desc *d = &r->desc;
    GLuint p = r->program;
    glUseProgram(p);
    gi_gpu_scene_bind(gs);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo);
    glViewport(0, 0, (GLsizei)d->size, (GLsizei)d->size);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    if (d->cull) {
        glEnable(GL_CULL_FACE);
        glCullFace(d->cull == 1 ? GL_BACK : GL_FRONT);
    } else {
        glDisable(GL_CULL_FACE);
    }
    glUniform1i(glGetUniformLocation(p, "u_metric"), (GLint)d->metric);
    glUniform1i(glGetUniformLocation(p, "u_local"), d->local);
    glUniform1i(glGetUniformLocation(p, "u_receiver_side"), (GLint)d->receiver_side);
    glUniform1i(glGetUniformLocation(p, "u_prev"), GI_TEX_CORE_DEPTH_PEEL);
    GLint loc_view = glGetUniformLocation(p, "u_view"),
          loc_proj = glGetUniformLocation(p, "u_proj");
    GLint loc_projection = glGetUniformLocation(p, "u_projection"),
          loc_range = glGetUniformLocation(p, "u_range");
    GLint loc_peel = glGetUniformLocation(p, "u_peel");
    const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(r->fbo, 2, bufs);
    const float far_value[4] = {FLT_MAX, FLT_MAX, FLT_MAX, FLT_MAX};
    int culled = r->cull_views && count > 0;
    if (culled && !depth_runs_build(r, gs))
        culled = 0; /* out of memory for the runs: everything is drawn */
    for (uint32_t v = 0; v < count; v++) {
        const gi_depth_view *dv = &views[v];
        int para = dv->projection == GI_PROJ_PARABOLOID;
        if (para)
            glEnable(GL_CLIP_DISTANCE0);
        else
            glDisable(GL_CLIP_DISTANCE0);
        glUniformMatrix4fv(loc_view, 1, GL_FALSE, dv->view);
        glUniformMatrix4fv(loc_proj, 1, GL_FALSE, dv->proj);
        glUniform1i(loc_projection, (GLint)dv->projection);
        glUniform2f(loc_range, dv->znear, dv->zfar);
        glNamedFramebufferTextureLayer(r->fbo, GL_COLOR_ATTACHMENT0, array_tex, 0,
                                       (GLint)(first_layer + v));
        /* Every channel starts at +inf: fewer surfaces than channels. */
        glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        glClearBufferfv(GL_COLOR, 0, far_value);
        /* a paraboloid's volume is not a frustum: drawn whole */
        GLsizei draws = culled && !para ? depth_cull_view(r, dv) : 0;
        for (uint32_t k = 0; k < d->surfaces; k++) {
            GLuint cur = r->peel[k & 1], prev = r->peel[(k + 1) & 1];
            glNamedFramebufferTexture(r->fbo, GL_COLOR_ATTACHMENT1, cur, 0);
            glColorMaski(0, k == 0, k == 1, k == 2, k == 3);
            glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
            glClearBufferfv(GL_COLOR, 1, far_value);
            glClear(GL_DEPTH_BUFFER_BIT);
            glBindTextureUnit(GI_TEX_CORE_DEPTH_PEEL, prev);
            glUniform1i(loc_peel, (GLint)k);
            if (culled && !para) {
                gi_gpu_scene_draw_ranges(gs, r->counts, r->offsets, draws);
            } else if ((d->skip_object || d->skip_objects) && !d->only_object) {
                for (uint32_t o = 0; o < gs->scene->object_count; o++)
                    if (object_drawn(d, gs->scene, o))
                        gi_gpu_scene_draw(gs, (int)o, 1);
            } else {
                gi_gpu_scene_draw(gs, d->only_object ? (int)d->only_object - 1 : -1, 1);
            }
        }
    }
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDisable(GL_CLIP_DISTANCE0);
    glDisable(GL_CULL_FACE);
    glBindTextureUnit(GI_TEX_CORE_DEPTH_PEEL, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glUseProgram(0);
    return gi_gl_check("depth-map pass", err);
}

void gi_depth_read_layer_into(GLuint array_tex, uint32_t size, uint32_t layer, float *out)
{
    size_t n = (size_t)size * size * 4;
    glGetTextureSubImage(array_tex, 0, 0, 0, (GLint)layer, (GLsizei)size, (GLsizei)size, 1, GL_RGBA,
                         GL_FLOAT, (GLsizei)(n * sizeof *out), out);
}

float *gi_depth_read_layer(GLuint array_tex, uint32_t size, uint32_t layer)
{
    float *out = malloc((size_t)size * size * 4 * sizeof *out);
    if (out)
        gi_depth_read_layer_into(array_tex, size, layer, out);
    return out;
}

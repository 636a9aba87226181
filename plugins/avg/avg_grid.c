/* The Approximate Visibility Grid, §III-A (Fig. 2): the scene voxelised by
 * the rasteriser into two 3D textures every frame.
 *
 * The paper draws each triangle once per Z slice it spans, one pass per
 * slice, from a geometry shader. Here the passes are one instanced draw
 * (instance k = slice k) into a layered framebuffer that holds both 3D
 * textures as layers (gl_Layer = k): the same work, one draw call, no
 * image stores (so additive blending does the summing exactly as in the
 * paper, and the result does not depend on the order of fragments).
 *
 * The single-pass voxeliser (AVG_VOX_SINGLE, beside the paper's) draws the
 * scene once: each triangle projected along its dominant axis, each pixel
 * a column of voxels tested against the triangle, sums by integer atomics
 * into a buffer that a compute pass turns into the two textures
 * (shaders/avg_vox1.*, avg_vox_resolve.comp). */
#include "avg.h"
#include "shaders/avg_bindings.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static GLuint make_tex3d(uint32_t n)
{
    GLuint t;
    glCreateTextures(GL_TEXTURE_3D, 1, &t);
    glTextureStorage3D(t, 1, GL_RGBA32F, (GLsizei)n, (GLsizei)n, (GLsizei)n);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    return t;
}

avg_grid *avg_grid_create(uint32_t n, gi_error *err)
{
    avg_grid *g = calloc(1, sizeof *g);
    if (!g) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "avg: out of memory");
        return NULL;
    }
    g->n = n;
    g->h = 1.0f;
    if (gi_shader_register(gi_avg_shaders, err) != GI_OK) {
        avg_grid_free(g);
        return NULL;
    }
    for (int mode = 0; mode < 2; mode++) {
        g->program[mode] =
            gi_program_build("avg_vox.vert", "avg_vox.geom", "avg_vox.frag", NULL, err);
        if (!g->program[mode]) {
            avg_grid_free(g);
            return NULL;
        }
    }
    g->program[AVG_VOX_SINGLE] =
        gi_program_build("avg_vox.vert", "avg_vox1.geom", "avg_vox1.frag", NULL, err);
    g->prog_resolve = g->program[AVG_VOX_SINGLE]
                          ? gi_program_build_compute("avg_vox_resolve.comp", NULL, err)
                          : 0;
    if (!g->prog_resolve) {
        avg_grid_free(g);
        return NULL;
    }
    glCreateFramebuffers(1, &g->fbo_single);
    glNamedFramebufferParameteri(g->fbo_single, GL_FRAMEBUFFER_DEFAULT_WIDTH, (GLint)n);
    glNamedFramebufferParameteri(g->fbo_single, GL_FRAMEBUFFER_DEFAULT_HEIGHT, (GLint)n);
    g->tex_normal = make_tex3d(n);
    g->tex_colour = make_tex3d(n);
    glCreateFramebuffers(1, &g->fbo);
    glNamedFramebufferTexture(g->fbo, GL_COLOR_ATTACHMENT0, g->tex_normal, 0);
    glNamedFramebufferTexture(g->fbo, GL_COLOR_ATTACHMENT1, g->tex_colour, 0);
    const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(g->fbo, 2, bufs);
    GLenum status = glCheckNamedFramebufferStatus(g->fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        gi_error_set(err, GI_ERR_GL, "avg: layered grid framebuffer incomplete (0x%x)", status);
        avg_grid_free(g);
        return NULL;
    }
    if (gi_gl_check("avg: grid creation", err) != GI_OK) {
        avg_grid_free(g);
        return NULL;
    }
    return g;
}

void avg_grid_free(avg_grid *g)
{
    if (!g)
        return;
    if (g->fbo)
        glDeleteFramebuffers(1, &g->fbo);
    if (g->tex_normal)
        glDeleteTextures(1, &g->tex_normal);
    if (g->tex_colour)
        glDeleteTextures(1, &g->tex_colour);
    if (g->ssbo_colours)
        glDeleteBuffers(1, &g->ssbo_colours);
    if (g->ssbo_sums)
        glDeleteBuffers(1, &g->ssbo_sums);
    if (g->fbo_single)
        glDeleteFramebuffers(1, &g->fbo_single);
    for (int i = 0; i < 3; i++)
        if (g->program[i])
            glDeleteProgram(g->program[i]);
    if (g->prog_resolve)
        glDeleteProgram(g->prog_resolve);
    free(g);
}

void avg_grid_place(avg_grid *g, const float bounds[6])
{
    float ext = 0.0f;
    for (int a = 0; a < 3; a++)
        ext = fmaxf(ext, bounds[3 + a] - bounds[a]);
    if (!(ext > 0.0f))
        ext = 1.0f;
    /* n - 3 voxels span the scene's largest extent, centred: 1.5 voxels of
     * margin, so that walls at the bounds lie in the middle of a voxel
     * layer rather than on the faces between two (which would fill both). */
    g->h = ext / (float)(g->n > 3 ? g->n - 3 : g->n);
    for (int a = 0; a < 3; a++)
        g->origin[a] = 0.5f * (bounds[a] + bounds[3 + a]) - 0.5f * g->h * (float)g->n;
}

/* Per material, the colour a voxel takes from it: the albedo times the
 * texture's mean colour, which is what the paper's "lowest mip-map level"
 * holds (the core keeps one level only, so the mean is computed here). */
static gi_result upload_material_colours(avg_grid *g, const gi_scene *s, gi_error *err)
{
    uint32_t n = s->material_count ? s->material_count : 1;
    float *c = calloc((size_t)n * 4, sizeof *c);
    if (!c)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "avg: out of memory");
    for (uint32_t m = 0; m < s->material_count; m++) {
        const gi_material *mat = &s->materials[m];
        double mean[3] = {1, 1, 1};
        if (mat->albedo_texture >= 0) {
            const gi_texture *t = &s->textures[mat->albedo_texture];
            size_t texels = (size_t)t->width * t->height;
            mean[0] = mean[1] = mean[2] = 0.0;
            for (size_t i = 0; i < texels; i++)
                for (int k = 0; k < 3; k++)
                    mean[k] += t->rgba[4 * i + k];
            for (int k = 0; k < 3; k++)
                mean[k] = texels ? mean[k] / (double)texels : 1.0;
        }
        for (int k = 0; k < 3; k++)
            c[4 * m + k] = (float)(mat->albedo[k] * mean[k]);
    }
    if (g->ssbo_colours)
        glDeleteBuffers(1, &g->ssbo_colours);
    glCreateBuffers(1, &g->ssbo_colours);
    glNamedBufferStorage(g->ssbo_colours, (GLsizeiptr)((size_t)n * 4 * sizeof *c), c, 0);
    free(c);
    g->colour_scene = s;
    return GI_OK;
}

gi_result avg_grid_check_single(uint32_t n, gi_error *err)
{
    size_t bytes = (size_t)n * n * n * 8 * sizeof(int32_t);
    GLint64 limit = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &limit);
    if ((GLint64)bytes > limit)
        return gi_error_set(
            err, GI_ERR_INVALID_ARGUMENT,
            "avg: voxeliser=single needs %zu MiB of sums at grid=%u, more than this GL's "
            "largest storage buffer (%lld MiB); use a smaller grid or voxeliser=conservative",
            bytes >> 20, n, (long long)(limit >> 20));
    return GI_OK;
}

/* One draw of the scene into the fixed-point sums, then the resolve
 * into the textures (AVG_VOX_SINGLE). */
static gi_result voxelise_single(avg_grid *g, const gi_gpu_scene *gs, gi_error *err)
{
    size_t bytes = (size_t)g->n * g->n * g->n * 8 * sizeof(int32_t);
    if (!g->ssbo_sums) {
        if (avg_grid_check_single(g->n, err) != GI_OK)
            return GI_ERR_INVALID_ARGUMENT;
        glCreateBuffers(1, &g->ssbo_sums);
        glNamedBufferStorage(g->ssbo_sums, (GLsizeiptr)bytes, NULL, GL_DYNAMIC_STORAGE_BIT);
        if (gi_gl_check("avg: single-pass voxel sums", err) != GI_OK)
            return GI_ERR_GL;
    }
    const int32_t zero = 0;
    glClearNamedBufferData(g->ssbo_sums, GL_R32I, GL_RED_INTEGER, GL_INT, &zero);
    GLuint p = g->program[AVG_VOX_SINGLE];
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo_single);
    glViewport(0, 0, (GLsizei)g->n, (GLsizei)g->n);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glUseProgram(p);
    glUniform3f(glGetUniformLocation(p, "u_grid_origin"), g->origin[0], g->origin[1], g->origin[2]);
    glUniform1f(glGetUniformLocation(p, "u_grid_h"), g->h);
    glUniform1i(glGetUniformLocation(p, "u_grid_n"), (GLint)g->n);
    gi_gpu_scene_bind(gs);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, AVG_SSBO_COLOURS, g->ssbo_colours);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, AVG_SSBO_VOX_SUMS, g->ssbo_sums);
    gi_gpu_scene_draw(gs, -1, 1);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    p = g->prog_resolve;
    glUseProgram(p);
    glUniform1i(glGetUniformLocation(p, "u_grid_n"), (GLint)g->n);
    glBindImageTexture(0, g->tex_normal, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, g->tex_colour, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    GLuint groups = (g->n + 3) / 4;
    glDispatchCompute(groups, groups, groups);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                    GL_TEXTURE_UPDATE_BARRIER_BIT);
    glUseProgram(0);
    return gi_gl_check("avg: single-pass voxelisation", err);
}

/* The per-slice passes (§III-A) as instanced draws of the scene: all n
 * slices in one draw without a host, else batches of about AVG_VOX_BATCH
 * triangles (times slices) with host->cancelled() asked before each
 * (llvmpipe runs a draw's vertex and geometry work inside the call). */
#define AVG_VOX_BATCH (1u << 19)
static gi_result draw_slices(const avg_grid *g, const gi_gpu_scene *gs, GLuint p, gi_error *err)
{
    uint32_t tris = gs->scene->triangle_count, step = g->n;
    if (g->host && g->host->cancelled) {
        step = AVG_VOX_BATCH / (tris ? tris : 1);
        step = step ? step : 1;
    }
    GLint loc = glGetUniformLocation(p, "u_first_slice");
    for (uint32_t first = 0; first < g->n; first += step) {
        if (g->host && g->host->cancelled && g->host->cancelled(g->host))
            return gi_error_set(err, GI_ERR_CANCELLED, "avg: voxelisation cancelled");
        glUniform1i(loc, (GLint)first);
        gi_gpu_scene_draw(gs, -1, (GLsizei)(g->n - first < step ? g->n - first : step));
    }
    return GI_OK;
}

gi_result avg_grid_voxelise(avg_grid *g, const gi_gpu_scene *gs, avg_vox_mode mode, gi_error *err)
{
    if (g->colour_scene != gs->scene && upload_material_colours(g, gs->scene, err) != GI_OK)
        return GI_ERR_OUT_OF_MEMORY;
    if (mode == AVG_VOX_SINGLE)
        return voxelise_single(g, gs, err);
    const float zero[4] = {0, 0, 0, 0};
    glClearTexImage(g->tex_normal, 0, GL_RGBA, GL_FLOAT, zero);
    glClearTexImage(g->tex_colour, 0, GL_RGBA, GL_FLOAT, zero);
    GLuint p = g->program[mode];
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
    glViewport(0, 0, (GLsizei)g->n, (GLsizei)g->n);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    glUseProgram(p);
    glUniform3f(glGetUniformLocation(p, "u_grid_origin"), g->origin[0], g->origin[1], g->origin[2]);
    glUniform1f(glGetUniformLocation(p, "u_grid_h"), g->h);
    glUniform1i(glGetUniformLocation(p, "u_grid_n"), (GLint)g->n);
    glUniform1i(glGetUniformLocation(p, "u_mode"), (GLint)mode);
    glUniform1f(glGetUniformLocation(p, "u_epsilon"), 0.5f);
    gi_gpu_scene_bind(gs);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, AVG_SSBO_COLOURS, g->ssbo_colours);
    gi_result r = draw_slices(g, gs, p, err);
    glUseProgram(0);
    glDisable(GL_BLEND);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    return r != GI_OK ? r : gi_gl_check("avg: voxelisation", err);
}

float *avg_grid_read(const avg_grid *g, int colour)
{
    size_t count = (size_t)g->n * g->n * g->n * 4;
    float *out = malloc(count * sizeof *out);
    if (!out)
        return NULL;
    glGetTextureImage(colour ? g->tex_colour : g->tex_normal, 0, GL_RGBA, GL_FLOAT,
                      (GLsizei)(count * sizeof *out), out);
    return out;
}

void avg_grid_bind(const avg_grid *g, GLuint program, GLuint unit_normal, GLuint unit_colour)
{
    glBindTextureUnit(unit_normal, g->tex_normal);
    glBindTextureUnit(unit_colour, g->tex_colour);
    glUniform3f(glGetUniformLocation(program, "u_grid_origin"), g->origin[0], g->origin[1],
                g->origin[2]);
    glUniform1f(glGetUniformLocation(program, "u_grid_h"), g->h);
    glUniform1i(glGetUniformLocation(program, "u_grid_n"), (GLint)g->n);
}

/* The `direct` method: unshadowed direct light, the "no visibility"
 * baseline of every comparison (the AVG paper's "FPS (NV)" column).
 *
 * Per pixel of the core's G-buffer, in one compute pass (shaders/direct.comp):
 *  - emission seen directly;
 *  - area lights: `light_samples` points per pixel and frame, emitter
 *    chosen by power, uniform on the triangle (area measure);
 *  - point, spot and directional lights evaluated exactly;
 *  - the environment map: `env_samples` draws from its luminance CDF, with
 *    multiple importance sampling against BRDF samples when `mis` is on;
 *    ideal mirrors reflect the environment along the mirror direction.
 * No visibility test anywhere: everything a light could reach, it reaches.
 * Area lights are not seen through mirrors (that needs a ray query).
 * Frames of a still view average progressively; a moved camera or scene
 * restarts the average. */
#include "gi/method.h"
#include "gi/passes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gi_shader_source gi_direct_shaders[];

typedef struct direct {
    const gi_host *host;
    int light_samples, env_samples, mis, accumulate;
    gi_gbuffer *gbuffer;
    GLuint program, accum;
    uint32_t width, height;
    uint32_t frames; /* frames in the running average */
    float last_view_proj[16];
    const gi_gpu_scene *scene;
    char error[GI_ERROR_MAX];
} direct;

static const gi_param_desc direct_params[] = {
    {"light_samples", GI_PARAM_INT, 16, 1, 4096, NULL, "S (area lights)",
     "area-light samples per pixel and frame"},
    {"env_samples", GI_PARAM_INT, 16, 0, 4096, NULL, "S (environment)",
     "environment-map samples per pixel and frame (and as many BRDF samples with mis)"},
    {"mis", GI_PARAM_BOOL, 1, 0, 1, NULL, NULL, "combine environment and BRDF sampling (power heuristic)"},
    {"accumulate", GI_PARAM_BOOL, 1, 0, 1, NULL, NULL, "average frames of a still view"},
    {0},
};

static gi_result fail(direct *d, gi_result r, const char *msg)
{
    snprintf(d->error, sizeof d->error, "%s", msg);
    return r;
}

static gi_result direct_create(const gi_host *host, const gi_params *params, void **out)
{
    direct *d = calloc(1, sizeof *d);
    if (!d)
        return GI_ERR_OUT_OF_MEMORY;
    d->host = host;
    d->light_samples = gi_params_int(params, "light_samples");
    d->env_samples = gi_params_int(params, "env_samples");
    d->mis = gi_params_bool(params, "mis");
    d->accumulate = gi_params_bool(params, "accumulate");
    gi_shader_register(gi_direct_shaders);
    *out = d;
    return GI_OK;
}

static gi_result direct_prepare(void *inst, const gi_gpu_scene *scene)
{
    direct *d = inst;
    gi_error err;
    d->scene = scene;
    d->program = gi_program_build_compute("direct.comp", NULL, &err);
    if (!d->program)
        return fail(d, GI_ERR_GL, err.text);
    return GI_OK;
}

static gi_result direct_update(void *inst, const gi_gpu_scene *scene, const gi_changes *changes)
{
    direct *d = inst;
    d->scene = scene;
    if (changes->flags)
        d->frames = 0;
    return GI_OK;
}

static gi_result ensure_size(direct *d, uint32_t w, uint32_t h)
{
    if (d->gbuffer && d->width == w && d->height == h)
        return GI_OK;
    gi_gbuffer_free(d->gbuffer);
    glDeleteTextures(1, &d->accum);
    gi_error err;
    d->gbuffer = gi_gbuffer_create(w, h, &err);
    if (!d->gbuffer)
        return fail(d, GI_ERR_GL, err.text);
    glCreateTextures(GL_TEXTURE_2D, 1, &d->accum);
    glTextureStorage2D(d->accum, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
    d->width = w;
    d->height = h;
    d->frames = 0;
    return GI_OK;
}

static gi_result direct_render(void *inst, const gi_view *view, const gi_target *target)
{
    direct *d = inst;
    gi_error err;
    gi_result r = ensure_size(d, view->width, view->height);
    if (r != GI_OK)
        return r;
    if (!d->accumulate || view->frame_index == 0 || memcmp(d->last_view_proj, view->view_proj, sizeof d->last_view_proj))
        d->frames = 0;
    memcpy(d->last_view_proj, view->view_proj, sizeof d->last_view_proj);

    d->host->stage_begin(d->host, "gbuffer");
    r = gi_gbuffer_render(d->gbuffer, d->scene, view->view, view->proj, &err);
    d->host->stage_end(d->host, "gbuffer");
    if (r != GI_OK)
        return fail(d, r, err.text);

    d->host->stage_begin(d->host, "shade");
    GLuint p = d->program;
    glUseProgram(p);
    gi_gpu_scene_bind(d->scene);
    gi_gbuffer_bind(d->gbuffer, GI_BINDING_PLUGIN_FIRST);
    glBindImageTexture(0, d->accum, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(1, target->texture, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform3f(glGetUniformLocation(p, "u_eye"), view->eye.x, view->eye.y, view->eye.z);
    glUniformMatrix4fv(glGetUniformLocation(p, "u_inv_view_proj"), 1, GL_FALSE, view->inv_view_proj);
    glUniform2i(glGetUniformLocation(p, "u_size"), (GLint)view->width, (GLint)view->height);
    glUniform1ui(glGetUniformLocation(p, "u_frame"), d->frames);
    glUniform1ui(glGetUniformLocation(p, "u_seed"), view->seed);
    glUniform1i(glGetUniformLocation(p, "u_light_samples"), d->light_samples);
    glUniform1i(glGetUniformLocation(p, "u_env_samples"), d->env_samples);
    glUniform1i(glGetUniformLocation(p, "u_mis"), d->mis);
    glDispatchCompute((view->width + 7) / 8, (view->height + 7) / 8, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                    GL_FRAMEBUFFER_BARRIER_BIT);
    glUseProgram(0);
    d->host->stage_end(d->host, "shade");
    d->frames++;
    d->host->stat(d->host, "samples_per_pixel_area", (double)d->frames * d->light_samples);
    d->host->stat(d->host, "samples_per_pixel_env", (double)d->frames * d->env_samples);
    if (gi_gl_check("direct: shading pass", &err) != GI_OK)
        return fail(d, GI_ERR_GL, err.text);
    return GI_OK;
}

static void direct_destroy(void *inst)
{
    direct *d = inst;
    if (!d)
        return;
    gi_gbuffer_free(d->gbuffer);
    if (d->accum)
        glDeleteTextures(1, &d->accum);
    if (d->program)
        glDeleteProgram(d->program);
    free(d);
}

static const char *direct_last_error(void *inst)
{
    return inst ? ((direct *)inst)->error : "";
}

static const gi_method direct_method = {
    .struct_size = sizeof(gi_method),
    .abi_version = GI_ABI_VERSION,
    .id = "direct",
    .title = "Unshadowed direct light (no-visibility baseline)",
    .citation = "gibench baseline: direct light without visibility",
    .version = "1.0",
    .caps = GI_CAP_DIRECT | GI_CAP_GLOSSY | GI_CAP_MIRROR | GI_CAP_AREA_LIGHTS | GI_CAP_POINT_LIGHTS |
            GI_CAP_DIRECTIONAL | GI_CAP_ENVIRONMENT | GI_CAP_RIGID_MOTION | GI_CAP_PROGRESSIVE |
            GI_CAP_TEXTURES,
    .max_bounces = 0,
    .params = direct_params,
    .create = direct_create,
    .prepare = direct_prepare,
    .update = direct_update,
    .render = direct_render,
    .destroy = direct_destroy,
    .last_error = direct_last_error,
};

GI_EXPORT const gi_method *gi_method_entry(uint32_t host_abi_version)
{
    if (GI_ABI_VERSION_MAJOR(host_abi_version) != GI_ABI_MAJOR)
        return NULL;
    return &direct_method;
}

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
#include "gi/kit.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gi_shader_source gi_direct_shaders[];

typedef struct direct {
    gi_kit kit;
    int light_samples, env_samples, mis, accumulate;
    GLuint program;
} direct;

static const gi_param_desc direct_params[] = {
    {"light_samples", GI_PARAM_INT, 16, 1, 4096, GI_QUALITY_UP(2), "S (area lights)",
     "area-light samples per pixel and frame"},
    {"env_samples", GI_PARAM_INT, 16, 0, 4096, GI_QUALITY_UP(2), "S (environment)",
     "environment-map samples per pixel and frame (and as many BRDF samples with mis)"},
    {"mis", GI_PARAM_BOOL, 1, 0, 1, NULL, NULL,
     "combine environment and BRDF sampling (power heuristic)"},
    {"accumulate", GI_PARAM_BOOL, 1, 0, 1, NULL, NULL, "average frames of a still view"},
    {0},
};

static gi_result direct_create(const gi_host *host, const gi_params *params, void **out)
{
    direct *d = calloc(1, sizeof *d);
    if (!d)
        return GI_ERR_OUT_OF_MEMORY;
    if (gi_kit_init(&d->kit, host, gi_direct_shaders) != GI_OK) {
        free(d);
        return GI_ERR_INVALID_ARGUMENT;
    }
    d->light_samples = gi_params_int(params, "light_samples");
    d->env_samples = gi_params_int(params, "env_samples");
    d->mis = gi_params_bool(params, "mis");
    d->accumulate = gi_params_bool(params, "accumulate");
    *out = d;
    return GI_OK;
}

static gi_result direct_prepare(void *inst, const gi_gpu_scene *scene)
{
    direct *d = inst;
    gi_kit_prepare(&d->kit, scene);
    if (!d->program) {
        gi_error err;
        d->program = gi_program_build_compute("direct.comp", NULL, &err);
        if (!d->program)
            return gi_kit_fail_with(&d->kit, GI_ERR_GL, &err);
    }
    return GI_OK;
}

static gi_result direct_update(void *inst, const gi_gpu_scene *scene, const gi_changes *changes)
{
    gi_kit_update(&((direct *)inst)->kit, scene, changes);
    return GI_OK;
}

static gi_result direct_render(void *inst, const gi_view *view, const gi_target *target)
{
    direct *d = inst;
    gi_kit *k = &d->kit;
    const gi_host *host = k->host;
    gi_result r = gi_kit_frame_begin(
        k, view, GI_KIT_GBUFFER | GI_KIT_ACCUMULATE | (d->accumulate ? 0 : GI_KIT_NO_AVERAGE));
    if (r == GI_OK)
        r = gi_kit_render_gbuffer(k, view, "gbuffer");
    if (r != GI_OK)
        return r;

    host->stage_begin(host, "shade");
    GLuint p = d->program;
    glUseProgram(p);
    gi_kit_bind(k, p, view, target);
    glUniform1i(glGetUniformLocation(p, "u_light_samples"), d->light_samples);
    glUniform1i(glGetUniformLocation(p, "u_env_samples"), d->env_samples);
    glUniform1i(glGetUniformLocation(p, "u_mis"), d->mis);
    gi_kit_dispatch_8x8(view->width, view->height);
    glUseProgram(0);
    host->stage_end(host, "shade");
    gi_kit_frame_end(k);
    host->stat(host, "samples_per_pixel_area", (double)k->frames * d->light_samples);
    host->stat(host, "samples_per_pixel_env", (double)k->frames * d->env_samples);
    gi_error err;
    if (gi_gl_check("direct: shading pass", &err) != GI_OK)
        return gi_kit_fail_with(k, GI_ERR_GL, &err);
    return GI_OK;
}

static void direct_destroy(void *inst)
{
    direct *d = inst;
    if (!d)
        return;
    gi_kit_free(&d->kit);
    if (d->program)
        glDeleteProgram(d->program);
    free(d);
}

static const char *direct_last_error(void *inst)
{
    return inst ? gi_kit_last_error(&((direct *)inst)->kit) : "";
}

GI_METHOD_EXPORT(direct, .id = "direct",
                 .title = "Unshadowed direct light (no-visibility baseline)",
                 .citation = "gibench baseline: direct light without visibility", .version = "1.0",
                 .caps = GI_CAP_DIRECT | GI_CAP_GLOSSY | GI_CAP_MIRROR | GI_CAP_AREA_LIGHTS |
                         GI_CAP_POINT_LIGHTS | GI_CAP_DIRECTIONAL | GI_CAP_ENVIRONMENT |
                         GI_CAP_RIGID_MOTION | GI_CAP_DEFORMATION | GI_CAP_PROGRESSIVE |
                         GI_CAP_TEXTURES,
                 .max_bounces = 0, .params = direct_params);

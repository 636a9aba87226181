/* The `example_env` method: the complete plugin that docs/plugins.md walks
 * through (it shows this file verbatim, and a test keeps the two equal).
 *
 * Unshadowed environment light on Lambertian surfaces: per G-buffer pixel,
 * `samples` cosine-weighted directions a frame, each weighted by the
 * environment's radiance (albedo / pi x L x cos / (cos / pi) = albedo x L),
 * averaged over the frames of a still view. No visibility, no glossy lobe,
 * no other light: its caps say so, and the harness marks other scenes n/a. */
#include "gi/kit.h"

#include <stdlib.h>

extern const gi_shader_source gi_example_env_shaders[]; /* shaders/, embedded by the build */

typedef struct example_env {
    gi_kit kit; /* host, scene, G-buffer, running average, error text */
    GLuint program;
    int samples;
} example_env;

static const gi_param_desc example_env_params[] = {
    {"samples", GI_PARAM_INT, 4, 1, 256, NULL, "S",
     "cosine-weighted directions per pixel and frame"},
    {0},
};

static gi_result example_env_create(const gi_host *host, const gi_params *params, void **out)
{
    example_env *e = calloc(1, sizeof *e);
    if (!e)
        return GI_ERR_OUT_OF_MEMORY;
    if (gi_kit_init(&e->kit, host, gi_example_env_shaders) != GI_OK) {
        free(e);
        return GI_ERR_INVALID_ARGUMENT;
    }
    e->samples = gi_params_int(params, "samples");
    *out = e;
    return GI_OK;
}

static gi_result example_env_prepare(void *inst, const gi_gpu_scene *scene)
{
    example_env *e = inst;
    gi_kit_prepare(&e->kit, scene);
    if (e->program)
        return GI_OK;
    gi_error err;
    e->program = gi_program_build_compute("example_env.comp", NULL, &err);
    return e->program ? GI_OK : gi_kit_fail_with(&e->kit, GI_ERR_GL, &err);
}

static gi_result example_env_update(void *inst, const gi_gpu_scene *scene,
                                    const gi_changes *changes)
{
    gi_kit_update(&((example_env *)inst)->kit, scene, changes);
    return GI_OK;
}

static gi_result example_env_render(void *inst, const gi_view *view, const gi_target *target)
{
    example_env *e = inst;
    gi_kit *k = &e->kit;
    gi_result r = gi_kit_frame_begin(k, view, GI_KIT_GBUFFER | GI_KIT_ACCUMULATE);
    if (r == GI_OK)
        r = gi_kit_render_gbuffer(k, view, "gbuffer");
    if (r != GI_OK)
        return r;
    k->host->stage_begin(k->host, "shade");
    glUseProgram(e->program);
    gi_kit_bind(k, e->program, view, target);
    glUniform1i(glGetUniformLocation(e->program, "u_samples"), e->samples);
    gi_kit_dispatch_8x8(view->width, view->height);
    glUseProgram(0);
    k->host->stage_end(k->host, "shade");
    gi_kit_frame_end(k);
    k->host->stat(k->host, "samples_per_pixel_env", (double)k->frames * e->samples);
    gi_error err;
    return gi_gl_check("example_env: shading", &err) == GI_OK
               ? GI_OK
               : gi_kit_fail_with(k, GI_ERR_GL, &err);
}

static void example_env_destroy(void *inst)
{
    example_env *e = inst;
    if (!e)
        return;
    gi_kit_free(&e->kit);
    if (e->program)
        glDeleteProgram(e->program);
    free(e);
}

static const char *example_env_last_error(void *inst)
{
    return inst ? gi_kit_last_error(&((example_env *)inst)->kit) : "";
}

GI_METHOD_EXPORT(
    example_env, .id = "example_env",
    .title =
        "Unshadowed environment light by cosine sampling (the example plugin of docs/plugins.md)",
    .citation = "gibench example", .version = "1.0",
    .caps = GI_CAP_DIRECT | GI_CAP_ENVIRONMENT | GI_CAP_RIGID_MOTION | GI_CAP_DEFORMATION |
            GI_CAP_PROGRESSIVE | GI_CAP_TEXTURES,
    .max_bounces = 0, .params = example_env_params);

/* The method kit (kit.h): sizing, accumulation restarts, bindings and error
 * text that every G-buffer method needs. */
#include "gi/kit.h"
#include "gi/log.h"

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

gi_result gi_kit_init(gi_kit *k, const gi_host *host, const gi_shader_source *shaders)
{
    memset(k, 0, sizeof *k);
    k->host = host;
    if (shaders && gi_shader_register(shaders, &k->error) != GI_OK) {
        if (host && host->log)
            host->log(host, GI_LOG_ERROR, "%s", k->error.text);
        return GI_ERR_INVALID_ARGUMENT;
    }
    return GI_OK;
}

void gi_kit_prepare(gi_kit *k, const gi_gpu_scene *gs)
{
    k->scene = gs;
    k->frames = 0;
}

void gi_kit_update(gi_kit *k, const gi_gpu_scene *gs, const gi_changes *changes)
{
    k->scene = gs;
    if (changes && changes->flags)
        k->frames = 0;
}

static void free_sized(gi_kit *k)
{
    gi_gbuffer_free(k->gbuffer);
    k->gbuffer = NULL;
    if (k->accum)
        glDeleteTextures(1, &k->accum);
    k->accum = 0;
}

gi_result gi_kit_frame_begin(gi_kit *k, const gi_view *v, unsigned what)
{
    int resized = k->width != v->width || k->height != v->height;
    if (resized || (!k->gbuffer && (what & GI_KIT_GBUFFER)) ||
        (!k->accum && (what & GI_KIT_ACCUMULATE))) {
        free_sized(k);
        gi_error err;
        if (what & GI_KIT_GBUFFER) {
            k->gbuffer = gi_gbuffer_create(v->width, v->height, &err);
            if (!k->gbuffer)
                return gi_kit_fail_with(k, GI_ERR_GL, &err);
        }
        if (what & GI_KIT_ACCUMULATE)
            k->accum = gi_gpu_texture_2d(GL_RGBA32F, v->width, v->height);
        k->width = v->width;
        k->height = v->height;
        k->frames = 0;
    }
    if ((what & GI_KIT_NO_AVERAGE) || v->frame_index == 0 ||
        memcmp(k->last_view_proj, v->view_proj, sizeof k->last_view_proj) != 0)
        k->frames = 0;
    memcpy(k->last_view_proj, v->view_proj, sizeof k->last_view_proj);
    return GI_OK;
}

gi_result gi_kit_render_gbuffer(gi_kit *k, const gi_view *v, const char *stage)
{
    if (!k->gbuffer || !k->scene)
        return gi_kit_fail(
            k, GI_ERR_INVALID_ARGUMENT,
            "G-buffer asked for before prepare() or without GI_KIT_GBUFFER in gi_kit_frame_begin");
    if (stage)
        k->host->stage_begin(k->host, stage);
    gi_error err;
    gi_result r = gi_gbuffer_render(k->gbuffer, k->scene, v->view, v->proj, &err);
    if (stage)
        k->host->stage_end(k->host, stage);
    return r == GI_OK ? GI_OK : gi_kit_fail_with(k, r, &err);
}

void gi_kit_bind(const gi_kit *k, GLuint program, const gi_view *v, const gi_target *t)
{
    if (k->scene)
        gi_gpu_scene_bind(k->scene);
    if (k->gbuffer)
        gi_gbuffer_bind(k->gbuffer, GI_TEX_GBUFFER_POSITION);
    if (k->accum)
        glBindImageTexture(GI_IMAGE_ACCUM, k->accum, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (t)
        glBindImageTexture(GI_IMAGE_TARGET, t->texture, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform3f(glGetUniformLocation(program, "u_eye"), v->eye.x, v->eye.y, v->eye.z);
    glUniformMatrix4fv(glGetUniformLocation(program, "u_inv_view_proj"), 1, GL_FALSE,
                       v->inv_view_proj);
    glUniform2i(glGetUniformLocation(program, "u_size"), (GLint)v->width, (GLint)v->height);
    glUniform1ui(glGetUniformLocation(program, "u_frame"), k->frames);
    glUniform1ui(glGetUniformLocation(program, "u_seed"), v->seed);
}

void gi_kit_frame_end(gi_kit *k)
{
    k->frames++;
}

GLuint gi_kit_scratch_texture(gi_kit *k, unsigned slot, GLenum format, uint32_t width,
                              uint32_t height)
{
    if (slot >= GI_KIT_SCRATCH_MAX)
        return 0;
    gi_kit_scratch *s = &k->scratch[slot];
    if (s->texture && s->format == format && s->width == width && s->height == height)
        return s->texture;
    if (s->texture)
        glDeleteTextures(1, &s->texture);
    s->texture = gi_gpu_texture_2d(format, width, height);
    s->format = format;
    s->width = width;
    s->height = height;
    return s->texture;
}

GLuint gi_kit_debug_target(gi_kit *k, GLuint program, unsigned slot, uint32_t width,
                           uint32_t height)
{
    GLuint tex = gi_kit_scratch_texture(k, slot, GL_RGBA32F, width, height);
    if (!tex)
        return 0;
    /* both images at the scratch texture, as a first frame: the average and
     * the target the next render() continues from stay untouched */
    glBindImageTexture(GI_IMAGE_ACCUM, tex, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(GI_IMAGE_TARGET, tex, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform1ui(glGetUniformLocation(program, "u_frame"), 0u);
    return tex;
}

void gi_kit_free(gi_kit *k)
{
    if (!k)
        return;
    free_sized(k);
    for (unsigned i = 0; i < GI_KIT_SCRATCH_MAX; i++)
        if (k->scratch[i].texture)
            glDeleteTextures(1, &k->scratch[i].texture);
    memset(k->scratch, 0, sizeof k->scratch);
}

gi_result gi_kit_fail(gi_kit *k, gi_result r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(k->error.text, sizeof k->error.text, fmt, ap);
    va_end(ap);
    return r;
}

gi_result gi_kit_fail_with(gi_kit *k, gi_result r, const gi_error *err)
{
    if (err != &k->error)
        snprintf(k->error.text, sizeof k->error.text, "%s", err->text);
    return r;
}

const char *gi_kit_last_error(const gi_kit *k)
{
    return k ? k->error.text : "";
}

gi_result gi_abi_layout_check(const gi_abi_layout *plugin, gi_error *err)
{
    static const gi_abi_layout host = GI_ABI_LAYOUT;
#define FIELD(f, type)                                                                             \
    {                                                                                              \
        offsetof(gi_abi_layout, f), #type                                                          \
    }
    static const struct {
        size_t offset;
        const char *name;
    } fields[] = {FIELD(host, gi_host),
                  FIELD(view, gi_view),
                  FIELD(target, gi_target),
                  FIELD(changes, gi_changes),
                  FIELD(gpu_scene, gi_gpu_scene),
                  FIELD(gpu_material, gi_gpu_material),
                  FIELD(gpu_light, gi_gpu_light),
                  FIELD(gpu_emitter, gi_gpu_emitter),
                  FIELD(scene, gi_scene),
                  FIELD(object, gi_object),
                  FIELD(material, gi_material),
                  FIELD(light, gi_light),
                  FIELD(camera, gi_camera),
                  FIELD(vertex, gi_vertex),
                  FIELD(param_desc, gi_param_desc),
                  FIELD(gbuffer, gi_gbuffer),
                  FIELD(depth_view, gi_depth_view),
                  FIELD(depth_desc, gi_depth_desc),
                  FIELD(depth_atlas_desc, gi_depth_atlas_desc),
                  FIELD(kit, gi_kit)};
#undef FIELD
    _Static_assert(sizeof fields / sizeof fields[0] * sizeof(uint32_t) + sizeof(uint32_t) ==
                       sizeof(gi_abi_layout),
                   "every gi_abi_layout field is checked");
    if (plugin->revision != host.revision)
        return gi_error_set(err, GI_ERR_UNSUPPORTED,
                            "built against data layout revision %u, this gibench has %u",
                            plugin->revision, host.revision);
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++) {
        uint32_t p, h;
        memcpy(&p, (const char *)plugin + fields[i].offset, sizeof p);
        memcpy(&h, (const char *)&host + fields[i].offset, sizeof h);
        if (p != h)
            return gi_error_set(
                err, GI_ERR_UNSUPPORTED,
                "built against %s of %u bytes, this gibench has %u: rebuild the plugin",
                fields[i].name, p, h);
    }
    return GI_OK;
}

void gi_kit_dispatch_8x8(uint32_t width, uint32_t height)
{
    glDispatchCompute((width + 7) / 8, (height + 7) / 8, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    GL_TEXTURE_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT |
                    GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}

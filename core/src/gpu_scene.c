/* The scene on the GPU, uploaded once; transforms, lights, emitters and the
 * vertices of morphing objects refreshed per frame. */
#include "gi/envmap.h"
#include "gi/gpu.h"
#include "gi/image.h"
#include "gi/log.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* std140 scene-info block (see scene.glsl GiSceneInfo). */
typedef struct scene_info {
    uint32_t counts[4];
    float params[4];
    float bounds_min[4];
    float bounds_max[4];
} scene_info;

static GLuint make_buffer(const void *data, size_t size, GLbitfield flags)
{
    GLuint b;
    glCreateBuffers(1, &b);
    /* Zero-size buffers cannot be bound; keep at least 64 bytes. */
    if (size == 0) {
        static const char zeros[64];
        glNamedBufferStorage(b, sizeof zeros, zeros, flags);
    } else {
        glNamedBufferStorage(b, (GLsizeiptr)size, data, flags);
    }
    return b;
}

GLuint gi_gpu_texture_2d(GLenum format, uint32_t width, uint32_t height)
{
    GLuint t;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, 1, format, (GLsizei)width, (GLsizei)height);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

static GLuint make_texture_2d(GLenum format, uint32_t w, uint32_t h, GLenum data_format,
                              const float *data)
{
    GLuint t = gi_gpu_texture_2d(format, w, h);
    glTextureSubImage2D(t, 0, 0, 0, (GLsizei)w, (GLsizei)h, data_format, GL_FLOAT, data);
    return t;
}

static int upload_environment(gi_gpu_scene *gs, const gi_envmap *env)
{
    uint32_t w = env->width, h = env->height;
    float *rgba = malloc((size_t)w * h * 4 * sizeof(float));
    if (!rgba)
        return 0;
    for (size_t i = 0; i < (size_t)w * h; i++) {
        rgba[4 * i + 0] = env->rgb[3 * i + 0];
        rgba[4 * i + 1] = env->rgb[3 * i + 1];
        rgba[4 * i + 2] = env->rgb[3 * i + 2];
        rgba[4 * i + 3] = 1.0f;
    }
    /* Row 0 of the image is the top (v = 0); GL's row 0 is t = 0, so the
     * shader indexes rows by v directly with texelFetch. */
    gs->tex_env = make_texture_2d(GL_RGBA32F, w, h, GL_RGBA, rgba);
    free(rgba);
    gs->tex_env_cond = make_texture_2d(GL_R32F, w + 1, h, GL_RED, env->cond_cdf);
    gs->tex_env_marg = make_texture_2d(GL_R32F, h + 1, 1, GL_RED, env->marg_cdf);
    return 1;
}

/* Resamples every material texture (bilinear) to the largest size and
 * stacks them as layers: core GL 4.5 has no bindless textures. */
static void upload_textures(gi_gpu_scene *gs, const gi_scene *s)
{
    uint32_t w = 1, h = 1, layers = s->texture_count ? s->texture_count : 1;
    for (uint32_t i = 0; i < s->texture_count; i++) {
        w = s->textures[i].width > w ? s->textures[i].width : w;
        h = s->textures[i].height > h ? s->textures[i].height : h;
    }
    glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &gs->tex_albedo);
    glTextureStorage3D(gs->tex_albedo, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h, (GLsizei)layers);
    float *px = malloc((size_t)w * h * 4 * sizeof(float));
    if (!px)
        return;
    for (uint32_t l = 0; l < layers; l++) {
        if (!s->texture_count) {
            px[0] = px[1] = px[2] = px[3] = 1.0f;
        } else {
            const gi_texture *t = &s->textures[l];
            for (uint32_t y = 0; y < h; y++)
                for (uint32_t x = 0; x < w; x++) {
                    /* GL row y holds t = (y + 0.5) / h; glTF's v runs down the image. */
                    float u = (x + 0.5f) / w * t->width - 0.5f;
                    float v = (y + 0.5f) / h * t->height - 0.5f;
                    int x0 = (int)floorf(u), y0 = (int)floorf(v);
                    float fx = u - x0, fy = v - y0;
                    for (int c = 0; c < 4; c++) {
                        float acc = 0.0f;
                        for (int k = 0; k < 4; k++) {
                            int xx = x0 + (k & 1), yy = y0 + (k >> 1);
                            xx = xx < 0 ? 0 : (xx >= (int)t->width ? (int)t->width - 1 : xx);
                            yy = yy < 0 ? 0 : (yy >= (int)t->height ? (int)t->height - 1 : yy);
                            float wgt = ((k & 1) ? fx : 1 - fx) * ((k >> 1) ? fy : 1 - fy);
                            acc +=
                                wgt * t->rgba[((size_t)yy * t->width + (size_t)xx) * 4 + (size_t)c];
                        }
                        px[((size_t)y * w + x) * 4 + (size_t)c] = acc;
                    }
                }
        }
        glTextureSubImage3D(gs->tex_albedo, 0, 0, 0, (GLint)l, (GLsizei)w, (GLsizei)h, 1, GL_RGBA,
                            GL_FLOAT, px);
    }
    free(px);
    glTextureParameteri(gs->tex_albedo, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(gs->tex_albedo, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(gs->tex_albedo, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(gs->tex_albedo, GL_TEXTURE_WRAP_T, GL_REPEAT);
}

gi_gpu_scene *gi_gpu_scene_upload(gi_gpu *gpu, const gi_scene *s, gi_error *err)
{
    if (s->object_count > GI_MAX_OBJECTS) {
        gi_error_set(err, GI_ERR_UNSUPPORTED, "%s: %u objects, the GPU scene holds at most %u",
                     s->path, s->object_count, GI_MAX_OBJECTS);
        return NULL;
    }
    gi_gpu_scene *gs = calloc(1, sizeof *gs);
    gi_gpu_material *mats = calloc(s->material_count ? s->material_count : 1, sizeof *mats);
    if (!gs || !mats) {
        free(gs);
        free(mats);
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory uploading the scene");
        return NULL;
    }
    gs->gpu = gpu;
    gs->scene = s;
    gs->triangle_count = s->triangle_count;
    gs->vertex_count = s->vertex_count;
    gs->light_count = s->light_count;
    gs->emitter_count = s->emitter_count;

    /* Updatable: morph targets (set_time) and gi_gpu_scene_update_vertices. */
    gs->vbo = make_buffer(s->vertices, (size_t)s->vertex_count * sizeof(gi_vertex),
                          GL_DYNAMIC_STORAGE_BIT);
    gs->deforming = gi_scene_deforms(s);
    gs->ibo = make_buffer(s->indices, (size_t)s->triangle_count * 3 * sizeof(uint32_t), 0);
    glCreateVertexArrays(1, &gs->vao);
    glVertexArrayVertexBuffer(gs->vao, 0, gs->vbo, 0, sizeof(gi_vertex));
    glVertexArrayElementBuffer(gs->vao, gs->ibo);
    struct {
        GLuint loc;
        GLint size;
        GLenum type;
        size_t offset;
    } attrs[] = {{0, 3, GL_FLOAT, offsetof(gi_vertex, position)},
                 {1, 1, GL_UNSIGNED_INT, offsetof(gi_vertex, object)},
                 {2, 3, GL_FLOAT, offsetof(gi_vertex, normal)},
                 {3, 1, GL_UNSIGNED_INT, offsetof(gi_vertex, material)},
                 {4, 2, GL_FLOAT, offsetof(gi_vertex, uv)}};
    for (size_t i = 0; i < sizeof attrs / sizeof attrs[0]; i++) {
        glEnableVertexArrayAttrib(gs->vao, attrs[i].loc);
        if (attrs[i].type == GL_UNSIGNED_INT)
            glVertexArrayAttribIFormat(gs->vao, attrs[i].loc, attrs[i].size, attrs[i].type,
                                       (GLuint)attrs[i].offset);
        else
            glVertexArrayAttribFormat(gs->vao, attrs[i].loc, attrs[i].size, attrs[i].type, GL_FALSE,
                                      (GLuint)attrs[i].offset);
        glVertexArrayAttribBinding(gs->vao, attrs[i].loc, 0);
    }

    for (uint32_t i = 0; i < s->material_count; i++) {
        const gi_material *m = &s->materials[i];
        memcpy(mats[i].albedo, m->albedo, sizeof mats[i].albedo);
        mats[i].texture_layer = m->albedo_texture >= 0 ? m->albedo_texture : -1;
        memcpy(mats[i].ks, m->ks, sizeof mats[i].ks);
        mats[i].exponent = m->exponent;
        memcpy(mats[i].emission, m->emission, sizeof mats[i].emission);
        mats[i].flags = (m->mirror ? 1u : 0u) | (m->double_sided ? 2u : 0u);
    }
    gs->ssbo_materials = make_buffer(mats, (size_t)s->material_count * sizeof *mats, 0);
    free(mats);
    gs->ssbo_lights =
        make_buffer(NULL, (size_t)(s->light_count ? s->light_count : 1) * sizeof(gi_gpu_light),
                    GL_DYNAMIC_STORAGE_BIT);
    gs->ssbo_emitters = make_buffer(
        NULL, (size_t)(s->emitter_count ? s->emitter_count : 1) * sizeof(gi_gpu_emitter),
        GL_DYNAMIC_STORAGE_BIT);
    gs->ubo_objects =
        make_buffer(NULL, (size_t)GI_MAX_OBJECTS * 32 * sizeof(float), GL_DYNAMIC_STORAGE_BIT);
    upload_textures(gs, s);
    if (s->envmap && !upload_environment(gs, s->envmap)) {
        gi_gpu_scene_free(gs);
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory uploading the environment map");
        return NULL;
    }
    gs->time = -1.0f;
    gi_gpu_scene_set_time(gs, 0.0f);
    if (gi_gl_check("uploading the scene", err) != GI_OK) {
        gi_gpu_scene_free(gs);
        return NULL;
    }
    return gs;
}

/* The objects' transforms at t and their normal matrices. */
static void upload_transforms(gi_gpu_scene *gs, float t)
{
    const gi_scene *s = gs->scene;
    float ubo[GI_MAX_OBJECTS][32];
    memset(ubo, 0, sizeof ubo);
    for (uint32_t o = 0; o < s->object_count; o++) {
        float *m = gs->world_from_local[o], inv[16];
        gi_scene_object_transform(s, o, t, m);
        memcpy(ubo[o], m, 16 * sizeof(float));
        /* Normal matrix: inverse transpose of the object transform. */
        if (gi_mat4_invert(inv, m))
            gi_mat4_transpose(ubo[o] + 16, inv);
        else
            gi_mat4_identity(ubo[o] + 16);
    }
    glNamedBufferSubData(gs->ubo_objects, 0, (GLsizeiptr)(s->object_count * 32 * sizeof(float)),
                         ubo);
}

/* Morphing objects: their vertices at t into the vertex buffer (one
 * upload per object; the rest of the buffer is untouched). */
static void upload_morphed_vertices(gi_gpu_scene *gs, float t)
{
    const gi_scene *s = gs->scene;
    gi_vertex *v = NULL;
    size_t cap = 0;
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *obj = &s->objects[o];
        if (!obj->morph_count || !obj->vertex_count)
            continue;
        if (obj->vertex_count > cap) {
            free(v);
            cap = obj->vertex_count;
            v = malloc(cap * sizeof *v);
            if (!v) {
                gi_log(GI_LOG_ERROR, "gpu scene: out of memory morphing object %u", o);
                break;
            }
        }
        gi_scene_object_vertices(s, o, t, v);
        glNamedBufferSubData(gs->vbo, (GLintptr)((size_t)obj->first_vertex * sizeof *v),
                             (GLsizeiptr)((size_t)obj->vertex_count * sizeof *v), v);
    }
    free(v);
}

/* The punctual lights at t. */
static void upload_lights(gi_gpu_scene *gs, float t)
{
    const gi_scene *s = gs->scene;
    gi_gpu_light *lights = calloc(s->light_count, sizeof *lights);
    for (uint32_t i = 0; lights && i < s->light_count; i++) {
        const gi_light *l = &s->lights[i];
        gi_light_frame f = gi_scene_light_at(s, i, t);
        gi_v3_store(f.position, lights[i].position);
        gi_v3_store(f.direction, lights[i].direction);
        lights[i].type = (uint32_t)l->type;
        lights[i].range = l->range;
        memcpy(lights[i].intensity, l->intensity, sizeof lights[i].intensity);
        lights[i].cos_inner = cosf(l->inner_cone);
        lights[i].cos_outer = cosf(l->outer_cone);
    }
    if (lights)
        glNamedBufferSubData(gs->ssbo_lights, 0, (GLsizeiptr)(s->light_count * sizeof *lights),
                             lights);
    free(lights);
}

/* The emissive triangles at t with their areas and the CDF of their power;
 * sets gs->emitter_power. */
static void upload_emitters(gi_gpu_scene *gs, float t)
{
    const gi_scene *s = gs->scene;
    gi_gpu_emitter *em = calloc(s->emitter_count, sizeof *em);
    double total = 0.0;
    for (uint32_t i = 0; em && i < s->emitter_count; i++) {
        gi_vec3 p[3];
        gi_scene_triangle_world(s, s->emitters[i], t, p);
        float area = 0.5f * gi_v3_length(gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0])));
        float power = area * gi_luminance(gi_scene_triangle_emission(s, s->emitters[i])) * GI_PI;
        em[i].triangle = s->emitters[i];
        em[i].area = area;
        em[i].pdf = power;
        total += power;
        em[i].cdf = (float)total;
    }
    for (uint32_t i = 0; em && i < s->emitter_count; i++) {
        em[i].cdf = total > 0 ? (float)(em[i].cdf / total) : (float)(i + 1) / s->emitter_count;
        em[i].pdf = total > 0 ? (float)(em[i].pdf / total) : 1.0f / s->emitter_count;
    }
    if (em) {
        em[s->emitter_count - 1].cdf = 1.0f;
        glNamedBufferSubData(gs->ssbo_emitters, 0, (GLsizeiptr)(s->emitter_count * sizeof *em), em);
    }
    free(em);
    gs->emitter_power = (float)total;
}

/* The scene-info block at t (scene.glsl GiSceneInfo), made on first use. */
static void upload_info(gi_gpu_scene *gs, float t)
{
    const gi_scene *s = gs->scene;
    scene_info info = {{s->triangle_count, s->light_count, s->emitter_count, s->envmap ? 1u : 0u},
                       {gs->emitter_power,
                        s->envmap ? gi_envmap_average_radiance(s->envmap) * 4.0f * GI_PI : 0.0f, t,
                        s->envmap ? s->envmap->rotation : 0.0f},
                       {gs->bounds[0], gs->bounds[1], gs->bounds[2], 0},
                       {gs->bounds[3], gs->bounds[4], gs->bounds[5], 0}};
    if (!gs->ubo_info)
        gs->ubo_info = make_buffer(NULL, sizeof info, GL_DYNAMIC_STORAGE_BIT);
    glNamedBufferSubData(gs->ubo_info, 0, sizeof info, &info);
}

void gi_gpu_scene_set_time(gi_gpu_scene *gs, float t)
{
    const gi_scene *s = gs->scene;
    upload_transforms(gs, t);
    if (gs->deforming)
        upload_morphed_vertices(gs, t);
    if (s->light_count)
        upload_lights(gs, t);
    gs->emitter_power = 0.0f;
    if (s->emitter_count)
        upload_emitters(gs, t);
    gi_scene_bounds_at(s, t, gs->bounds);
    upload_info(gs, t);
    gs->time = t;
}

gi_result gi_gpu_scene_update_vertices(gi_gpu_scene *gs, uint32_t first_vertex, uint32_t count,
                                       const gi_vertex *v, gi_error *err)
{
    if (!gs || (!v && count))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "gpu scene: update_vertices: %s is NULL",
                            !gs ? "the scene" : "the vertex array");
    if (first_vertex > gs->vertex_count || count > gs->vertex_count - first_vertex)
        return gi_error_set(
            err, GI_ERR_INVALID_ARGUMENT,
            "gpu scene: update_vertices: vertices %u..%u+%u past the %u of the scene", first_vertex,
            first_vertex, count, gs->vertex_count);
    const gi_scene *s = gs->scene;
    for (uint32_t i = 0; i < count; i++) {
        const gi_vertex *x = &v[i], *old = &s->vertices[first_vertex + i];
        if (x->object != old->object || x->material != old->material)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "gpu scene: update_vertices: vertex %u changes its object or "
                                "material (%u/%u -> %u/%u)",
                                first_vertex + i, old->object, old->material, x->object,
                                x->material);
        for (int k = 0; k < 3; k++)
            if (!isfinite(x->position[k]) || !isfinite(x->normal[k]))
                return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                    "gpu scene: update_vertices: vertex %u is not finite",
                                    first_vertex + i);
    }
    if (count)
        glNamedBufferSubData(gs->vbo, (GLintptr)((size_t)first_vertex * sizeof *v),
                             (GLsizeiptr)((size_t)count * sizeof *v), v);
    return gi_gl_check("gpu scene: update_vertices", err);
}

void gi_gpu_scene_bind(const gi_gpu_scene *gs)
{
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_VERTICES, gs->vbo);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_INDICES, gs->ibo);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_MATERIALS, gs->ssbo_materials);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_LIGHTS, gs->ssbo_lights);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_EMITTERS, gs->ssbo_emitters);
    glBindBufferBase(GL_UNIFORM_BUFFER, GI_UBO_OBJECTS, gs->ubo_objects);
    glBindBufferBase(GL_UNIFORM_BUFFER, GI_UBO_FRAME, gs->ubo_info);
    glBindTextureUnit(GI_TEX_ALBEDO, gs->tex_albedo);
    if (gs->tex_env) {
        glBindTextureUnit(GI_TEX_ENV, gs->tex_env);
        glBindTextureUnit(GI_TEX_ENV_COND, gs->tex_env_cond);
        glBindTextureUnit(GI_TEX_ENV_MARG, gs->tex_env_marg);
    }
}

void gi_gpu_scene_draw(const gi_gpu_scene *gs, int object, GLsizei instances)
{
    const gi_scene *s = gs->scene;
    GLsizei count = (GLsizei)(s->triangle_count * 3);
    size_t first = 0;
    if (object >= 0 && (uint32_t)object < s->object_count) {
        count = (GLsizei)(s->objects[object].triangle_count * 3);
        first = (size_t)s->objects[object].first_triangle * 3 * sizeof(uint32_t);
    }
    glBindVertexArray(gs->vao);
    glDrawElementsInstanced(GL_TRIANGLES, count, GL_UNSIGNED_INT, (const void *)first,
                            instances > 0 ? instances : 1);
    glBindVertexArray(0);
}

void gi_gpu_scene_draw_ranges(const gi_gpu_scene *gs, const GLsizei *counts,
                              const void *const *offsets, GLsizei ranges)
{
    if (ranges <= 0)
        return;
    glBindVertexArray(gs->vao);
    glMultiDrawElements(GL_TRIANGLES, counts, GL_UNSIGNED_INT, offsets, ranges);
    glBindVertexArray(0);
}

void gi_gpu_scene_draw_indices(const gi_gpu_scene *gs, GLuint ibo, uint32_t index_count,
                               GLsizei instances)
{
    /* The scene's VAO with this index buffer for the one draw, then its own again. */
    glVertexArrayElementBuffer(gs->vao, ibo);
    glBindVertexArray(gs->vao);
    glDrawElementsInstanced(GL_TRIANGLES, (GLsizei)index_count, GL_UNSIGNED_INT, NULL,
                            instances > 0 ? instances : 1);
    glBindVertexArray(0);
    glVertexArrayElementBuffer(gs->vao, gs->ibo);
}

void gi_gpu_scene_free(gi_gpu_scene *gs)
{
    if (!gs)
        return;
    GLuint bufs[] = {gs->vbo,           gs->ibo,         gs->ssbo_materials, gs->ssbo_lights,
                     gs->ssbo_emitters, gs->ubo_objects, gs->ubo_info};
    glDeleteBuffers(sizeof bufs / sizeof bufs[0], bufs);
    GLuint texs[] = {gs->tex_env, gs->tex_env_cond, gs->tex_env_marg, gs->tex_albedo};
    glDeleteTextures(sizeof texs / sizeof texs[0], texs);
    glDeleteVertexArrays(1, &gs->vao);
    free(gs);
}

gi_image *gi_gpu_read_texture(GLuint tex, uint32_t width, uint32_t height)
{
    gi_image *img = gi_image_create(width, height);
    if (!img)
        return NULL;
    glGetTextureImage(tex, 0, GL_RGBA, GL_FLOAT,
                      (GLsizei)((size_t)width * height * 4 * sizeof(float)), img->rgba);
    gi_image_flip_rows(img);
    return img;
}

/* The method kit (gi/kit.h): when the running average restarts, what is
 * re-made on a resize, scratch textures, error text, the shader-name check
 * in gi_kit_init, and the shared C/GLSL constants seen from a shader. */
#include "check.h"
#include "gpu_fixture.h"

#include "gi/kit.h"

#include <stdarg.h>
#include <string.h>

static int stages_begun;
static void host_log(const gi_host *h, int level, const char *fmt, ...)
{
    (void)h, (void)level, (void)fmt;
}
static void stage_begin(const gi_host *h, const char *name)
{
    (void)h, (void)name;
    stages_begun++;
}
static void stage_end(const gi_host *h, const char *name)
{
    (void)h, (void)name;
}

static gi_view view_of(uint32_t w, uint32_t h, float shift, uint32_t frame_index)
{
    gi_view v;
    memset(&v, 0, sizeof v);
    v.width = w;
    v.height = h;
    gi_mat4_identity(v.view);
    gi_mat4_perspective(v.proj, 1.0f, (float)w / (float)h, 0.1f, 10.0f);
    v.view[14] = -2.0f - shift;
    gi_mat4_mul(v.view_proj, v.proj, v.view);
    gi_mat4_invert(v.inv_view_proj, v.view_proj);
    v.frame_index = frame_index;
    return v;
}

/* One frame through the kit; returns the frame number the shader would see. */
static uint32_t frame(gi_kit *k, const gi_view *v, unsigned what)
{
    CHECK(gi_kit_frame_begin(k, v, what) == GI_OK);
    uint32_t f = k->frames;
    gi_kit_frame_end(k);
    return f;
}

static const gi_shader_source clash[] = {
    {"scene.glsl", "plugins/x/shaders/scene.glsl", "\n"},
    {0, 0, 0},
};

/* The constants of glsl_shared.h as a shader sees them, written to an SSBO. */
static const char *constants_kernel =
    "#include \"glsl_shared.h\"\n"
    "layout(local_size_x = 1) in;\n"
    "layout(std430, binding = GI_SSBO_PLUGIN_FIRST) buffer O { uint v[8]; };\n"
    "void main() { v[0] = uint(GI_MAX_OBJECTS); v[1] = GI_MATERIAL_FLAG_DOUBLE_SIDED; v[2] = "
    "GI_LIGHT_TYPE_SPOT;\n"
    "  v[3] = uint(GI_TEX_GBUFFER_IDS); v[4] = uint(GI_TEX_PLUGIN_FIRST); v[5] = "
    "uint(GI_IMAGE_TARGET);\n"
    "  v[6] = uint(GI_SSBO_DEPTH_ATLAS); v[7] = GI_NO_ID; }\n";

int main(void)
{
    gi_gpu *gpu;
    gi_scene *s;
    gi_gpu_scene *gs;
    if (!gpu_fixture_load(GI_SOURCE_DIR "/scenes/cornell_box_coarse.gltf", &gpu, &s, &gs) || !gs)
        return gi_test_finish();
    gi_host host = {.struct_size = sizeof host,
                    .log = host_log,
                    .stage_begin = stage_begin,
                    .stage_end = stage_end};

    gi_kit k;
    CHECK(gi_kit_init(&k, &host, clash) == GI_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(gi_kit_last_error(&k), "plugins/x/shaders/scene.glsl: named like the core's"),
              "'%s'", gi_kit_last_error(&k));
    CHECK(gi_kit_init(&k, &host, NULL) == GI_OK && gi_kit_last_error(&k)[0] == '\0');

    /* Restarts: a new run, a moved view, a resize, a scene change, no averaging. */
    const unsigned what = GI_KIT_GBUFFER | GI_KIT_ACCUMULATE;
    gi_view a = view_of(16, 8, 0.0f, 0), a1 = view_of(16, 8, 0.0f, 1), b = view_of(16, 8, 0.5f, 2);
    gi_kit_prepare(&k, gs);
    CHECK(frame(&k, &a, what) == 0);
    CHECK(k.gbuffer && k.accum && k.width == 16 && k.height == 8);
    CHECK(frame(&k, &a1, what) == 1 && frame(&k, &a1, what) == 2);
    CHECK(frame(&k, &b, what) == 0); /* the view moved */
    CHECK(frame(&k, &b, what) == 1);
    CHECK(frame(&k, &a, what) == 0); /* frame_index 0: a new run */
    gi_changes none = {0}, moved = {.flags = GI_CHANGED_TRANSFORMS};
    gi_kit_update(&k, gs, &none);
    CHECK(frame(&k, &a1, what) == 1); /* nothing changed */
    gi_kit_update(&k, gs, &moved);
    CHECK(frame(&k, &a1, what) == 0); /* the scene changed */
    gi_view big = view_of(24, 12, 0.0f, 5);
    CHECK(frame(&k, &big, what) == 0); /* resized: re-made */
    CHECK(k.width == 24 && k.height == 12 && k.gbuffer && k.gbuffer->width == 24 && k.accum);
    CHECK(frame(&k, &big, what | GI_KIT_NO_AVERAGE) == 0 &&
          frame(&k, &big, what | GI_KIT_NO_AVERAGE) == 0);
    gi_kit_prepare(&k, gs);
    CHECK(frame(&k, &big, what) == 0); /* prepare restarts */

    /* The G-buffer for the view, inside the named stage. */
    int before = stages_begun;
    CHECK(gi_kit_render_gbuffer(&k, &big, "gbuffer") == GI_OK && stages_begun == before + 1);
    CHECK(gi_kit_render_gbuffer(&k, &big, NULL) == GI_OK && stages_begun == before + 1);

    /* Scratch textures: kept while format and size stay, re-made otherwise. */
    GLuint t0 = gi_kit_scratch_texture(&k, 0, GL_RGBA32F, 8, 8);
    CHECK(t0 != 0 && gi_kit_scratch_texture(&k, 0, GL_RGBA32F, 8, 8) == t0);
    GLuint t1 = gi_kit_scratch_texture(&k, 0, GL_RGBA32F, 9, 8);
    CHECK(t1 != 0 && k.scratch[0].width == 9);
    CHECK(gi_kit_scratch_texture(&k, GI_KIT_SCRATCH_MAX, GL_RGBA32F, 8, 8) == 0);

    /* Error text. */
    CHECK(gi_kit_fail(&k, GI_ERR_GL, "pass %d: %s", 3, "broken") == GI_ERR_GL);
    CHECK(strcmp(gi_kit_last_error(&k), "pass 3: broken") == 0);
    gi_error e;
    gi_error_set(&e, GI_OK, "from elsewhere");
    CHECK(gi_kit_fail_with(&k, GI_ERR_IO, &e) == GI_ERR_IO &&
          strcmp(gi_kit_last_error(&k), "from elsewhere") == 0);
    gi_kit_free(&k);
    CHECK(k.gbuffer == NULL && k.accum == 0 && k.scratch[0].texture == 0);
    gi_kit_free(&k); /* twice is harmless */

    /* The shared constants as GLSL sees them equal the C values. */
    gi_error err;
    GLuint prog =
        gi_program_build_compute_text("tests/kit_constants.comp", constants_kernel, NULL, &err);
    CHECK_MSG(prog != 0, "%s", err.text);
    if (prog) {
        GLuint buf;
        uint32_t out[8] = {0};
        glCreateBuffers(1, &buf);
        glNamedBufferStorage(buf, sizeof out, out, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_PLUGIN_FIRST, buf);
        glUseProgram(prog);
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glGetNamedBufferSubData(buf, 0, sizeof out, out);
        CHECK(out[0] == GI_MAX_OBJECTS && out[1] == GI_MATERIAL_FLAG_DOUBLE_SIDED &&
              out[2] == (uint32_t)GI_LIGHT_SPOT);
        CHECK(out[3] == GI_TEX_GBUFFER_IDS && out[4] == GI_TEX_PLUGIN_FIRST &&
              out[5] == GI_IMAGE_TARGET);
        CHECK(out[6] == GI_SSBO_DEPTH_ATLAS && out[7] == GI_NO_ID);
        glDeleteBuffers(1, &buf);
        glDeleteProgram(prog);
    }
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
    return gi_test_finish();
}

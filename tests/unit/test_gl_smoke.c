/* EGL/GL smoke test: a 4.5 core context on this machine (llvmpipe without a
 * GPU), a compute shader that includes a core file, and compile errors
 * mapped back to "path:line: message". */
#include "check.h"
#include "gi/gpu.h"
#include "gi/shader.h"

#include <string.h>

static const gi_shader_source test_sources[] = {
    {"smoke_lib.glsl", "tests/smoke_lib.glsl", "float smoke_twice(float x) { return 2.0 * x; }\n"},
    {"smoke_bad.glsl", "tests/smoke_bad.glsl",
     "// line 1\n// line 2\nfloat broken( { return 1.0; }\n"},
    {"smoke_user.comp", "tests/smoke_user.comp",
     "#include \"smoke_lib.glsl\"\n#include \"smoke_bad.glsl\"\nlayout(local_size_x = 1) in;\nvoid "
     "main() {}\n"},
    {0, 0, 0},
};

/* Two more tables: one reuses a core shader's name (refused), two define the
 * same helper name (each file sees its own; a top-level lookup is ambiguous). */
static const gi_shader_source clash_core[] = {
    {"brdf.glsl", "plugins/clash/shaders/brdf.glsl", "float nothing() { return 0.0; }\n"},
    {0, 0, 0},
};
static const gi_shader_source plugin_a[] = {
    {"helper.glsl", "plugins/a/shaders/helper.glsl", "float helper() { return 1.0; }\n"},
    {"a.comp", "plugins/a/shaders/a.comp",
     "#include \"helper.glsl\"\nlayout(local_size_x = 1) in;\nlayout(std430, binding = 8) buffer O "
     "{ float v; };\n"
     "void main() { v = helper(); }\n"},
    {0, 0, 0},
};
static const gi_shader_source plugin_b[] = {
    {"helper.glsl", "plugins/b/shaders/helper.glsl", "float helper() { return 2.0; }\n"},
    {"b.comp", "plugins/b/shaders/b.comp",
     "#include \"helper.glsl\"\nlayout(local_size_x = 1) in;\nlayout(std430, binding = 8) buffer O "
     "{ float v; };\n"
     "void main() { v = helper(); }\n"},
    {0, 0, 0},
};

/* Runs a one-invocation program writing one float; returns it. */
static float run_one(GLuint prog)
{
    GLuint buf;
    float v = -1.0f;
    glCreateBuffers(1, &buf);
    glNamedBufferStorage(buf, sizeof v, &v, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, buf);
    glUseProgram(prog);
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(buf, 0, sizeof v, &v);
    glUseProgram(0);
    glDeleteBuffers(1, &buf);
    return v;
}

static void check_namespaces(void)
{
    gi_error err;
    CHECK(gi_shader_register(clash_core, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK_MSG(
        strstr(err.text,
               "plugins/clash/shaders/brdf.glsl: named like the core's core/shaders/brdf.glsl"),
        "'%s'", err.text);
    CHECK(gi_shader_find("brdf.glsl") &&
          strcmp(gi_shader_find("brdf.glsl")->path, "core/shaders/brdf.glsl") == 0);
    CHECK(gi_shader_register(plugin_a, &err) == GI_OK &&
          gi_shader_register(plugin_b, NULL) == GI_OK);
    GLuint pa = gi_program_build_compute("a.comp", NULL, &err);
    CHECK_MSG(pa != 0, "%s", err.text);
    GLuint pb = gi_program_build_compute("b.comp", NULL, &err);
    CHECK_MSG(pb != 0, "%s", err.text);
    CHECK(pa && run_one(pa) == 1.0f);
    CHECK(pb && run_one(pb) == 2.0f);
    glDeleteProgram(pa);
    glDeleteProgram(pb);
    CHECK(gi_shader_expand("helper.glsl", NULL, &err) == NULL);
    CHECK_MSG(strstr(err.text, "'helper.glsl' is ambiguous: plugins/a/shaders/helper.glsl and "
                               "plugins/b/shaders/helper.glsl"),
              "'%s'", err.text);
    CHECK(gi_shader_find("plugins/b/shaders/helper.glsl") == &plugin_b[0]);
}

int main(void)
{
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    CHECK_MSG(gpu != NULL, "%s", err.text);
    if (!gpu)
        return gi_test_finish();
    printf("renderer: %s | %s | %s\n", gi_gpu_renderer(gpu), gi_gpu_version(gpu),
           gi_gpu_platform(gpu));
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    CHECK(major * 10 + minor >= 45);
    GLint profile = 0;
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    CHECK(profile & GL_CONTEXT_CORE_PROFILE_BIT);

    CHECK(gi_shader_register(test_sources, &err) == GI_OK);
    /* A compute shader that uses an included function and writes an SSBO. */
    const char *text =
        "#include \"smoke_lib.glsl\"\n"
        "layout(local_size_x = 64) in;\n"
        "layout(std430, binding = 8) buffer Out { float v[]; };\n"
        "void main() { uint i = gl_GlobalInvocationID.x; v[i] = smoke_twice(float(i)) + K; }\n";
    GLuint prog =
        gi_program_build_compute_text("tests/smoke_inline.comp", text, "#define K 0.5\n", &err);
    CHECK_MSG(prog != 0, "%s", err.text);
    GLuint buf;
    glCreateBuffers(1, &buf);
    glNamedBufferStorage(buf, 256 * sizeof(float), NULL, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, buf);
    glUseProgram(prog);
    glDispatchCompute(4, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    float out[256];
    glGetNamedBufferSubData(buf, 0, sizeof out, out);
    int ok = 1;
    for (int i = 0; i < 256; i++)
        ok &= out[i] == 2.0f * i + 0.5f;
    CHECK(ok);
    glDeleteBuffers(1, &buf);
    glDeleteProgram(prog);

    /* The error on line 3 of the included file is reported against it. */
    prog = gi_program_build_compute("smoke_user.comp", NULL, &err);
    CHECK(prog == 0);
    CHECK_MSG(strncmp(err.text, "tests/smoke_bad.glsl:3: ", 24) == 0, "'%s'", err.text);
    /* Missing include and unknown program names. */
    CHECK(gi_shader_expand("nope.glsl", NULL, &err) == NULL &&
          strstr(err.text, "no shader source named 'nope.glsl'"));
    const char *missing = "#include \"missing.glsl\"\nvoid main() {}\n";
    CHECK(gi_program_build_compute_text("tests/missing.comp", missing, NULL, &err) == 0);
    CHECK_MSG(strcmp(err.text, "tests/missing.comp:1: #include \"missing.glsl\": no shader source "
                               "named 'missing.glsl'") == 0,
              "'%s'", err.text);
    check_namespaces();
    /* Every core shader compiles on this driver. */
    const char *programs[][2] = {{"gbuffer.vert", "gbuffer.frag"}, {"depth.vert", "depth.frag"}};
    for (int i = 0; i < 2; i++) {
        prog = gi_program_build(programs[i][0], NULL, programs[i][1], NULL, &err);
        CHECK_MSG(prog != 0, "%s", err.text);
        glDeleteProgram(prog);
    }
    CHECK(gi_gl_check("smoke", &err) == GI_OK);
    gi_gpu_destroy(gpu);
    return gi_test_finish();
}

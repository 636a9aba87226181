/* Headless OpenGL 4.5 core context through EGL (see gpu.h).
 *
 * Order of attempts: EGL devices that are not software (EGL_EXT_device_query
 * without EGL_MESA_device_software), then Mesa's surfaceless platform. Each
 * failed attempt leaves a reason; if all fail the error lists them. */
#include "gi/gpu.h"
#include "gi/log.h"

#include <epoxy/egl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct gi_gpu {
    EGLDisplay display;
    EGLContext context;
    char renderer[256];
    char version[256];
    const char *platform;
    int software;
    int adopted; /* the caller's context (gi_gpu_desc.adopt_current): not ours to destroy */
};

static int has_ext(const char *list, const char *name)
{
    size_t n = strlen(name);
    for (const char *p = list; p && (p = strstr(p, name)) != NULL; p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
            return 1;
    return 0;
}

static void append(char *buf, size_t size, const char *fmt, const char *a, const char *b)
{
    size_t used = strlen(buf);
    if (used < size)
        snprintf(buf + used, size - used, fmt, a, b);
}

/* Makes a 4.5 core context current on `dpy`; returns 0 and a reason on failure. */
static int try_display(gi_gpu *gpu, EGLDisplay dpy, int debug, const char **why)
{
    EGLint major, minor;
    if (dpy == EGL_NO_DISPLAY) {
        *why = "no display";
        return 0;
    }
    if (!eglInitialize(dpy, &major, &minor)) {
        *why = "eglInitialize failed";
        return 0;
    }
    const char *exts = eglQueryString(dpy, EGL_EXTENSIONS);
    if (!has_ext(exts, "EGL_KHR_surfaceless_context")) {
        *why = "no EGL_KHR_surfaceless_context";
        eglTerminate(dpy);
        return 0;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        *why = "eglBindAPI(EGL_OPENGL_API) failed";
        eglTerminate(dpy);
        return 0;
    }
    EGLint cfg_attr[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig cfg = NULL;
    EGLint ncfg = 0;
    int have_cfg = eglChooseConfig(dpy, cfg_attr, &cfg, 1, &ncfg) && ncfg > 0;
    EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION,
                         4,
                         EGL_CONTEXT_MINOR_VERSION,
                         5,
                         EGL_CONTEXT_OPENGL_PROFILE_MASK,
                         EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                         EGL_CONTEXT_OPENGL_DEBUG,
                         debug ? EGL_TRUE : EGL_FALSE,
                         EGL_NONE};
    /* EGL_KHR_no_config_context lets us skip the config on Mesa. */
    EGLContext ctx =
        eglCreateContext(dpy, have_cfg ? cfg : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attr);
    if (ctx == EGL_NO_CONTEXT) {
        *why = "no OpenGL 4.5 core context";
        eglTerminate(dpy);
        return 0;
    }
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        *why = "eglMakeCurrent failed";
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        return 0;
    }
    if (epoxy_gl_version() < 45) {
        *why = "context reports a GL version below 4.5";
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        return 0;
    }
    gpu->display = dpy;
    gpu->context = ctx;
    return 1;
}

static int try_devices(gi_gpu *gpu, int debug, char *reasons, size_t size)
{
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!has_ext(client, "EGL_EXT_device_enumeration") ||
        !has_ext(client, "EGL_EXT_platform_device")) {
        append(reasons, size, "%s%s; ", "device: no EGL_EXT_platform_device", "");
        return 0;
    }
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    if (!eglQueryDevicesEXT(16, devices, &count) || count == 0) {
        append(reasons, size, "%s%s; ", "device: no EGL devices", "");
        return 0;
    }
    for (EGLint i = 0; i < count; i++) {
        const char *dexts = eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS);
        if (has_ext(dexts, "EGL_MESA_device_software"))
            continue; /* llvmpipe comes through the surfaceless fallback */
        EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], NULL);
        const char *why = NULL;
        if (try_display(gpu, dpy, debug, &why)) {
            gpu->platform = "device";
            return 1;
        }
        append(reasons, size, "device %s: %s; ", dexts ? "" : "?", why);
    }
    append(reasons, size, "%s%s; ", "device: no hardware EGL device gave GL 4.5", "");
    return 0;
}

static int try_surfaceless(gi_gpu *gpu, int debug, char *reasons, size_t size)
{
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!has_ext(client, "EGL_MESA_platform_surfaceless")) {
        append(reasons, size, "%s%s; ", "surfaceless: no EGL_MESA_platform_surfaceless", "");
        return 0;
    }
    EGLDisplay dpy =
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    const char *why = NULL;
    if (try_display(gpu, dpy, debug, &why)) {
        gpu->platform = "surfaceless";
        return 1;
    }
    append(reasons, size, "surfaceless: %s%s; ", why, "");
    return 0;
}

static void GLAPIENTRY debug_cb(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei len,
                                const GLchar *msg, const void *user)
{
    (void)source, (void)id, (void)len, (void)user;
    if (severity == GL_DEBUG_SEVERITY_NOTIFICATION)
        return;
    gi_log(type == GL_DEBUG_TYPE_ERROR ? GI_LOG_WARN : GI_LOG_DEBUG, "GL: %s", msg);
}

/* What every context gets once current: names, the debug output, the clip convention. */
static void finish_setup(gi_gpu *gpu, const gi_gpu_desc *d)
{
    snprintf(gpu->renderer, sizeof gpu->renderer, "%s", (const char *)glGetString(GL_RENDERER));
    snprintf(gpu->version, sizeof gpu->version, "%s", (const char *)glGetString(GL_VERSION));
    gpu->software = strstr(gpu->renderer, "llvmpipe") || strstr(gpu->renderer, "softpipe") ||
                    strstr(gpu->renderer, "swrast") || strstr(gpu->renderer, "SwiftShader");
    if (d->debug) {
        glEnable(GL_DEBUG_OUTPUT);
        glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
        glDebugMessageCallback(debug_cb, NULL);
    }
    /* Depth in [0, 1] gives better precision for every depth pass. */
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    gi_log(GI_LOG_INFO, "GL %s on %s (%s)", gpu->version, gpu->renderer, gpu->platform);
}

/* gi_gpu_desc.adopt_current: the caller's current context, if it is 4.5 core. */
static gi_gpu *adopt_current(const gi_gpu_desc *d, gi_error *err)
{
    if (epoxy_gl_version() < 45) {
        gi_error_set(err, GI_ERR_GL, "the current context is OpenGL %d.%d, not 4.5",
                     epoxy_gl_version() / 10, epoxy_gl_version() % 10);
        return NULL;
    }
    gi_gpu *gpu = calloc(1, sizeof *gpu);
    if (!gpu) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
        return NULL;
    }
    gpu->adopted = 1;
    gpu->platform = "adopted";
    finish_setup(gpu, d);
    return gpu;
}

gi_gpu *gi_gpu_create(const gi_gpu_desc *desc, gi_error *err)
{
    gi_gpu_desc d = {0};
    if (desc)
        d = *desc;
    if (d.adopt_current)
        return adopt_current(&d, err);
    const char *want = d.platform ? d.platform : getenv("GIBENCH_EGL");
    if (want && *want && strcmp(want, "device") != 0 && strcmp(want, "surfaceless") != 0) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "GIBENCH_EGL='%s' is not one of device, surfaceless", want);
        return NULL;
    }
    gi_gpu *gpu = calloc(1, sizeof *gpu);
    if (!gpu) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
        return NULL;
    }
    char reasons[1024] = "";
    int ok = 0;
    if (!want || !*want || strcmp(want, "device") == 0)
        ok = try_devices(gpu, d.debug, reasons, sizeof reasons);
    if (!ok && (!want || !*want || strcmp(want, "surfaceless") == 0))
        ok = try_surfaceless(gpu, d.debug, reasons, sizeof reasons);
    if (!ok) {
        size_t n = strlen(reasons);
        if (n >= 2)
            reasons[n - 2] = '\0';
        gi_error_set(err, GI_ERR_GL, "no OpenGL 4.5 core context through EGL (%s)", reasons);
        free(gpu);
        return NULL;
    }
    finish_setup(gpu, &d);
    return gpu;
}

void gi_gpu_destroy(gi_gpu *gpu)
{
    if (!gpu)
        return;
    if (gpu->adopted) {
        free(gpu);
        return;
    }
    eglMakeCurrent(gpu->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(gpu->display, gpu->context);
    /* No eglTerminate: the display is a per-process singleton that the next
     * gi_gpu_create reuses, and terminating it unloads the driver, after
     * which its own small leaks can no longer be attributed (or suppressed)
     * by LeakSanitizer. */
    free(gpu);
}

const char *gi_gpu_renderer(const gi_gpu *gpu)
{
    return gpu->renderer;
}
const char *gi_gpu_version(const gi_gpu *gpu)
{
    return gpu->version;
}
const char *gi_gpu_platform(const gi_gpu *gpu)
{
    return gpu->platform;
}
int gi_gpu_is_software(const gi_gpu *gpu)
{
    return gpu->software;
}

gi_result gi_gl_check(const char *what, gi_error *err)
{
    GLenum e = glGetError();
    if (e == GL_NO_ERROR)
        return GI_OK;
    const char *name = "GL error";
    switch (e) {
    case GL_INVALID_ENUM:
        name = "GL_INVALID_ENUM";
        break;
    case GL_INVALID_VALUE:
        name = "GL_INVALID_VALUE";
        break;
    case GL_INVALID_OPERATION:
        name = "GL_INVALID_OPERATION";
        break;
    case GL_INVALID_FRAMEBUFFER_OPERATION:
        name = "GL_INVALID_FRAMEBUFFER_OPERATION";
        break;
    case GL_OUT_OF_MEMORY:
        name = "GL_OUT_OF_MEMORY";
        break;
    default:
        break;
    }
    while (glGetError() != GL_NO_ERROR) {
    }
    return gi_error_set(err, e == GL_OUT_OF_MEMORY ? GI_ERR_OUT_OF_MEMORY : GI_ERR_GL, "%s: %s",
                        what, name);
}

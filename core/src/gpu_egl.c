/* Headless OpenGL 4.5 core context through EGL (see gpu.h).
 *
 * Order of attempts (GIBENCH_EGL unset or "auto"): EGL devices that are not
 * software (EGL_EXT_device_query without EGL_MESA_device_software), then
 * Mesa's surfaceless platform. GIBENCH_EGL=device|surfaceless|<index>|<name>
 * picks one (see gi/gpu.h). Each failed attempt leaves a reason; if all fail
 * the error lists them. */
#include "gi/gpu.h"
#include "gi/log.h"

#include <epoxy/egl.h>
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct gi_gpu {
    EGLDisplay display;
    EGLContext context;
    char renderer[256];
    char version[256];
    char vendor[128];
    char device[192]; /* which EGL device: "device 0 of 2 (NVIDIA Corporation)", "surfaceless
                         (Mesa)" */
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

/* Is `want` a device index ("0", "1", ...)? Sets *index. */
static int parse_index(const char *want, EGLint *index)
{
    char *end = NULL;
    long v = want && *want ? strtol(want, &end, 10) : -1;
    if (!end || *end != '\0' || v < 0 || v > 1000)
        return 0;
    *index = (EGLint)v;
    return 1;
}

/* Case-insensitive: does `hay` contain `needle`? */
static int contains_ci(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (; hay && *hay; hay++) {
        size_t k = 0;
        while (k < n && hay[k] &&
               tolower((unsigned char)hay[k]) == tolower((unsigned char)needle[k]))
            k++;
        if (k == n)
            return 1;
    }
    return 0;
}

/* Drops the context try_display made (a device that did not match a name). */
static void drop_display(gi_gpu *gpu)
{
    eglMakeCurrent(gpu->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(gpu->display, gpu->context);
    gpu->display = EGL_NO_DISPLAY;
    gpu->context = EGL_NO_CONTEXT;
}

/* EGL devices. `want`: NULL/"auto"/"device" = the first that is not software
 * (llvmpipe then comes through the surfaceless platform, as it always has);
 * a number = that device, software or not; any other text = the first device
 * whose GL_VENDOR, GL_RENDERER or EGL driver name contains it. */
static int try_devices(gi_gpu *gpu, const char *want, int debug, char *reasons, size_t size)
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
    EGLint index = -1;
    int by_index = parse_index(want, &index);
    int by_name = want && *want && !by_index && strcmp(want, "auto") && strcmp(want, "device");
    for (EGLint i = 0; i < count; i++) {
        const char *dexts = eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS);
        int software = has_ext(dexts, "EGL_MESA_device_software");
        if (by_index ? i != index : !by_name && software)
            continue; /* llvmpipe comes through the surfaceless fallback */
        EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], NULL);
        const char *why = NULL;
        if (!try_display(gpu, dpy, debug, &why)) {
            char num[16];
            snprintf(num, sizeof num, "%d", (int)i);
            append(reasons, size, "device %s: %s; ", num, why);
            continue;
        }
        const char *driver = has_ext(dexts, "EGL_EXT_device_query_name")
                                 ? eglQueryDeviceStringEXT(devices[i], EGL_VENDOR)
                                 : NULL;
        const char *vendor = (const char *)glGetString(GL_VENDOR);
        const char *rend = (const char *)glGetString(GL_RENDERER);
        if (by_name && !contains_ci(vendor, want) && !contains_ci(rend, want) &&
            !contains_ci(driver, want)) {
            drop_display(gpu);
            continue;
        }
        snprintf(gpu->device, sizeof gpu->device, "device %d of %d (%s)", (int)i, (int)count,
                 vendor ? vendor : "?");
        gpu->platform = "device";
        return 1;
    }
    if (by_index && index >= count) {
        char num[64];
        snprintf(num, sizeof num, "%d (there are %d)", (int)index, (int)count);
        append(reasons, size, "device: no EGL device %s%s; ", num, "");
    } else if (by_name)
        append(reasons, size, "device: no EGL device named like '%s'%s; ", want, "");
    else
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
        snprintf(gpu->device, sizeof gpu->device, "surfaceless (Mesa)");
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
    snprintf(gpu->vendor, sizeof gpu->vendor, "%s", (const char *)glGetString(GL_VENDOR));
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
    snprintf(gpu->device, sizeof gpu->device, "adopted (the caller's context)");
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
    if (want && !*want)
        want = NULL;
    gi_gpu *gpu = calloc(1, sizeof *gpu);
    if (!gpu) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
        return NULL;
    }
    char reasons[1024] = "";
    int surfaceless_only = want && !strcmp(want, "surfaceless");
    int ok = 0;
    if (!surfaceless_only)
        ok = try_devices(gpu, want, d.debug, reasons, sizeof reasons);
    /* auto falls back to llvmpipe; a device asked for by name or number does not,
     * so a benchmark meant for a GPU never quietly times the CPU */
    if (!ok && (!want || surfaceless_only || !strcmp(want, "auto")))
        ok = try_surfaceless(gpu, d.debug, reasons, sizeof reasons);
    if (!ok) {
        size_t n = strlen(reasons);
        if (n >= 2)
            reasons[n - 2] = '\0';
        gi_error_set(err, GI_ERR_GL, "no OpenGL 4.5 core context through EGL (%s%s%s)", reasons,
                     want ? "; GIBENCH_EGL=" : "", want ? want : "");
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
const char *gi_gpu_vendor(const gi_gpu *gpu)
{
    return gpu->vendor;
}
const char *gi_gpu_device(const gi_gpu *gpu)
{
    return gpu->device;
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

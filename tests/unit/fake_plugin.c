/* Fake method plugins for the loader tests, one per defect: built several
 * times with one FAKE_* macro defined (tests/CMakeLists.txt). The FAKE_CONF_*
 * kinds render something (a constant per pixel) for the conformance suite's
 * own tests: each breaks one rule the suite must catch. FAKE_ENTRY_CRASH and
 * FAKE_CTOR_CRASH crash while loading (in gi_method_entry, in a constructor);
 * FAKE_CTOR_PRINT prints to stdout from a constructor.
 * FAKE_DTOR_CRASH loads fine and crashes in its destructor, when unloaded or
 * at the exit of the process that loaded it.
 * FAKE_CONF_DEPART declares a furnace departure (gi_departure) whose remedy
 * fix=true renders the furnace's closed form; at its defaults it renders
 * the emission alone, as FAKE_CONF_WRONG does. FAKE_CONF_DEPART_NOFIX
 * declares the same, but its remedy changes nothing: the suite must fail it.
 * FAKE_BAKED renders a constant grey, lacks GI_CAP_RIGID_MOTION and refuses
 * moved lights in update(), as a method that bakes its lights at prepare
 * would: the viewer's tests of a method that cannot follow a change.
 * FAKE_ABI12 is built for ABI 1.2 (no debug buffers); FAKE_BUFFERS declares
 * debug buffers (ABI 1.3), some of which break the contract: a
 * screen-space buffer of the wrong size, one holding NaN, one that fails. */
#define _POSIX_C_SOURCE 200809L
#include "gi/kit.h" /* GI_ABI_LAYOUT */

#include <math.h>
#include <stdio.h>
#include <signal.h>
#include <stddef.h>
#include <string.h>
#include <unistd.h>

#if defined(FAKE_CHANGES)
static const gi_host *fake_host;
static uint32_t fake_flags_seen, fake_updates;
#endif

#if defined(FAKE_CONF_DEPART) || defined(FAKE_CONF_DEPART_NOFIX)
#define FAKE_DEPART 1
static int fake_fix;      /* the remedy's parameter */
static float fake_rho;    /* the first material's albedo (the furnace's rho) */
static int fake_emitters; /* the scene has an area light */
#endif

static gi_result fake_create(const gi_host *host, const gi_params *params, void **inst)
{
    (void)host, (void)params;
#if defined(FAKE_DEPART)
    fake_fix = gi_params_bool(params, "fix");
#endif
#if defined(FAKE_CHANGES)
    fake_host = host;
#endif
    static int dummy;
    *inst = &dummy;
    return GI_OK;
}
static gi_result fake_prepare(void *inst, const gi_gpu_scene *s)
{
    (void)inst, (void)s;
#if defined(FAKE_DEPART)
    fake_rho = s->scene->material_count ? s->scene->materials[0].albedo[0] : 0.0f;
    fake_emitters = s->scene->emitter_count > 0;
#endif
    return GI_OK;
}
static gi_result fake_update(void *inst, const gi_gpu_scene *s, const gi_changes *c)
{
    (void)inst, (void)s, (void)c;
#if defined(FAKE_BAKED)
    if (c->flags & GI_CHANGED_LIGHTS)
        return GI_ERR_UNSUPPORTED;
#endif
#if defined(FAKE_CHANGES) /* reports what the harness passed (stats in --timings) */
    fake_flags_seen |= c->flags;
    fake_updates++;
    fake_host->stat(fake_host, "updates", fake_updates);
    fake_host->stat(fake_host, "changed_vertices", (fake_flags_seen & GI_CHANGED_VERTICES) ? 1 : 0);
    fake_host->stat(fake_host, "changed_transforms",
                    (fake_flags_seen & GI_CHANGED_TRANSFORMS) ? 1 : 0);
    fake_host->stat(fake_host, "changed_lights", (fake_flags_seen & GI_CHANGED_LIGHTS) ? 1 : 0);
    fake_host->stat(fake_host, "changed_camera", (fake_flags_seen & GI_CHANGED_CAMERA) ? 1 : 0);
#endif
    return GI_OK;
}
#if defined(FAKE_CONF_WRONG) || defined(FAKE_CONF_NAN) || defined(FAKE_CONF_NONDET) ||             \
    defined(FAKE_CONF_LIAR)
#define FAKE_CONF 1
static uint32_t fake_renders; /* renders so far in this process */
#endif

static gi_result fake_render(void *inst, const gi_view *v, const gi_target *t)
{
    (void)inst, (void)v, (void)t;
#if defined(FAKE_CONF)
    float c[4] = {1.0f, 1.0f, 1.0f, 1.0f};
#if defined(FAKE_CONF_WRONG) /* the emission alone: no bounce at all in the furnace */
    c[0] = c[1] = c[2] = 1.0f;
#elif defined(FAKE_CONF_NAN)
    c[0] = c[1] = c[2] = NAN;
#elif defined(FAKE_CONF_NONDET) /* a different image on every call */
    c[0] = c[1] = c[2] = 0.5f + 0.01f * (float)(fake_renders % 64u);
#elif defined(FAKE_CONF_LIAR)   /* claims every light, renders none */
    c[0] = c[1] = c[2] = 0.0f;
#endif
    fake_renders++;
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, 0, c);
#elif defined(FAKE_DEPART)
    /* the emission alone at the defaults; with the remedy Le (1 + rho), the furnace's closed
     * form at max_bounces 0 (B = 1); black without an area light */
    float e = !fake_emitters ? 0.0f : fake_fix ? 1.0f + fake_rho : 1.0f;
#if defined(FAKE_CONF_DEPART_NOFIX)
    e = fake_emitters ? 1.0f : 0.0f;
#endif
    const float c[4] = {e, e, e, 1.0f};
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, 0, c);
#elif defined(FAKE_BAKED)
    const float grey[4] = {0.5f, 0.5f, 0.5f, 1.0f};
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, 0, grey);
#elif defined(FAKE_CRASH)
    raise(SIGSEGV); /* compare must survive a method that crashes */
#elif defined(FAKE_HANG)
    for (;;) /* ... and one that never returns */
        sleep(1);
#endif
    return GI_OK;
}
static void fake_destroy(void *inst)
{
    (void)inst;
#if defined(FAKE_DESTROY_CRASH)
    raise(SIGSEGV); /* renders, then crashes in destroy(): costs its own runs only */
#endif
}
static const char *fake_last_error(void *inst)
{
    (void)inst;
#if defined(FAKE_BAKED)
    return "lights are baked at prepare";
#else
    return "";
#endif
}

static const gi_param_desc fake_params[] = {
#if defined(FAKE_BAD_PARAM)
    {"n", GI_PARAM_INT, 100, 0, 10, NULL, "n", "default outside its range"},
#else
    {"n", GI_PARAM_INT, 4, 1, 64, NULL, "N", "a count"},
    {"mode", GI_PARAM_ENUM, 1, 0, 0, "a|b|c", NULL, "a choice"},
#endif
#if defined(FAKE_DEPART)
    {"fix", GI_PARAM_BOOL, 0, 0, 1, NULL, NULL, "the remedy: render the furnace right"},
#endif
    {0},
};

#if defined(FAKE_DEPART)
static const gi_departure fake_departures[] = {
    {"furnace", "the fake's paper renders the emission alone", "fix=true"},
    {"held_out", "the fake's paper renders a constant", "fix=true"},
    {NULL, NULL, NULL},
};
#endif

#if defined(FAKE_BUFFERS)
static const gi_debug_buffer_desc fake_buffers[] = {
    {"ramp", "x / width in red, y / height in green", GI_DEBUG_SCREEN},
    {"tile", "a 3 x 2 image of its own", GI_DEBUG_OWN_SIZE},
    {"wrong_size", "1 x 1, though declared in screen space", GI_DEBUG_SCREEN},
    {"nan", "NaN everywhere", GI_DEBUG_SCREEN},
    {"fails", "returns an error", GI_DEBUG_SCREEN},
    {NULL, NULL, 0},
};
static gi_result fake_debug_buffer(void *inst, const char *name, const gi_view *view,
                                   gi_image **out)
{
    (void)inst;
    *out = NULL;
    if (!strcmp(name, "fails"))
        return GI_ERR_UNSUPPORTED;
    int own = !strcmp(name, "tile"), tiny = !strcmp(name, "wrong_size");
    uint32_t w = own ? 3 : tiny ? 1 : view->width, h = own ? 2 : tiny ? 1 : view->height;
    if (!(*out = gi_image_create(w, h)))
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            float *p = &(*out)->rgba[4 * ((size_t)y * w + x)];
            p[0] = !strcmp(name, "nan") ? NAN : (float)x / (float)w;
            p[1] = (float)y / (float)h;
        }
    return GI_OK;
}
#endif

#if defined(FAKE_ABI12)
/* Built for ABI 1.2: its descriptor ends before debug_buffers, so the host
 * must not see the table that lies beyond (in this build's struct). */
static const gi_debug_buffer_desc fake_buffers[] = {
    {"beyond", "lies beyond struct_size", GI_DEBUG_SCREEN},
    {NULL, NULL, 0},
};
#endif

static const gi_method fake_method = {
#if defined(FAKE_SMALL_STRUCT)
    .struct_size = offsetof(gi_method, render),
#elif defined(FAKE_ABI12)
    .struct_size = offsetof(gi_method, debug_buffers),
#else
    .struct_size = sizeof(gi_method),
#endif
#if defined(FAKE_WRONG_ABI)
    .abi_version = ((GI_ABI_MAJOR + 1u) << 16),
#elif defined(FAKE_ABI12)
    .abi_version = (1u << 16) | 2u,
#else
    .abi_version = GI_ABI_VERSION,
#endif
#if defined(FAKE_BAD_ID)
    .id = "Bad Id!",
#elif defined(FAKE_DUPLICATE_ID)
    .id = "fake_good",
#else
    .id = FAKE_ID,
#endif
    .title = "Fake method",
    .citation = "none",
    .version = "0",
#if defined(FAKE_CRASH) || defined(FAKE_HANG) || defined(FAKE_DESTROY_CRASH) ||                    \
    defined(FAKE_CONF_WRONG) || defined(FAKE_CONF_NAN) || defined(FAKE_CONF_NONDET) ||             \
    defined(FAKE_DEPART)
    .caps = GI_CAP_DIRECT | GI_CAP_AREA_LIGHTS,
#elif defined(FAKE_CONF_LIAR)
    .caps = GI_CAP_DIRECT | GI_CAP_AREA_LIGHTS | GI_CAP_POINT_LIGHTS | GI_CAP_DIRECTIONAL |
            GI_CAP_ENVIRONMENT,
#elif defined(FAKE_BAKED) /* no GI_CAP_RIGID_MOTION */
    .caps = GI_CAP_DIRECT | GI_CAP_AREA_LIGHTS | GI_CAP_POINT_LIGHTS | GI_CAP_DIRECTIONAL |
            GI_CAP_ENVIRONMENT | GI_CAP_PRECOMPUTE,
#else
    .caps = GI_CAP_DIRECT,
#endif
    .params = fake_params,
    .create = fake_create,
    .prepare = fake_prepare,
    .update = fake_update,
#if !defined(FAKE_MISSING_FN)
    .render = fake_render,
#endif
    .destroy = fake_destroy,
    .last_error = fake_last_error,
    .layout = GI_ABI_LAYOUT,
#if defined(FAKE_DEPART)
    .departures = fake_departures,
#endif
#if defined(FAKE_ABI12)
    .debug_buffers = fake_buffers,
#elif defined(FAKE_BUFFERS)
    .debug_buffers = fake_buffers,
    .debug_buffer = fake_debug_buffer,
#endif
};

#if defined(FAKE_CTOR_CRASH) /* crashes as it is mapped, before any symbol is looked up */
__attribute__((constructor)) static void fake_ctor(void)
{
    raise(SIGSEGV);
}
#endif

#if defined(FAKE_CTOR_PRINT) /* chatters on stdout as it is mapped (and again, unbuffered) */
__attribute__((constructor)) static void fake_ctor(void)
{
    printf("fake_ctor_print: hello from a constructor\n");
    (void)!write(STDOUT_FILENO, "fake_ctor_print: raw\n", 21);
}
#endif

#if defined(FAKE_DTOR_CRASH) /* crashes as it is unloaded: at dlclose, or at exit */
__attribute__((destructor)) static void fake_dtor(void)
{
    raise(SIGSEGV);
}
#endif

GI_EXPORT const gi_method *gi_method_entry(uint32_t host_abi_version)
{
#if defined(FAKE_ENTRY_CRASH) /* the loader must survive a plugin that crashes in its entry */
    raise(SIGSEGV);
#endif
#if defined(FAKE_NULL_ENTRY)
    (void)host_abi_version;
    return NULL;
#else
    if (GI_ABI_VERSION_MAJOR(host_abi_version) != GI_ABI_MAJOR)
        return NULL;
#if defined(FAKE_LAYOUT_OLD) || defined(FAKE_LAYOUT_NEW) || defined(FAKE_LAYOUT_REVISION)
    /* Built against other headers: a copy of the descriptor with the layout
     * such a build would have recorded. */
    static gi_method other;
    other = fake_method;
#if defined(FAKE_LAYOUT_OLD)   /* an older gi_view, 16 bytes shorter */
    other.layout.view -= 16;
#elif defined(FAKE_LAYOUT_NEW) /* a newer gi_scene, 8 bytes longer */
    other.layout.scene += 8;
#else                          /* same sizes, a struct reordered */
    other.layout.revision += 1;
#endif
    return &other;
#else
    return &fake_method;
#endif
#endif
}

/* The fixtures of avg_tests (avg_tests.h): a minimal host for driving
 * the method in-process, scenes on the GPU, targets, frames and the
 * G-buffer read back. */
#include "avg_tests.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed (this file's). */
#include "check.h"
#define EXPECT CHECK_MSG

static void host_log(const gi_host *h, int level, const char *fmt, ...)
{
    (void)h;
    (void)level;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}
static void host_progress(const gi_host *h, const char *task, float f)
{
    (void)h, (void)task, (void)f;
}
static void host_stage(const gi_host *h, const char *name)
{
    (void)h, (void)name;
}
static void host_stat(const gi_host *h, const char *name, double v)
{
    (void)h, (void)name, (void)v;
}
static int host_cancelled(const gi_host *h)
{
    (void)h;
    return 0;
}

static gi_host make_host(const gi_gpu_scene *gs)
{
    gi_host h;
    memset(&h, 0, sizeof h);
    h.struct_size = sizeof h;
    h.abi_version = GI_ABI_VERSION;
    h.log = host_log;
    h.progress = host_progress;
    h.stage_begin = host_stage;
    h.stage_end = host_stage;
    h.stat = host_stat;
    h.cancelled = host_cancelled;
    h.gpu_scene = gs;
    return h;
}

void avg_test_make_view(const gi_scene *s, float t, uint32_t w, uint32_t h, gi_view *v)
{
    gi_camera_frame cf = gi_scene_camera_at(s, s->camera_count ? 0 : -1, t);
    gi_view_from_camera(&cf, w, h, t, v);
    v->seed = 1;
}

avg *avg_test_make_avg(const gi_host *host, const gi_gpu_scene *gs, const char *const *kv,
                       uint32_t n)
{
    const gi_method *m = gi_method_entry(GI_ABI_VERSION);
    gi_error err;
    gi_params *p = gi_params_parse("avg", m->params, kv, n, &err);
    if (!p) {
        fprintf(stderr, "%s\n", err.text);
        return NULL;
    }
    void *inst = NULL;
    gi_result r = m->create(host, p, &inst);
    gi_params_free(p);
    if (r != GI_OK)
        return NULL;
    if (m->prepare(inst, gs) != GI_OK) {
        fprintf(stderr, "prepare: %s\n", m->last_error(inst));
        m->destroy(inst);
        return NULL;
    }
    return inst;
}

avg_test_target avg_test_make_target(uint32_t w, uint32_t h)
{
    avg_test_target t = {0, 0, w, h};
    glCreateTextures(GL_TEXTURE_2D, 1, &t.tex);
    glTextureStorage2D(t.tex, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
    glCreateFramebuffers(1, &t.fbo);
    glNamedFramebufferTexture(t.fbo, GL_COLOR_ATTACHMENT0, t.tex, 0);
    return t;
}

int avg_test_render(avg *a, const gi_view *v, const avg_test_target *t)
{
    const gi_method *m = gi_method_entry(GI_ABI_VERSION);
    gi_target gt = {t->tex, t->fbo, t->w, t->h};
    if (m->render(a, v, &gt) != GI_OK) {
        fprintf(stderr, "render: %s\n", m->last_error(a));
        return 0;
    }
    return 1;
}

int avg_test_load_fixture(gi_gpu *gpu, const char *scene_path, avg_test_fixture *f)
{
    gi_error err;
    f->s = gi_scene_load(scene_path, &err);
    if (!f->s) {
        EXPECT(0, "%s", err.text);
        return 0;
    }
    f->gs = gi_gpu_scene_upload(gpu, f->s, &err);
    if (!f->gs) {
        EXPECT(0, "set-up failed: upload of %s: %s", scene_path, err.text);
        gi_scene_free(f->s);
        return 0;
    }
    gi_gpu_scene_set_time(f->gs, 0.0f);
    f->host = make_host(f->gs);
    return 1;
}

void avg_test_free_fixture(avg_test_fixture *f)
{
    gi_gpu_scene_free(f->gs);
    gi_scene_free(f->s);
}

avg_test_target avg_test_render_frame(avg *a, const gi_scene *s, uint32_t w, uint32_t h)
{
    avg_test_target t = avg_test_make_target(w, h);
    gi_view v;
    avg_test_make_view(s, 0.0f, w, h, &v);
    EXPECT(avg_test_render(a, &v, &t), "render");
    return t;
}

avg_test_gbuffer avg_test_read_gbuffer(const avg *a, uint32_t w, uint32_t h)
{
    avg_test_gbuffer g = {gi_gpu_read_texture(a->kit.gbuffer->tex_position, w, h),
                          gi_gpu_read_texture(a->kit.gbuffer->tex_normal, w, h),
                          gi_gpu_read_texture(a->kit.gbuffer->tex_albedo, w, h),
                          gi_gpu_read_texture(a->kit.gbuffer->tex_emission, w, h)};
    return g;
}

void avg_test_free_gbuffer(avg_test_gbuffer *g)
{
    gi_image_free(g->pos);
    gi_image_free(g->nrm);
    gi_image_free(g->alb);
    gi_image_free(g->emi);
}

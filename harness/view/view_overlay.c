/* gibench view's overlay, drawn with GL over the image (docs/commands.md "gibench view",
 * "Overlay"): the method, its parameters, the GL renderer, frames accumulated, exposure, the last
 * frame's per-stage times as a bar chart, the method's message when it cannot follow a change, and
 * a progress bar while a method precomputes. Text is stb_easy_font's (Debian libstb-dev): quads of
 * a small vector font, turned into triangles here. */
#define _POSIX_C_SOURCE 200809L
#include "view.h"

#include "gi/shader.h"
#include "gi/timer.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stb/stb_easy_font.h>

typedef struct ov_vert {
    float x, y;
    unsigned char rgba[4];
} ov_vert;

#define OV_MAX_VERTS 60000

static const char ov_vs[] =
    "layout(location = 0) in vec2 p;\n"
    "layout(location = 1) in vec4 c;\n"
    "uniform vec2 size;\n"
    "out vec4 col;\n"
    "void main() {\n"
    "    col = c;\n"
    "    gl_Position = vec4(p.x / size.x * 2.0 - 1.0, 1.0 - p.y / size.y * 2.0, 0.0, 1.0);\n"
    "}\n";
static const char ov_fs[] = "in vec4 col;\n"
                            "out vec4 color;\n"
                            "void main() { color = col; }\n";

typedef struct overlay {
    GLuint prog, vao, vbo;
    ov_vert *verts;
    int n;
} overlay;

int view_overlay_init(viewer *v)
{
    overlay *o = calloc(1, sizeof *o);
    if (!o)
        return 0;
    v->overlay = o;
    o->verts = malloc(OV_MAX_VERTS * sizeof *o->verts);
    gi_error err;
    o->prog = o->verts ? gi_program_build_text("view overlay", ov_vs, ov_fs, NULL, &err) : 0;
    if (!o->prog)
        return 0;
    glCreateBuffers(1, &o->vbo);
    glNamedBufferStorage(o->vbo, OV_MAX_VERTS * sizeof(ov_vert), NULL, GL_DYNAMIC_STORAGE_BIT);
    glCreateVertexArrays(1, &o->vao);
    glVertexArrayVertexBuffer(o->vao, 0, o->vbo, 0, sizeof(ov_vert));
    glEnableVertexArrayAttrib(o->vao, 0);
    glEnableVertexArrayAttrib(o->vao, 1);
    glVertexArrayAttribFormat(o->vao, 0, 2, GL_FLOAT, GL_FALSE, offsetof(ov_vert, x));
    glVertexArrayAttribFormat(o->vao, 1, 4, GL_UNSIGNED_BYTE, GL_TRUE, offsetof(ov_vert, rgba));
    glVertexArrayAttribBinding(o->vao, 0, 0);
    glVertexArrayAttribBinding(o->vao, 1, 0);
    return 1;
}

void view_overlay_free(viewer *v)
{
    overlay *o = v->overlay;
    if (!o)
        return;
    if (o->prog)
        glDeleteProgram(o->prog);
    if (o->vao)
        glDeleteVertexArrays(1, &o->vao);
    if (o->vbo)
        glDeleteBuffers(1, &o->vbo);
    free(o->verts);
    free(o);
    v->overlay = NULL;
}

static void put(overlay *o, float x, float y, const unsigned char c[4])
{
    if (o->n >= OV_MAX_VERTS)
        return;
    ov_vert *p = &o->verts[o->n++];
    p->x = x;
    p->y = y;
    memcpy(p->rgba, c, 4);
}

static void rect(overlay *o, float x0, float y0, float x1, float y1, const unsigned char c[4])
{
    if (o->n + 6 > OV_MAX_VERTS)
        return;
    put(o, x0, y0, c);
    put(o, x1, y0, c);
    put(o, x1, y1, c);
    put(o, x0, y0, c);
    put(o, x1, y1, c);
    put(o, x0, y1, c);
}

/* Text at (x, y) (top left), stb_easy_font's quads as triangles. */
static void text(overlay *o, float x, float y, const char *s, const unsigned char c[4])
{
    static char quads[64 * 1024];
    unsigned char col[4];
    memcpy(col, c, 4);
    int nq = stb_easy_font_print(x, y, (char *)s, col, quads, (int)sizeof quads);
    for (int q = 0; q < nq && o->n + 6 <= OV_MAX_VERTS; q++) {
        const float *v0 = (const float *)(quads + (size_t)(4 * q + 0) * 16);
        const float *v1 = (const float *)(quads + (size_t)(4 * q + 1) * 16);
        const float *v2 = (const float *)(quads + (size_t)(4 * q + 2) * 16);
        const float *v3 = (const float *)(quads + (size_t)(4 * q + 3) * 16);
        put(o, v0[0], v0[1], c);
        put(o, v1[0], v1[1], c);
        put(o, v2[0], v2[1], c);
        put(o, v0[0], v0[1], c);
        put(o, v2[0], v2[1], c);
        put(o, v3[0], v3[1], c);
    }
}

#define LINE 11.0f

static const unsigned char WHITE[4] = {235, 235, 235, 255}, GREY[4] = {160, 160, 160, 255},
                           ORANGE[4] = {255, 170, 60, 255}, PANEL[4] = {0, 0, 0, 150},
                           BAR[4] = {90, 170, 255, 255}, BAR_BG[4] = {60, 60, 60, 200},
                           GREEN[4] = {110, 220, 110, 255};

/* Text wrapped at the window's width; returns the next line's y. */
static float wrapped(overlay *o, float x, float y, float width, const char *s,
                     const unsigned char c[4])
{
    size_t per = width > 24 ? (size_t)((width - x - 4) / 6.0f) : 4;
    if (per < 4)
        per = 4;
    char line[512];
    size_t len = strlen(s);
    for (size_t at = 0; at < len;) {
        size_t n = len - at < per ? len - at : per;
        if (n == per) /* break after a comma or space where there is one */
            for (size_t k = n; k > per / 2; k--)
                if (s[at + k - 1] == ',' || s[at + k - 1] == ' ') {
                    n = k;
                    break;
                }
        if (n >= sizeof line)
            n = sizeof line - 1;
        memcpy(line, s + at, n);
        line[n] = '\0';
        text(o, x, y, line, c);
        y += LINE;
        at += n;
    }
    return y;
}

/* Draws o's triangles over the current framebuffer (fw x fh pixels, the
 * window's w x h screen units). */
static void flush(viewer *v, int fw, int fh, int w, int h)
{
    overlay *o = v->overlay;
    if (!o->n)
        return;
    glNamedBufferSubData(o->vbo, 0, (GLsizeiptr)((size_t)o->n * sizeof(ov_vert)), o->verts);
    glViewport(0, 0, fw, fh);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(o->prog);
    glUniform2f(glGetUniformLocation(o->prog, "size"), (float)(w > 0 ? w : 1),
                (float)(h > 0 ? h : 1));
    glBindVertexArray(o->vao);
    glDrawArrays(GL_TRIANGLES, 0, o->n);
    glBindVertexArray(0);
    glUseProgram(0);
    glDisable(GL_BLEND);
    o->n = 0;
}

void view_overlay_draw(viewer *v, int fw, int fh)
{
    overlay *o = v->overlay;
    if (!o || !v->show_overlay)
        return;
    double t0 = gi_now();
    float w = (float)v->win_w, x = 4, y = 4;
    char buf[1024];
    o->n = 0;
    /* a panel behind the text: drawn first, sized after the text is laid out */
    int panel = o->n;
    rect(o, 0, 0, 0, 0, PANEL);
    int ref = v->method_index < 0;
    if (ref)
        snprintf(buf, sizeof buf, "reference (path tracer) | %llu spp",
                 (unsigned long long)v->ref_spp);
    else
        snprintf(buf, sizeof buf, "%s%s", v->m ? v->m->id : "-",
                 v->split == 1   ? " | reference right"
                 : v->split == 2 ? " | error right (1e-3 blue .. 1 red)"
                                 : "");
    y = wrapped(o, x, y, w, buf, WHITE);
    y = wrapped(o, x, y, w, gi_gpu_renderer(v->gpu), GREY);
    if (!ref && v->params && v->params->count) {
        char *all = gi_params_to_string(v->params);
        /* the parameter TAB selected in brackets */
        uint32_t sel = (uint32_t)v->param_sel % v->params->count, k = 0;
        size_t used = 0;
        for (const char *p = all; p && *p && used + 4 < sizeof buf; p++) {
            if ((p == all || p[-1] == ',') && k++ == sel)
                buf[used++] = '[';
            if (*p == ',' && k - 1 == sel)
                buf[used++] = ']';
            buf[used++] = *p == ',' ? ' ' : *p;
        }
        if (k - 1 == sel && used + 1 < sizeof buf)
            buf[used++] = ']';
        buf[used] = '\0';
        free(all);
        y = wrapped(o, x, y, w, buf, GREY);
    }
    if (ref)
        snprintf(buf, sizeof buf, "EV %+.1f | t %.2f%s | ui %.2f ms", (double)v->exposure,
                 (double)v->time, v->playing ? " playing" : "", v->display_ms);
    else
        snprintf(buf, sizeof buf, "frame %u | %.1f ms | EV %+.1f | t %.2f%s | ui %.2f ms",
                 v->frame_index, v->frame_ms, (double)v->exposure, (double)v->time,
                 v->playing ? " playing" : "", v->display_ms);
    y = wrapped(o, x, y, w, buf, WHITE);
    if (v->status[0])
        y = wrapped(o, x, y, w, v->status, ORANGE);
    if (v->sel_object >= 0 && (uint32_t)v->sel_object < v->scene->object_count) {
        const char *n = v->scene->objects[v->sel_object].name;
        snprintf(buf, sizeof buf, "object %s", n ? n : "?");
        y = wrapped(o, x, y, w, buf, GREEN);
    }
    /* the last frame's stages, a bar each, scaled to the longest */
    if (!ref && v->stage_count) {
        double most = 0;
        for (int i = 0; i < v->stage_count; i++)
            most = fmax(most, v->stage_ms[i]);
        float bx = x + 60, bw = fmaxf(20.0f, fminf(160.0f, w - bx - 60));
        for (int i = 0; i < v->stage_count; i++) {
            text(o, x, y, v->stage_name[i], GREY);
            rect(o, bx, y + 1, bx + bw, y + 8, BAR_BG);
            rect(o, bx, y + 1, bx + bw * (float)(most > 0 ? v->stage_ms[i] / most : 0), y + 8, BAR);
            snprintf(buf, sizeof buf, "%.2f ms", v->stage_ms[i]);
            text(o, bx + bw + 4, y, buf, GREY);
            y += LINE;
        }
    }
    ov_vert *p = &o->verts[panel];
    float pw = fminf(w, 420.0f), ph = y + 2;
    float xs[6] = {0, pw, pw, 0, pw, 0}, ys[6] = {0, 0, ph, 0, ph, ph};
    for (int i = 0; i < 6; i++) {
        p[i].x = xs[i];
        p[i].y = ys[i];
    }
    flush(v, fw, fh, v->win_w, v->win_h);
    v->overlay_ms = 1e3 * (gi_now() - t0);
}

/* The host's progress callback while the viewer's method precomputes:
 * the terminal line as before, and a bar in the window (at most ten
 * redraws a second). The plugin's GL state is saved and put back. */
/* The viewer whose method precomputes: a process has one viewer, and the
 * host the callback gets may be either of its two methods' (view_slot). */
static viewer *progress_owner;

void view_overlay_progress_owner(viewer *v)
{
    progress_owner = v;
}

void view_overlay_progress(const gi_host *h, const char *task, float fraction)
{
    viewer *v = progress_owner;
    if (v->host_progress)
        v->host_progress(h, task, fraction);
    double now = gi_now();
    if (!v->overlay || (now - v->last_progress < 0.1 && fraction < 1.0f))
        return;
    v->last_progress = now;
    GLint fbo_draw = 0, fbo_read = 0, prog = 0, vao = 0, vp[4], blend_src = 0, blend_dst = 0;
    GLboolean blend = glIsEnabled(GL_BLEND), depth = glIsEnabled(GL_DEPTH_TEST),
              cull = glIsEnabled(GL_CULL_FACE), scissor = glIsEnabled(GL_SCISSOR_TEST), mask[4];
    GLfloat clear[4];
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fbo_draw);
    glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &fbo_read);
    glGetIntegerv(GL_CURRENT_PROGRAM, &prog);
    glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &vao);
    glGetIntegerv(GL_VIEWPORT, vp);
    glGetIntegerv(GL_BLEND_SRC_RGB, &blend_src);
    glGetIntegerv(GL_BLEND_DST_RGB, &blend_dst);
    glGetBooleanv(GL_COLOR_WRITEMASK, mask);
    glGetFloatv(GL_COLOR_CLEAR_VALUE, clear);

    int fw = 0, fh = 0;
    glfwGetFramebufferSize(v->win, &fw, &fh);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_SCISSOR_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glClearColor(0.05f, 0.05f, 0.05f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    overlay *o = v->overlay;
    o->n = 0;
    float w = (float)v->win_w, wh = (float)v->win_h;
    char buf[256];
    snprintf(buf, sizeof buf, "preparing %s", v->m ? v->m->id : "");
    float y = wrapped(o, 4, 0.5f * wh - 2 * LINE, w, buf, WHITE);
    y = wrapped(o, 4, y, w, task, GREY);
    float bw = w - 8, f = fminf(1.0f, fmaxf(0.0f, fraction));
    rect(o, 4, y + 2, 4 + bw, y + 10, BAR_BG);
    rect(o, 4, y + 2, 4 + bw * f, y + 10, BAR);
    snprintf(buf, sizeof buf, "%.0f %%", 100.0 * f);
    text(o, 4, y + 13, buf, WHITE);
    flush(v, fw, fh, v->win_w, v->win_h);
    glfwSwapBuffers(v->win);

    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)fbo_draw);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, (GLuint)fbo_read);
    glUseProgram((GLuint)prog);
    glBindVertexArray((GLuint)vao);
    glViewport(vp[0], vp[1], vp[2], vp[3]);
    glBlendFunc((GLenum)blend_src, (GLenum)blend_dst);
    if (blend)
        glEnable(GL_BLEND);
    if (depth)
        glEnable(GL_DEPTH_TEST);
    if (cull)
        glEnable(GL_CULL_FACE);
    if (scissor)
        glEnable(GL_SCISSOR_TEST);
    glColorMask(mask[0], mask[1], mask[2], mask[3]);
    glClearColor(clear[0], clear[1], clear[2], clear[3]);
}

/* gibench view: the window's redraw (docs/commands.md "gibench view"): the
 * display shader (exposure and sRGB; in split view the reference or the
 * method's error right of the divider), the overlay, the title line, the
 * window written to a PNG on request, and the reference's newest image. */
#include "view.h"

#include "gi/image.h"
#include "gi/log.h"
#include "gi/shader.h"
#include "gi/tonemap.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char display_vs[] = "out vec2 uv;\n"
                                 "void main() {\n"
                                 "    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);\n"
                                 "    uv = p;\n"
                                 "    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);\n"
                                 "}\n";
/* The display mapping of core/shaders/tonemap.glsl (exposure, clamp,
 * sRGB) of what the image region shows (view_zoom.c maps its pixels to
 * image pixels: t = origin + (x, y) * span, top left origin). Sources
 * ("kinds"): 0 the method (img, bottom row first, as GL renders), 1 the
 * method's relative luminance error against the reference,
 * |L - Lref| / (Lref + 0.01), on a log scale from 1e-3 (blue) to 1 (red),
 * 2 the reference (`ref`, top row first), 3 a debug buffer (top row
 * first), 4 the second method (bottom row first). In split view the right
 * of the divider shows `right`. */
static const char display_fs[] =
    "in vec2 uv;\n"
    "out vec4 color;\n"
    "layout(binding = 0) uniform sampler2D img;\n"
    "layout(binding = 1) uniform sampler2D ref;\n"
    "layout(binding = 2) uniform sampler2D img2;\n"
    "layout(binding = 3) uniform sampler2D dbg;\n"
    "uniform float scale;\n"
    "uniform int left;\n"
    "uniform int right;\n"
    "uniform int split;\n"
    "uniform float divider;\n"
    "uniform float pixel;\n"
    "uniform vec2 origin;\n"
    "uniform vec2 span;\n"
    "float enc(float x) {\n"
    "    x = x > 0.0 ? min(x, 1.0) : 0.0;\n"
    "    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;\n"
    "}\n"
    "float lum(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }\n"
    "vec3 ramp(float t) {\n"
    "    t = clamp(t, 0.0, 1.0);\n"
    "    return clamp(vec3(1.5 - abs(4.0 * t - 3.0), 1.5 - abs(4.0 * t - 2.0), 1.5 - abs(4.0 * t - "
    "1.0)), 0.0, 1.0);\n"
    "}\n"
    "vec3 fetch(int k, vec2 t) {\n"
    "    vec2 g = vec2(t.x, 1.0 - t.y);\n"
    "    return k == 0 ? texture(img, g).rgb : k == 2 ? texture(ref, t).rgb\n"
    "         : k == 3 ? texture(dbg, t).rgb : texture(img2, g).rgb;\n"
    "}\n"
    "void main() {\n"
    "    vec2 t = origin + vec2(uv.x, 1.0 - uv.y) * span;\n"
    "    if (split != 0 && abs(uv.x - divider) < pixel) {\n"
    "        color = vec4(1.0);\n"
    "        return;\n"
    "    }\n"
    "    if (any(lessThan(t, vec2(0.0))) || any(greaterThanEqual(t, vec2(1.0)))) {\n"
    "        color = vec4(0.12, 0.12, 0.12, 1.0);\n"
    "        return;\n"
    "    }\n"
    "    int k = split != 0 && uv.x > divider ? right : left;\n"
    "    if (k == 1) {\n"
    "        float e = abs(lum(fetch(0, t)) - lum(fetch(2, t))) / (lum(fetch(2, t)) + 0.01);\n"
    "        color = vec4(ramp((log(max(e, 1e-4)) / log(10.0) + 3.0) / 3.0), 1.0);\n"
    "        return;\n"
    "    }\n"
    "    vec3 c = fetch(k, t) * scale;\n"
    "    color = vec4(enc(c.r), enc(c.g), enc(c.b), 1.0);\n"
    "}\n";

int view_build_display(viewer *v)
{
    gi_error err;
    v->display_prog = gi_program_build_text("view display", display_vs, display_fs, NULL, &err);
    if (!v->display_prog)
        return cli_fail(EXIT_RUN, "view: display shader: %s", err.text);
    glCreateVertexArrays(1, &v->display_vao);
    return EXIT_OK;
}

/* The window as shown (split view, divider and all) into a PNG: read back
 * from the back buffer before the swap. */
static void write_window(viewer *v, int fw, int fh)
{
    if (v->window_shot_image) { /* the image region: the left image_w columns */
        int ww = 0, wh = 0;
        glfwGetWindowSize(v->win, &ww, &wh);
        fw = ww > 0 ? (int)((double)v->image_w * fw / ww + 0.5) : fw;
    }
    gi_image *img = fw > 0 && fh > 0 ? gi_image_create((uint32_t)fw, (uint32_t)fh) : NULL;
    unsigned char *px = malloc((size_t)fw * (size_t)(fh > 0 ? fh : 0) * 4);
    gi_error err;
    if (!img || !px) {
        v->exit_code = cli_fail(EXIT_RUN, "view: out of memory reading the window back");
    } else {
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadBuffer(GL_BACK);
        glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, px);
        for (int y = 0; y < fh; y++) /* bottom row first -> top row first; sRGB -> linear */
            for (int x = 0; x < fw; x++)
                for (int c = 0; c < 4; c++) {
                    float b = px[4 * ((size_t)(fh - 1 - y) * (size_t)fw + (size_t)x) + (size_t)c] /
                              255.0f;
                    img->rgba[4 * ((size_t)y * (size_t)fw + (size_t)x) + (size_t)c] =
                        c == 3 ? 1.0f : gi_srgb_decode(b);
                }
        if (gi_image_write(v->window_shot, img, NULL, &err) != GI_OK)
            v->exit_code = cli_fail(EXIT_RUN, "view: %s", err.text);
        else if (gi_log_get_level() >= GI_LOG_WARN)
            printf("view: window %s\n", v->window_shot);
    }
    free(px);
    gi_image_free(img);
}

/* The kinds of display_fs the left side and the split's right side show. */
static void display_kinds(const viewer *v, int *left, int *right, int *split)
{
    static const int kind_of_source[VIEW_SRC_COUNT] = {0, 1, 2, 3};
    int ref = v->method_index < 0;
    *left = ref ? 2 : kind_of_source[v->source];
    *split = ref ? 0 : v->split;
    if (*split == 3 && (v->second.method_index < 0 || !v->second.target_tex))
        *split = 0;
    *right = *split == 1 ? 2 : *split == 2 ? 1 : 4;
}

/* The image into its region (left of the panels), zoomed and panned. */
static void draw_image(viewer *v, int fw, int fh)
{
    view_region_update(v);
    int ww = 0, wh = 0;
    glfwGetWindowSize(v->win, &ww, &wh);
    double sx = ww > 0 ? (double)fw / ww : 1.0; /* framebuffer pixels per window pixel */
    int rw = (int)(v->image_w * sx + 0.5);
    glViewport(0, 0, rw, fh);
    int left, right, split;
    display_kinds(v, &left, &right, &split);
    GLuint p = v->display_prog;
    glUseProgram(p);
    glUniform1f(glGetUniformLocation(p, "scale"), exp2f(v->exposure));
    glUniform1i(glGetUniformLocation(p, "left"), left);
    glUniform1i(glGetUniformLocation(p, "right"), right);
    glUniform1i(glGetUniformLocation(p, "split"), split);
    glUniform1f(glGetUniformLocation(p, "divider"), v->divider);
    glUniform1f(glGetUniformLocation(p, "pixel"), rw > 0 ? 0.75f / (float)rw : 0.0f);
    /* region pixel (x, y) -> image pixel pan + x * w / (image_w zoom) (view_zoom.c) */
    float span_x = 1.0f / v->zoom, span_y = (float)v->image_h * (float)v->width /
                                            ((float)v->image_w * (float)v->height * v->zoom);
    glUniform2f(glGetUniformLocation(p, "origin"), v->pan_x / (float)v->width,
                v->pan_y / (float)v->height);
    glUniform2f(glGetUniformLocation(p, "span"), span_x, span_y);
    glBindTextureUnit(0, v->target_tex);
    glBindTextureUnit(1, v->ref_tex);
    glBindTextureUnit(2, v->second.target_tex ? v->second.target_tex : v->target_tex);
    glBindTextureUnit(3, v->buf_tex);
    for (GLuint u = 0; u < 4; u++)
        glBindSampler(u, 0);
    glBindVertexArray(v->display_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
}

void view_display(viewer *v)
{
    double t0 = gi_now();
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(v->win, &fw, &fh);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fw, fh);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glDisable(GL_SCISSOR_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    draw_image(v, fw, fh);
    glViewport(0, 0, fw, fh);
    if (v->show_panels)
        view_panels_draw(v);
    else
        view_overlay_draw(v, fw, fh);
    v->sum_overlay_ms += v->overlay_ms;
    if (v->window_shot) {
        write_window(v, fw, fh);
        v->window_shot = NULL;
    }
    glfwSwapBuffers(v->win);
    glFinish();
    v->display_ms = 1e3 * (gi_now() - t0);
    v->sum_display_ms += v->display_ms;
    v->n_displays++;
    v->need_display = 0;

    char title[768];
    int ref = v->method_index < 0;
    if (ref)
        snprintf(title, sizeof title,
                 "gibench view | reference | %llu spp | EV %+.1f | t %.2f%s | ui %.1f ms",
                 (unsigned long long)v->ref_spp, (double)v->exposure, (double)v->time,
                 v->playing ? " playing" : "", v->display_ms);
    else
        snprintf(title, sizeof title,
                 "gibench view | %s%s | %.1f ms/frame | frame %u | EV %+.1f | t %.2f%s | ui %.1f "
                 "ms | %s%s%s",
                 v->m ? v->m->id : "-",
                 v->split == 1   ? " | reference right"
                 : v->split == 2 ? " | error right (log, 1e-3 blue .. 1 red)"
                                 : "",
                 v->frame_ms, v->frame_index, (double)v->exposure, (double)v->time,
                 v->playing ? " playing" : "", v->display_ms, gi_gpu_renderer(v->gpu),
                 v->status[0] ? " | " : "", v->status);
    if (!ref && v->params && v->params->count) {
        /* the parameter TAB selected, with its value */
        char *all = gi_params_to_string(v->params);
        uint32_t sel = (uint32_t)v->param_sel % v->params->count;
        const char *p = all;
        for (uint32_t k = 0; p && k < sel; k++) {
            p = strchr(p, ',');
            p = p ? p + 1 : NULL;
        }
        if (p) {
            size_t used = strlen(title);
            const char *end = strchr(p, ',');
            snprintf(title + used, sizeof title - used, " | param %.*s (TAB, PgUp/PgDn)",
                     (int)(end ? end - p : (long)strlen(p)), p);
        }
        free(all);
    }
    glfwSetWindowTitle(v->win, title);
}

/* Takes a fresh reference image into ref_tex. */
void view_poll_reference(viewer *v)
{
    uint64_t spp = 0;
    gi_image *img = view_ref_take(&v->ref, 0, &spp);
    if (!img)
        return;
    glTextureSubImage2D(v->ref_tex, 0, 0, 0, (GLsizei)img->width, (GLsizei)img->height, GL_RGBA,
                        GL_FLOAT, img->rgba);
    gi_image_free(v->ref_img); /* kept for the live error and the pixel read-out */
    v->ref_img = img;
    v->err_dirty = 1;
    v->ref_spp = spp;
    v->need_display = 1;
}

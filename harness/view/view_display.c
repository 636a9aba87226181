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
 * sRGB); in split view, right of the divider, the reference (`ref`, top
 * row first) or the method's relative luminance error against it,
 * |L - Lref| / (Lref + 0.01), on a log scale from 1e-3 (blue) to 1 (red). */
static const char display_fs[] =
    "in vec2 uv;\n"
    "out vec4 color;\n"
    "layout(binding = 0) uniform sampler2D img;\n"
    "layout(binding = 1) uniform sampler2D ref;\n"
    "uniform float scale;\n"
    "uniform int flip;\n"
    "uniform int split;\n"
    "uniform float divider;\n"
    "uniform float pixel;\n"
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
    "void main() {\n"
    "    vec2 t = flip != 0 ? vec2(uv.x, 1.0 - uv.y) : uv;\n"
    "    vec3 c = texture(img, t).rgb;\n"
    "    if (split != 0 && abs(uv.x - divider) < pixel) {\n"
    "        color = vec4(1.0);\n"
    "        return;\n"
    "    }\n"
    "    if (split != 0 && uv.x > divider) {\n"
    "        vec3 r = texture(ref, vec2(uv.x, 1.0 - uv.y)).rgb;\n"
    "        if (split == 2) {\n"
    "            float e = abs(lum(c) - lum(r)) / (lum(r) + 0.01);\n"
    "            color = vec4(ramp((log(max(e, 1e-4)) / log(10.0) + 3.0) / 3.0), 1.0);\n"
    "            return;\n"
    "        }\n"
    "        c = r;\n"
    "    }\n"
    "    c *= scale;\n"
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
    glUseProgram(v->display_prog);
    glUniform1f(glGetUniformLocation(v->display_prog, "scale"), exp2f(v->exposure));
    int ref = v->method_index < 0;
    glUniform1i(glGetUniformLocation(v->display_prog, "flip"), ref); /* images are top row first */
    glUniform1i(glGetUniformLocation(v->display_prog, "split"), ref ? 0 : v->split);
    glUniform1f(glGetUniformLocation(v->display_prog, "divider"), v->divider);
    glUniform1f(glGetUniformLocation(v->display_prog, "pixel"), fw > 0 ? 0.75f / (float)fw : 0.0f);
    glBindTextureUnit(0, ref ? v->ref_tex : v->target_tex);
    glBindTextureUnit(1, v->ref_tex);
    glBindSampler(0, 0);
    glBindSampler(1, 0);
    glBindVertexArray(v->display_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
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
    gi_image_free(img);
    v->ref_spp = spp;
    v->need_display = 1;
}

/* gibench view --script FILE: replays input, one event per line, so that
 * the viewer can be driven and tested without a person (docs/commands.md
 * "gibench view", "Scripts"). Lines:
 *     key NAME [shift|ctrl]   a key press: a letter, a digit, SPACE, ESCAPE, LEFT, RIGHT, UP,
 *                             DOWN, MINUS, EQUAL, LEFT_BRACKET, RIGHT_BRACKET, COMMA, PERIOD,
 *                             TAB, PAGE_UP, PAGE_DOWN
 *     drag X0 Y0 X1 Y1 [left|right|middle] [shift|ctrl]
 *                             press at (X0, Y0), move to (X1, Y1) in 8 steps, release
 *                             (window pixels, top left origin); with shift after key L,
 *                             the selected light is dragged
 *     press X Y [left|right|middle] [shift|ctrl]   a mouse button pressed at (X, Y)
 *     move X Y                the mouse moved to (X, Y)
 *     release X Y [left|right|middle]              the button released
 *     scroll DY [ctrl]        the mouse wheel at the mouse's place: zooms the image
 *                             (with ctrl: dollies the camera)
 *     zoom F X Y              the image zoomed by factor F about window point (X, Y)
 *     pan DX DY               the image panned by (DX, DY) window pixels
 *     panels on|off           the panels shown (the window grows by their width) or not
 *     source NAME             the image shows output, error, reference or buffer
 *     source buffer NAME      the image shows the method's debug buffer NAME
 *     split N                 split mode 0 off, 1 reference, 2 error, 3 the second method
 *     split2 ID|none          the second method (split mode 3), or none
 *     param NAME=VALUE        a parameter of the method shown set, the method made again
 *     print-state [PREFIX]    one line "state: ..." on stdout (method, split, zoom, the
 *                             live relMSE, the pixel read-out at the mouse, ...); with
 *                             PREFIX also PREFIX_method.exr and PREFIX_ref.exr, the pair
 *                             the relMSE is of
 *     method ID               show method ID (or "reference")
 *     wait N                  N frames; on the reference, N more samples per pixel
 *     wait-spp N              until the reference (shown or not) has N samples per pixel
 *     save-view FILE.json     the view, as key V saves it
 *     screenshot PREFIX       PREFIX.exr, PREFIX.png and PREFIX.json (its view)
 *     window-shot FILE.png [image]   the window as shown (split view, divider, panels) at
 *                             the next redraw; with "image" only the image region
 *     resize W H              the image region resized to W x H (the window to W x H and
 *                             the panels' width; the image is rendered again at that size)
 *     quit                    exit 0 (so does the end of the file)
 * Blank lines and lines starting with # are skipped. A line runs only once
 * the frame of the line before it has been rendered. */
#define _POSIX_C_SOURCE 200809L
#include "view.h"

#include "debug_buffer.h"

#include "gi/timer.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define REF_WAIT_S 300.0 /* a wait for reference samples gives up after this */

typedef struct key_name {
    const char *name;
    int key;
} key_name;

static const key_name keys[] = {
    {"SPACE", GLFW_KEY_SPACE},
    {"ESCAPE", GLFW_KEY_ESCAPE},
    {"LEFT", GLFW_KEY_LEFT},
    {"RIGHT", GLFW_KEY_RIGHT},
    {"UP", GLFW_KEY_UP},
    {"DOWN", GLFW_KEY_DOWN},
    {"MINUS", GLFW_KEY_MINUS},
    {"EQUAL", GLFW_KEY_EQUAL},
    {"LEFT_BRACKET", GLFW_KEY_LEFT_BRACKET},
    {"RIGHT_BRACKET", GLFW_KEY_RIGHT_BRACKET},
    {"COMMA", GLFW_KEY_COMMA},
    {"PERIOD", GLFW_KEY_PERIOD},
    {"TAB", GLFW_KEY_TAB},
    {"PAGE_UP", GLFW_KEY_PAGE_UP},
    {"PAGE_DOWN", GLFW_KEY_PAGE_DOWN},
    {"F1", GLFW_KEY_F1},
};

static int key_code(const char *name)
{
    if (strlen(name) == 1 && isalpha((unsigned char)name[0]))
        return GLFW_KEY_A + (toupper((unsigned char)name[0]) - 'A');
    if (strlen(name) == 1 && isdigit((unsigned char)name[0]))
        return GLFW_KEY_0 + (name[0] - '0');
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (!strcmp(keys[i].name, name))
            return keys[i].key;
    return -1;
}

/* "left", "right", "middle" (NULL or "": left) -> GLFW button, -1 unknown. */
static int button_code(const char *name)
{
    if (!name || !*name || !strcmp(name, "left"))
        return GLFW_MOUSE_BUTTON_LEFT;
    return !strcmp(name, "right")    ? GLFW_MOUSE_BUTTON_RIGHT
           : !strcmp(name, "middle") ? GLFW_MOUSE_BUTTON_MIDDLE
                                     : -1;
}

/* "shift", "ctrl" (or "") -> GLFW modifier bits, -1 unknown. */
static int mod_code(const char *name)
{
    if (!name || !*name)
        return 0;
    return !strcmp(name, "shift") ? GLFW_MOD_SHIFT : !strcmp(name, "ctrl") ? GLFW_MOD_CONTROL : -1;
}

static int bad(viewer *v, const char *what)
{
    return cli_fail(EXIT_USAGE, "view: %s:%d: %s", v->script_path, v->script_line, what);
}

/* The method shown by id ("reference": the path tracer); -2 when unknown. */
static int method_by_id(const viewer *v, const char *id)
{
    if (!strcmp(id, "reference"))
        return -1;
    for (uint32_t i = 0; i < v->reg->count; i++)
        if (!strcmp(v->reg->items[i].method->id, id))
            return (int)i;
    return -2;
}

/* 1 while the reference has no sample of the current view (after
 * REF_WAIT_S an error is printed and *rc set). */
static int reference_pending(viewer *v, int *rc)
{
    if (v->method_index >= 0 || view_ref_spp(&v->ref) > 0)
        return 0;
    if (v->wait_deadline == 0)
        v->wait_deadline = gi_now() + REF_WAIT_S;
    if (gi_now() > v->wait_deadline) {
        *rc = bad(v, "the reference rendered no sample in time");
        return 1;
    }
    return 1;
}

/* A script line split into its first words: the command, up to two
 * arguments, and n, how many of the three sscanf read. */
typedef struct script_line {
    const char *text, *cmd, *a, *b;
    int n;
} script_line;

static int key_line(viewer *v, const script_line *s)
{
    int k = s->n >= 2 ? key_code(s->a) : -1;
    if (k < 0)
        return bad(v, "key: unknown key name (a letter, a digit, SPACE, ESCAPE, LEFT, ...)");
    int mods = mod_code(s->n == 3 ? s->b : NULL);
    if (mods < 0)
        return bad(v, "key NAME [shift|ctrl]");
    return view_key(v, k, mods);
}

/* The events of a mouse line at x[0..4) (drag: from x[0], x[1] to x[2], x[3]). */
static void mouse_events(viewer *v, const char *cmd, const double *x, int bt, int mods)
{
    if (!strcmp(cmd, "press")) {
        view_button(v, bt, 1, x[0], x[1], mods);
    } else if (!strcmp(cmd, "move")) {
        view_cursor(v, x[0], x[1]);
    } else if (!strcmp(cmd, "release")) {
        view_cursor(v, x[0], x[1]);
        view_button(v, bt, 0, x[0], x[1], 0);
    } else {
        view_cursor(v, x[0], x[1]); /* the mouse is there before the press */
        view_button(v, bt, 1, x[0], x[1], mods);
        for (int i = 1; i <= 8; i++)
            view_cursor(v, x[0] + (x[2] - x[0]) * i / 8.0, x[1] + (x[3] - x[1]) * i / 8.0);
        view_button(v, bt, 0, x[2], x[3], 0);
    }
}

/* drag, press, move and release. */
static int mouse_line(viewer *v, const script_line *s)
{
    const char *cmd = s->cmd, *line = s->text;
    double x[4];
    char w1[16] = "", w2[16] = "", extra[16] = "";
    int need = !strcmp(cmd, "drag") ? 4 : 2, m;
    if (need == 4)
        m = sscanf(line, "%*s %lf %lf %lf %lf %15s %15s %15s", &x[0], &x[1], &x[2], &x[3], w1, w2,
                   extra);
    else
        m = sscanf(line, "%*s %lf %lf %15s %15s %15s", &x[0], &x[1], w1, w2, extra);
    /* the words after the numbers: a button, then a modifier (either may be left out) */
    int bt = button_code(w1), mods = 0;
    if (bt < 0) {
        bt = GLFW_MOUSE_BUTTON_LEFT;
        mods = mod_code(w1);
        if (w2[0])
            mods = -1;
    } else {
        mods = mod_code(w2);
    }
    int words = m - need;
    const char *usage = need == 4 ? "drag X0 Y0 X1 Y1 [left|right|middle] [shift|ctrl]"
                        : !strcmp(cmd, "press") ? "press X Y [left|right|middle] [shift|ctrl]"
                        : !strcmp(cmd, "move")  ? "move X Y"
                                                : "release X Y [left|right|middle]";
    if (m < need || extra[0] || mods < 0 || (!strcmp(cmd, "move") && words > 0) ||
        (!strcmp(cmd, "release") && (mods != 0 || words > 1)))
        return bad(v, usage);
    mouse_events(v, cmd, x, bt, mods);
    return v->exit_code;
}

static int scroll_line(viewer *v, const script_line *s)
{
    double dy;
    char mod[16] = "", extra[16] = "";
    int n = sscanf(s->text, "%*s %lf %15s %15s", &dy, mod, extra);
    int mods = mod_code(mod);
    if (n < 1 || extra[0] || (mod[0] && mods != GLFW_MOD_CONTROL))
        return bad(v, "scroll DY [ctrl]");
    view_scroll(v, dy, mods);
    return EXIT_OK;
}

static int zoom_line(viewer *v, const script_line *s)
{
    double f, x, y;
    char extra[8] = "";
    if (sscanf(s->text, "%*s %lf %lf %lf %7s", &f, &x, &y, extra) != 3 || !(f > 0) || f > 1e3)
        return bad(v, "zoom F X Y (F > 0)");
    view_zoom_at(v, (float)f, x, y);
    return EXIT_OK;
}

static int pan_line(viewer *v, const script_line *s)
{
    double dx, dy;
    char extra[8] = "";
    if (sscanf(s->text, "%*s %lf %lf %7s", &dx, &dy, extra) != 2)
        return bad(v, "pan DX DY");
    view_pan(v, dx, dy);
    return EXIT_OK;
}

static int panels_line(viewer *v, const script_line *s)
{
    if (s->n != 2 || (strcmp(s->a, "on") && strcmp(s->a, "off")))
        return bad(v, "panels on|off");
    if (v->show_panels == !strcmp(s->a, "on"))
        return EXIT_OK;
    int ww = 0, wh = 0, fw = 0, fh = 0;
    glfwGetWindowSize(v->win, &ww, &wh);
    int want = ww + (v->show_panels ? -VIEW_PANEL_W : VIEW_PANEL_W);
    view_toggle_panels(v);
    /* the X server answers asynchronously: wait for the new size (up to 5 s) */
    double until = gi_now() + 5.0;
    do {
        glfwPollEvents();
        glfwGetFramebufferSize(v->win, &fw, &fh);
    } while (fw != want && gi_now() < until);
    if (fw != want)
        return bad(v, "panels: the window did not take its new size");
    view_region_update(v);
    return EXIT_OK;
}

/* `source buffer NAME`: the method's debug buffer NAME selected. */
static int buffer_select(viewer *v, const char *name)
{
    for (uint32_t i = 0; i < view_buffer_count(v); i++)
        if (!strcmp(view_buffer_name(v, i), name)) {
            v->buffer_sel = (int)i;
            v->source = VIEW_SRC_BUFFER;
            v->need_display = 1;
            view_buffer_upload(v);
            return EXIT_OK;
        }
    char names[512];
    debug_buffer_names(v->m, names, sizeof names);
    return cli_fail(EXIT_USAGE, "view: %s:%d: %s has no debug buffer '%s' (buffers: %s)",
                    v->script_path, v->script_line, v->m ? v->m->id : "reference", name, names);
}

static int source_line(viewer *v, const script_line *s)
{
    static const char *names[VIEW_SRC_COUNT] = {"output", "error", "reference", "buffer"};
    if (s->n == 3 && !strcmp(s->a, "buffer"))
        return buffer_select(v, s->b);
    for (int i = 0; s->n == 2 && i < VIEW_SRC_COUNT; i++)
        if (!strcmp(s->a, names[i])) {
            v->source = i;
            v->need_display = 1;
            view_reference_as_needed(v);
            return EXIT_OK;
        }
    return bad(v, "source output|error|reference|buffer [NAME]");
}

static int split_line(viewer *v, const script_line *s)
{
    unsigned long k;
    if (s->n != 2 || !cli_parse_uint(s->a, 0, 3, &k))
        return bad(v, "split N (0 off, 1 reference, 2 error, 3 the second method)");
    if (k == 3 && v->second.method_index < 0)
        return bad(v, "split 3: no second method (split2 ID first)");
    v->split = (int)k;
    v->need_display = 1;
    view_reference_as_needed(v);
    return EXIT_OK;
}

static int split2_line(viewer *v, const script_line *s)
{
    int idx = s->n == 2 ? (!strcmp(s->a, "none") ? -1 : method_by_id(v, s->a)) : -2;
    if (idx < -1 || (s->n == 2 && !strcmp(s->a, "reference")))
        return bad(v, "split2: no such method (see gibench methods; or none)");
    return view_second_select(v, idx);
}

static int param_line(viewer *v, const script_line *s)
{
    if (s->n != 2)
        return bad(v, "param NAME=VALUE");
    return view_set_param(v, s->a);
}

static int print_state_line(viewer *v, const script_line *s)
{
    if (s->n > 2)
        return bad(v, "print-state [PREFIX]");
    return view_print_state(v, s->n == 2 ? s->a : NULL);
}

static int method_line(viewer *v, const script_line *s)
{
    int idx = s->n >= 2 ? method_by_id(v, s->a) : -2;
    if (idx < -1)
        return bad(v, "method: no such method (see gibench methods; or reference)");
    if (idx >= 0)
        v->last_method = idx;
    return view_select(v, idx);
}

static int wait_line(viewer *v, const script_line *s)
{
    unsigned long k;
    if (s->n != 2 || !cli_parse_uint(s->a, 1, 100000, &k))
        return bad(v, "wait N (frames, 1..100000)");
    v->wait_left = (uint32_t)k;
    v->wait_spp = view_ref_spp(&v->ref) + k;
    v->wait_deadline = gi_now() + REF_WAIT_S;
    return EXIT_OK;
}

static int wait_spp_line(viewer *v, const script_line *s)
{
    unsigned long k;
    if (s->n != 2 || !cli_parse_uint(s->a, 1, 100000, &k))
        return bad(v, "wait-spp N (samples per pixel, 1..100000)");
    if (!view_needs_reference(v))
        return bad(v, "wait-spp: the reference is not running (panels on, split 1 or 2, or "
                      "source error or reference)");
    v->wait_left = 1;
    v->wait_ref = 1;
    v->wait_spp = k;
    v->wait_deadline = gi_now() + REF_WAIT_S;
    return EXIT_OK;
}

static int save_view_line(viewer *v, const script_line *s)
{
    return s->n == 2 ? view_save(v, s->a) : bad(v, "save-view FILE.json");
}

static int screenshot_line(viewer *v, const script_line *s)
{
    return s->n == 2 ? view_screenshot(v, s->a) : bad(v, "screenshot PREFIX");
}

static int window_shot_line(viewer *v, const script_line *s)
{
    if (s->n < 2 || (s->n == 3 && strcmp(s->b, "image")))
        return bad(v, "window-shot FILE.png [image]");
    v->window_shot_image = s->n == 3;
    free(v->window_shot_buf);
    v->window_shot_buf = strdup(s->a);
    if (!v->window_shot_buf)
        return cli_fail(EXIT_RUN, "out of memory");
    v->window_shot = v->window_shot_buf;
    v->need_display = 1;
    return EXIT_OK;
}

static int resize_line(viewer *v, const script_line *s)
{
    unsigned long w, h;
    if (s->n != 3 || !cli_parse_uint(s->a, 1, GI_MAX_IMAGE_SIDE, &w) ||
        !cli_parse_uint(s->b, 1, GI_MAX_IMAGE_SIDE, &h) || !gi_image_size_ok(w, h))
        return bad(v, "resize W H (" GI_IMAGE_SIZE_RULE ")");
    unsigned long pw = v->show_panels ? VIEW_PANEL_W : 0;
    glfwSetWindowSize(v->win, (int)(w + pw), (int)h);
    /* the X server answers asynchronously: wait for the new size (up to 5 s) */
    double until = gi_now() + 5.0;
    int fw = 0, fh = 0;
    do {
        glfwPollEvents();
        glfwGetFramebufferSize(v->win, &fw, &fh);
    } while (((unsigned long)fw != w + pw || (unsigned long)fh != h) && gi_now() < until);
    if ((unsigned long)fw != w + pw || (unsigned long)fh != h)
        return bad(v, "resize: the window did not take the size");
    v->need_render = 1;
    return EXIT_OK;
}

static int quit_line(viewer *v, const script_line *s)
{
    v->quit = 1;
    return EXIT_OK;
}

static const struct {
    const char *name;
    int (*run)(viewer *v, const script_line *s);
} commands[] = {
    {"key", key_line},
    {"drag", mouse_line},
    {"press", mouse_line},
    {"move", mouse_line},
    {"release", mouse_line},
    {"scroll", scroll_line},
    {"method", method_line},
    {"wait", wait_line},
    {"wait-spp", wait_spp_line},
    {"save-view", save_view_line},
    {"screenshot", screenshot_line},
    {"window-shot", window_shot_line},
    {"resize", resize_line},
    {"zoom", zoom_line},
    {"pan", pan_line},
    {"panels", panels_line},
    {"source", source_line},
    {"split", split_line},
    {"split2", split2_line},
    {"param", param_line},
    {"print-state", print_state_line},
    {"quit", quit_line},
};

static int run_line(viewer *v, char *line)
{
    char cmd[32] = "", a[4096] = "", b[32] = "";
    int n = sscanf(line, "%31s %4095s %31s", cmd, a, b);
    if (n < 1)
        return EXIT_OK;
    script_line s = {line, cmd, a, b, n};
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(cmd, commands[i].name))
            return commands[i].run(v, &s);
    return bad(
        v, "unknown command (key, drag, press, move, release, scroll, zoom, pan, resize, "
           "panels, source, split, split2, param, method, wait, wait-spp, save-view, screenshot, "
           "window-shot, print-state, quit)");
}

int view_script_step(viewer *v)
{
    int rc = EXIT_OK;
    if (v->need_render)
        return EXIT_OK; /* the last line's frame first */
    if (v->wait_left) {
        if (v->method_index < 0 || v->wait_ref) {
            if (view_ref_spp(&v->ref) >= v->wait_spp) {
                v->wait_left = 0;
                v->wait_ref = 0;
            } else if (gi_now() > v->wait_deadline) {
                return bad(v, "wait: the reference did not reach the samples in time");
            } else {
                struct timespec ts = {0, 5000000};
                nanosleep(&ts, NULL);
            }
        } else {
            v->wait_left--;
        }
        return EXIT_OK;
    }
    char line[8192];
    long pos = ftell(v->script);
    if (!fgets(line, sizeof line, v->script)) {
        v->quit = 1;
        return EXIT_OK;
    }
    char *p = line;
    while (isspace((unsigned char)*p))
        p++;
    if (!strncmp(p, "screenshot", 10) || !strncmp(p, "save-view", 9)) {
        /* the reference shows something only after its first pass */
        if (reference_pending(v, &rc)) {
            fseek(v->script, pos, SEEK_SET);
            return rc;
        }
    }
    v->wait_deadline = 0;
    v->script_line++;
    if (*p == '#' || *p == '\0')
        return EXIT_OK;
    return run_line(v, p);
}

/* gibench view: input (docs/commands.md "gibench view"): keys, mouse buttons,
 * mouse motion and the wheel, from the window's callbacks or, in a
 * scripted run, from the script alone (view_script.c). */
#include "view.h"
#include "view_panels.h"

#include "gi/vecmath.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>

static int method_count(const viewer *v)
{
    return (int)v->reg->count;
}

/* Keys M/N (the next or previous method, then the reference, and round),
 * R (the reference and back), TAB (the next parameter) and PAGE_UP /
 * PAGE_DOWN (its value). */
static int method_key(viewer *v, int key, int mods)
{
    switch (key) {
    case GLFW_KEY_M:
    case GLFW_KEY_N: {
        /* through every plugin, then the reference, and round */
        int n = method_count(v) + 1, cur = v->method_index < 0 ? n - 1 : v->method_index;
        int back = key == GLFW_KEY_N || (mods & GLFW_MOD_SHIFT);
        int next = (cur + (back ? n - 1 : 1)) % n;
        v->param_sel = 0;
        return view_select(v, next == n - 1 ? -1 : next);
    }
    case GLFW_KEY_R:
        if (v->method_index < 0)
            return view_select(v, v->last_method < 0 ? 0 : v->last_method);
        v->last_method = v->method_index;
        return view_select(v, -1);
    case GLFW_KEY_TAB:
        v->param_sel =
            v->params && v->params->count ? (v->param_sel + 1) % (int)v->params->count : 0;
        return EXIT_OK;
    default: /* PAGE_UP, PAGE_DOWN */
        return v->method_index >= 0 ? view_step_param(v, key == GLFW_KEY_PAGE_UP ? 1 : -1)
                                    : EXIT_OK;
    }
}

/* The camera: key C (the scene's next camera), W/S, A/D, Q/E (the orbit's
 * centre forward, right, up; with Shift the selected light instead) and
 * the arrows (yaw and pitch). */
static int camera_key(viewer *v, int key, int mods)
{
    float step = 0.05f * v->dist;
    gi_vec3 eye = view_eye(v);
    gi_vec3 fwd = gi_v3_normalize(gi_v3_sub(v->center, eye));
    gi_vec3 right = gi_v3_normalize(gi_v3_cross(fwd, gi_v3(0, 1, 0)));
    switch (key) {
    case GLFW_KEY_C:
        view_camera_from_scene(
            v, v->scene->camera_count ? (v->scene_camera + 1) % (int)v->scene->camera_count : -1);
        return EXIT_OK;
    case GLFW_KEY_W:
    case GLFW_KEY_S:
        if (mods & GLFW_MOD_SHIFT)
            return view_light_move(v, gi_v3_scale(fwd, key == GLFW_KEY_W ? 1.0f : -1.0f));
        v->center = gi_v3_add(v->center, gi_v3_scale(fwd, key == GLFW_KEY_W ? step : -step));
        break;
    case GLFW_KEY_A:
    case GLFW_KEY_D:
        if (mods & GLFW_MOD_SHIFT)
            return view_light_move(v, gi_v3_scale(right, key == GLFW_KEY_D ? 1.0f : -1.0f));
        v->center = gi_v3_add(v->center, gi_v3_scale(right, key == GLFW_KEY_D ? step : -step));
        break;
    case GLFW_KEY_Q:
    case GLFW_KEY_E:
        if (mods & GLFW_MOD_SHIFT)
            return view_light_move(v, gi_v3(0, key == GLFW_KEY_E ? 1.0f : -1.0f, 0));
        v->center = gi_v3_add(v->center, gi_v3(0, key == GLFW_KEY_E ? step : -step, 0));
        break;
    case GLFW_KEY_LEFT:
    case GLFW_KEY_RIGHT:
        v->yaw += key == GLFW_KEY_LEFT ? -0.1f : 0.1f;
        break;
    default: /* UP, DOWN */
        v->pitch += key == GLFW_KEY_UP ? 0.1f : -0.1f;
        break;
    }
    view_changed(v);
    return EXIT_OK;
}

/* Keys P (a screenshot) and V (the view saved), to the next free name. */
static int save_key(viewer *v, int key)
{
    char name[4096];
    view_next_name(v, name, sizeof name);
    if (key == GLFW_KEY_P)
        return view_screenshot(v, name);
    char path[4200];
    snprintf(path, sizeof path, "%s.json", name);
    return view_save(v, path);
}

int view_key(viewer *v, int key, int mods)
{
    v->need_display = 1;
    switch (key) {
    case GLFW_KEY_ESCAPE:
        v->quit = 1;
        return EXIT_OK;
    case GLFW_KEY_M:
    case GLFW_KEY_N:
    case GLFW_KEY_R:
    case GLFW_KEY_TAB:
    case GLFW_KEY_PAGE_UP:
    case GLFW_KEY_PAGE_DOWN:
        return method_key(v, key, mods);
    case GLFW_KEY_X:
        /* off, reference, error, and the second method where one is chosen */
        v->split = (v->split + 1) % (v->second.method_index >= 0 ? 4 : 3);
        view_reference_as_needed(v);
        return EXIT_OK;
    case GLFW_KEY_Z:
        view_zoom_reset(v);
        return EXIT_OK;
    case GLFW_KEY_F1:
        return view_toggle_panels(v);
    case GLFW_KEY_SPACE:
        v->playing = !v->playing;
        v->last_tick = gi_now();
        return EXIT_OK;
    case GLFW_KEY_PERIOD:
        return view_set_time(v, v->time + 1.0f / 30.0f);
    case GLFW_KEY_COMMA:
        return view_set_time(v, fmaxf(0.0f, v->time - 1.0f / 30.0f));
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_RIGHT_BRACKET:
        v->exposure = fminf(64.0f, v->exposure + 0.5f);
        return EXIT_OK;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_LEFT_BRACKET:
        v->exposure = fmaxf(-64.0f, v->exposure - 0.5f);
        return EXIT_OK;
    case GLFW_KEY_L:
        return view_light_select(v);
    case GLFW_KEY_O:
        v->show_overlay = !v->show_overlay;
        return EXIT_OK;
    case GLFW_KEY_C:
    case GLFW_KEY_W:
    case GLFW_KEY_S:
    case GLFW_KEY_A:
    case GLFW_KEY_D:
    case GLFW_KEY_Q:
    case GLFW_KEY_E:
    case GLFW_KEY_LEFT:
    case GLFW_KEY_RIGHT:
    case GLFW_KEY_UP:
    case GLFW_KEY_DOWN:
        if (mods & GLFW_MOD_CONTROL) { /* Ctrl + arrows: the image panned by 32 pixels */
            view_pan(v,
                     key == GLFW_KEY_LEFT    ? 32
                     : key == GLFW_KEY_RIGHT ? -32
                                             : 0,
                     key == GLFW_KEY_UP     ? 32
                     : key == GLFW_KEY_DOWN ? -32
                                            : 0);
            return EXIT_OK;
        }
        return camera_key(v, key, mods);
    case GLFW_KEY_P:
    case GLFW_KEY_V:
        return save_key(v, key);
    default:
        return EXIT_OK;
    }
}

/* Mouse buttons over the image region: left drag orbits (Shift: moves the
 * object under the mouse or the selected light, Ctrl: rotates the object;
 * near the split's divider: moves the divider), right drag dollies, middle
 * drag pans the image (Ctrl + middle: pans the camera). Window points go
 * through the zoom to image points for picking (view_to_image). */
void view_button(viewer *v, int button, int press, double x, double y, int mods)
{
    if (!press && v->drag_object) {
        v->drag_object = 0;
        return;
    }
    if (press && x >= v->image_w)
        return; /* on the panels */
    if (press && button == GLFW_MOUSE_BUTTON_LEFT && (mods & (GLFW_MOD_SHIFT | GLFW_MOD_CONTROL))) {
        /* Shift: move the selected light (key L), or else the object under
         * the mouse, in the view plane; Ctrl: rotate the object */
        double ix, iy;
        view_to_image(v, x, y, &ix, &iy);
        int rc = v->sel_light >= 0 && !(mods & GLFW_MOD_CONTROL)
                     ? view_light_pick(v, ix, iy)
                     : view_pick(v, ix, iy, (mods & GLFW_MOD_CONTROL) ? 2 : 1);
        if (rc != EXIT_OK && v->script)
            v->exit_code = rc;
        v->mx = x;
        v->my = y;
        v->need_display = 1;
        return;
    }
    int ww = v->image_w;
    if (press && button == GLFW_MOUSE_BUTTON_LEFT && v->split && v->method_index >= 0 && ww > 0 &&
        fabs(x - v->divider * ww) <= 6.0) {
        v->dragging_divider = 1;
        return;
    }
    if (!press && v->dragging_divider) {
        v->dragging_divider = 0;
        return;
    }
    if (press) {
        v->drag_button = button;
        v->drag_mods = mods;
        v->mx = x;
        v->my = y;
    } else if (button == v->drag_button) {
        v->drag_button = -1;
    }
}

void view_cursor(viewer *v, double x, double y)
{
    double dx = x - v->mx, dy = y - v->my;
    v->mx = x;
    v->my = y;
    double ix, iy;
    int inside = view_to_image(v, x, y, &ix, &iy);
    int px = inside ? (int)ix : -1, py = inside ? (int)iy : -1;
    if (px != v->cursor_px || py != v->cursor_py) {
        v->cursor_px = px;
        v->cursor_py = py;
        v->need_display |= v->show_panels; /* the pixel read-out */
    }
    if (v->drag_object) {
        if (dx == 0 && dy == 0)
            return;
        int rc = view_drag_to(v, ix, iy);
        if (rc != EXIT_OK)
            v->exit_code = rc;
        return;
    }
    if (v->dragging_divider) {
        int ww = v->image_w;
        v->divider = ww > 0 ? fminf(1.0f, fmaxf(0.0f, (float)(x / ww))) : 0.5f;
        v->need_display = 1;
        return;
    }
    if (v->drag_button < 0 || (dx == 0 && dy == 0))
        return;
    if (v->drag_button == GLFW_MOUSE_BUTTON_MIDDLE && !(v->drag_mods & GLFW_MOD_CONTROL)) {
        view_pan(v, dx, dy); /* the image, not the camera */
        return;
    }
    if (v->drag_button == GLFW_MOUSE_BUTTON_LEFT) { /* orbit */
        v->yaw -= (float)dx * 0.01f;
        v->pitch += (float)dy * 0.01f;
    } else if (v->drag_button == GLFW_MOUSE_BUTTON_RIGHT) { /* dolly */
        v->dist *= expf((float)dy * 0.01f);
    } else { /* Ctrl + middle: pan the camera */
        gi_vec3 eye = view_eye(v);
        gi_vec3 fwd = gi_v3_normalize(gi_v3_sub(v->center, eye));
        gi_vec3 right = gi_v3_normalize(gi_v3_cross(fwd, gi_v3(0, 1, 0)));
        gi_vec3 up = gi_v3_cross(right, fwd);
        float s = 2.0f * v->dist * tanf(0.5f * v->yfov) / (float)v->height;
        v->center = gi_v3_add(v->center, gi_v3_add(gi_v3_scale(right, -(float)dx * s),
                                                   gi_v3_scale(up, (float)dy * s)));
    }
    view_changed(v);
}

/* The wheel zooms the image about the cursor; with Ctrl it dollies the camera. */
void view_scroll(viewer *v, double dy, int mods)
{
    if (!(mods & GLFW_MOD_CONTROL)) {
        view_zoom_at(v, powf(1.25f, (float)dy), v->mx, v->my);
        return;
    }
    v->dist *= expf(-(float)dy * 0.1f);
    view_changed(v);
}

static viewer *from(GLFWwindow *w)
{
    return glfwGetWindowUserPointer(w);
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode;
    viewer *v = from(w);
    if (v->show_panels)
        view_panels_key(w, key, scancode, action, mods);
    if (action == GLFW_RELEASE || v->script || view_panels_want_keyboard(v))
        return; /* a scripted run takes its events from the script only */
    int rc = view_key(v, key, mods);
    if (rc != EXIT_OK && v->exit_code == EXIT_OK)
        v->status_error = 1; /* interactive: keep running; the message was printed */
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    viewer *v = from(w);
    if (v->script)
        return;
    if (v->show_panels) {
        view_panels_button(w, button, action, mods);
        v->need_display = 1;
        if (action == GLFW_PRESS && view_panels_want_mouse(v))
            return;
    }
    double x, y;
    glfwGetCursorPos(w, &x, &y);
    view_button(v, button, action == GLFW_PRESS, x, y, mods);
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    viewer *v = from(w);
    if (v->script)
        return;
    if (v->show_panels && x >= v->image_w)
        v->need_display = 1; /* hovered widgets */
    view_cursor(v, x, y);
}

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
    viewer *v = from(w);
    if (v->script)
        return;
    if (v->show_panels) {
        view_panels_scroll(w, dx, dy);
        v->need_display = 1;
        if (view_panels_want_mouse(v))
            return;
    }
    int mods = glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                       glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS
                   ? GLFW_MOD_CONTROL
                   : 0;
    view_scroll(v, dy, mods);
}

static void on_size(GLFWwindow *w, int width, int height)
{
    viewer *v = from(w);
    v->win_w = width;
    v->win_h = height;
    v->need_display = 1;
}

static void on_char(GLFWwindow *w, unsigned int c)
{
    viewer *v = from(w);
    if (v->show_panels && !v->script)
        view_panels_char(w, c);
}

static void on_refresh(GLFWwindow *w)
{
    from(w)->need_display = 1;
}

void view_input_listen(viewer *v)
{
    glfwSetWindowUserPointer(v->win, v);
    glfwSetKeyCallback(v->win, on_key);
    glfwSetMouseButtonCallback(v->win, on_button);
    glfwSetCursorPosCallback(v->win, on_cursor);
    glfwSetScrollCallback(v->win, on_scroll);
    glfwSetCharCallback(v->win, on_char);
    glfwSetWindowRefreshCallback(v->win, on_refresh);
    glfwSetWindowSizeCallback(v->win, on_size);
}

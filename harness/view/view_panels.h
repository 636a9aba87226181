/* gibench view's panels beside the image (Dear ImGui; view_panels.cpp): a
 * small C interface to the C++ library. */
#ifndef GIBENCH_VIEW_PANELS_H
#define GIBENCH_VIEW_PANELS_H

#ifdef __cplusplus
extern "C" {
#endif

struct viewer;
struct GLFWwindow;

/* Dear ImGui on the window's current context; 1 on success. */
int view_panels_init(struct viewer *v);
void view_panels_free(struct viewer *v);
/* What the widgets of the last frame asked for (a method, a parameter, the
 * split...), done by the main loop after the frame was drawn. */
void view_panels_apply(struct viewer *v);
/* Whether the panels take the mouse (the cursor is over them or a widget
 * is held) or the keyboard (a text field has the focus). */
int view_panels_want_mouse(const struct viewer *v);
int view_panels_want_keyboard(const struct viewer *v);
/* The window's events, passed on to Dear ImGui. */
void view_panels_button(struct GLFWwindow *w, int button, int action, int mods);
void view_panels_scroll(struct GLFWwindow *w, double dx, double dy);
void view_panels_key(struct GLFWwindow *w, int key, int scancode, int action, int mods);
void view_panels_char(struct GLFWwindow *w, unsigned int c);

#ifdef __cplusplus
}
#endif
#endif

/* gibench view's state, shared by its files: the options and main loop
 * (cmd_view.c), the camera (view_camera.c), the method shown
 * (view_method.c), the display (view_display.c), screenshots and saved
 * views (view_save.c), input (view_input.c), moves (view_move.c), the
 * overlay (view_overlay.c) and the script player (view_script.c). */
#ifndef GIBENCH_VIEW_H
#define GIBENCH_VIEW_H

#include "cli.h"
#include "gi/gpu.h"
#include "gi/timer.h"
#include "view_file.h"
#include "view_ref.h"

#include <stdio.h>

typedef struct GLFWwindow GLFWwindow;

/* What the image viewport shows (panel "Show"; script line `source`): the
 * method's output, its error against the reference, the reference, or one
 * of the method's named debug buffers (view_buffers.c). */
enum { VIEW_SRC_OUTPUT, VIEW_SRC_ERROR, VIEW_SRC_REFERENCE, VIEW_SRC_BUFFER, VIEW_SRC_COUNT };

/* The panels' width in pixels, right of the image (view_panels.cpp). */
#define VIEW_PANEL_W 340
/* Frame times kept for the panel's graph. */
#define VIEW_FRAME_HISTORY 120

/* What one shown method owns: the first lives in the viewer's fields, the
 * second (the split's right side, view_second.c) in a view_slot that is
 * swapped into those fields while it is created, rendered or told of a
 * change, so that both go through the same code. */
typedef struct view_slot {
    int method_index;
    const gi_method *m;
    void *inst;
    gi_view last_view;
    gi_params *params;
    cli_host *host;
    int host_ready;
    char status[256];
    uint32_t frame_index;
    int stale, need_render;
    unsigned target_tex, target_fbo;
    struct gi_timer *timer;
    uint32_t timer_frames;
    int stage_count;
    double frame_ms, prepare_ms;
} view_slot;

typedef struct viewer {
    /* options */
    const char *scene_path, *start_method, *script_path, *shot_dir, *camera_name;
    const char *opt_params[VIEW_FILE_MAX_PARAMS];
    uint32_t opt_param_count;
    uint32_t width, height, seed;
    float exposure, time;
    /* window, scene, GPU */
    int glfw_ready;
    GLFWwindow *win;
    gi_scene *scene;
    gi_gpu *gpu;
    gi_gpu_scene *gs;
    gi_plugins *reg;
    char *cache_dir;
    float prepared_time; /* the scene time the GPU scene was uploaded at */
    GLuint target_tex, target_fbo, ref_tex, display_prog, display_vao;
    /* the method shown: an index into reg, or -1 for the reference */
    int method_index, last_method;
    const gi_method *m;
    void *inst;
    gi_view last_view; /* the view of the method's last render(), for its debug buffers */
    gi_params *params;
    cli_host *host; /* host_store[0]; host_store[1] while the second method is swapped in */
    cli_host host_store[2];
    int host_ready;
    char status[256]; /* what the method's caps leave out, shown in the title */
    int status_error;
    uint32_t frame_index; /* frames rendered since the last change */
    int need_render, need_display;
    double frame_ms, display_ms, prepare_ms;
    uint64_t frames_since_event;
    /* totals for the summary line at exit: method frames and window redraws */
    double sum_frame_ms, sum_display_ms;
    uint64_t n_frames, n_displays;
    /* the orbit camera: eye at dist from center, at yaw and pitch */
    gi_vec3 center;
    float yaw, pitch, dist, yfov, znear, zfar;
    int scene_camera;
    /* animation */
    int playing;
    double last_tick;
    /* mouse */
    int drag_button, drag_mods;
    double mx, my;
    /* parameter keys: the parameter selected (TAB) and the values a method
     * was last rebuilt with (PAGE_UP / PAGE_DOWN), for method kv_method */
    int param_sel;
    view_file kv;
    char kv_method[64];
    /* split view: 0 off, 1 the method left of the divider and the reference
     * right of it, 2 the method's relative error against the reference right */
    int split;        /* ... 3, the second method (second) right of the divider */
    view_slot second; /* the second method; method_index -1 when none */
    int second_swapped;
    float divider; /* the divider's place, a fraction of the window width */
    int dragging_divider;
    const char *window_shot; /* the next display also writes the window to this PNG */
    int window_shot_image;   /* ... only its image region */
    char *window_shot_buf;   /* its storage (script) */
    /* the reference */
    view_ref ref;
    uint64_t ref_spp;
    /* screenshots */
    unsigned shot_counter;
    /* the script */
    FILE *script;
    int script_line;
    uint32_t wait_left;   /* frames (or reference passes) still to wait */
    int wait_ref;         /* wait-spp: the wait is for the reference's samples */
    uint64_t wait_spp;    /* the reference's samples to reach */
    double wait_deadline; /* a wait for the reference gives up after this */
    int quit, exit_code;
    /* objects and lights moved by hand (view_move.c) */
    float (*base_trs)[10];     /* each node's translation, rotation, scale as the file has them */
    float (*moved_trs)[10];    /* the user's placement while view_nodes_swap has the file's in */
    unsigned char *node_moved; /* the nodes placed anew */
    unsigned char *file_animated; /* per object: animated by the scene file */
    struct gi_rt *pick_rt;        /* the scene placed for picking; NULL after a change */
    int sel_object, sel_light;    /* -1: none */
    int drag_object, drag_node;   /* 1 moving the picked object's (or the selected light's) node, 2
                                     rotating it; 0 none */
    double drag_x0, drag_y0;
    float drag_trs[10];
    gi_vec3 drag_origin, drag_pivot;
    float drag_scale; /* world length of a window pixel at the picked point's depth */
    int stale;        /* the method could not follow a move: it shows no image */
    int win_w, win_h; /* the window's size in screen coordinates */
    /* the overlay (view_overlay.c) and the last frame's stage times */
    struct overlay *overlay;
    int show_overlay;
    double overlay_ms,
        sum_overlay_ms; /* the overlay's part of the last redraw (display_ms), and the sum */
    double last_progress;
    void (*host_progress)(const gi_host *h, const char *task, float fraction); /* cli_host's own */
    gi_timer *timer; /* the method's stages, for the overlay's chart */
    uint32_t timer_frames;
    char stage_name[GI_TIMER_MAX_STAGES][GI_TIMER_NAME_MAX];
    double stage_ms[GI_TIMER_MAX_STAGES];
    int stage_count;
    /* the panels (view_panels.cpp): shown or not, and their state */
    int show_panels;
    struct view_panels *panels;
    double frame_hist[VIEW_FRAME_HISTORY];
    uint32_t frame_hist_n;
    /* zoom and pan of the image (view_zoom.c): a window pixel (x, y) of the
     * image region shows image pixel (pan_x + x / zoom, pan_y + y / zoom) */
    float zoom, pan_x, pan_y;
    int image_w, image_h; /* the image region's size, window pixels */
    int source;           /* VIEW_SRC_* */
    int buffer_sel;       /* the debug buffer shown (VIEW_SRC_BUFFER) */
    unsigned buf_tex;     /* its image (top row first); black when there is none */
    /* the live error (view_error.c): the reference image last taken, the
     * method's relMSE against it (NaN: none yet), and when it is out of date */
    struct gi_image *ref_img;
    uint64_t err_spp;
    double relmse, err_time;
    int err_dirty;
    /* the pixel read-out: the image pixel under the cursor (-1: none) */
    int cursor_px, cursor_py;
    float px_method[3], px_ref[3], px_err;
    int px_valid;
} viewer;

/* Input, as the window's callbacks and the script deliver it. Keys are
 * GLFW key codes; they return EXIT_OK or an exit code after printing why. */
int view_key(viewer *v, int key, int mods);
void view_button(viewer *v, int button, int press, double x, double y, int mods);
void view_cursor(viewer *v, double x, double y);
void view_scroll(viewer *v, double dy, int mods);
/* Key F1: the panels shown or hidden; the window grows or shrinks by
 * their width, so that the image keeps its size. */
int view_toggle_panels(viewer *v);
/* Shows method `index` (-1: the reference). */
int view_select(viewer *v, int index);
int view_screenshot(viewer *v, const char *prefix);
int view_save(const viewer *v, const char *path);
void view_describe(const viewer *v, view_file *f);
/* The camera moved or the scene changed: accumulation starts again. */
void view_changed(viewer *v);
gi_vec3 view_eye(const viewer *v);
gi_camera_frame view_camera(const viewer *v);
void view_camera_from_scene(viewer *v, int index);

/* The reference runs while it is shown (alone, in split modes 1 and 2, as
 * the source error or reference) or the panels show the live error; it
 * idles otherwise. */
int view_needs_reference(const viewer *v);
void view_reference_as_needed(viewer *v);

/* The method shown made again (create + prepare) with `params` ("k=v,...",
 * taken and freed; NULL: out of memory), the selected parameter kept. */
int view_remake(viewer *v, char *params);

/* The method shown (view_method.c): unloaded (none shown), a parameter
 * stepped (keys PAGE_UP and PAGE_DOWN), a frame rendered, the animation
 * at time t; they return EXIT_OK or an exit code after printing why. */
void view_unload_method(viewer *v);
int view_step_param(viewer *v, int dir);
int view_render_method(viewer *v);
int view_set_time(viewer *v, float t);

/* The display (view_display.c): its shader made once the context is
 * current, the window redrawn, the reference's newest image taken in. */
int view_build_display(viewer *v);
/* The debug buffer buffer_sel of the method shown into buf_tex (black when
 * it has none). */
void view_buffer_upload(viewer *v);
void view_display(viewer *v);
void view_poll_reference(viewer *v);

/* The next free name for keys P and V (view_save.c). */
void view_next_name(viewer *v, char *out, size_t size);

/* The window's input callbacks, which deliver to the functions above
 * (view_input.c). */
void view_input_listen(viewer *v);

/* Moving objects and lights (view_move.c). */
int view_move_init(viewer *v);
void view_move_free(viewer *v);
int view_moved_any(const viewer *v);
/* The file's placement of the moved nodes in the scene (base 1) or the
 * user's back (base 0), the GPU scene placed to match; the reference is
 * held (the caller restarts it with view_changed). */
void view_nodes_swap(viewer *v, int base);
void view_describe_nodes(const viewer *v, view_file *f);
/* The method's update() for the nodes flagged in `moved`, or a message
 * on screen and no image where it cannot follow. */
int view_tell_method(viewer *v, const unsigned char *moved);
/* The method can no longer show a true image: black until it is made again. */
void view_go_stale(viewer *v);
/* Picks the object under window point (x, y) and starts moving (mode 1)
 * or rotating (mode 2) it. */
int view_pick(viewer *v, double x, double y, int mode);
int view_drag_to(viewer *v, double x, double y);
/* Key L: the next punctual light; Shift+W/A/S/D/Q/E: moves it along dir;
 * Shift+drag (view_light_pick, then view_drag_to): moves it in the plane
 * facing the camera through it, following the mouse. */
int view_light_select(viewer *v);
int view_light_pick(viewer *v, double x, double y);
int view_light_move(viewer *v, gi_vec3 dir);

/* The overlay (view_overlay.c): made once the context is current, drawn
 * over the image on each redraw (key O shows or hides it); the progress
 * callback draws a bar while a method precomputes. */
int view_overlay_init(viewer *v);
void view_overlay_free(viewer *v);
void view_overlay_draw(viewer *v, int fw, int fh);
void view_overlay_progress(const gi_host *h, const char *task, float fraction);
void view_overlay_progress_owner(viewer *v);

/* The panels (view_panels.h) drawn right of the image. */
void view_panels_draw(viewer *v);

/* ASan build only: keeps Mesa's DRI driver loaded to the end, so that
 * LeakSanitizer's report names it (view_lsan.c); nothing otherwise. */
void view_pin_gl_driver(void);

/* The second method of the split (view_second.c): shown right of the
 * divider in split mode 3, rendered with the same view. index -1 unloads it. */
int view_second_select(viewer *v, int index);
void view_second_unload(viewer *v);
int view_second_wants_frame(const viewer *v);
int view_second_render(viewer *v);
int view_second_set_time(viewer *v);
int view_second_tell(viewer *v, const unsigned char *moved);
void view_second_changed(viewer *v);
void view_slot_swap(viewer *v);

/* Zoom and pan (view_zoom.c). The image region of the window (left of the
 * panels), window point -> image pixel (continuous, top left origin; 0
 * outside the image), zoom by factor f about window point (x, y), pan by
 * window pixels, reset. */
void view_region_update(viewer *v);
int view_to_image(const viewer *v, double x, double y, double *ix, double *iy);
void view_zoom_at(viewer *v, float f, double x, double y);
void view_pan(viewer *v, double dx, double dy);
void view_zoom_reset(viewer *v);

/* The live error and the pixel read-out (view_error.c): the method's relMSE
 * against the reference taken last, as `gibench diff` computes it, brought
 * up to date (`force`: now; else at most four times a second); the read-out
 * of image pixel (x, y); the state line of script line print-state, with
 * PREFIX_method.exr and PREFIX_ref.exr, the pair the relMSE is of, when
 * prefix is not NULL. */
void view_error_update(viewer *v, int force);
void view_pixel_readout(viewer *v, int x, int y);
int view_print_state(viewer *v, const char *prefix);
/* Sets parameter "k=v" of the method shown and makes it again (script
 * line param, the panels' sliders). */
int view_set_param(viewer *v, const char *kv);

/* Debug buffers (view_buffers.c): the names the method shown offers, and
 * one fetched as a float RGB image (top row first). Empty until the
 * method ABI offers them. */
uint32_t view_buffer_count(const viewer *v);
const char *view_buffer_name(const viewer *v, uint32_t i);
struct gi_image *view_buffer_fetch(viewer *v, uint32_t i);

/* Runs the script's next line when the previous one has taken effect;
 * sets quit at its end. EXIT_OK, or an exit code after printing why. */
int view_script_step(viewer *v);

#endif

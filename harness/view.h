/* gibench view's state, shared by the window code (cmd_view.c) and the
 * script player (view_script.c). */
#ifndef GIBENCH_VIEW_H
#define GIBENCH_VIEW_H

#include "cli.h"
#include "gi/gpu.h"
#include "view_file.h"
#include "view_ref.h"

#include <stdio.h>

typedef struct GLFWwindow GLFWwindow;

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
    gi_params *params;
    cli_host host;
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
    int drag_button;
    double mx, my;
    /* parameter keys: the parameter selected (TAB) and the values a method
     * was last rebuilt with (PAGE_UP / PAGE_DOWN), for method kv_method */
    int param_sel;
    view_file kv;
    char kv_method[64];
    /* split view: 0 off, 1 the method left of the divider and the reference
     * right of it, 2 the method's relative error against the reference right */
    int split;
    float divider;        /* the divider's place, a fraction of the window width */
    int dragging_divider;
    const char *window_shot; /* the next display also writes the window to this PNG */
    char *window_shot_buf;   /* its storage (script) */
    /* the reference */
    view_ref ref;
    uint64_t ref_spp;
    /* screenshots */
    unsigned shot_counter;
    /* the script */
    FILE *script;
    int script_line;
    uint32_t wait_left;    /* frames (or reference passes) still to wait */
    uint64_t wait_spp;     /* the reference's samples to reach */
    double wait_deadline;  /* a wait for the reference gives up after this */
    int quit, exit_code;
} viewer;

/* Input, as the window's callbacks and the script deliver it. Keys are
 * GLFW key codes; they return EXIT_OK or an exit code after printing why. */
int view_key(viewer *v, int key, int mods);
void view_button(viewer *v, int button, int press, double x, double y);
void view_cursor(viewer *v, double x, double y);
void view_scroll(viewer *v, double dy);
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

/* Runs the script's next line when the previous one has taken effect;
 * sets quit at its end. EXIT_OK, or an exit code after printing why. */
int view_script_step(viewer *v);

#endif

/* libgibench: gibench in one process, for scripting (the Python package
 * python/gibench is a thin module over it; docs/python.md).
 *
 * One process keeps one GL context (created on first use, on the calling
 * thread; every later call must come from that thread), the installed
 * method plugins, and per gibench_scene one loaded scene with its GPU
 * upload. A render is the same code as gibench render (the render loop of
 * harness/run/render_loop.h): with the same options it makes the same
 * image bit for bit.
 *
 *     gi_error err;
 *     gibench_scene *s = NULL;
 *     gibench_scene_open("scenes/cornell_box.gltf", &s, &err);
 *     gibench_render_opts o = gibench_render_defaults();
 *     o.method = "direct"; o.width = o.height = 64;
 *     float *rgb = malloc(sizeof(float) * 3 * 64 * 64);
 *     char *timings = NULL;
 *     if (gibench_render(s, &o, rgb, &timings, &err) != GI_OK)
 *         fprintf(stderr, "%s\n", err.text);  // the CLI's one-line message
 *     gibench_free(timings);
 *     gibench_scene_close(s);
 *
 * Errors follow docs/STYLE.md: a gi_result, the message in *err (the line
 * gibench prints after "gibench: "). GI_ERR_INVALID_ARGUMENT and
 * GI_ERR_UNSUPPORTED are bad usage or input (the CLI's exit status 2),
 * anything else a failure while running (exit status 1).
 *
 * Strings returned through char ** are JSON texts owned by the caller and
 * released with gibench_free. Images are rows top to bottom as gibench
 * writes them to files, RGB float32 interleaved.
 */
#ifndef GI_GIBENCH_H
#define GI_GIBENCH_H

#include "gi/common.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gibench_scene gibench_scene;

/* The options of gibench render, with its defaults (gibench_render_defaults). */
typedef struct gibench_render_opts {
    const char *method;        /* required: a method id (gibench methods) */
    const char *camera;        /* a camera name or "#k"; NULL for the first */
    const char *const *params; /* "k=v" as --param takes them */
    uint32_t param_count;
    uint32_t width, height;  /* 256x256 */
    uint32_t frames, warmup; /* 1, 0 */
    uint32_t seed;           /* 1 */
    float time;              /* 0: the scene's time in seconds */
    float exposure;          /* 0 stops (only reaches the method's view) */
    int no_cache;            /* 1: precompute afresh and keep nothing on disk */
    int fresh;               /* 1: a new instance even where gibench_render keeps one */
} gibench_render_opts;

gibench_render_opts gibench_render_defaults(void);

/* The installed methods as gibench methods --json prints them. */
gi_result gibench_methods_json(char **out, gi_error *err);

/* Loads a scene (glTF) and uploads it to the process's GL context into
 * *out; a file that does not load is GI_ERR_INVALID_ARGUMENT. */
gi_result gibench_scene_open(const char *path, gibench_scene **out, gi_error *err);
void gibench_scene_close(gibench_scene *s);
/* {"path", "cameras": [names], "duration", "objects", "lights"}. */
gi_result gibench_scene_info_json(const gibench_scene *s, char **out, gi_error *err);

/* One render, as gibench render --scene S --method M ... --out: the last
 * frame's RGB into rgb (width * height * 3 floats) and, when timings is
 * not NULL, the run's timings ({"method", "params", "prepare": {stage:
 * stats}, "render": {...}, "stats": {...}, "reused", ...}).
 *
 * The scene keeps the instance of its last render: the next render with
 * the same method, parameters, size, time, camera and no_cache (seed,
 * frames, warmup and exposure may differ), and no node moved since, uses
 * it again from frame 0 instead of creating and preparing a new one
 * ("reused": true; "prepare" then holds the stats of the prepare it had).
 * The image is the one a new instance makes, bit for bit (a method starts
 * its accumulation and sequences again at frame_index 0; tests/python
 * checks every method). o->fresh = 1 makes a new instance; a failed
 * render keeps none; gibench_scene_close releases it. */
gi_result gibench_render(gibench_scene *s, const gibench_render_opts *o, float *rgb, char **timings,
                         gi_error *err);

/* A method instance that stays alive across calls (an animation, or more
 * frames of a still view): created and prepared once with o (o->frames
 * unused), then any number of update and render calls. */
typedef struct gibench_method gibench_method;
gi_result gibench_method_open(gibench_scene *s, const gibench_render_opts *o, gibench_method **out,
                              gi_error *err);
/* The scene moved to `time` (its animation: transforms, lights, camera,
 * deformation), and, when camera is not NULL, another camera; the method's
 * update() told what that changes, as gibench render --animate tells it
 * between frames. The next frame is frame_index 0 again. */
gi_result gibench_method_update(gibench_method *m, float time, const char *camera, gi_error *err);
/* One node placed by hand, as gibench view moves it: node is its name or
 * its index in decimal; the parts whose has_ flag is 0 keep their values. */
typedef struct gibench_node_move {
    const char *node;
    int has_translation, has_rotation, has_scale;
    float translation[3], rotation[4]; /* rotation: a unit quaternion x y z w */
    float scale[3];
} gibench_node_move;
/* The nodes placed so (their objects and lights with them) and the method
 * told what that changes, as gibench render --view VIEW does for a view's
 * moved nodes: objects that were not moving before are marked moving and
 * the instance is created and prepared again first (as gibench view
 * remakes it). The scene keeps the placements. The next frame is
 * frame_index 0 again. */
gi_result gibench_method_move(gibench_method *m, const gibench_node_move *moves, uint32_t count,
                              gi_error *err);
/* `frames` more frames (frame_index counting on from the last update) and
 * the last one's RGB into rgb, timings as for gibench_render. */
gi_result gibench_method_render(gibench_method *m, uint32_t frames, float *rgb, char **timings,
                                gi_error *err);
/* Debug buffer `name` (plugin ABI 1.3, `gibench render --buffer`) of the
 * instance after its last frame, as gibench_image_read returns an image
 * (RGBA, row 0 the top row; free *rgba with gibench_free): the view's size
 * for a screen-space buffer, its own otherwise. An unknown name
 * (GI_ERR_INVALID_ARGUMENT) lists the method's buffers; so does a call
 * before a frame was rendered since the last update. */
gi_result gibench_method_buffer(gibench_method *m, const char *name, float **rgba, uint32_t *width,
                                uint32_t *height, gi_error *err);
/* The instance destroyed; the scene must outlive it. */
void gibench_method_close(gibench_method *m);

/* The options of gibench reference, with its defaults
 * (gibench_reference_defaults): 256x256, seed 1, unlimited bounces. With
 * none of spp, seconds, target_se and target_relmse, 256 samples per pixel. */
typedef struct gibench_reference_opts {
    const char *camera; /* a camera name or "#k"; NULL for the first */
    uint32_t width, height;
    uint64_t spp;         /* --spp: stop at this many samples per pixel (0: no limit) */
    double seconds;       /* --time: stop after this long (0: none) */
    double target_se;     /* --target-se: stop at this mean relative standard error */
    int max_bounces;      /* --max-bounces; -1 unlimited */
    uint32_t seed;        /* --seed */
    uint32_t threads;     /* --threads; 0 every core */
    float time;           /* --time-of-scene */
    int pixel_center;     /* --pixel center (1) or box (0) */
    int robust_traversal; /* --traversal robust (1) or fast (0) */
    double target_relmse; /* --target-relmse: stop at this estimated relMSE of the mean */
} gibench_reference_opts;

gibench_reference_opts gibench_reference_defaults(void);

/* The path-traced reference as gibench reference renders it (the same
 * progressive loop, gi_ref_progressive): the mean into mean and, when not
 * NULL, the variance of the mean into variance (width * height * 3 each);
 * stats: {"spp", "stop", "render_seconds", "mean_rel_se", "relmse_estimate",
 * ...}. */
gi_result gibench_reference(gibench_scene *s, const gibench_reference_opts *o, float *mean,
                            float *variance, char **stats, gi_error *err);

/* gibench diff of test against ref (RGB, width * height * 3 each): the
 * metrics under gibench diff --json's names into *out; when not NULL, the
 * per-pixel relative error and FLIP maps (width * height each). flip_ppd 0
 * is FLIP's default. */
gi_result gibench_metrics(const float *test, const float *ref, uint32_t width, uint32_t height,
                          float exposure, float flip_ppd, float *relerr_map, float *flip_map,
                          char **out, gi_error *err);

/* Reads an image file (EXR, PFM, PNG) with gibench's reader: *rgba holds
 * width * height * 4 floats (gibench_free). */
gi_result gibench_image_read(const char *path, float **rgba, uint32_t *width, uint32_t *height,
                             gi_error *err);
/* Reads layer `layer` of an EXR (e.g. "variance", which gibench reference
 * writes beside the mean: channels variance.R/G/B) as gibench_image_read
 * reads the image; a file without that layer is GI_ERR_IO. */
gi_result gibench_image_read_layer(const char *path, const char *layer, float **rgba,
                                   uint32_t *width, uint32_t *height, gi_error *err);
/* Writes an RGB image (alpha 1) as gibench render writes its --out:
 * EXR/PFM linear, PNG with the exposure in stops and sRGB. */
gi_result gibench_image_write(const char *path, const float *rgb, uint32_t width, uint32_t height,
                              float exposure, gi_error *err);

void gibench_free(void *p);

#ifdef __cplusplus
}
#endif

#endif

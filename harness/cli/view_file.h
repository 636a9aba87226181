/* A saved view of gibench view ("save view", docs/commands.md "gibench view"):
 * scene, camera, time, method and its parameters, image size, exposure and
 * the frames accumulated, as a small JSON file that `gibench render --view
 * FILE` reproduces in batch. */
#ifndef GIBENCH_VIEW_FILE_H
#define GIBENCH_VIEW_FILE_H

#include "gi/scene.h"

#include <stddef.h>
#include <stdint.h>

#define VIEW_FILE_MAX_PARAMS 64
#define VIEW_FILE_MAX_NODES 256

/* A node of the scene placed where the viewer's user put it (an object
 * dragged or rotated, a light moved): its local translation, rotation
 * (quaternion x y z w) and scale replace the file's. */
typedef struct view_node {
    uint32_t node;  /* index into gi_scene.nodes */
    char name[128]; /* the node's name ("" when it has none), checked on load */
    float translation[3], rotation[4], scale[3];
} view_node;

typedef struct view_file {
    char scene[4096];
    char method[64];                    /* a method id, or "reference" for the path tracer */
    char *params[VIEW_FILE_MAX_PARAMS]; /* "k=v", malloc'd */
    uint32_t param_count;
    uint32_t width, height;
    uint32_t frames; /* frames accumulated since the last change (progressive methods) */
    uint32_t seed;
    float time, exposure;
    gi_vec3 eye, forward, up; /* the camera: eye looking along forward, up roughly +Y */
    float yfov, znear, zfar;
    view_node nodes[VIEW_FILE_MAX_NODES]; /* the moved nodes, in node order */
    uint32_t node_count;
} view_file;

/* Sets params from gi_params_to_string's canonical "a=1,b=x" text (replacing any). */
int view_file_set_params(view_file *v, const char *canonical);
/* The camera frame the view describes. */
gi_camera_frame view_file_camera(const view_file *v);
/* Writes the view as JSON; 1 on success, else 0 with why. */
int view_file_write(const char *path, const view_file *v, char *why, size_t why_size);
/* Reads and checks a view (finite camera, sizes gi_image_size_ok, known keys);
 * 1 on success, else 0 with a one-line why. Free with view_file_free. */
int view_file_read(const char *path, view_file *v, char *why, size_t why_size);
void view_file_free(view_file *v);

/* The moved nodes against a loaded scene: each index in range, its name
 * the scene's, not animated by the file (a moved node must hold still);
 * 1, else 0 with a one-line why. */
int view_file_check_nodes(const view_file *v, const gi_scene *s, char *why, size_t why_size);
/* Marks the objects under node (the node itself or a descendant) as moving
 * (gi_object.animated), so that a method prepared afterwards treats them
 * as the rigid motion they are; 1 when some object was not marked yet. */
int view_scene_mark_moving(gi_scene *s, uint32_t node);
/* Whether node `node` or one of its ancestors is in `moved` (node_count flags). */
int view_scene_under(const gi_scene *s, int node, const unsigned char *moved);
/* What a method's update is told after the nodes flagged in `moved` were
 * placed anew: GI_CHANGED_TRANSFORMS and moved_objects for the objects
 * under them, GI_CHANGED_LIGHTS when an emitting object or a punctual
 * light is among them. */
void view_scene_changes(const gi_scene *s, const unsigned char *moved, uint32_t *flags,
                        uint64_t *moved_objects);
/* A camera named "view:FILE.json" (render --camera, reference --camera, a
 * study's "camera"): the saved view's camera and moved nodes, nothing else
 * of it. 0 when `camera` is not such a name; 1 with *v read; -1 with why. */
int view_camera_read(const char *camera, view_file *v, char *why, size_t why_size);
/* Writes the view's node placements into the scene (after view_file_check_nodes). */
void view_file_apply_nodes(const view_file *v, gi_scene *s);

#endif

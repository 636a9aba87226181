/* gibench view: objects picked with the mouse and moved or rotated, lights
 * selected with key L and moved with keys or dragged with the mouse
 * (docs/commands.md "gibench view", "Moving objects and lights").
 * A move writes the node's translation and rotation into the viewer's own
 * copy of the scene, places the GPU scene again (gi_gpu_scene_set_time, as
 * the animation does) and tells the method through update() with the
 * GI_CHANGED_* flags of what moved. A saved view records the moved nodes;
 * `gibench render --view` places them the same way. */
#define _POSIX_C_SOURCE 200809L
#include "view.h"

#include "gi/log.h"
#include "gi/raytrace.h"
#include "gi/vecmath.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Node TRS as 10 floats: translation 3, rotation 4 (x y z w), scale 3. */
static void get_trs(const gi_node *n, float trs[10])
{
    memcpy(trs, n->translation, 3 * sizeof(float));
    memcpy(trs + 3, n->rotation, 4 * sizeof(float));
    memcpy(trs + 7, n->scale, 3 * sizeof(float));
}

static void set_trs(gi_node *n, const float trs[10])
{
    memcpy(n->translation, trs, 3 * sizeof(float));
    memcpy(n->rotation, trs + 3, 4 * sizeof(float));
    memcpy(n->scale, trs + 7, 3 * sizeof(float));
}

int view_move_init(viewer *v)
{
    gi_scene *s = v->scene;
    v->base_trs = calloc(s->node_count ? s->node_count : 1, sizeof *v->base_trs);
    v->node_moved = calloc(s->node_count ? s->node_count : 1, 1);
    v->moved_trs = calloc(s->node_count ? s->node_count : 1, sizeof *v->moved_trs);
    v->file_animated = calloc(s->object_count ? s->object_count : 1, 1);
    if (!v->base_trs || !v->moved_trs || !v->node_moved || !v->file_animated)
        return 0;
    for (uint32_t i = 0; i < s->node_count; i++)
        get_trs(&s->nodes[i], v->base_trs[i]);
    for (uint32_t o = 0; o < s->object_count; o++)
        v->file_animated[o] = (unsigned char)(s->objects[o].animated != 0);
    v->sel_object = -1;
    v->sel_light = -1;
    return 1;
}

void view_move_free(viewer *v)
{
    gi_rt_free(v->pick_rt);
    v->pick_rt = NULL;
    free(v->base_trs);
    free(v->moved_trs);
    free(v->node_moved);
    free(v->file_animated);
    v->base_trs = NULL;
    v->moved_trs = NULL;
    v->node_moved = NULL;
    v->file_animated = NULL;
}

int view_moved_any(const viewer *v)
{
    for (uint32_t i = 0; v->node_moved && i < v->scene->node_count; i++)
        if (v->node_moved[i])
            return 1;
    return 0;
}

void view_nodes_swap(viewer *v, int base)
{
    view_ref_hold(&v->ref);
    for (uint32_t i = 0; i < v->scene->node_count; i++) {
        if (!v->node_moved[i])
            continue;
        /* v->moved_trs keeps the user's placement while the base one is in */
        if (base) {
            get_trs(&v->scene->nodes[i], v->moved_trs[i]);
            set_trs(&v->scene->nodes[i], v->base_trs[i]);
        } else {
            set_trs(&v->scene->nodes[i], v->moved_trs[i]);
        }
    }
    gi_gpu_scene_set_time(v->gs, v->time);
}

void view_describe_nodes(const viewer *v, view_file *f)
{
    f->node_count = 0;
    for (uint32_t i = 0; i < v->scene->node_count && f->node_count < VIEW_FILE_MAX_NODES; i++) {
        if (!v->node_moved[i])
            continue;
        view_node *n = &f->nodes[f->node_count++];
        const gi_node *d = &v->scene->nodes[i];
        n->node = i;
        snprintf(n->name, sizeof n->name, "%s", d->name ? d->name : "");
        memcpy(n->translation, d->translation, sizeof n->translation);
        memcpy(n->rotation, d->rotation, sizeof n->rotation);
        memcpy(n->scale, d->scale, sizeof n->scale);
    }
}

/* The method told of the nodes moved (the flags in `moved`): update(), or,
 * where its caps cannot follow, no image and a message on screen. */
int view_tell_method(viewer *v, const unsigned char *moved)
{
    if (!v->inst || v->stale)
        return EXIT_OK; /* a stale method stays so (and said so once) until it is made again */
    gi_changes ch = {0, v->time, 0};
    view_scene_changes(v->scene, moved, &ch.flags, &ch.moved_objects);
    if ((ch.flags & GI_CHANGED_TRANSFORMS) && !(v->m->caps & GI_CAP_RIGID_MOTION)) {
        snprintf(v->status, sizeof v->status,
                 "%s cannot follow moving objects (no GI_CAP_RIGID_MOTION): no image", v->m->id);
        view_go_stale(v);
        gi_log(GI_LOG_WARN, "view: %s", v->status);
        return EXIT_OK;
    }
    gi_result res = v->m->update(v->inst, v->gs, &ch);
    if (res != GI_OK) {
        const char *msg = v->m->last_error(v->inst);
        snprintf(v->status, sizeof v->status, "%s cannot follow the move (%s%s%s): no image",
                 v->m->id, gi_result_name(res), msg && *msg ? ": " : "", msg ? msg : "");
        view_go_stale(v);
        gi_log(GI_LOG_WARN, "view: %s", v->status);
    }
    return EXIT_OK;
}

/* Node `node` placed at trs: the scene, the GPU scene and the method. */
static int place_node(viewer *v, int node, const float trs[10])
{
    view_ref_hold(&v->ref);
    set_trs(&v->scene->nodes[node], trs);
    v->node_moved[node] = 1;
    gi_gpu_scene_set_time(v->gs, v->time);
    gi_rt_free(v->pick_rt);
    v->pick_rt = NULL;
    unsigned char *one = calloc(v->scene->node_count, 1);
    if (!one)
        return cli_fail(EXIT_RUN, "out of memory");
    one[node] = 1;
    int rc = view_tell_method(v, one);
    if (rc == EXIT_OK)
        rc = view_second_tell(v, one);
    free(one);
    view_changed(v);
    return rc;
}

/* The world transform of node's parent (identity for a root). */
static void parent_world(const viewer *v, int node, float out[16])
{
    int p = v->scene->nodes[node].parent;
    if (p >= 0)
        gi_scene_node_transform(v->scene, p, v->time, out);
    else
        gi_mat4_identity(out);
}

/* The camera ray through image point (x, y) (pixels, top left origin; the
 * input maps window points through the zoom to image points, view_zoom.c). */
static void window_ray(const viewer *v, double x, double y, gi_vec3 *o, gi_vec3 *d)
{
    int ww = (int)v->width, wh = (int)v->height;
    gi_camera_frame cf = view_camera(v);
    float th = tanf(0.5f * cf.yfov), aspect = (float)v->width / (float)v->height;
    float nx = 2.0f * (float)x / (float)(ww > 0 ? ww : 1) - 1.0f,
          ny = 1.0f - 2.0f * (float)y / (float)(wh > 0 ? wh : 1);
    *o = cf.eye;
    *d =
        gi_v3_normalize(gi_mat4_dir(cf.world_from_camera, gi_v3(nx * th * aspect, ny * th, -1.0f)));
}

int view_pick(viewer *v, double x, double y, int mode)
{
    if (!v->pick_rt) {
        gi_error err;
        if (gi_rt_create(v->scene, v->time, &v->pick_rt, &err) != GI_OK) {
            v->pick_rt = NULL;
            return cli_fail(EXIT_RUN, "view: picking: %s", err.text);
        }
    }
    gi_vec3 o, d;
    window_ray(v, x, y, &o, &d);
    gi_rt_hit hit;
    if (!gi_rt_intersect(v->pick_rt, o, d, 0.0f, INFINITY, &hit)) {
        v->sel_object = -1;
        snprintf(v->status, sizeof v->status, "nothing under the mouse");
        return EXIT_OK;
    }
    int obj = (int)hit.object;
    const gi_object *ob = &v->scene->objects[obj];
    v->sel_object = obj;
    if (v->file_animated[obj]) {
        snprintf(v->status, sizeof v->status,
                 "%s follows the scene's animation: it cannot be moved by hand",
                 ob->name ? ob->name : "the object");
        return EXIT_OK;
    }
    int node = ob->node;
    gi_camera_frame cf = view_camera(v);
    float depth = gi_v3_dot(gi_v3_sub(hit.position, cf.eye), gi_v3_normalize(cf.forward));
    if (gi_log_get_level() >= GI_LOG_WARN)
        printf("view: picked object %d '%s' at depth %.4g (%s)\n", obj, ob->name ? ob->name : "",
               (double)depth, mode == 2 ? "rotate" : "move");
    /* the objects under the node become moving ones: the method is made
     * again so that it treats them so from its prepare (as a scene
     * animating them would have it) */
    if (view_scene_mark_moving(v->scene, (uint32_t)node) && v->method_index >= 0) {
        int sel = v->param_sel;
        int rc = view_select(v, v->method_index);
        v->param_sel = sel;
        if (rc != EXIT_OK) {
            /* the method cannot be made with this object moving (its
             * message is printed): no image, and it says so */
            view_go_stale(v);
            snprintf(v->status, sizeof v->status,
                     "%s cannot be made with '%s' moving: no image (M: another method)",
                     v->m ? v->m->id : "the method", ob->name ? ob->name : "the object");
            gi_log(GI_LOG_WARN, "view: %s", v->status);
            return EXIT_OK;
        }
    }
    float world[16];
    gi_scene_node_transform(v->scene, node, v->time, world);
    v->drag_object = mode;
    v->drag_node = node;
    v->drag_x0 = x;
    v->drag_y0 = y;
    get_trs(&v->scene->nodes[node], v->drag_trs);
    v->drag_origin = gi_v3(world[12], world[13], world[14]);
    v->drag_scale = 2.0f * depth * tanf(0.5f * cf.yfov) / (float)(v->height > 0 ? v->height : 1);
    /* the pivot of a rotation: the centre of the object's bounds */
    const float *b = ob->local_bounds;
    float ow[16];
    gi_scene_object_transform(v->scene, (uint32_t)obj, v->time, ow);
    v->drag_pivot =
        gi_mat4_point(ow, gi_v3(0.5f * (b[0] + b[3]), 0.5f * (b[1] + b[4]), 0.5f * (b[2] + b[5])));
    v->status[0] = '\0';
    return EXIT_OK;
}

/* Quaternion product a b (x y z w). */
static void quat_mul(float out[4], const float a[4], const float b[4])
{
    float r[4] = {a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
                  a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
                  a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
                  a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]};
    memcpy(out, r, sizeof r);
}

int view_drag_to(viewer *v, double x, double y)
{
    int node = v->drag_node;
    float trs[10], pw[16], pinv[16];
    memcpy(trs, v->drag_trs, sizeof trs);
    parent_world(v, node, pw);
    if (!gi_mat4_invert(pinv, pw))
        gi_mat4_identity(pinv);
    float dx = (float)(x - v->drag_x0), dy = (float)(y - v->drag_y0);
    gi_vec3 origin;
    if (v->drag_object == 1) {
        /* in the view plane, at the picked point's depth: the object follows the mouse */
        gi_camera_frame cf = view_camera(v);
        gi_vec3 right = gi_v3_load(cf.world_from_camera), up = gi_v3_load(cf.world_from_camera + 4);
        origin = gi_v3_add(v->drag_origin, gi_v3_add(gi_v3_scale(right, dx * v->drag_scale),
                                                     gi_v3_scale(up, -dy * v->drag_scale)));
    } else {
        /* about the vertical through the object's centre, 0.01 rad a pixel */
        float a = dx * 0.01f, c = cosf(a), s = sinf(a);
        gi_vec3 r = gi_v3_sub(v->drag_origin, v->drag_pivot);
        origin = gi_v3_add(v->drag_pivot, gi_v3(c * r.x + s * r.z, r.y, -s * r.x + c * r.z));
        gi_vec3 axis = gi_v3_normalize(gi_mat4_dir(pinv, gi_v3(0, 1, 0)));
        float q[4] = {axis.x * sinf(0.5f * a), axis.y * sinf(0.5f * a), axis.z * sinf(0.5f * a),
                      cosf(0.5f * a)};
        quat_mul(trs + 3, q, v->drag_trs + 3);
        gi_quat_normalize(trs + 3);
    }
    gi_v3_store(gi_mat4_point(pinv, origin), trs);
    return place_node(v, node, trs);
}

int view_light_select(viewer *v)
{
    if (v->scene->light_count == 0) {
        snprintf(v->status, sizeof v->status,
                 "no punctual light in the scene (an emitting object moves with Shift+drag)");
        return EXIT_OK;
    }
    v->sel_light = v->sel_light + 1 >= (int)v->scene->light_count ? -1 : v->sel_light + 1;
    if (v->sel_light >= 0) {
        const gi_light *l = &v->scene->lights[v->sel_light];
        unsigned char *moved = calloc(v->scene->node_count, 1);
        int animated = 0;
        if (moved) {
            for (uint32_t i = 0; i < v->scene->node_count; i++) {
                const gi_node *n = &v->scene->nodes[i];
                moved[i] = (unsigned char)(n->anim_t.count || n->anim_r.count || n->anim_s.count);
            }
            animated = view_scene_under(v->scene, l->node, moved);
            free(moved);
        }
        snprintf(v->status, sizeof v->status, "light %d '%s' selected%s", v->sel_light,
                 l->name ? l->name : "",
                 animated ? " (animated by the scene: it cannot be moved by hand)"
                          : " (Shift+drag or Shift+W/A/S/D/Q/E moves it; L again until none to "
                            "pick objects)");
        if (animated)
            v->sel_light = -1;
    } else {
        snprintf(v->status, sizeof v->status, "no light selected");
    }
    return EXIT_OK;
}

int view_light_pick(viewer *v, double x, double y)
{
    if (v->sel_light < 0)
        return EXIT_OK;
    const gi_light *l = &v->scene->lights[v->sel_light];
    int node = l->node;
    float world[16];
    gi_scene_node_transform(v->scene, node, v->time, world);
    gi_vec3 pos = gi_v3(world[12], world[13], world[14]);
    gi_camera_frame cf = view_camera(v);
    float depth = gi_v3_dot(gi_v3_sub(pos, cf.eye), gi_v3_normalize(cf.forward));
    if (!(depth > cf.znear)) {
        /* no plane facing the camera through it that the mouse can reach */
        snprintf(v->status, sizeof v->status,
                 "light %d '%s' is behind the camera: orbit to see its place, or move it with "
                 "Shift+W/A/S/D/Q/E",
                 v->sel_light, l->name ? l->name : "");
        return EXIT_OK;
    }
    if (gi_log_get_level() >= GI_LOG_WARN)
        printf("view: picked light %d '%s' at depth %.4g (move)\n", v->sel_light,
               l->name ? l->name : "", (double)depth);
    v->drag_object = 1;
    v->drag_node = node;
    v->drag_x0 = x;
    v->drag_y0 = y;
    get_trs(&v->scene->nodes[node], v->drag_trs);
    v->drag_origin = pos;
    v->drag_pivot = pos;
    /* as for an object: a window pixel at the light's depth, so that the
     * light moves on the screen as far as the mouse does */
    v->drag_scale = 2.0f * depth * tanf(0.5f * cf.yfov) / (float)(v->height > 0 ? v->height : 1);
    v->status[0] = '\0';
    return EXIT_OK;
}

int view_light_move(viewer *v, gi_vec3 dir)
{
    if (v->sel_light < 0) {
        snprintf(v->status, sizeof v->status, "no light selected (L selects one)");
        return EXIT_OK;
    }
    int node = v->scene->lights[v->sel_light].node;
    const float *b = v->scene->bounds;
    float step = 0.05f * gi_v3_length(gi_v3(b[3] - b[0], b[4] - b[1], b[5] - b[2]));
    float world[16], pw[16], pinv[16], trs[10];
    gi_scene_node_transform(v->scene, node, v->time, world);
    parent_world(v, node, pw);
    if (!gi_mat4_invert(pinv, pw))
        gi_mat4_identity(pinv);
    gi_vec3 origin = gi_v3_add(gi_v3(world[12], world[13], world[14]), gi_v3_scale(dir, step));
    get_trs(&v->scene->nodes[node], trs);
    gi_v3_store(gi_mat4_point(pinv, origin), trs);
    return place_node(v, node, trs);
}

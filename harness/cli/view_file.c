/* Saved views (view_file.h). */
#include "view_file.h"

#include "cli.h"
#include "gi/method.h"
#include "gi/vecmath.h"

#include <json-c/json.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void clear_params(view_file *v)
{
    for (uint32_t i = 0; i < v->param_count; i++)
        free(v->params[i]);
    v->param_count = 0;
}

void view_file_free(view_file *v)
{
    clear_params(v);
}

static int add_param(view_file *v, const char *kv, size_t n)
{
    if (v->param_count == VIEW_FILE_MAX_PARAMS || n == 0)
        return n == 0;
    char *s = malloc(n + 1);
    if (!s)
        return 0;
    memcpy(s, kv, n);
    s[n] = '\0';
    v->params[v->param_count++] = s;
    return 1;
}

int view_file_set_params(view_file *v, const char *canonical)
{
    clear_params(v);
    const char *p = canonical ? canonical : "";
    while (*p) {
        const char *comma = strchr(p, ',');
        size_t n = comma ? (size_t)(comma - p) : strlen(p);
        if (!add_param(v, p, n))
            return 0;
        p += n + (comma ? 1 : 0);
    }
    return 1;
}

gi_camera_frame view_file_camera(const view_file *v)
{
    gi_camera_frame cf;
    memset(&cf, 0, sizeof cf);
    float view[16];
    gi_vec3 target = gi_v3_add(v->eye, v->forward);
    gi_mat4_look_at(view, v->eye, target, v->up);
    gi_mat4_invert(cf.world_from_camera, view);
    cf.eye = v->eye;
    cf.forward = gi_v3_normalize(v->forward);
    cf.up = v->up;
    cf.yfov = v->yfov;
    cf.znear = v->znear;
    cf.zfar = v->zfar;
    return cf;
}

static json_object *vec3_json(gi_vec3 a)
{
    json_object *j = json_object_new_array();
    json_object_array_add(j, json_object_new_double(a.x));
    json_object_array_add(j, json_object_new_double(a.y));
    json_object_array_add(j, json_object_new_double(a.z));
    return j;
}

static json_object *floats_json(const float *a, int n)
{
    json_object *j = json_object_new_array();
    for (int i = 0; i < n; i++)
        json_object_array_add(j, json_object_new_double(a[i]));
    return j;
}

int view_file_write(const char *path, const view_file *v, char *why, size_t why_size)
{
    json_object *j = json_object_new_object();
    json_object_object_add(j, "gibench_view", json_object_new_int(1));
    json_object_object_add(j, "scene", json_object_new_string(v->scene));
    json_object_object_add(j, "method", json_object_new_string(v->method));
    json_object *pa = json_object_new_array();
    for (uint32_t i = 0; i < v->param_count; i++)
        json_object_array_add(pa, json_object_new_string(v->params[i]));
    json_object_object_add(j, "params", pa);
    json_object_object_add(j, "width", json_object_new_int((int32_t)v->width));
    json_object_object_add(j, "height", json_object_new_int((int32_t)v->height));
    json_object_object_add(j, "frames", json_object_new_int((int32_t)v->frames));
    json_object_object_add(j, "seed", json_object_new_int64(v->seed));
    json_object_object_add(j, "time", json_object_new_double(v->time));
    json_object_object_add(j, "exposure", json_object_new_double(v->exposure));
    json_object *cam = json_object_new_object();
    json_object_object_add(cam, "eye", vec3_json(v->eye));
    json_object_object_add(cam, "forward", vec3_json(v->forward));
    json_object_object_add(cam, "up", vec3_json(v->up));
    json_object_object_add(cam, "yfov", json_object_new_double(v->yfov));
    json_object_object_add(cam, "znear", json_object_new_double(v->znear));
    json_object_object_add(cam, "zfar", json_object_new_double(v->zfar));
    json_object_object_add(j, "camera", cam);
    json_object *nodes = json_object_new_array();
    for (uint32_t i = 0; i < v->node_count; i++) {
        const view_node *n = &v->nodes[i];
        json_object *o = json_object_new_object();
        json_object_object_add(o, "node", json_object_new_int((int32_t)n->node));
        json_object_object_add(o, "name", json_object_new_string(n->name));
        json_object_object_add(o, "translation", floats_json(n->translation, 3));
        json_object_object_add(o, "rotation", floats_json(n->rotation, 4));
        json_object_object_add(o, "scale", floats_json(n->scale, 3));
        json_object_array_add(nodes, o);
    }
    json_object_object_add(j, "nodes", nodes);
    int ok = cli_write_json(path, j, why, why_size);
    json_object_put(j);
    return ok;
}

static int get_num(json_object *o, const char *key, double lo, double hi, double *out)
{
    json_object *v;
    if (!json_object_object_get_ex(o, key, &v) ||
        !(json_object_is_type(v, json_type_double) || json_object_is_type(v, json_type_int)))
        return 0;
    double d = json_object_get_double(v);
    if (!isfinite(d) || d < lo || d > hi)
        return 0;
    *out = d;
    return 1;
}

static int get_vec3(json_object *o, const char *key, gi_vec3 *out)
{
    json_object *a;
    if (!json_object_object_get_ex(o, key, &a) || !json_object_is_type(a, json_type_array) ||
        json_object_array_length(a) != 3)
        return 0;
    float f[3];
    for (int i = 0; i < 3; i++) {
        json_object *e = json_object_array_get_idx(a, (size_t)i);
        if (!(json_object_is_type(e, json_type_double) || json_object_is_type(e, json_type_int)))
            return 0;
        double d = json_object_get_double(e);
        if (!isfinite(d) || fabs(d) > 1e30)
            return 0;
        f[i] = (float)d;
    }
    *out = gi_v3(f[0], f[1], f[2]);
    return 1;
}

static int get_floats(json_object *o, const char *key, float *out, int n)
{
    json_object *a;
    if (!json_object_object_get_ex(o, key, &a) || !json_object_is_type(a, json_type_array) ||
        json_object_array_length(a) != (size_t)n)
        return 0;
    for (int i = 0; i < n; i++) {
        json_object *e = json_object_array_get_idx(a, (size_t)i);
        if (!(json_object_is_type(e, json_type_double) || json_object_is_type(e, json_type_int)))
            return 0;
        double d = json_object_get_double(e);
        if (!isfinite(d) || fabs(d) > 1e30)
            return 0;
        out[i] = (float)d;
    }
    return 1;
}

/* "nodes": the moved nodes (absent in views without any). */
static const char *get_nodes(json_object *j, view_file *v)
{
    json_object *a;
    if (!json_object_object_get_ex(j, "nodes", &a))
        return NULL;
    if (!json_object_is_type(a, json_type_array) ||
        json_object_array_length(a) > VIEW_FILE_MAX_NODES)
        return "nodes (an array of at most 256 node placements)";
    for (size_t i = 0; i < json_object_array_length(a); i++) {
        json_object *o = json_object_array_get_idx(a, i), *name;
        view_node *n = &v->nodes[v->node_count];
        double d;
        if (!json_object_is_type(o, json_type_object) || !get_num(o, "node", 0, 1e9, &d) ||
            (n->node = (uint32_t)d) != d)
            return "nodes[].node (an index)";
        if (!json_object_object_get_ex(o, "name", &name) ||
            !json_object_is_type(name, json_type_string) ||
            strlen(json_object_get_string(name)) >= sizeof n->name)
            return "nodes[].name";
        snprintf(n->name, sizeof n->name, "%s", json_object_get_string(name));
        if (!get_floats(o, "translation", n->translation, 3))
            return "nodes[].translation (3 numbers)";
        if (!get_floats(o, "rotation", n->rotation, 4))
            return "nodes[].rotation (a quaternion x y z w)";
        float len = sqrtf(n->rotation[0] * n->rotation[0] + n->rotation[1] * n->rotation[1] +
                          n->rotation[2] * n->rotation[2] + n->rotation[3] * n->rotation[3]);
        if (fabsf(len - 1.0f) > 1e-3f)
            return "nodes[].rotation (not a unit quaternion)";
        if (!get_floats(o, "scale", n->scale, 3))
            return "nodes[].scale (3 numbers)";
        if (i > 0 && n->node <= v->nodes[v->node_count - 1].node)
            return "nodes (in increasing node order, each once)";
        v->node_count++;
    }
    return NULL;
}

static int get_str(json_object *o, const char *key, char *out, size_t size)
{
    json_object *v;
    if (!json_object_object_get_ex(o, key, &v) || !json_object_is_type(v, json_type_string))
        return 0;
    const char *s = json_object_get_string(v);
    if (!*s || strlen(s) >= size)
        return 0;
    snprintf(out, size, "%s", s);
    return 1;
}

int view_file_read(const char *path, view_file *v, char *why, size_t why_size)
{
    memset(v, 0, sizeof *v);
    json_object *j = cli_read_json_strict(path, why, why_size);
    if (!j)
        return 0;
    if (!json_object_is_type(j, json_type_object)) {
        snprintf(why, why_size, "%s: not a JSON view file (an object)", path);
        json_object_put(j);
        return 0;
    }
    const char *bad = NULL;
    double d;
    json_object *cam = NULL, *pa = NULL;
    if (!get_num(j, "gibench_view", 1, 1, &d))
        bad = "gibench_view (1)";
    else if (!get_str(j, "scene", v->scene, sizeof v->scene))
        bad = "scene";
    else if (!get_str(j, "method", v->method, sizeof v->method))
        bad = "method";
    else if (!get_num(j, "width", 1, GI_MAX_IMAGE_SIDE, &d) || (v->width = (uint32_t)d) != d)
        bad = "width (" GI_IMAGE_SIZE_RULE ")";
    else if (!get_num(j, "height", 1, GI_MAX_IMAGE_SIDE, &d) || (v->height = (uint32_t)d) != d ||
             !gi_image_size_ok(v->width, v->height))
        bad = "height (" GI_IMAGE_SIZE_RULE ")";
    else if (!get_num(j, "frames", 1, 1000000, &d) || (v->frames = (uint32_t)d) != d)
        bad = "frames (1..1000000)";
    else if (!get_num(j, "seed", 0, 4294967295.0, &d) || (v->seed = (uint32_t)d) != d)
        bad = "seed";
    else if (!get_num(j, "time", 0, 1e9, &d) || !((v->time = (float)d) >= 0))
        bad = "time (>= 0)";
    else if (!get_num(j, "exposure", -64, 64, &d) || !isfinite(v->exposure = (float)d))
        bad = "exposure (-64..64)";
    else if (!json_object_object_get_ex(j, "camera", &cam) ||
             !json_object_is_type(cam, json_type_object))
        bad = "camera";
    else if (!get_vec3(cam, "eye", &v->eye))
        bad = "camera.eye";
    else if (!get_vec3(cam, "forward", &v->forward) || gi_v3_length(v->forward) < 1e-12f)
        bad = "camera.forward (non-zero)";
    else if (!get_vec3(cam, "up", &v->up) ||
             gi_v3_length(gi_v3_cross(v->forward, v->up)) <
                 1e-6f * gi_v3_length(v->forward) * gi_v3_length(v->up))
        bad = "camera.up (not along forward)";
    else if (!get_num(cam, "yfov", 1e-4, 3.14, &d) || !isfinite(v->yfov = (float)d))
        bad = "camera.yfov (radians, 0..pi)";
    else if (!get_num(cam, "znear", 1e-9, 1e30, &d) || !isfinite(v->znear = (float)d))
        bad = "camera.znear (> 0)";
    else if (!get_num(cam, "zfar", 0, 1e30, &d) || !((v->zfar = (float)d) > v->znear))
        bad = "camera.zfar (> znear)";
    else if (!json_object_object_get_ex(j, "params", &pa) ||
             !json_object_is_type(pa, json_type_array) ||
             json_object_array_length(pa) > VIEW_FILE_MAX_PARAMS)
        bad = "params (an array of \"k=v\")";
    for (size_t i = 0; !bad && i < json_object_array_length(pa); i++) {
        json_object *e = json_object_array_get_idx(pa, i);
        const char *s = json_object_is_type(e, json_type_string) ? json_object_get_string(e) : NULL;
        if (!s || !strchr(s, '=') || !add_param(v, s, strlen(s)))
            bad = "params (an array of \"k=v\")";
    }
    if (!bad)
        bad = get_nodes(j, v);
    json_object_put(j);
    if (bad) {
        snprintf(why, why_size, "%s: missing or bad %s", path, bad);
        view_file_free(v);
        return 0;
    }
    return 1;
}

int view_scene_under(const gi_scene *s, int node, const unsigned char *moved)
{
    for (int k = node, hops = 0;
         k >= 0 && (uint32_t)k < s->node_count && hops <= (int)s->node_count;
         k = s->nodes[k].parent, hops++)
        if (moved[k])
            return 1;
    return 0;
}

/* Whether node k or an ancestor carries an animation track. */
static int node_animated(const gi_scene *s, int node)
{
    for (int k = node, hops = 0; k >= 0 && hops <= (int)s->node_count;
         k = s->nodes[k].parent, hops++) {
        const gi_node *n = &s->nodes[k];
        if (n->anim_t.count || n->anim_r.count || n->anim_s.count)
            return 1;
    }
    return 0;
}

int view_file_check_nodes(const view_file *v, const gi_scene *s, char *why, size_t why_size)
{
    for (uint32_t i = 0; i < v->node_count; i++) {
        const view_node *n = &v->nodes[i];
        if (n->node >= s->node_count) {
            snprintf(why, why_size, "the view moves node %u; the scene has %u nodes", n->node,
                     s->node_count);
            return 0;
        }
        const char *name = s->nodes[n->node].name ? s->nodes[n->node].name : "";
        if (strcmp(name, n->name)) {
            snprintf(why, why_size, "the view moves node %u '%s'; the scene's node %u is '%s'",
                     n->node, n->name, n->node, name);
            return 0;
        }
        if (node_animated(s, (int)n->node)) {
            snprintf(why, why_size, "the view moves node %u '%s', which the scene animates",
                     n->node, name);
            return 0;
        }
    }
    return 1;
}

int view_scene_mark_moving(gi_scene *s, uint32_t node)
{
    unsigned char *moved = calloc(s->node_count, 1);
    if (!moved)
        return 0;
    moved[node] = 1;
    int changed = 0;
    for (uint32_t o = 0; o < s->object_count; o++)
        if (view_scene_under(s, s->objects[o].node, moved) && !s->objects[o].animated) {
            s->objects[o].animated = 1;
            changed = 1;
        }
    free(moved);
    return changed;
}

static int object_emits(const gi_scene *s, uint32_t o)
{
    const gi_object *obj = &s->objects[o];
    for (uint32_t t = obj->first_triangle; t < obj->first_triangle + obj->triangle_count; t++) {
        const float *e = gi_scene_triangle_emission(s, t);
        if (e[0] > 0 || e[1] > 0 || e[2] > 0)
            return 1;
    }
    return 0;
}

void view_scene_changes(const gi_scene *s, const unsigned char *moved, uint32_t *flags,
                        uint64_t *moved_objects)
{
    *flags = 0;
    *moved_objects = 0;
    for (uint32_t o = 0; o < s->object_count; o++)
        if (view_scene_under(s, s->objects[o].node, moved)) {
            *flags |= GI_CHANGED_TRANSFORMS | (object_emits(s, o) ? GI_CHANGED_LIGHTS : 0u);
            if (o < 64)
                *moved_objects |= 1ull << o;
        }
    for (uint32_t l = 0; l < s->light_count; l++)
        if (view_scene_under(s, s->lights[l].node, moved))
            *flags |= GI_CHANGED_LIGHTS;
}

void view_file_apply_nodes(const view_file *v, gi_scene *s)
{
    for (uint32_t i = 0; i < v->node_count; i++) {
        const view_node *n = &v->nodes[i];
        gi_node *d = &s->nodes[n->node];
        memcpy(d->translation, n->translation, sizeof d->translation);
        memcpy(d->rotation, n->rotation, sizeof d->rotation);
        memcpy(d->scale, n->scale, sizeof d->scale);
    }
}

int view_camera_read(const char *camera, view_file *v, char *why, size_t why_size)
{
    if (!camera || strncmp(camera, "view:", 5))
        return 0;
    if (!camera[5]) {
        snprintf(why, why_size,
                 "camera 'view:' names no file (view:FILE.json, a view saved by gibench view)");
        return -1;
    }
    return view_file_read(camera + 5, v, why, why_size) ? 1 : -1;
}

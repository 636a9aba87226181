/* The scene API of scene.h: loading (file reading, the environment map; the
 * glTF parsing itself is gltf_shim.cpp), freeing, and everything computed
 * from the immutable scene at a time t: animated node transforms, light and
 * camera frames, world-space triangles and bounds, textured albedo.
 */
#define _POSIX_C_SOURCE 200809L

#include "gi/scene.h"

#include "gi/log.h"

#include "gi/envmap.h"
#include "gi/image.h"
#include "gltf_shim.h"

#include <assert.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- loading ------------------------------------------------------------ */

/* Reads the whole file, refusing anything but a regular file of at most
 * GI_MAX_FILE_BYTES (O_NONBLOCK: a FIFO must not hang the loader). */
static void *read_scene_file(const char *path, size_t *size, gi_error *err)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        gi_error_set(err, GI_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
        return NULL;
    }
    struct stat st;
    char *data = NULL;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        gi_error_set(err, GI_ERR_IO, "%s: not a regular file", path);
    } else if ((unsigned long long)st.st_size > GI_MAX_FILE_BYTES) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %lld bytes exceed the 1 GiB file limit",
                     path, (long long)st.st_size);
    } else {
        size_t n = (size_t)st.st_size, done = 0;
        data = malloc(n ? n : 1);
        if (!data)
            gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
        while (data && done < n) {
            ssize_t r = read(fd, data + done, n - done);
            if (r < 0 && errno == EINTR)
                continue;
            if (r <= 0) {
                gi_error_set(err, GI_ERR_IO, "%s: read error: %s", path,
                             r < 0 ? strerror(errno) : "file shrank");
                free(data);
                data = NULL;
            } else {
                done += (size_t)r;
            }
        }
        *size = n;
    }
    close(fd);
    return data;
}

/* "dir/name.gltf" -> "dir"; "name.gltf" -> "." (malloc'd). */
static char *directory_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        return strdup(".");
    size_t n = slash == path ? 1 : (size_t)(slash - path);
    char *dir = malloc(n + 1);
    if (dir) {
        memcpy(dir, path, n);
        dir[n] = '\0';
    }
    return dir;
}

static int load_environment(gi_scene *s, const char *name, const char *pointer, gi_error *err)
{
    gi_error ierr = {{0}};
    gi_image *img = gi_image_read(s->environment.path, &ierr);
    if (!img) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "%s: %s: cannot read environment map '%.100s': %s", name, pointer,
                     s->environment.uri, ierr.text);
        return 0;
    }
    uint32_t bx = 0, by = 0;
    uint64_t bad = gi_envmap_count_nonfinite(img->rgba, img->width, img->height, &bx, &by);
    if (bad) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "%s: %s: environment map '%.100s' has %llu NaN or infinite texels (the first "
                     "at x %u, y %u)",
                     name, pointer, s->environment.uri, (unsigned long long)bad, bx, by);
        gi_image_free(img);
        return 0;
    }
    s->envmap = gi_envmap_create(img->rgba, img->width, img->height, s->environment.intensity,
                                 s->environment.rotation_deg);
    gi_image_free(img);
    if (!s->envmap) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: %s: cannot build the environment map", name,
                     pointer);
        return 0;
    }
    return 1;
}

static float object_handedness(const gi_scene *s, uint32_t object, float t);

/* glTF 2.0 (meshes): the determinant of a node's global transform defines
 * the winding: counter-clockwise where it is positive, clockwise where it is
 * negative, so a mirrored instance keeps its front where the mesh has it
 * (Unity and Unreal do the same). Every pass tests facing on world-space
 * corners (gi/scene.h), so the corners of each triangle of a mirroring
 * object are stored in the reverse order: its world-space counter-clockwise
 * side is then its front. Normals stay as they are: the normal matrix takes
 * a local front normal (flat normals are computed on the file's order, in
 * object-local space) to the world front. The handedness at t = 0 decides;
 * an animation that changes it later is not followed. */
static void mirror_winding(gi_scene *s)
{
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *ob = &s->objects[o];
        if (object_handedness(s, o, 0.0f) > 0.0f)
            continue;
        for (uint32_t t = 0; t < ob->triangle_count; t++) {
            uint32_t *idx = s->indices + 3 * ((size_t)ob->first_triangle + t);
            uint32_t k = idx[1];
            idx[1] = idx[2];
            idx[2] = k;
        }
    }
}

/* 1 when text data could begin a JSON value (after white space): anything
 * else (an image, an OBJ file) is named as not glTF instead of reaching the
 * JSON parser's error. */
static int may_be_json(const unsigned char *p, size_t size)
{
    size_t i = 0;
    while (i < size && (p[i] == ' ' || p[i] == '\t' || p[i] == '\n' || p[i] == '\r'))
        i++;
    if (i == size)
        return 1; /* empty: the parser says so */
    return strchr("{[\"-0123456789tfn", p[i]) != NULL && p[i] != '\0';
}

gi_scene *gi_scene_load_memory(const void *data, size_t size, int binary, const char *base_dir,
                               const char *name, gi_error *err)
{
    if (err)
        err->text[0] = '\0';
    name = name ? name : "(memory)";
    if (!binary && !may_be_json(data, size)) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "%s: not a glTF file (neither glTF JSON nor GLB; scenes are .gltf or .glb)",
                     name);
        return NULL;
    }
    gi_gltf_source src = {data, size, binary, base_dir, name};
    char pointer[GI_GLTF_POINTER_MAX];
    gi_scene *s = gi_gltf_parse(&src, pointer, err);
    if (!s)
        return NULL;
    s->path = strdup(name);
    if (!s->path) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", name);
        gi_scene_free(s);
        return NULL;
    }
    if (s->has_environment && !load_environment(s, name, pointer, err)) {
        gi_scene_free(s);
        return NULL;
    }
    gi_scene_bounds_at(s, 0.0f, s->bounds);
    mirror_winding(s);
    if (s->camera_count == 0) /* said once, where the scene is loaded (issue 28) */
        gi_log(GI_LOG_WARN,
               "%s: no camera; using the default camera (looking down -Z at the centre of the "
               "bounds, the bounding sphere filling its 45-degree field of view)",
               name);
    return s;
}

gi_scene *gi_scene_load(const char *path, gi_error *err)
{
    if (err)
        err->text[0] = '\0';
    size_t size = 0;
    void *data = read_scene_file(path, &size, err);
    if (!data)
        return NULL;
    char *dir = directory_of(path);
    gi_scene *s = NULL;
    if (!dir) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } else {
        int binary = size >= 4 && memcmp(data, "glTF", 4) == 0;
        s = gi_scene_load_memory(data, size, binary, dir, path, err);
    }
    free(dir);
    free(data);
    return s;
}

static void free_track(gi_track *t)
{
    free(t->times);
    free(t->values);
}

void gi_scene_free(gi_scene *s)
{
    if (!s)
        return;
    free(s->path);
    free(s->vertices);
    free(s->indices);
    for (uint32_t i = 0; s->materials && i < s->material_count; i++)
        free(s->materials[i].name);
    free(s->materials);
    for (uint32_t i = 0; s->textures && i < s->texture_count; i++) {
        free(s->textures[i].name);
        free(s->textures[i].rgba);
    }
    free(s->textures);
    for (uint32_t i = 0; s->nodes && i < s->node_count; i++) {
        free(s->nodes[i].name);
        free_track(&s->nodes[i].anim_t);
        free_track(&s->nodes[i].anim_r);
        free_track(&s->nodes[i].anim_s);
    }
    free(s->nodes);
    for (uint32_t i = 0; s->objects && i < s->object_count; i++) {
        free(s->objects[i].name);
        free(s->objects[i].morph_positions);
        free(s->objects[i].morph_normals);
        free(s->objects[i].morph_weights);
        free(s->objects[i].flat_triangles);
        free_track(&s->objects[i].morph_track);
    }
    free(s->objects);
    for (uint32_t i = 0; s->lights && i < s->light_count; i++)
        free(s->lights[i].name);
    free(s->lights);
    for (uint32_t i = 0; s->cameras && i < s->camera_count; i++)
        free(s->cameras[i].name);
    free(s->cameras);
    free(s->emitters);
    free(s->environment.uri);
    free(s->environment.path);
    gi_envmap_free(s->envmap);
    free(s);
}

/* ---- animation and transforms ------------------------------------------ */

/* Value of a track at t (`width` floats a key): held before the first and
 * after the last key; STEP holds each key until the next; LINEAR
 * interpolates, with slerp along the shorter arc when `slerp` (rotations). */
static void sample_track_any(const gi_track *tr, int width, int slerp, float t, float *out)
{
    uint32_t n = tr->count;
    if (!(t > tr->times[0]) || n == 1) { /* NaN lands here too */
        memcpy(out, tr->values, (size_t)width * sizeof(float));
        return;
    }
    if (t >= tr->times[n - 1]) {
        memcpy(out, tr->values + (size_t)(n - 1) * width, (size_t)width * sizeof(float));
        return;
    }
    uint32_t lo = 0, hi = n - 1; /* times[lo] <= t < times[hi] */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (tr->times[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    const float *a = tr->values + (size_t)lo * width, *b = tr->values + (size_t)hi * width;
    if (tr->step) {
        memcpy(out, a, (size_t)width * sizeof(float));
        return;
    }
    float u = (t - tr->times[lo]) / (tr->times[hi] - tr->times[lo]);
    if (slerp) {
        float d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
        float bb[4] = {b[0], b[1], b[2], b[3]};
        if (d < 0.0f)
            for (int k = 0; k < 4; k++)
                bb[k] = -bb[k];
        gi_quat_slerp(out, a, bb, u);
        return;
    }
    for (int k = 0; k < width; k++)
        out[k] = a[k] + (b[k] - a[k]) * u;
}

/* Translation/scale (width 3) and rotation (width 4) tracks. */
static void sample_track(const gi_track *tr, int width, float t, float *out)
{
    sample_track_any(tr, width, width == 4, t, out);
}

/* Node transform relative to its parent at t. */
static void local_transform(const gi_node *n, float t, float out[16])
{
    float tr[3], r[4], sc[3];
    memcpy(tr, n->translation, sizeof tr);
    memcpy(r, n->rotation, sizeof r);
    memcpy(sc, n->scale, sizeof sc);
    if (n->anim_t.count)
        sample_track(&n->anim_t, 3, t, tr);
    if (n->anim_r.count)
        sample_track(&n->anim_r, 4, t, r);
    if (n->anim_s.count)
        sample_track(&n->anim_s, 3, t, sc);
    gi_mat4_trs(out, tr, r, sc);
}

void gi_scene_node_transform(const gi_scene *s, int node, float t, float out[16])
{
    assert(s && node >= 0 && (uint32_t)node < s->node_count);
    local_transform(&s->nodes[node], t, out);
    for (int p = s->nodes[node].parent; p >= 0; p = s->nodes[p].parent) {
        float m[16];
        local_transform(&s->nodes[p], t, m);
        gi_mat4_mul(out, m, out); /* parent * child */
    }
}

int gi_scene_node_animated(const gi_scene *s, int node)
{
    assert(s && node < (int)s->node_count);
    for (int n = node; n >= 0; n = s->nodes[n].parent) {
        const gi_node *nd = &s->nodes[n];
        if (nd->anim_t.count || nd->anim_r.count || nd->anim_s.count)
            return 1;
    }
    return 0;
}

int gi_scene_camera_animated(const gi_scene *s, int camera)
{
    assert(s);
    if (camera < 0 || (uint32_t)camera >= s->camera_count)
        return 0;
    return gi_scene_node_animated(s, s->cameras[camera].node);
}

int gi_scene_lights_animated(const gi_scene *s)
{
    assert(s);
    for (uint32_t i = 0; i < s->light_count; i++)
        if (gi_scene_node_animated(s, s->lights[i].node))
            return 1;
    for (uint32_t i = 0; i < s->emitter_count; i++) {
        uint32_t tri = s->emitters[i];
        for (uint32_t o = 0; o < s->object_count; o++) {
            const gi_object *ob = &s->objects[o];
            if (tri >= ob->first_triangle && tri - ob->first_triangle < ob->triangle_count) {
                if (ob->animated || ob->morph_track.count)
                    return 1;
                break;
            }
        }
    }
    return 0;
}

void gi_scene_object_transform(const gi_scene *s, uint32_t object, float t, float out[16])
{
    assert(s && object < s->object_count);
    gi_scene_node_transform(s, s->objects[object].node, t, out);
}

static gi_vec3 unit_or(gi_vec3 v, gi_vec3 fallback)
{
    float l = gi_v3_length(v);
    return l > 0.0f && isfinite(l) ? gi_v3_scale(v, 1.0f / l) : fallback;
}

gi_light_frame gi_scene_light_at(const gi_scene *s, uint32_t light, float t)
{
    assert(s && light < s->light_count);
    float m[16];
    gi_scene_node_transform(s, s->lights[light].node, t, m);
    gi_light_frame f;
    f.position = gi_mat4_point(m, gi_v3(0.0f, 0.0f, 0.0f));
    f.direction = unit_or(gi_mat4_dir(m, gi_v3(0.0f, 0.0f, -1.0f)), gi_v3(0.0f, 0.0f, -1.0f));
    return f;
}

/* ---- cameras ------------------------------------------------------------ */

/* Rigid camera frame from eye, viewing direction and an up hint. */
static void set_frame(gi_camera_frame *f, gi_vec3 eye, gi_vec3 forward, gi_vec3 up_hint)
{
    gi_vec3 right = gi_v3_cross(forward, up_hint);
    if (!(gi_v3_length(right) > 1e-6f)) /* up parallel to forward: any perpendicular */
        right = gi_v3_cross(forward, fabsf(forward.y) < 0.9f ? gi_v3(0, 1, 0) : gi_v3(1, 0, 0));
    right = gi_v3_normalize(right);
    gi_vec3 up = gi_v3_cross(right, forward);
    f->eye = eye;
    f->forward = forward;
    f->up = up;
    float *m = f->world_from_camera;
    gi_mat4_identity(m);
    gi_v3_store(right, m);
    gi_v3_store(up, m + 4);
    gi_v3_store(gi_v3_scale(forward, -1.0f), m + 8);
    gi_v3_store(eye, m + 12);
}

/* Distance from eye to the farthest corner of the box, at least `floor_`. */
static float far_distance(const float b[6], gi_vec3 eye, float floor_)
{
    float far = floor_;
    for (int c = 0; c < 8; c++) {
        gi_vec3 p = gi_v3(b[(c & 1) ? 3 : 0], b[(c & 2) ? 4 : 1], b[(c & 4) ? 5 : 2]);
        far = fmaxf(far, gi_v3_length(gi_v3_sub(p, eye)));
    }
    return far;
}

/* No camera: the bounds seen from +Z with a 45 degree field of view. */
static gi_camera_frame default_camera(const gi_scene *s)
{
    gi_camera_frame f;
    const float *b = s->bounds;
    gi_vec3 lo = gi_v3_load(b), hi = gi_v3_load(b + 3);
    gi_vec3 center = gi_v3_scale(gi_v3_add(lo, hi), 0.5f);
    float radius = 0.5f * gi_v3_length(gi_v3_sub(hi, lo));
    if (!(radius > 0.0f) || !isfinite(radius))
        radius = 1.0f;
    f.yfov = 45.0f * GI_PI / 180.0f;
    float dist = radius / sinf(0.5f * f.yfov);
    set_frame(&f, gi_v3_add(center, gi_v3(0.0f, 0.0f, dist)), gi_v3(0.0f, 0.0f, -1.0f),
              gi_v3(0.0f, 1.0f, 0.0f));
    f.znear = fmaxf(dist - radius, 0.0f) * 0.5f;
    f.znear = fmaxf(f.znear, dist * 1e-3f);
    f.zfar = (dist + radius) * 1.5f;
    return f;
}

gi_camera_frame gi_scene_camera_at(const gi_scene *s, int camera, float t)
{
    assert(s);
    if (camera < 0 || (uint32_t)camera >= s->camera_count)
        return default_camera(s);
    const gi_camera *c = &s->cameras[camera];
    float m[16];
    gi_scene_node_transform(s, c->node, t, m);
    gi_camera_frame f;
    gi_vec3 eye = gi_mat4_point(m, gi_v3(0.0f, 0.0f, 0.0f));
    gi_vec3 fwd = unit_or(gi_mat4_dir(m, gi_v3(0.0f, 0.0f, -1.0f)), gi_v3(0.0f, 0.0f, -1.0f));
    gi_vec3 up = unit_or(gi_mat4_dir(m, gi_v3(0.0f, 1.0f, 0.0f)), gi_v3(0.0f, 1.0f, 0.0f));
    set_frame(&f, eye, fwd, up);
    f.yfov = c->yfov;
    f.znear = c->znear;
    if (c->zfar > 0.0f) {
        f.zfar = c->zfar;
    } else { /* infinite in the file: just beyond the farthest corner of the scene */
        float b[6];
        gi_scene_bounds_at(s, t, b);
        f.zfar = far_distance(b, eye, 2.0f * c->znear) * 1.01f;
    }
    return f;
}

int gi_scene_find_camera(const gi_scene *s, const char *name)
{
    assert(s && name);
    for (uint32_t i = 0; i < s->camera_count; i++)
        if (s->cameras[i].name && strcmp(s->cameras[i].name, name) == 0)
            return (int)i;
    if (name[0] == '#' && name[1] >= '0' && name[1] <= '9') {
        char *end = NULL;
        errno = 0;
        unsigned long k = strtoul(name + 1, &end, 10);
        if (*end == '\0' && errno == 0 && k < s->camera_count)
            return (int)k;
    }
    return -1;
}

/* ---- geometry ----------------------------------------------------------- */

int gi_scene_deforms(const gi_scene *s)
{
    assert(s);
    for (uint32_t o = 0; o < s->object_count; o++)
        if (s->objects[o].morph_count)
            return 1;
    return 0;
}

void gi_scene_morph_weights(const gi_scene *s, uint32_t object, float t, float *out)
{
    assert(s && object < s->object_count);
    const gi_object *o = &s->objects[object];
    if (!o->morph_count)
        return;
    if (o->morph_track.count)
        sample_track_any(&o->morph_track, (int)o->morph_count, 0, t, out);
    else
        memcpy(out, o->morph_weights, (size_t)o->morph_count * sizeof *out);
}

/* Morph targets hold at most GI_MAX_VERTICES x 3 floats in all; weights on
 * the stack up to this many targets, on the heap beyond. */
#define MORPH_STACK 16

gi_vec3 gi_scene_vertex_position(const gi_scene *s, uint32_t vertex, float t)
{
    assert(s && vertex < s->vertex_count);
    const gi_vertex *v = &s->vertices[vertex];
    const gi_object *o = v->object < s->object_count ? &s->objects[v->object] : NULL;
    if (!o || !o->morph_count)
        return gi_v3_load(v->position);
    float wbuf[MORPH_STACK],
        *w = o->morph_count <= MORPH_STACK ? wbuf : malloc(o->morph_count * sizeof *w);
    if (!w)
        return gi_v3_load(v->position);
    gi_scene_morph_weights(s, v->object, t, w);
    size_t i = vertex - o->first_vertex, nv = o->vertex_count;
    double p[3] = {v->position[0], v->position[1], v->position[2]};
    for (uint32_t k = 0; k < o->morph_count; k++)
        for (int c = 0; c < 3; c++)
            p[c] += (double)w[k] * o->morph_positions[((size_t)k * nv + i) * 3 + (size_t)c];
    if (w != wbuf)
        free(w);
    return gi_v3((float)p[0], (float)p[1], (float)p[2]);
}

/* -1 when the object's world transform at t mirrors (negative
 * determinant): glTF then reverses the winding (mirror_winding). */
static float object_handedness(const gi_scene *s, uint32_t object, float t)
{
    float m[16];
    gi_scene_object_transform(s, object, t, m);
    float det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[4] * (m[1] * m[10] - m[2] * m[9]) +
                m[8] * (m[1] * m[6] - m[2] * m[5]);
    return det < 0.0f ? -1.0f : 1.0f;
}

/* A primitive without NORMAL has flat normals at every weight (glTF 2.0
 * §3.7.2.1): the front face normal of the morphed triangle, on its three
 * own vertices (the loader unshared them). */
static void flat_face_normals(const gi_scene *s, uint32_t object, gi_vertex *out)
{
    const gi_object *o = &s->objects[object];
    /* the corners of a mirroring object are stored reversed (mirror_winding):
     * their cross product is minus the file's, the local front normal */
    float sign = object_handedness(s, object, 0.0f);
    for (uint32_t t = 0; t < o->triangle_count; t++) {
        if (!o->flat_triangles[t])
            continue;
        const uint32_t *idx = s->indices + 3 * ((size_t)o->first_triangle + t);
        gi_vertex *v[3] = {&out[idx[0] - o->first_vertex], &out[idx[1] - o->first_vertex],
                           &out[idx[2] - o->first_vertex]};
        double e1[3], e2[3];
        for (int c = 0; c < 3; c++) {
            e1[c] = (double)v[1]->position[c] - v[0]->position[c];
            e2[c] = (double)v[2]->position[c] - v[0]->position[c];
        }
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0.0) || !isfinite(l))
            continue; /* degenerate at these weights: the rest normal stays */
        for (int j = 0; j < 3; j++)
            for (int c = 0; c < 3; c++)
                v[j]->normal[c] = sign * (float)(n[c] / l);
    }
}

void gi_scene_object_vertices(const gi_scene *s, uint32_t object, float t, gi_vertex *out)
{
    assert(s && object < s->object_count && out);
    const gi_object *o = &s->objects[object];
    size_t nv = o->vertex_count;
    memcpy(out, s->vertices + o->first_vertex, nv * sizeof *out);
    if (!o->morph_count)
        return;
    float wbuf[MORPH_STACK],
        *w = o->morph_count <= MORPH_STACK ? wbuf : malloc(o->morph_count * sizeof *w);
    if (!w)
        return;
    gi_scene_morph_weights(s, object, t, w);
    for (size_t i = 0; i < nv; i++) {
        double p[3] = {out[i].position[0], out[i].position[1], out[i].position[2]};
        double n[3] = {out[i].normal[0], out[i].normal[1], out[i].normal[2]};
        for (uint32_t k = 0; k < o->morph_count; k++) {
            const float *dp = o->morph_positions + ((size_t)k * nv + i) * 3;
            for (int c = 0; c < 3; c++)
                p[c] += (double)w[k] * dp[c];
            if (o->morph_normals) {
                const float *dn = o->morph_normals + ((size_t)k * nv + i) * 3;
                for (int c = 0; c < 3; c++)
                    n[c] += (double)w[k] * dn[c];
            }
        }
        for (int c = 0; c < 3; c++)
            out[i].position[c] = (float)p[c];
        if (o->morph_normals) {
            double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (l > 0.0 && isfinite(l)) /* else the rest normal stays */
                for (int c = 0; c < 3; c++)
                    out[i].normal[c] = (float)(n[c] / l);
        }
    }
    if (w != wbuf)
        free(w);
    if (o->flat_triangles)
        flat_face_normals(s, object, out);
}

void gi_scene_triangle_world(const gi_scene *s, uint32_t tri, float t, gi_vec3 p[3])
{
    assert(s && tri < s->triangle_count);
    const uint32_t *idx = s->indices + (size_t)tri * 3;
    float m[16];
    gi_scene_object_transform(s, s->vertices[idx[0]].object, t, m);
    for (int k = 0; k < 3; k++)
        p[k] = gi_mat4_point(m, gi_scene_vertex_position(s, idx[k], t));
}

/* Each object's local box, transformed at t (conservative under rotation). */
void gi_scene_bounds_at(const gi_scene *s, float t, float out[6])
{
    assert(s);
    float b[6] = {FLT_MAX, FLT_MAX, FLT_MAX, -FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t o = 0; o < s->object_count; o++) {
        const float *lb = s->objects[o].local_bounds;
        float m[16];
        gi_scene_object_transform(s, o, t, m);
        for (int c = 0; c < 8; c++) {
            gi_vec3 p = gi_mat4_point(
                m, gi_v3(lb[(c & 1) ? 3 : 0], lb[(c & 2) ? 4 : 1], lb[(c & 4) ? 5 : 2]));
            float v[3] = {p.x, p.y, p.z};
            for (int k = 0; k < 3; k++) {
                b[k] = fminf(b[k], v[k]);
                b[k + 3] = fmaxf(b[k + 3], v[k]);
            }
        }
    }
    if (s->object_count == 0)
        memset(b, 0, sizeof b);
    memcpy(out, b, sizeof b);
}

const float *gi_scene_triangle_emission(const gi_scene *s, uint32_t tri)
{
    assert(s && tri < s->triangle_count);
    return s->materials[s->vertices[s->indices[(size_t)tri * 3]].material].emission;
}

/* ---- textures ----------------------------------------------------------- */

/* Wraps a texel coordinate into [0, n) (repeat). */
static uint32_t wrap(long long i, uint32_t n)
{
    long long r = i % (long long)n;
    return (uint32_t)(r < 0 ? r + n : r);
}

/* Bilinear RGB lookup with repeat wrapping; texel centres at half-integers,
 * v = 0 at the top row (glTF's convention and the texture's row order). */
static void texture_rgb(const gi_texture *tex, const float uv[2], float out[3])
{
    float u = uv[0] - floorf(uv[0]), v = uv[1] - floorf(uv[1]);
    if (!isfinite(u) || !isfinite(v))
        u = v = 0.0f;
    float x = u * (float)tex->width - 0.5f, y = v * (float)tex->height - 0.5f;
    float fx = floorf(x), fy = floorf(y);
    float ax = x - fx, ay = y - fy;
    uint32_t x0 = wrap((long long)fx, tex->width), x1 = wrap((long long)fx + 1, tex->width);
    uint32_t y0 = wrap((long long)fy, tex->height), y1 = wrap((long long)fy + 1, tex->height);
    const float *p00 = tex->rgba + ((size_t)y0 * tex->width + x0) * 4;
    const float *p10 = tex->rgba + ((size_t)y0 * tex->width + x1) * 4;
    const float *p01 = tex->rgba + ((size_t)y1 * tex->width + x0) * 4;
    const float *p11 = tex->rgba + ((size_t)y1 * tex->width + x1) * 4;
    for (int k = 0; k < 3; k++) {
        float top = p00[k] + (p10[k] - p00[k]) * ax;
        float bottom = p01[k] + (p11[k] - p01[k]) * ax;
        out[k] = top + (bottom - top) * ay;
    }
}

void gi_scene_albedo(const gi_scene *s, uint32_t material, const float uv[2], float out[3])
{
    assert(s && material < s->material_count);
    const gi_material *m = &s->materials[material];
    float tex[3] = {1.0f, 1.0f, 1.0f};
    if (m->albedo_texture >= 0 && (uint32_t)m->albedo_texture < s->texture_count)
        texture_rgb(&s->textures[m->albedo_texture], uv, tex);
    for (int k = 0; k < 3; k++)
        out[k] = m->albedo[k] * tex[k];
}

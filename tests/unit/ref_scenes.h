/* Small glTF scenes built in memory for the reference tests: closed
 * spheres (geodesic, normals inward), planes, polygonal disks, a camera
 * looking at a point, punctual lights and an environment map. Each scene is
 * written as glTF JSON with a base64 buffer and goes through the real
 * loader (gi_scene_load_memory), so the tests see what a file would give.
 *
 *     tg_scene b;
 *     tg_init(&b);
 *     int m = tg_material(&b, albedo, emission, 0);
 *     tg_icosphere(&b, 1.0f, 4, 1, m);
 *     tg_camera(&b, eye, target, 90.0f, 0.01f);
 *     gi_scene *s = tg_load(&b, NULL, &err);   // frees the builder's memory
 */
#ifndef GI_TEST_REF_SCENES_H
#define GI_TEST_REF_SCENES_H

#include "gi/scene.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TG_PI 3.14159265358979323846

typedef struct tg_str {
    char *p;
    size_t n, cap;
} tg_str;

static inline void tg_reserve(tg_str *s, size_t more)
{
    if (s->n + more + 1 <= s->cap)
        return;
    size_t cap = s->cap ? s->cap : 256;
    while (cap < s->n + more + 1)
        cap *= 2;
    s->p = realloc(s->p, cap);
    if (!s->p) {
        fprintf(stderr, "out of memory\n");
        abort();
    }
    s->cap = cap;
}

static inline void tg_bytes(tg_str *s, const void *data, size_t n)
{
    tg_reserve(s, n);
    memcpy(s->p + s->n, data, n);
    s->n += n;
    s->p[s->n] = '\0';
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static inline void
tg_printf(tg_str *s, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    tg_reserve(s, (size_t)n);
    va_start(ap, fmt);
    vsnprintf(s->p + s->n, (size_t)n + 1, fmt, ap);
    va_end(ap);
    s->n += (size_t)n;
}

typedef struct tg_scene {
    tg_str bin, meshes, accessors, views, nodes, materials, lights, extras;
    int n_meshes, n_accessors, n_views, n_nodes, n_materials, n_lights, has_camera;
    tg_str camera_node, camera;
} tg_scene;

static inline void tg_init(tg_scene *b)
{
    memset(b, 0, sizeof *b);
}

static inline void tg_free(tg_scene *b)
{
    tg_str *all[] = {&b->bin,       &b->meshes, &b->accessors, &b->views,       &b->nodes,
                     &b->materials, &b->lights, &b->extras,    &b->camera_node, &b->camera};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        free(all[i]->p);
    memset(b, 0, sizeof *b);
}

/* A material; emission is radiance (split into factor x strength). */
static inline int tg_material(tg_scene *b, const float albedo[3], const float emission[3],
                              int double_sided)
{
    float e = fmaxf(emission[0], fmaxf(emission[1], emission[2]));
    float f[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++)
        f[k] = e > 0 ? emission[k] / e : 0.0f;
    tg_printf(&b->materials,
              "%s{\"pbrMetallicRoughness\":{\"baseColorFactor\":[%.9g,%.9g,%.9g,1]},"
              "\"emissiveFactor\":[%.9g,%.9g,%.9g],"
              "\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":%.9g}},"
              "\"doubleSided\":%s}",
              b->n_materials ? "," : "", albedo[0], albedo[1], albedo[2], f[0], f[1], f[2],
              e > 0 ? e : 1.0f, double_sided ? "true" : "false");
    return b->n_materials++;
}

/* Appends data to the buffer as one buffer view; returns the view index. */
static inline int tg_view(tg_scene *b, const void *data, size_t size)
{
    size_t off = b->bin.n;
    tg_bytes(&b->bin, data, size);
    tg_printf(&b->views, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}",
              b->n_views ? "," : "", off, size);
    return b->n_views++;
}

static inline int tg_accessor_vec3(tg_scene *b, const float *v, uint32_t n)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], v[3 * i + k]);
            hi[k] = fmaxf(hi[k], v[3 * i + k]);
        }
    int view = tg_view(b, v, (size_t)n * 3 * sizeof(float));
    tg_printf(&b->accessors,
              "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\","
              "\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]}",
              b->n_accessors ? "," : "", view, n, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    return b->n_accessors++;
}

/* One object: a node holding a mesh of one triangle primitive. nrm may be
 * NULL (the loader then computes normals from the faces). */
static inline void tg_mesh(tg_scene *b, const float *pos, const float *nrm, uint32_t nverts,
                           const uint32_t *idx, uint32_t ntris, int material)
{
    int ap = tg_accessor_vec3(b, pos, nverts);
    int an = nrm ? tg_accessor_vec3(b, nrm, nverts) : -1;
    int iv = tg_view(b, idx, (size_t)ntris * 3 * sizeof(uint32_t));
    tg_printf(&b->accessors,
              ",{\"bufferView\":%d,\"componentType\":5125,\"count\":%u,\"type\":\"SCALAR\"}", iv,
              ntris * 3);
    int ai = b->n_accessors++;
    if (an >= 0)
        tg_printf(
            &b->meshes,
            "%s{\"primitives\":[{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d},\"indices\":%d,"
            "\"material\":%d}]}",
            b->n_meshes ? "," : "", ap, an, ai, material);
    else
        tg_printf(&b->meshes,
                  "%s{\"primitives\":[{\"attributes\":{\"POSITION\":%d},\"indices\":%d,"
                  "\"material\":%d}]}",
                  b->n_meshes ? "," : "", ap, ai, material);
    tg_printf(&b->nodes, "%s{\"mesh\":%d}", b->n_nodes ? "," : "", b->n_meshes);
    b->n_meshes++;
    b->n_nodes++;
}

/* Geodesic sphere: an icosahedron subdivided `level` times (20 * 4^level
 * triangles), corners on the sphere of radius r about the origin, front
 * faces (CCW) inside. smooth: radial normals pointing inward; otherwise no
 * normals (flat faces: vertices are not shared). */
static inline void tg_icosphere(tg_scene *b, float r, int level, int smooth, int material)
{
    const float t = 1.6180339887f;
    const float ico_v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    const int ico_f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                              {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                              {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                              {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    uint32_t n = 20u << (2 * level);
    float *tri = malloc((size_t)n * 9 * sizeof(float));
    uint32_t count = 0;
    for (int f = 0; f < 20; f++)
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++)
                tri[(size_t)f * 9 + k * 3 + c] = ico_v[ico_f[f][k]][c];
    count = 20;
    for (int l = 0; l < level; l++) { /* split each triangle into four, in place from the back */
        float *next = malloc((size_t)count * 4 * 9 * sizeof(float));
        for (uint32_t i = 0; i < count; i++) {
            const float *a = tri + (size_t)i * 9, *bb = a + 3, *c = a + 6;
            float ab[3], bc[3], ca[3];
            for (int k = 0; k < 3; k++) {
                ab[k] = 0.5f * (a[k] + bb[k]);
                bc[k] = 0.5f * (bb[k] + c[k]);
                ca[k] = 0.5f * (c[k] + a[k]);
            }
            const float *sub[4][3] = {{a, ab, ca}, {ab, bb, bc}, {ca, bc, c}, {ab, bc, ca}};
            for (int s = 0; s < 4; s++)
                for (int k = 0; k < 3; k++)
                    memcpy(next + ((size_t)i * 4 + s) * 9 + k * 3, sub[s][k], 3 * sizeof(float));
        }
        free(tri);
        tri = next;
        count *= 4;
    }
    float *pos = malloc((size_t)count * 9 * sizeof(float));
    float *nrm = malloc((size_t)count * 9 * sizeof(float));
    uint32_t *idx = malloc((size_t)count * 3 * sizeof(uint32_t));
    for (uint32_t i = 0; i < count; i++) {
        float p[3][3];
        for (int k = 0; k < 3; k++) {
            const float *q = tri + (size_t)i * 9 + k * 3;
            double l = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2]);
            for (int c = 0; c < 3; c++)
                p[k][c] = (float)(q[c] / l * r);
        }
        /* Wind so that cross(p1 - p0, p2 - p0) points to the centre. */
        float e1[3], e2[3];
        for (int c = 0; c < 3; c++) {
            e1[c] = p[1][c] - p[0][c];
            e2[c] = p[2][c] - p[0][c];
        }
        float cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        if (cr[0] * p[0][0] + cr[1] * p[0][1] + cr[2] * p[0][2] > 0) {
            float tmp[3];
            memcpy(tmp, p[1], sizeof tmp);
            memcpy(p[1], p[2], sizeof tmp);
            memcpy(p[2], tmp, sizeof tmp);
        }
        for (int k = 0; k < 3; k++) {
            for (int c = 0; c < 3; c++) {
                pos[(size_t)i * 9 + k * 3 + c] = p[k][c];
                nrm[(size_t)i * 9 + k * 3 + c] = -p[k][c] / r;
            }
            idx[(size_t)i * 3 + k] = i * 3 + (uint32_t)k;
        }
    }
    tg_mesh(b, pos, smooth ? nrm : NULL, count * 3, idx, count, material);
    free(tri);
    free(pos);
    free(nrm);
    free(idx);
}

/* Square of side 2 * half in the plane y = height, front face up (+Y). */
static inline void tg_plane(tg_scene *b, float half, float height, int material)
{
    const float pos[12] = {-half, height, -half, -half, height, half,
                           half,  height, half,  half,  height, -half};
    const float nrm[12] = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    tg_mesh(b, pos, nrm, 4, idx, 2, material);
}

/* Regular `segments`-gon of circumradius r in the plane y = height, centred
 * on the Y axis, front face down (-Y): a fan about the centre. */
static inline void tg_disk(tg_scene *b, float r, float height, uint32_t segments, int material)
{
    float *pos = malloc((size_t)(segments + 1) * 3 * sizeof(float));
    float *nrm = malloc((size_t)(segments + 1) * 3 * sizeof(float));
    uint32_t *idx = malloc((size_t)segments * 3 * sizeof(uint32_t));
    pos[0] = 0;
    pos[1] = height;
    pos[2] = 0;
    for (uint32_t i = 0; i < segments; i++) {
        double a = 2.0 * TG_PI * i / segments;
        pos[3 * (i + 1) + 0] = (float)(r * cos(a));
        pos[3 * (i + 1) + 1] = height;
        pos[3 * (i + 1) + 2] = (float)(r * sin(a));
    }
    for (uint32_t i = 0; i <= segments; i++) {
        nrm[3 * i] = 0;
        nrm[3 * i + 1] = -1;
        nrm[3 * i + 2] = 0;
    }
    /* (centre, a_i, a_{i+1}) with angle growing from +X to +Z: the cross
     * product (a_i - c) x (a_{i+1} - c) points to -Y. */
    for (uint32_t i = 0; i < segments; i++) {
        idx[3 * i] = 0;
        idx[3 * i + 1] = i + 1;
        idx[3 * i + 2] = (i + 1) % segments + 1;
    }
    tg_mesh(b, pos, nrm, segments + 1, idx, segments, material);
    free(pos);
    free(nrm);
    free(idx);
}

/* Rotation (x, y, z, w) that turns -Z to the unit direction of f (+Y up
 * unless f is along it, then +Z up): how glTF orients cameras and lights. */
static inline void tg_look_quat(const float fwd[3], double q[4])
{
    double f[3] = {fwd[0], fwd[1], fwd[2]};
    double len = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int k = 0; k < 3; k++)
        f[k] /= len;
    double up[3] = {0, 1, 0};
    if (fabs(f[1]) > 0.999) {
        up[1] = 0;
        up[2] = 1;
    }
    double rt[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2],
                    f[0] * up[1] - f[1] * up[0]};
    double rl = sqrt(rt[0] * rt[0] + rt[1] * rt[1] + rt[2] * rt[2]);
    for (int k = 0; k < 3; k++)
        rt[k] /= rl;
    double u[3] = {rt[1] * f[2] - rt[2] * f[1], rt[2] * f[0] - rt[0] * f[2],
                   rt[0] * f[1] - rt[1] * f[0]};
    /* Rotation matrix columns: right, up, -forward. */
    double m[3][3] = {
        {rt[0], u[0], -f[0]}, {rt[1], u[1], -f[1]}, {rt[2], u[2], -f[2]}}; /* m[row][col] */
    double tr = m[0][0] + m[1][1] + m[2][2];
    if (tr > 0) {
        double s = sqrt(tr + 1.0) * 2;
        q[3] = 0.25 * s;
        q[0] = (m[2][1] - m[1][2]) / s;
        q[1] = (m[0][2] - m[2][0]) / s;
        q[2] = (m[1][0] - m[0][1]) / s;
    } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
        double s = sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2;
        q[3] = (m[2][1] - m[1][2]) / s;
        q[0] = 0.25 * s;
        q[1] = (m[0][1] + m[1][0]) / s;
        q[2] = (m[0][2] + m[2][0]) / s;
    } else if (m[1][1] > m[2][2]) {
        double s = sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2;
        q[3] = (m[0][2] - m[2][0]) / s;
        q[0] = (m[0][1] + m[1][0]) / s;
        q[1] = 0.25 * s;
        q[2] = (m[1][2] + m[2][1]) / s;
    } else {
        double s = sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2;
        q[3] = (m[1][0] - m[0][1]) / s;
        q[0] = (m[0][2] + m[2][0]) / s;
        q[1] = (m[1][2] + m[2][1]) / s;
        q[2] = 0.25 * s;
    }
}

/* A perspective camera at eye looking at target. */
static inline void tg_camera(tg_scene *b, const float eye[3], const float target[3], float yfov_deg,
                             float znear)
{
    float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    double q[4];
    tg_look_quat(f, q);
    tg_printf(
        &b->camera_node,
        "{\"camera\":0,\"translation\":[%.9g,%.9g,%.9g],\"rotation\":[%.12g,%.12g,%.12g,%.12g]}",
        eye[0], eye[1], eye[2], q[0], q[1], q[2], q[3]);
    tg_printf(&b->camera,
              "{\"type\":\"perspective\",\"perspective\":{\"yfov\":%.9g,\"znear\":%.9g}}",
              yfov_deg * TG_PI / 180.0, znear);
    b->has_camera = 1;
}

/* A KHR_lights_punctual light: `type_json` is the light object's body
 * without braces; placed at p pointing along dir. */
static inline void tg_light(tg_scene *b, const char *type_json, const float p[3],
                            const float dir[3])
{
    double q[4];
    tg_look_quat(dir, q);
    tg_printf(&b->lights, "%s{%s}", b->n_lights ? "," : "", type_json);
    tg_printf(&b->nodes,
              "%s{\"translation\":[%.9g,%.9g,%.9g],\"rotation\":[%.12g,%.12g,%.12g,%.12g],"
              "\"extensions\":{\"KHR_lights_punctual\":{\"light\":%d}}}",
              b->n_nodes ? "," : "", p[0], p[1], p[2], q[0], q[1], q[2], q[3], b->n_lights);
    b->n_lights++;
    b->n_nodes++;
}

/* A point light of radiant intensity I (white) at p. */
static inline void tg_point_light(tg_scene *b, const float p[3], float intensity)
{
    char body[64];
    const float down[3] = {0, -1, 0};
    snprintf(body, sizeof body, "\"type\":\"point\",\"intensity\":%.9g", intensity);
    tg_light(b, body, p, down);
}

/* The scene's environment map (a file name relative to the base dir). */
static inline void tg_environment(tg_scene *b, const char *uri, float intensity, float rotation_deg)
{
    tg_printf(&b->extras,
              "\"extras\":{\"gibench\":{\"environment\":{\"uri\":\"%s\",\"intensity\":%.9g,"
              "\"rotation_deg\":%.9g}}},",
              uri, intensity, rotation_deg);
}

static inline void tg_base64(tg_str *out, const unsigned char *d, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    tg_reserve(out, (n + 2) / 3 * 4);
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) |
                     (i + 2 < n ? d[i + 2] : 0);
        char q[4] = {tab[v >> 18 & 63], tab[v >> 12 & 63], i + 1 < n ? tab[v >> 6 & 63] : '=',
                     i + 2 < n ? tab[v & 63] : '='};
        tg_bytes(out, q, 4);
    }
}

/* The glTF text of the scene built so far. */
static inline char *tg_json(tg_scene *b)
{
    tg_str j = {0};
    tg_printf(&j,
              "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_materials_emissive_"
              "strength\"%s],",
              b->n_lights ? ",\"KHR_lights_punctual\"" : "");
    int cam_node = b->has_camera ? b->n_nodes : -1;
    tg_printf(&j, "\"scene\":0,\"scenes\":[{%s\"nodes\":[", b->extras.p ? b->extras.p : "");
    for (int i = 0; i < b->n_nodes + (cam_node >= 0); i++)
        tg_printf(&j, "%s%d", i ? "," : "", i);
    tg_printf(&j, "]}],\"nodes\":[%s", b->nodes.p ? b->nodes.p : "");
    if (b->has_camera)
        tg_printf(&j, "%s%s],\"cameras\":[%s]", b->n_nodes ? "," : "", b->camera_node.p,
                  b->camera.p);
    else
        tg_printf(&j, "]");
    tg_printf(&j, ",\"materials\":[%s],\"meshes\":[%s],\"accessors\":[%s],\"bufferViews\":[%s]",
              b->materials.p ? b->materials.p : "", b->meshes.p ? b->meshes.p : "",
              b->accessors.p ? b->accessors.p : "", b->views.p ? b->views.p : "");
    if (b->n_lights)
        tg_printf(&j, ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[%s]}}", b->lights.p);
    tg_printf(&j,
              ",\"buffers\":[{\"byteLength\":%zu,\"uri\":\"data:application/octet-stream;base64,",
              b->bin.n);
    tg_base64(&j, (const unsigned char *)b->bin.p, b->bin.n);
    tg_printf(&j, "\"}]}");
    return j.p;
}

/* Loads the scene (external files from base_dir, NULL for none) and frees
 * the builder. */
static inline gi_scene *tg_load(tg_scene *b, const char *base_dir, gi_error *err)
{
    char *json = tg_json(b);
    gi_scene *s = gi_scene_load_memory(json, strlen(json), 0, base_dir, "test-scene.gltf", err);
    free(json);
    tg_free(b);
    return s;
}

#endif

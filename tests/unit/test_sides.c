/* glTF fidelity of the core (issue 28): flat normals where a primitive has
 * no NORMAL, and the one rule for sides (gi/scene.h) in ray casting
 * (gi_rt), the G-buffer and depth maps, on the hand-made scenes of
 * tests/data/truth/:
 *  - box_light_flat.gltf: every vertex normal is its triangle's face normal
 *    (the old loader averaged the shared block corners);
 *  - sphere_in_ss.gltf: a sphere wound inward, single-sided, seen from
 *    outside. Along the ray from the camera through its centre the near
 *    half is culled: the first surface is the far half's inside, at
 *    |eye - centre| + r; nothing occludes the segment from the eye to the
 *    centre; the G-buffer and a depth map see the far half too, the
 *    G-buffer's normal facing the eye. With GI_RT_ALL_FACES the near half
 *    is hit, as the old code hit it always;
 *  - sphere_out_ds.gltf: a double-sided sphere wound outward is hit from
 *    its centre, gi_side says GI_SIDE_BACK and reverses the normal;
 *  - a triangle without NORMAL under a mirroring node (scale z = -1): its
 *    flat normal points out of the front in world space (glTF: a negative
 *    determinant reverses the winding), and a morphing one gets the face
 *    normal of its morphed corners. */
#include "check.h"
#include "gpu_fixture.h"
#include "gi/gpu.h"
#include "gi/passes.h"
#include "gi/raytrace.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void test_flat_normals(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_TEST_DATA "/truth/box_light_flat.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    uint32_t bad = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const uint32_t *idx = s->indices + 3 * (size_t)t;
        gi_vec3 p0 = gi_v3_load(s->vertices[idx[0]].position);
        gi_vec3 ng =
            gi_v3_normalize(gi_v3_cross(gi_v3_sub(gi_v3_load(s->vertices[idx[1]].position), p0),
                                        gi_v3_sub(gi_v3_load(s->vertices[idx[2]].position), p0)));
        for (int k = 0; k < 3; k++)
            bad += gi_v3_dot(gi_v3_load(s->vertices[idx[k]].normal), ng) < 0.99999f;
    }
    printf("flat normals: %u of %u vertex normals differ from the face normal\n", bad,
           3 * s->triangle_count);
    CHECK(s->triangle_count > 0 && bad == 0);
    gi_scene_free(s);
}

/* The eye, the unit direction to the ball's centre, and their distance. */
typedef struct ball_ray {
    gi_vec3 eye, d, centre;
    float dist, radius;
} ball_ray;

static int find_ball(const gi_scene *s, ball_ray *b)
{
    for (uint32_t o = 0; o < s->object_count; o++) {
        if (!s->objects[o].name || strcmp(s->objects[o].name, "ball") != 0)
            continue;
        const float *lb = s->objects[o].local_bounds;
        float m[16];
        gi_scene_object_transform(s, o, 0.0f, m);
        b->centre = gi_mat4_point(
            m, gi_v3(0.5f * (lb[0] + lb[3]), 0.5f * (lb[1] + lb[4]), 0.5f * (lb[2] + lb[5])));
        b->radius = 0.5f * (lb[3] - lb[0]);
        b->eye = gi_scene_camera_at(s, 0, 0.0f).eye;
        gi_vec3 to = gi_v3_sub(b->centre, b->eye);
        b->dist = gi_v3_length(to);
        b->d = gi_v3_scale(to, 1.0f / b->dist);
        return 1;
    }
    return 0;
}

static void test_rt_single_sided(const gi_scene *s, const ball_ray *b)
{
    gi_error err;
    gi_rt *rt = NULL, *raw = NULL;
    CHECK_MSG(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK, "%s", err.text);
    CHECK_MSG(gi_rt_create_ex(s, 0.0f, GI_RT_ALL_FACES, &raw, &err) == GI_OK, "%s", err.text);
    if (!rt || !raw)
        goto done;
    gi_rt_hit h;
    int hit = gi_rt_intersect(rt, b->eye, b->d, 0.0f, INFINITY, &h);
    printf("single-sided ball: hit at %.4f, near side %.4f, far side %.4f\n", hit ? h.t : -1.0,
           b->dist - b->radius, b->dist + b->radius);
    /* The icosphere's faces lie within 5 % of r inside the sphere. */
    CHECK(hit && fabsf(h.t - (b->dist + b->radius)) < 0.05f * b->radius);
    CHECK(hit && gi_side(0, h.ng, gi_v3_scale(b->d, -1.0f)) == GI_SIDE_FRONT);
    CHECK(!gi_rt_occluded(rt, b->eye, b->d, 0.0f, b->dist));
    CHECK(gi_rt_occluded(rt, b->eye, b->d, 0.0f, b->dist + 1.1f * b->radius));
    uint32_t tri;
    float t, u, v;
    CHECK(gi_rt_intersect_tuv(rt, b->eye, b->d, 0.0f, INFINITY, &t, &u, &v, &tri) &&
          fabsf(t - (b->dist + b->radius)) < 0.05f * b->radius);
    /* Raw geometry: the near half is there. */
    hit = gi_rt_intersect(raw, b->eye, b->d, 0.0f, INFINITY, &h);
    CHECK(hit && fabsf(h.t - (b->dist - b->radius)) < 0.05f * b->radius);
    CHECK(gi_side(0, h.ng, gi_v3_scale(b->d, -1.0f)) == GI_SIDE_NONE);
    CHECK(gi_rt_occluded(raw, b->eye, b->d, 0.0f, b->dist));
done:
    gi_rt_free(rt);
    gi_rt_free(raw);
}

static void test_rt_double_sided(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_TEST_DATA "/truth/sphere_out_ds.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    gi_rt *rt = NULL;
    if (s)
        CHECK_MSG(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK, "%s", err.text);
    if (rt) {
        gi_camera_frame cam = gi_scene_camera_at(s, 0, 0.0f);
        gi_rt_hit h;
        int hit = gi_rt_intersect(rt, cam.eye, cam.forward, 0.0f, INFINITY, &h);
        CHECK(hit && h.t > 0.9f && h.t < 1.01f);
        gi_vec3 wo = gi_v3_scale(cam.forward, -1.0f);
        gi_side_kind side = gi_side(1, h.ng, wo);
        CHECK(side == GI_SIDE_BACK);
        CHECK(gi_v3_dot(gi_side_normal(side, h.ng), wo) > 0.0f);
    }
    gi_rt_free(rt);
    gi_scene_free(s);
}

/* The first two peeled surfaces of one view at the centre texel
 * (FLT_MAX: none). 0 when the renderer fails (a check says so). */
static int depth_two(gi_gpu_scene *gs, gi_sides mode, const gi_depth_view *dv, uint32_t W,
                     float out[2])
{
    gi_error err;
    gi_depth_desc d2 = {.size = W, .surfaces = 2, .metric = GI_DEPTH_EYE_Z, .receiver_side = mode};
    gi_depth_renderer *r2 = gi_depth_renderer_create(&d2, &err);
    CHECK_MSG(r2 != NULL, "%s", err.text);
    if (!r2)
        return 0;
    GLuint t2 = gi_depth_texture_create(r2, 1);
    CHECK(gi_depth_render(r2, gs, dv, 1, t2, 0, &err) == GI_OK);
    float *m2 = gi_depth_read_layer(t2, W, 0);
    const size_t i = ((size_t)(W / 2) * W + W / 2) * 4;
    out[0] = m2 ? m2[i] : NAN;
    out[1] = m2 ? m2[i + 1] : NAN;
    free(m2);
    glDeleteTextures(1, &t2);
    gi_depth_renderer_free(r2);
    return 1;
}

/* The dual-depth modes of gi_sides on the inward single-sided ball. From
 * outside, along the axis: its near half is seen from behind (a surface
 * for rays cast from the receivers inside it toward the eye), its far half
 * from the front. BOTH: near, far. EYE_THEN_BOTH: far, then what lies
 * behind the ball. RECEIVERS_THEN_BOTH: near, far. ANY_THEN_RECEIVERS:
 * near (a surface for the receivers, so not negated), far. From the centre
 * every face is seen from the front and none is a surface for the
 * receivers: ANY_THEN_RECEIVERS gives -r (marked) and no second surface,
 * RECEIVERS_THEN_BOTH nothing. A mode beyond the enum is refused. */
static void test_depth_modes(gi_gpu_scene *gs, const ball_ray *b, const gi_depth_view *dv,
                             uint32_t W)
{
    const float nr = b->dist - b->radius, fr = b->dist + b->radius, tol = 0.05f * b->radius;
    const struct {
        gi_sides mode;
        float want0, want1; /* FLT_MAX: none; NAN: anything behind the ball */
    } outside[] = {{GI_SIDES_BOTH, nr, fr},
                   {GI_SIDES_EYE_THEN_BOTH, fr, NAN},
                   {GI_SIDES_RECEIVERS_THEN_BOTH, nr, fr},
                   {GI_SIDES_ANY_THEN_RECEIVERS, nr, fr}};
    for (size_t k = 0; k < sizeof outside / sizeof outside[0]; k++) {
        float z[2];
        if (!depth_two(gs, outside[k].mode, dv, W, z))
            return;
        printf("depth map, receiver_side %d: surfaces %.4f, %.4g (want %.4f, %.4g)\n",
               (int)outside[k].mode, z[0], z[1], outside[k].want0, outside[k].want1);
        CHECK(fabsf(z[0] - outside[k].want0) < tol);
        CHECK(isnan(outside[k].want1)       ? z[1] > fr + tol
              : outside[k].want1 == FLT_MAX ? z[1] == FLT_MAX
                                            : fabsf(z[1] - outside[k].want1) < tol);
    }
    gi_depth_view c = {.projection = GI_PROJ_PERSPECTIVE};
    gi_mat4_look_at(c.view, b->centre, gi_v3_add(b->centre, b->d), gi_v3(0, 1, 0));
    gi_mat4_perspective(c.proj, 1.0f, 1.0f, 0.01f * b->radius, 10.0f * b->radius);
    float z[2];
    if (!depth_two(gs, GI_SIDES_ANY_THEN_RECEIVERS, &c, W, z))
        return;
    printf("depth map from the centre, receiver_side %d: %.4f, %.4g (want %.4f, none)\n",
           GI_SIDES_ANY_THEN_RECEIVERS, z[0], z[1], -b->radius);
    CHECK(fabsf(z[0] + b->radius) < tol && z[1] == FLT_MAX);
    if (!depth_two(gs, GI_SIDES_RECEIVERS_THEN_BOTH, &c, W, z))
        return;
    printf("depth map from the centre, receiver_side %d: %.4g (want none)\n",
           GI_SIDES_RECEIVERS_THEN_BOTH, z[0]);
    CHECK(z[0] == FLT_MAX);
    gi_error err;
    gi_depth_desc bad = {.size = W, .receiver_side = (gi_sides)(GI_SIDES_ANY_THEN_RECEIVERS + 1)};
    gi_depth_renderer *r = gi_depth_renderer_create(&bad, &err);
    printf("receiver_side %d: %s\n", (int)bad.receiver_side, r ? "accepted" : err.text);
    CHECK(r == NULL);
    gi_depth_renderer_free(r);
}

/* The G-buffer and a depth map through the file's camera: the centre pixel
 * shows the ball's far half. */
static void test_raster_single_sided(const gi_scene *s, gi_gpu_scene *gs, const ball_ray *b)
{
    gi_error err;
    const uint32_t W = 33; /* odd: a pixel centre on the axis */
    gi_camera_frame cam = gi_scene_camera_at(s, 0, 0.0f);
    float view[16], proj[16];
    gi_mat4_look_at(view, b->eye, b->centre, cam.up);
    gi_mat4_perspective(proj, cam.yfov, 1.0f, cam.znear, cam.zfar);
    gi_gbuffer *gb = gi_gbuffer_create(W, W, &err);
    CHECK_MSG(gb != NULL, "%s", err.text);
    if (!gb)
        return;
    CHECK(gi_gbuffer_render(gb, gs, view, proj, &err) == GI_OK);
    float *pos = malloc(W * W * 16), *nrm = malloc(W * W * 16);
    glGetTextureImage(gb->tex_position, 0, GL_RGBA, GL_FLOAT, (GLsizei)(W * W * 16), pos);
    glGetTextureImage(gb->tex_normal, 0, GL_RGBA, GL_FLOAT, (GLsizei)(W * W * 16), nrm);
    size_t i = ((size_t)(W / 2) * W + W / 2) * 4;
    printf("G-buffer: centre depth %.4f (far side %.4f)\n", pos[i + 3], b->dist + b->radius);
    CHECK(fabsf(pos[i + 3] - (b->dist + b->radius)) < 0.05f * b->radius);
    CHECK(nrm[i] * -b->d.x + nrm[i + 1] * -b->d.y + nrm[i + 2] * -b->d.z > 0.9f);
    free(pos);
    free(nrm);
    gi_gbuffer_free(gb);

    gi_depth_desc desc = {.size = W, .surfaces = 1, .metric = GI_DEPTH_EYE_Z};
    gi_depth_renderer *dr = gi_depth_renderer_create(&desc, &err);
    CHECK_MSG(dr != NULL, "%s", err.text);
    if (!dr)
        return;
    GLuint tex = gi_depth_texture_create(dr, 1);
    gi_depth_view dv = {.projection = GI_PROJ_PERSPECTIVE};
    memcpy(dv.view, view, sizeof view);
    memcpy(dv.proj, proj, sizeof proj);
    CHECK(gi_depth_render(dr, gs, &dv, 1, tex, 0, &err) == GI_OK);
    float *map = gi_depth_read_layer(tex, W, 0);
    printf("depth map: centre %.4f\n", map ? map[i] : -1.0f);
    CHECK(map && fabsf(map[i] - (b->dist + b->radius)) < 0.05f * b->radius);
    free(map);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);

    test_depth_modes(gs, b, &dv, W);

    /* The depth atlas: seen from the eye the far half, seen from the
     * receivers (inside the ball, behind the near half) the near half. */
    for (int mode = GI_SIDES_EYE; mode <= GI_SIDES_RECEIVERS; mode++) {
        gi_depth_atlas_desc ad = {.tile = W,
                                  .capacity = 1,
                                  .projection = GI_PROJ_PERSPECTIVE,
                                  .metric = GI_DEPTH_EYE_Z,
                                  .receiver_side = (gi_sides)mode};
        gi_depth_atlas *at = gi_depth_atlas_create(&ad, &err);
        CHECK_MSG(at != NULL, "%s", err.text);
        if (!at)
            return;
        CHECK(gi_depth_atlas_render(at, gs, &dv, 1, &err) == GI_OK);
        float *tile = gi_depth_atlas_read_tile(at, 0);
        const float want = mode == GI_SIDES_EYE ? b->dist + b->radius : b->dist - b->radius;
        const float got = tile ? tile[(W / 2) * W + W / 2] : -1.0f;
        printf("depth atlas, receiver_side %d: centre %.4f (want %.4f)\n", mode, got, want);
        CHECK(fabsf(got - want) < 0.05f * b->radius);
        free(tile);
        gi_depth_atlas_free(at);
    }
}

/* Standard base64 of n bytes into out (4 (n + 2) / 3 characters + NUL). */
static void base64(const unsigned char *d, size_t n, char *out)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) |
                     (i + 2 < n ? d[i + 2] : 0);
        *out++ = tab[v >> 18 & 63];
        *out++ = tab[v >> 12 & 63];
        *out++ = i + 1 < n ? tab[v >> 6 & 63] : '=';
        *out++ = i + 2 < n ? tab[v & 63] : '=';
    }
    *out = '\0';
}

static void test_mirrored_and_morphed_flat(void)
{
    /* One triangle (0,0,0) (1,0,0) (0,1,0) without NORMAL; a morph target
     * lifting corner 2 by +Z. Node 0 mirrors it (scale z = -1), node 1
     * morphs it at weight 1. */
    const float data[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
    char b64[128], json[2048];
    base64((const unsigned char *)data, sizeof data, b64);
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],"
             "\"nodes\":[{\"mesh\":0,\"scale\":[1,1,-1]},{\"mesh\":1,\"translation\":[3,0,0]}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]},"
             "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"targets\":[{\"POSITION\":1}]}],"
             "\"weights\":[1]}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":"
             "\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,"
             "\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[0,0,1]}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,"
             "\"byteLength\":36}],\"buffers\":[{\"byteLength\":72,\"uri\":"
             "\"data:application/octet-stream;base64,%s\"}]}",
             b64);
    gi_error err;
    gi_scene *s = gi_scene_load_memory(json, strlen(json), 0, NULL, "mirror.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    CHECK(s->object_count == 2);
    gi_rt *rt = NULL;
    CHECK_MSG(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK, "%s", err.text);
    if (rt) {
        /* The mirrored triangle: its local front is +Z; the node mirrors z, and
         * glTF makes the winding clockwise under a negative determinant, so the
         * front stays where the mesh has it, mirrored: -Z (world corners wind
         * counter-clockwise seen from +Z, but that is now the back). */
        gi_rt_hit h;
        CHECK(gi_rt_intersect(rt, gi_v3(0.2f, 0.2f, -1.0f), gi_v3(0, 0, 1), 0, INFINITY, &h) &&
              h.object == 0 && h.ng.z < -0.99f);
        CHECK(!gi_rt_intersect(rt, gi_v3(0.2f, 0.2f, 1.0f), gi_v3(0, 0, -1), 0, INFINITY, &h));
        const float *n = gi_rt_normals(rt);
        uint32_t v0 = s->objects[0].first_vertex;
        printf("mirrored flat triangle: world shading normal %.3f %.3f %.3f\n", n[3 * v0],
               n[3 * v0 + 1], n[3 * v0 + 2]);
        CHECK(n[3 * v0 + 2] < -0.99f);
    }
    gi_rt_free(rt);
    gi_vertex out[3];
    CHECK(s->objects[1].vertex_count == 3);
    gi_scene_object_vertices(s, 1, 0.0f, out);
    const float r = 0.70710678f; /* cross((1,0,0), (0,1,1)) / sqrt 2 */
    printf("morphed flat triangle: normal %.3f %.3f %.3f\n", out[0].normal[0], out[0].normal[1],
           out[0].normal[2]);
    for (int k = 0; k < 3; k++)
        CHECK(fabsf(out[k].normal[0]) < 1e-5f && fabsf(out[k].normal[1] + r) < 1e-5f &&
              fabsf(out[k].normal[2] - r) < 1e-5f);
    gi_scene_free(s);
}

int main(void)
{
    test_mirrored_and_morphed_flat();
    test_flat_normals();
    test_rt_double_sided();
    gi_gpu *gpu;
    gi_scene *s;
    gi_gpu_scene *gs;
    if (gpu_fixture_load(GI_TEST_DATA "/truth/sphere_in_ss.gltf", &gpu, &s, &gs)) {
        ball_ray b;
        CHECK(find_ball(s, &b));
        test_rt_single_sided(s, &b);
        if (gs)
            test_raster_single_sided(s, gs, &b);
    }
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
    return gi_test_finish();
}

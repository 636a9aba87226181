/* The scene loader on the valid scenes of tests/data/valid (written by
 * tests/data/gen_scenes.py): counts, materials and textures, emission,
 * lights, cameras, parent x child transforms and animation sampling against
 * values worked out by hand, computed normals, bounds. */
#include "check.h"

#include "gi/envmap.h"
#include "gi/scene.h"
#include "gi/tonemap.h"

#include <string.h>

#define VALID GI_TEST_DATA "/valid/"
#define TOL 1e-5

static gi_scene *load(const char *path)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    return s;
}

#define CHECK_V3(v, X, Y, Z, tol)                                                                  \
    do {                                                                                           \
        CHECK_NEAR((v).x, X, tol);                                                                 \
        CHECK_NEAR((v).y, Y, tol);                                                                 \
        CHECK_NEAR((v).z, Z, tol);                                                                 \
    } while (0)

static void test_quad(void)
{
    gi_scene *s = load(VALID "quad.gltf");
    if (!s)
        return;
    /* No NORMAL in the file: flat normals, so each triangle owns its three
     * vertices (glTF 2.0 §3.7.2.1; issue 28). */
    CHECK(s->vertex_count == 6 && s->triangle_count == 2 && s->object_count == 1);
    CHECK(s->material_count == 1 && s->node_count == 2 && s->camera_count == 1);
    CHECK(s->light_count == 0 && s->emitter_count == 0 && s->texture_count == 0);
    CHECK(s->animation_length == 0.0f && !s->objects[0].animated && !s->has_environment);
    CHECK(strcmp(s->objects[0].name, "quad") == 0 && strcmp(s->materials[0].name, "white") == 0);
    CHECK(strcmp(s->path, VALID "quad.gltf") == 0);
    const gi_object *o = &s->objects[0];
    CHECK(o->first_vertex == 0 && o->vertex_count == 6 && o->first_triangle == 0 &&
          o->triangle_count == 2 && o->node == 0);
    for (uint32_t i = 0; i < 6; i++) { /* no NORMAL in the file: the face normal, +Z */
        const gi_vertex *v = &s->vertices[i];
        CHECK(v->object == 0 && v->material == 0);
        CHECK_NEAR(v->normal[0], 0, TOL);
        CHECK_NEAR(v->normal[1], 0, TOL);
        CHECK_NEAR(v->normal[2], 1, TOL);
        CHECK(v->uv[0] == 0.0f && v->uv[1] == 0.0f);
    }
    CHECK(s->indices[3] == 3 && s->indices[4] == 4 && s->indices[5] == 5);
    CHECK(memcmp(s->vertices[3].position, s->vertices[0].position, sizeof(float[3])) == 0 &&
          memcmp(s->vertices[4].position, s->vertices[2].position, sizeof(float[3])) == 0);
    CHECK_NEAR(s->materials[0].albedo[1], 0.8, TOL);
    CHECK(s->materials[0].albedo_texture == -1 && s->materials[0].exponent == 0.0f &&
          !s->materials[0].mirror && !s->materials[0].double_sided);
    float want[6] = {-1, -1, 0, 1, 1, 0};
    for (int k = 0; k < 6; k++) {
        CHECK_NEAR(o->local_bounds[k], want[k], TOL);
        CHECK_NEAR(s->bounds[k], want[k], TOL);
    }

    /* the file's camera, by name and by "#k" */
    CHECK(gi_scene_find_camera(s, "main") == 0 && gi_scene_find_camera(s, "#0") == 0);
    CHECK(gi_scene_find_camera(s, "#1") == -1 && gi_scene_find_camera(s, "nope") == -1);
    CHECK(gi_scene_find_camera(s, "#") == -1 && gi_scene_find_camera(s, "#0x") == -1);
    CHECK_NEAR(s->cameras[0].aspect, 1.5, TOL);
    gi_camera_frame c = gi_scene_camera_at(s, 0, 0.0f);
    CHECK_V3(c.eye, 0, 0, 3, TOL);
    CHECK_V3(c.forward, 0, 0, -1, TOL);
    CHECK_V3(c.up, 0, 1, 0, TOL);
    CHECK_NEAR(c.yfov, 0.8, TOL);
    CHECK_NEAR(c.znear, 0.1, TOL);
    CHECK_NEAR(c.zfar, sqrt(11.0) * 1.01, 1e-4); /* infinite in the file: farthest corner */
    CHECK_NEAR(c.world_from_camera[14], 3, TOL);
    CHECK_NEAR(c.world_from_camera[10], 1, TOL); /* camera +Z = world +Z */

    /* the default view frames the bounds from +Z */
    gi_camera_frame d = gi_scene_camera_at(s, -1, 0.0f);
    double radius = sqrt(2.0), dist = radius / sin(45.0 * 3.14159265358979 / 360.0);
    CHECK_V3(d.eye, 0, 0, dist, 1e-4);
    CHECK_V3(d.forward, 0, 0, -1, TOL);
    CHECK_V3(d.up, 0, 1, 0, TOL);
    CHECK(d.znear > 0.0f && d.znear < dist - radius && d.zfar > dist + radius);
    gi_scene_free(s);
}

/* Each valid scene as GLB (buffer in the BIN chunk, images in buffer views)
 * gives the same data as its .gltf. */
static void compare_glb(const char *name)
{
    char a_path[256], b_path[256];
    snprintf(a_path, sizeof a_path, VALID "%s.gltf", name);
    snprintf(b_path, sizeof b_path, VALID "%s.glb", name);
    gi_scene *a = load(a_path), *b = load(b_path);
    if (a && b) {
        CHECK_MSG(a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
                      a->object_count == b->object_count &&
                      a->material_count == b->material_count &&
                      a->texture_count == b->texture_count && a->light_count == b->light_count &&
                      a->camera_count == b->camera_count && a->node_count == b->node_count &&
                      a->emitter_count == b->emitter_count &&
                      a->animation_length == b->animation_length &&
                      a->has_environment == b->has_environment,
                  "%s: counts differ", name);
        CHECK(memcmp(a->vertices, b->vertices, a->vertex_count * sizeof(gi_vertex)) == 0);
        CHECK(memcmp(a->indices, b->indices, a->triangle_count * 3 * sizeof(uint32_t)) == 0);
        for (uint32_t i = 0; i < a->texture_count && i < b->texture_count; i++)
            CHECK_MSG(a->textures[i].width == b->textures[i].width &&
                          memcmp(a->textures[i].rgba, b->textures[i].rgba,
                                 (size_t)a->textures[i].width * a->textures[i].height * 16) == 0,
                      "%s: texture %u differs", name, i);
    }
    gi_scene_free(a);
    gi_scene_free(b);
}

static void test_glb(void)
{
    compare_glb("quad");
    compare_glb("animated");
    compare_glb("textured");
    compare_glb("lights");
    compare_glb("texture16");
}

/* The animated scene, worked by hand: parent = T(1,0,0) R_y(theta(t)) with
 * theta LINEAR 0 -> 90 deg over t 0..2; child = T(c(t)) S(s(t)) with c
 * LINEAR (0,0,1) @1, (0,2,1) @2, (0,2,5) @3 and s STEP 1 @0, 3 @1. */
static gi_vec3 expected_child_point(gi_vec3 p, double theta_deg, gi_vec3 c, double sc)
{
    double th = theta_deg * 3.14159265358979 / 180.0;
    double x = p.x * sc + c.x, y = p.y * sc + c.y, z = p.z * sc + c.z;
    return gi_v3((float)(x * cos(th) + z * sin(th) + 1.0), (float)y,
                 (float)(-x * sin(th) + z * cos(th)));
}

static void check_child_at(const gi_scene *s, float t, double theta, gi_vec3 c, double sc)
{
    float m[16];
    gi_scene_object_transform(s, 0, t, m);
    gi_vec3 p = gi_v3(1.0f, 0.5f, -0.25f);
    gi_vec3 got = gi_mat4_point(m, p), want = expected_child_point(p, theta, c, sc);
    CHECK_MSG(fabsf(got.x - want.x) < 1e-4f && fabsf(got.y - want.y) < 1e-4f &&
                  fabsf(got.z - want.z) < 1e-4f,
              "t=%g: got (%g %g %g) want (%g %g %g)", (double)t, (double)got.x, (double)got.y,
              (double)got.z, (double)want.x, (double)want.y, (double)want.z);
}

static void test_animated(void)
{
    gi_scene *s = load(VALID "animated.gltf");
    if (!s)
        return;
    CHECK(s->object_count == 2 && s->node_count == 3 && s->triangle_count == 3);
    CHECK_NEAR(s->animation_length, 3.0, TOL);
    const gi_object *child = &s->objects[0], *stat = &s->objects[1];
    CHECK(child->node == 1 && strcmp(child->name, "child") == 0 && child->animated);
    CHECK(stat->node == 2 && strcmp(stat->name, "static") == 0 && !stat->animated);
    CHECK(child->first_triangle == 0 && child->triangle_count == 1 && stat->first_triangle == 1 &&
          stat->triangle_count == 2 && stat->first_vertex == 3);
    CHECK(s->nodes[1].parent == 0 && s->nodes[0].parent == -1 && s->nodes[2].parent == -1);
    CHECK(s->nodes[1].anim_t.count == 3 && !s->nodes[1].anim_t.step && s->nodes[1].anim_s.step);
    for (uint32_t t = 0; t < s->triangle_count; t++) /* object index per vertex */
        CHECK(s->vertices[s->indices[t * 3]].object == (t == 0 ? 0u : 1u));

    check_child_at(s, 0.0f, 0.0, gi_v3(0, 0, 1), 1.0);   /* before the first translation key */
    check_child_at(s, 0.5f, 22.5, gi_v3(0, 0, 1), 1.0);  /* STEP scale still at key 0 */
    check_child_at(s, 1.0f, 45.0, gi_v3(0, 0, 1), 3.0);  /* slerp half-way; STEP reaches key 1 */
    check_child_at(s, 1.5f, 67.5, gi_v3(0, 1, 1), 3.0);  /* LINEAR between keys */
    check_child_at(s, 2.5f, 90.0, gi_v3(0, 2, 3), 3.0);  /* rotation after its last key */
    check_child_at(s, 10.0f, 90.0, gi_v3(0, 2, 5), 3.0); /* after every last key */
    check_child_at(s, -1.0f, 0.0, gi_v3(0, 0, 1), 1.0);  /* before time 0 */

    /* node transform = parent x child, checked on the parent alone too */
    float mp[16];
    gi_scene_node_transform(s, 0, 2.0f, mp);
    gi_vec3 q = gi_mat4_point(mp, gi_v3(1, 0, 0));
    CHECK_V3(q, 1, 0, -1, 1e-5);

    gi_vec3 p[3];
    gi_scene_triangle_world(s, 0, 10.0f, p);
    CHECK_V3(p[1], 6, 2, -3, 1e-4); /* local (1,0,0) */
    gi_scene_triangle_world(s, 1, 10.0f, p);
    CHECK_V3(p[0], -1, -3, 0, 1e-5); /* static quad: T(0,-2,0) */

    float b0[6], b10[6];
    gi_scene_bounds_at(s, 0.0f, b0);
    for (int k = 0; k < 6; k++)
        CHECK(b0[k] == s->bounds[k]);
    /* t = 0: triangle at x 1..2, y 0..1, z 1; quad x -1..1, y -3..-1, z 0 */
    float want0[6] = {-1, -3, 0, 2, 1, 1};
    for (int k = 0; k < 6; k++)
        CHECK_NEAR(b0[k], want0[k], 1e-5);
    gi_scene_bounds_at(s, 10.0f, b10); /* triangle corners (6,2,0) (6,2,-3) (6,5,0) */
    float want10[6] = {-1, -3, -3, 6, 5, 0};
    for (int k = 0; k < 6; k++)
        CHECK_NEAR(b10[k], want10[k], 1e-4);
    gi_scene_free(s);
}

static void test_textured(void)
{
    gi_scene *s = load(VALID "textured.gltf");
    if (!s)
        return;
    CHECK(s->material_count == 2 && s->texture_count == 1 && s->object_count == 2);
    const gi_material *g = &s->materials[0], *mir = &s->materials[1];
    CHECK(strcmp(g->name, "glossy") == 0 && g->albedo_texture == 0 && !g->mirror);
    CHECK_NEAR(g->ks[0], 0.2, TOL);
    CHECK_NEAR(g->ks[2], 0.4, TOL);
    CHECK_NEAR(g->exponent, 50, TOL);
    CHECK(mir->mirror && mir->double_sided && mir->albedo_texture == -1);
    CHECK_NEAR(mir->ks[1], 0.9, TOL);
    const gi_texture *t = &s->textures[0];
    CHECK(t->width == 2 && t->height == 2 && strcmp(t->name, "checker") == 0);
    /* row 0 = top: red, green; row 1: blue, grey 128 (sRGB-decoded) */
    double grey = gi_srgb_decode(128.0f / 255.0f);
    CHECK_NEAR(t->rgba[0], 1, TOL);
    CHECK_NEAR(t->rgba[5], 1, TOL);
    CHECK_NEAR(t->rgba[10], 1, TOL);
    CHECK_NEAR(t->rgba[12], grey, TOL);
    CHECK_NEAR(t->rgba[15], 1, TOL); /* alpha stays linear */

    float out[3];
    gi_scene_albedo(s, 0, (float[2]){0.25f, 0.25f}, out); /* red texel centre, x 0.5 factor */
    CHECK_NEAR(out[0], 0.5, TOL);
    CHECK_NEAR(out[1], 0, TOL);
    gi_scene_albedo(s, 0, (float[2]){0.75f, 0.75f}, out);
    CHECK_NEAR(out[2], 0.5 * grey, TOL);
    gi_scene_albedo(s, 0, (float[2]){0.5f, 0.25f}, out); /* half-way red -> green */
    CHECK_NEAR(out[0], 0.25, TOL);
    CHECK_NEAR(out[1], 0.25, TOL);
    gi_scene_albedo(s, 0, (float[2]){1.25f, -0.75f}, out); /* wraps to (0.25, 0.25) */
    CHECK_NEAR(out[0], 0.5, TOL);
    CHECK_NEAR(out[1], 0, TOL);
    gi_scene_albedo(s, 0, (float[2]){0.0f, 0.25f}, out); /* between texel 1 (wrapped) and 0 */
    CHECK_NEAR(out[0], 0.25, TOL);
    CHECK_NEAR(out[1], 0.25, TOL);
    gi_scene_albedo(s, 1, (float[2]){0.3f, 0.3f}, out); /* no texture: the factor */
    CHECK(out[0] == 0.0f && out[2] == 0.0f);

    /* float uvs, and normalised UNSIGNED_SHORT uvs; given normals normalised */
    CHECK(s->vertices[0].uv[0] == 0.0f && s->vertices[0].uv[1] == 1.0f);
    const gi_vertex *v = &s->vertices[s->objects[1].first_vertex + 2];
    CHECK(v->uv[0] == 1.0f && v->uv[1] == 1.0f && v->material == 1 && v->object == 1);
    CHECK_NEAR(v->normal[2], 1, TOL);
    gi_scene_free(s);
}

/* 16-bit texels: value / 65535, sRGB-decoded; alpha linear. */
static void test_texture16(void)
{
    gi_scene *s = load(VALID "texture16.gltf");
    if (!s)
        return;
    CHECK(s->texture_count == 1 && s->textures[0].width == 1);
    CHECK_NEAR(s->textures[0].rgba[0], gi_srgb_decode(32768.0f / 65535.0f), 1e-6);
    CHECK_NEAR(s->textures[0].rgba[3], 16384.0 / 65535.0, 1e-6);
    float out[3];
    gi_scene_albedo(s, 0, s->vertices[0].uv, out);
    CHECK_NEAR(out[1], gi_srgb_decode(32768.0f / 65535.0f), 1e-6);
    gi_scene_free(s);
}

static void test_lights(void)
{
    gi_scene *s = load(VALID "lights.gltf");
    if (!s)
        return;
    CHECK(s->object_count == 2 && s->light_count == 3 && s->material_count == 2);
    /* the floor has no material: the default white 0.8 Lambert, appended */
    const gi_material *def = &s->materials[1];
    CHECK(strcmp(def->name, "default") == 0 && def->albedo[0] == 0.8f && def->emission[0] == 0.0f);
    CHECK(s->vertices[s->objects[1].first_vertex].material == 1);
    /* emission = emissiveFactor x emissiveStrength; the lamp's two triangles emit */
    CHECK_NEAR(s->materials[0].emission[0], 4, TOL);
    CHECK_NEAR(s->materials[0].emission[1], 2, TOL);
    CHECK_NEAR(s->materials[0].emission[2], 1, TOL);
    CHECK(s->emitter_count == 2 && s->emitters[0] == 0 && s->emitters[1] == 1);
    CHECK(gi_scene_triangle_emission(s, 1)[0] == 4.0f &&
          gi_scene_triangle_emission(s, 2)[0] == 0.0f);

    const gi_light *bulb = &s->lights[0], *cone = &s->lights[1], *sun = &s->lights[2];
    CHECK(bulb->type == GI_LIGHT_POINT && strcmp(bulb->name, "bulb") == 0);
    CHECK_NEAR(bulb->intensity[0], 10, TOL);
    CHECK_NEAR(bulb->intensity[1], 5, TOL);
    CHECK_NEAR(bulb->intensity[2], 2.5, TOL);
    CHECK_NEAR(bulb->range, 20, TOL);
    CHECK(cone->type == GI_LIGHT_SPOT && cone->intensity[1] == 5.0f);
    CHECK_NEAR(cone->inner_cone, 0.2, TOL);
    CHECK_NEAR(cone->outer_cone, 0.6, TOL);
    CHECK(sun->type == GI_LIGHT_DIRECTIONAL && strcmp(sun->name, "sun_node") == 0);
    CHECK(sun->range == 0.0f && sun->intensity[2] == 2.0f);
    gi_light_frame f = gi_scene_light_at(s, 0, 0.0f);
    CHECK_V3(f.position, 0, 3, 0, TOL);
    f = gi_scene_light_at(s, 1, 0.0f); /* -90 deg about X: -Z turns to -Y */
    CHECK_V3(f.position, 1, 2, 0, TOL);
    CHECK_V3(f.direction, 0, -1, 0, TOL);
    f = gi_scene_light_at(s, 2, 0.0f);
    CHECK_V3(f.direction, 0, 0, -1, TOL);

    /* lamp quad turned +90 deg about X into y = 3; floor 4 x 4 at y = 0 */
    float want[6] = {-2, 0, -2, 2, 3, 2};
    for (int k = 0; k < 6; k++)
        CHECK_NEAR(s->bounds[k], want[k], 1e-5);
    CHECK_NEAR(s->vertices[0].normal[2], 1, TOL); /* local normal; world is +Y */

    /* the environment: path resolved beside the scene, map loaded */
    CHECK(s->has_environment && strcmp(s->environment.uri, "env/sky.pfm") == 0);
    CHECK(strcmp(s->environment.path, GI_TEST_DATA "/valid/env/sky.pfm") == 0);
    CHECK(s->environment.intensity == 2.0f && s->environment.rotation_deg == 90.0f);
    CHECK(s->envmap && s->envmap->width == 4 && s->envmap->height == 2);
    if (s->envmap) {
        CHECK_NEAR(s->envmap->rgb[0], 2, TOL); /* top-left texel (1,2,3) x intensity 2 */
        CHECK_NEAR(s->envmap->rgb[2], 6, TOL);
        CHECK_NEAR(s->envmap->rgb[4 * 3], 1, TOL); /* second row (0.5, ...) x 2 */
    }
    gi_scene_free(s);
}

/* Loading from memory: same scene; the base directory resolves the
 * environment; names go into messages and scene->path. */
static void test_memory(void)
{
    FILE *f = fopen(VALID "quad.gltf", "rb");
    CHECK(f != NULL);
    if (!f)
        return;
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    gi_error err;
    gi_scene *s = gi_scene_load_memory(buf, n, 0, NULL, "from-memory", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (s)
        CHECK(strcmp(s->path, "from-memory") == 0 && s->triangle_count == 2);
    gi_scene_free(s);
    gi_scene_free(NULL);
}

int main(void)
{
    test_quad();
    test_glb();
    test_animated();
    test_textured();
    test_texture16();
    test_lights();
    test_memory();
    return gi_test_finish();
}

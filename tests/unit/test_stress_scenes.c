/* The stress-case scenes (scenes/stress/, scripts/make_stress_scenes.py):
 * each loads, animated cameras and punctual lights follow their keyframes
 * (gi_scene_camera_at, gi_scene_light_at), and gi_scene_node_animated /
 * gi_scene_camera_animated / gi_scene_lights_animated say what moves, which
 * is what render --animate turns into update() flags. */
#include "check.h"
#include "gi/scene.h"

#include <stdio.h>
#include <string.h>

#define STRESS GI_SOURCE_DIR "/scenes/stress/"
#define TOL 1e-4

static gi_scene *load(const char *path)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    if (!s)
        fprintf(stderr, "%s\n", err.text);
    CHECK(s != NULL);
    return s;
}

static int object_named(const gi_scene *s, const char *name)
{
    for (uint32_t k = 0; k < s->object_count; k++)
        if (!strcmp(s->objects[k].name, name))
            return (int)k;
    return -1;
}

/* The light circles (2, 2.4, 2) with radius 1 once in 4 s, keys every 0.25 s. */
static void test_moving_light(void)
{
    gi_scene *s = load(STRESS "moving_light.gltf");
    if (!s)
        return;
    CHECK(s->light_count == 1 && s->emitter_count == 0);
    CHECK_NEAR(s->animation_length, 4.0, TOL);
    const float want[4][3] = {
        {3.0f, 2.4f, 2.0f}, {2.0f, 2.4f, 3.0f}, {1.0f, 2.4f, 2.0f}, {2.0f, 2.4f, 1.0f}};
    for (int k = 0; k < 4; k++) {
        gi_light_frame f = gi_scene_light_at(s, 0, (float)k);
        CHECK_NEAR(f.position.x, want[k][0], TOL);
        CHECK_NEAR(f.position.y, want[k][1], TOL);
        CHECK_NEAR(f.position.z, want[k][2], TOL);
    }
    CHECK(gi_scene_lights_animated(s) == 1);
    CHECK(gi_scene_camera_animated(s, 0) == 0);
    for (uint32_t k = 0; k < s->object_count; k++)
        CHECK(!s->objects[k].animated);
    gi_scene_free(s);
}

/* The camera's eye follows its five keys and it keeps looking at the block
 * (2, 0.8, 2) in between (slerp of look-at rotations). */
static void test_moving_camera(void)
{
    gi_scene *s = load(STRESS "moving_camera.gltf");
    if (!s)
        return;
    CHECK(s->camera_count == 1 && s->light_count == 0 && s->emitter_count == 2);
    const float eyes[5][3] = {{1.0f, 1.7f, -3.0f},
                              {0.9f, 1.8f, 0.8f},
                              {3.0f, 1.7f, -3.0f},
                              {2.0f, 2.2f, -4.5f},
                              {1.0f, 1.7f, -3.0f}};
    for (int k = 0; k < 5; k++) {
        gi_camera_frame c = gi_scene_camera_at(s, 0, (float)k);
        CHECK_NEAR(c.eye.x, eyes[k][0], TOL);
        CHECK_NEAR(c.eye.y, eyes[k][1], TOL);
        CHECK_NEAR(c.eye.z, eyes[k][2], TOL);
        gi_vec3 to = gi_v3_sub(gi_v3(2.0f, 0.8f, 2.0f), c.eye);
        CHECK_NEAR(gi_v3_dot(gi_v3_scale(to, 1.0f / gi_v3_length(to)), c.forward), 1.0, 1e-4);
    }
    gi_camera_frame a = gi_scene_camera_at(s, 0, 0.0f), b = gi_scene_camera_at(s, 0, 0.5f);
    CHECK(gi_v3_length(gi_v3_sub(a.eye, b.eye)) > 0.5f);
    CHECK(gi_scene_camera_animated(s, 0) == 1);
    CHECK(gi_scene_camera_animated(s, -1) == 0);
    CHECK(gi_scene_lights_animated(s) == 0);
    for (uint32_t k = 0; k < s->object_count; k++)
        CHECK(!s->objects[k].animated);
    gi_scene_free(s);
}

/* The block slides along z through the arch: z 0.8, 2.0, 3.3, 2.0, 0.8. */
static void test_hulls_overlap(void)
{
    gi_scene *s = load(STRESS "hulls_overlap.gltf");
    if (!s)
        return;
    int block = object_named(s, "block"), arch = object_named(s, "arch");
    CHECK(block >= 0 && arch >= 0);
    if (block < 0 || arch < 0) {
        gi_scene_free(s);
        return;
    }
    const float z[5] = {0.8f, 2.0f, 3.3f, 2.0f, 0.8f};
    for (int k = 0; k < 5; k++) {
        float m[16];
        gi_scene_object_transform(s, (uint32_t)block, (float)k, m);
        CHECK_NEAR(m[12], 2.0, TOL);
        CHECK_NEAR(m[14], z[k], TOL);
    }
    CHECK(s->objects[block].animated && !s->objects[arch].animated);
    CHECK(gi_scene_node_animated(s, s->objects[block].node) == 1);
    CHECK(gi_scene_node_animated(s, s->objects[arch].node) == 0);
    CHECK(gi_scene_node_animated(s, -1) == 0);
    CHECK(gi_scene_lights_animated(s) == 0 && gi_scene_camera_animated(s, 0) == 0);
    gi_scene_free(s);
}

/* Still scenes: nothing animated; the sweep's names are its triangle counts;
 * the point light of light_in_hull sits inside the cup (below the rim). */
static void test_still_scenes(void)
{
    const char *still[] = {"two_rooms_thin", "two_rooms_thick", "light_in_hull", "glossy"};
    for (size_t i = 0; i < sizeof still / sizeof *still; i++) {
        char path[512];
        snprintf(path, sizeof path, STRESS "%s.gltf", still[i]);
        gi_scene *s = load(path);
        if (!s)
            continue;
        CHECK(s->animation_length == 0.0f && gi_scene_lights_animated(s) == 0);
        CHECK(s->emitter_count + s->light_count > 0);
        if (!strcmp(still[i], "light_in_hull")) {
            int cup = object_named(s, "cup");
            CHECK(cup >= 0 && s->light_count == 1);
            if (cup >= 0 && s->light_count == 1) {
                const float *b = s->objects[cup].local_bounds;
                gi_light_frame f = gi_scene_light_at(s, 0, 0.0f);
                float m[16];
                gi_scene_object_transform(s, (uint32_t)cup, 0.0f, m);
                /* light within the cup's bounding cylinder, below its rim */
                float dx = f.position.x - m[12], dz = f.position.z - m[14];
                CHECK(dx * dx + dz * dz < b[3] * b[3]);
                CHECK(f.position.y > m[13] + b[1] && f.position.y < m[13] + b[4]);
            }
        }
        gi_scene_free(s);
    }
    const unsigned sweep[] = {116, 482, 1970, 7970, 32066, 57090};
    for (size_t i = 0; i < sizeof sweep / sizeof *sweep; i++) {
        char path[512];
        snprintf(path, sizeof path, STRESS "scale_t%05u.gltf", sweep[i]);
        gi_scene *s = load(path);
        if (!s)
            continue;
        CHECK(s->triangle_count == sweep[i] && s->emitter_count == 2);
        gi_scene_free(s);
    }
}

/* cornell_moving moves an object only: its light is not animated. */
static void test_cornell_moving(void)
{
    gi_scene *s = load(GI_SOURCE_DIR "/scenes/cornell_moving.gltf");
    if (!s)
        return;
    CHECK(gi_scene_lights_animated(s) == 0 && gi_scene_camera_animated(s, 0) == 0);
    /* an emissive object that moves counts as a moving light: mark the
     * light quad's object animated in this (test-owned) copy */
    int light = object_named(s, "light");
    CHECK(light >= 0 && s->emitter_count == 2);
    if (light >= 0) {
        s->objects[light].animated = 1;
        CHECK(gi_scene_lights_animated(s) == 1);
    }
    gi_scene_free(s);
}

int main(void)
{
    test_moving_light();
    test_moving_camera();
    test_hulls_overlap();
    test_still_scenes();
    test_cornell_moving();
    return gi_test_finish();
}

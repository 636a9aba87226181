/* The path-traced reference on the stress-case scenes (scenes/stress/):
 *  - two_rooms_thin / two_rooms_thick: the right-hand room (the left image
 *    half: the camera looks down +Z, so +X is on the left) gets no light at
 *    all, so every pixel there is exactly 0 while the lit room is bright:
 *    any energy a method puts there is leak;
 *  - moving_light: the reference follows the light's animation: at t = 0 the
 *    light is at x = 3 (the left half is the brighter), at t = 2 at x = 1
 *    (the right half is). */
#include "check.h"
#include "reference.h"

#include "gi/image.h"
#include "gi/scene.h"

#include <stdio.h>
#include <stdlib.h>

#define STRESS GI_SOURCE_DIR "/scenes/stress/"
#define SIZE 16

/* Mean luminance of the left and right image halves, and the largest
 * channel value in the left half. */
typedef struct halves {
    double left, right, left_max;
} halves;

static int render_halves(const char *path, float t, uint32_t spp, halves *h)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    if (!s) {
        fprintf(stderr, "%s\n", err.text);
        return 0;
    }
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = s;
    d.camera = 0;
    d.time = t;
    d.width = d.height = SIZE;
    d.seed = 7;
    gi_ref *r = NULL;
    int ok = gi_ref_create(&d, &r, &err) == GI_OK && gi_ref_render(r, spp, &err) == GI_OK;
    if (!ok)
        fprintf(stderr, "%s: %s\n", path, err.text);
    gi_image *img = ok ? gi_ref_mean_image(r) : NULL;
    if (img) {
        h->left = h->right = h->left_max = 0.0;
        for (uint32_t y = 0; y < SIZE; y++)
            for (uint32_t x = 0; x < SIZE; x++) {
                const float *p = &img->rgba[4 * ((size_t)y * SIZE + x)];
                double lum = (p[0] + p[1] + p[2]) / 3.0;
                if (x < SIZE / 2) {
                    h->left += lum;
                    for (int c = 0; c < 3; c++)
                        h->left_max = p[c] > h->left_max ? p[c] : h->left_max;
                } else {
                    h->right += lum;
                }
            }
        h->left /= SIZE * SIZE / 2;
        h->right /= SIZE * SIZE / 2;
        gi_image_free(img);
    }
    gi_ref_free(r);
    gi_scene_free(s);
    return img != NULL;
}

static void test_two_rooms(void)
{
    const char *k[2] = {"two_rooms_thin.gltf", "two_rooms_thick.gltf"};
    for (int i = 0; i < 2; i++) {
        char path[512];
        snprintf(path, sizeof path, STRESS "%s", k[i]);
        halves h;
        CHECK(render_halves(path, 0.0f, 32, &h));
        CHECK_MSG(h.left_max == 0.0, "%s: the dark room has a pixel of %g", k[i], h.left_max);
        CHECK_MSG(h.right > 0.05, "%s: the lit room's half has mean %g", k[i], h.right);
    }
}

static void test_moving_light(void)
{
    halves a, b;
    CHECK(render_halves(STRESS "moving_light.gltf", 0.0f, 32, &a));
    CHECK(render_halves(STRESS "moving_light.gltf", 2.0f, 32, &b));
    CHECK_MSG(a.left > 1.2 * a.right, "t = 0: left %g, right %g", a.left, a.right);
    CHECK_MSG(b.right > 1.2 * b.left, "t = 2: left %g, right %g", b.left, b.right);
}

int main(void)
{
    test_two_rooms();
    test_moving_light();
    return gi_test_finish();
}

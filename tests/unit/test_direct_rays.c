/* Direct irradiance by shadow rays (core/algo, gi/algo/direct_rays.h),
 * against closed forms on scenes built in memory (ref_scenes.h):
 *  - on the axis of a disk light of radius r at height h: pi Le r^2 /
 *    (h^2 + r^2), one seed and the mean of 16 (unbiased);
 *  - the same with a double-sided disk between (0: the unshadowed answer
 *    is the full value, so a missing shadow test fails);
 *  - above the disk, which emits downward only: 0 when single-sided,
 *    the on-axis value when double-sided (the one rule for sides);
 *  - a point light of intensity I at height h: I / h^2;
 *  - a plane under a uniform sky of radiance L: pi L;
 * and the error for NULL arguments. */
#include "check.h"
#include "ref_scenes.h"

#include "gi/algo/direct_rays.h"
#include "gi/image.h"

static void grey(float v, float out[3])
{
    out[0] = out[1] = out[2] = v;
}

/* Direct irradiance at (0, y, 0) with normal (0, ny, 0), mean over `seeds` seeds. */
static double irradiance(const gi_scene *s, float y, float ny, uint32_t samples, uint32_t seeds)
{
    gi_error err;
    gi_rt *rt = NULL;
    gi_direct_rays *d = NULL;
    if (gi_rt_create(s, 0.0f, &rt, &err) != GI_OK || gi_direct_rays_create(rt, &d, &err) != GI_OK) {
        fprintf(stderr, "%s\n", err.text);
        gi_rt_free(rt);
        return -1.0;
    }
    double sum = 0.0;
    for (uint32_t k = 0; k < seeds; k++) {
        float E[3];
        gi_direct_rays_irradiance(d, gi_v3(0, y, 0), gi_v3(0, ny, 0), samples, samples, k, E);
        sum += E[1];
    }
    gi_direct_rays_free(d);
    gi_rt_free(rt);
    return sum / seeds;
}

/* A plane at height 0 and a disk light (emitting downward) of radius r at
 * height h; with `blocker` a double-sided grey disk of radius 1.5 r at h / 2. */
static gi_scene *disk_scene(float r, float h, float Le, int double_sided, int blocker)
{
    tg_scene b;
    tg_init(&b);
    float alb[3], em[3], black[3] = {0, 0, 0};
    grey(0.5f, alb);
    grey(Le, em);
    tg_plane(&b, 50.0f, 0.0f, tg_material(&b, alb, black, 0));
    tg_disk(&b, r, h, 256, tg_material(&b, black, em, double_sided));
    if (blocker)
        tg_disk(&b, 1.5f * r, 0.5f * h, 64, tg_material(&b, alb, black, 1));
    const float eye[3] = {3.0f, 1.0f, 0.5f}, at[3] = {0, 0, 0};
    tg_camera(&b, eye, at, 30.0f, 0.01f);
    gi_error err;
    gi_scene *s = tg_load(&b, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    return s;
}

static void test_disk(void)
{
    const float r = 1.0f, h = 2.0f, Le = 5.0f;
    const double exact =
        TG_PI * Le * r * r / (h * h + r * r) * 0.9999; /* the 256-gon: 0.01 % less */
    gi_scene *s = disk_scene(r, h, Le, 0, 0);
    if (!s)
        return;
    double one = irradiance(s, 0.0f, 1.0f, 64, 1), mean = irradiance(s, 0.0f, 1.0f, 64, 16);
    double above = irradiance(s, 2.0f * h, -1.0f, 64, 1);
    printf("disk light on axis: exact %.5f, 64 rays %.5f (%+.3f %%), mean of 16 seeds %.5f (%+.3f "
           "%%); above the single-sided disk %.5f\n",
           exact, one, 100.0 * (one / exact - 1.0), mean, 100.0 * (mean / exact - 1.0), above);
    CHECK(fabs(one / exact - 1.0) < 0.01);
    CHECK(fabs(mean / exact - 1.0) < 0.003);
    CHECK(above == 0.0);
    gi_scene_free(s);

    s = disk_scene(r, h, Le, 1, 0);
    if (!s)
        return;
    above = irradiance(s, 2.0f * h, -1.0f, 64, 16);
    printf("above the double-sided disk %.5f (exact %.5f)\n", above, exact);
    CHECK(fabs(above / exact - 1.0) < 0.003);
    gi_scene_free(s);

    s = disk_scene(r, h, Le, 0, 1);
    if (!s)
        return;
    double blocked = irradiance(s, 0.0f, 1.0f, 64, 4);
    printf("behind a blocker: %.6f (the unshadowed answer %.5f)\n", blocked, exact);
    CHECK(blocked < 1e-6 * exact);
    gi_scene_free(s);
}

static void test_point_light(void)
{
    tg_scene b;
    tg_init(&b);
    float alb[3], black[3] = {0, 0, 0};
    grey(0.5f, alb);
    tg_plane(&b, 50.0f, 0.0f, tg_material(&b, alb, black, 0));
    const float p[3] = {0.0f, 2.0f, 0.0f};
    tg_point_light(&b, p, 10.0f);
    const float eye[3] = {3.0f, 1.0f, 0.5f}, at[3] = {0, 0, 0};
    tg_camera(&b, eye, at, 30.0f, 0.01f);
    gi_error err;
    gi_scene *s = tg_load(&b, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    double E = irradiance(s, 0.0f, 1.0f, 1, 1);
    printf("point light: %.6f (exact %.6f)\n", E, 10.0 / 4.0);
    CHECK(fabs(E / 2.5 - 1.0) < 1e-4);
    gi_scene_free(s);
}

static void test_sky(void)
{
    gi_image *img = gi_image_create(8, 4);
    CHECK(img != NULL);
    if (!img)
        return;
    for (size_t i = 0; i < 8 * 4; i++)
        for (int c = 0; c < 4; c++)
            img->rgba[4 * i + (size_t)c] = 1.0f;
    gi_error err;
    CHECK(gi_image_write(GI_BINARY_DIR "/tests/direct_rays_sky.exr", img, NULL, &err) == GI_OK);
    gi_image_free(img);
    tg_scene b;
    tg_init(&b);
    float alb[3], black[3] = {0, 0, 0};
    grey(0.5f, alb);
    tg_plane(&b, 100.0f, 0.0f, tg_material(&b, alb, black, 0));
    const float eye[3] = {0.0f, 1.0f, 0.1f}, at[3] = {0, 0, 0};
    tg_camera(&b, eye, at, 60.0f, 0.01f);
    tg_environment(&b, "direct_rays_sky.exr", 2.0f, 0.0f);
    gi_scene *s = tg_load(&b, GI_BINARY_DIR "/tests", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    double E = irradiance(s, 0.0f, 1.0f, 64, 1);
    printf("uniform sky: %.5f (exact %.5f)\n", E, 2.0 * TG_PI);
    CHECK(fabs(E / (2.0 * TG_PI) - 1.0) < 0.005);
    gi_scene_free(s);
}

int main(void)
{
    gi_error err;
    gi_direct_rays *d = (gi_direct_rays *)1;
    CHECK(gi_direct_rays_create(NULL, &d, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_direct_rays_emitters(NULL) == 0);
    test_disk();
    test_point_light();
    test_sky();
    return gi_test_finish();
}

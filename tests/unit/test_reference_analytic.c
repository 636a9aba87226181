/* The reference path tracer against closed-form radiance (pbrt-style
 * analytic integrator tests), each scene built in memory and loaded by the
 * real glTF loader:
 *  - inside a closed sphere of albedo rho emitting Le everywhere, L = Le / (1 - rho)
 *    (all bounces; exact for any closed polyhedron of uniform material);
 *  - a point light of intensity I at the centre of a sphere of radius R:
 *    L = rho I / (pi R^2 (1 - rho));
 *  - a diffuse plane under a uniform sky of radiance L: rho L;
 *  - on the axis of a disk light of radius r at height h above a diffuse
 *    plane: rho Le r^2 / (h^2 + r^2);
 *  - a diffuse plane under a non-uniform, rotated map: rho / pi times the
 *    map's cosine-weighted integral over the upper hemisphere, summed
 *    texel by texel in closed form;
 *  - a spot light (on its axis and inside its falloff ramp) and a
 *    directional light over a diffuse plane: rho / pi times the irradiance
 *    of lights.h;
 *  - a light whose irradiance overflows: every sample discarded and counted.
 * Each must hold within 1% (and within a few standard errors of the
 * estimate). The disk and the sky are also rendered with light-only and
 * BSDF-only sampling, which must agree as well. Under AddressSanitizer the
 * sample counts drop and the tolerance widens to 3%: that build checks
 * memory, the release build checks the numbers. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "ref_scenes.h"
#include "reference.h"

#include "gi/image.h"

#include <time.h>

#ifdef __SANITIZE_ADDRESS__
#define SPP_SCALE 8 /* divide sample counts */
#define TOL 0.03
#else
#define SPP_SCALE 1
#define TOL 0.01
#endif

typedef struct estimate {
    double mean[3], se[3]; /* image mean and its standard error, per channel */
    double seconds;
} estimate;

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Renders spp samples per pixel and averages over the image. */
static int render(const gi_scene *s, uint32_t w, uint32_t h, uint32_t spp, gi_ref_strategy strategy,
                  estimate *e)
{
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = s;
    d.width = w;
    d.height = h;
    d.seed = 7;
    d.strategy = strategy;
    gi_ref *r;
    gi_error err;
    if (gi_ref_create(&d, &r, &err) != GI_OK) {
        fprintf(stderr, "gi_ref_create: %s\n", err.text);
        return 0;
    }
    double t0 = seconds_now();
    spp = spp / SPP_SCALE > 4 ? spp / SPP_SCALE : 4;
    int ok = gi_ref_render(r, spp, &err) == GI_OK;
    e->seconds = seconds_now() - t0;
    gi_image *m = gi_ref_mean_image(r), *v = gi_ref_variance_image(r);
    gi_ref_stats st;
    gi_ref_get_stats(r, &st);
    ok = ok && m && v && st.nonfinite == 0;
    size_t n = (size_t)w * h;
    for (int c = 0; ok && c < 3; c++) {
        double sum = 0, var = 0;
        for (size_t i = 0; i < n; i++) {
            sum += m->rgba[4 * i + c];
            var += v->rgba[4 * i + c];
        }
        e->mean[c] = sum / (double)n;
        e->se[c] = sqrt(var) / (double)n;
    }
    gi_image_free(m);
    gi_image_free(v);
    gi_ref_free(r);
    return ok;
}

/* Channel 1 (green) of the estimate against the expected value: within the
 * tolerance and within 5 standard errors plus 0.2% (the geometry's own
 * departure from the ideal shape). All scenes here are grey. */
static void check_value(const char *what, const estimate *e, double expected)
{
    if (expected == 0.0) {
        printf("%-34s %.6f expected 0\n", what, e->mean[1]);
        CHECK_MSG(e->mean[0] == 0.0 && e->mean[1] == 0.0 && e->mean[2] == 0.0, "%s: %g", what,
                  e->mean[1]);
        return;
    }
    double err = fabs(e->mean[1] - expected) / expected;
    printf("%-34s %.6f expected %.6f: error %.3f%%, standard error %.3f%%, %.2f s\n", what,
           e->mean[1], expected, 100.0 * err, 100.0 * e->se[1] / expected, e->seconds);
    CHECK_MSG(err <= TOL, "%s: %.6f vs %.6f (%.3f%%)", what, e->mean[1], expected, 100.0 * err);
    CHECK_MSG(fabs(e->mean[1] - expected) <= 5.0 * e->se[1] + 0.002 * expected,
              "%s: %.6f vs %.6f is %.1f standard errors", what, e->mean[1], expected,
              fabs(e->mean[1] - expected) / e->se[1]);
    CHECK(fabs(e->mean[0] - e->mean[1]) <= 1e-6 * expected + 5.0 * (e->se[0] + e->se[1]));
}

static void grey(float v, float out[3])
{
    out[0] = out[1] = out[2] = v;
}

/* Closed emitting sphere: every surface point sees the same radiance L, so
 * L = Le + rho L; flat faces make it exact for the polyhedron. */
static void test_emitting_sphere(void)
{
    const float rho = 0.8f, Le = 1.0f;
    tg_scene b;
    tg_init(&b);
    float alb[3], em[3];
    grey(rho, alb);
    grey(Le, em);
    tg_icosphere(&b, 1.0f, 3, 0, tg_material(&b, alb, em, 0));
    const float eye[3] = {0.1f, -0.2f, 0.05f}, at[3] = {1, 0.3f, 0.2f};
    tg_camera(&b, eye, at, 90.0f, 0.01f);
    gi_error err;
    gi_scene *s = tg_load(&b, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    estimate e;
    CHECK(render(s, 8, 8, 4096, GI_REF_STRATEGY_MIS, &e));
    check_value("emitting sphere, rho 0.8 (MIS)", &e, Le / (1.0 - rho));
    gi_scene_free(s);
}

/* Point light at the centre of a sphere: direct irradiance I / R^2
 * everywhere, then the sphere's interreflection (every point sees every
 * other with the same form factor) multiplies by 1 / (1 - rho). */
static void test_point_in_sphere(void)
{
    const float rho = 0.5f, I = 10.0f, R = 2.0f;
    tg_scene b;
    tg_init(&b);
    float alb[3], em[3];
    grey(rho, alb);
    grey(0.0f, em);
    tg_icosphere(&b, R, 5, 1, tg_material(&b, alb, em, 0));
    const float c[3] = {0, 0, 0}, at[3] = {0.3f, 1.0f, -0.4f};
    tg_point_light(&b, c, I);
    tg_camera(&b, c, at, 90.0f, 0.01f);
    gi_error err;
    gi_scene *s = tg_load(&b, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    estimate e;
    CHECK(render(s, 8, 8, 1024, GI_REF_STRATEGY_MIS, &e));
    check_value("point light in sphere, rho 0.5", &e, rho * I / (GI_PI * R * R * (1.0 - rho)));
    gi_scene_free(s);
}

/* Grey maps written next to the test binaries: constant, or the test
 * pattern of map_texel. */
static float map_texel(uint32_t i, uint32_t j)
{
    return (i == 5 && j == 2) ? 40.0f : 0.2f + 0.1f * (float)j + 0.05f * (float)i;
}

static int write_sky(const char *path, float L, uint32_t w, uint32_t h)
{
    gi_image *img = gi_image_create(w, h);
    if (!img)
        return 0;
    for (uint32_t j = 0; j < h; j++)
        for (uint32_t i = 0; i < w; i++) {
            float *p = img->rgba + 4 * ((size_t)j * w + i);
            p[0] = p[1] = p[2] = L > 0 ? L : map_texel(i, j);
            p[3] = 1.0f;
        }
    gi_error err;
    int ok = gi_image_write(path, img, NULL, &err) == GI_OK;
    if (!ok)
        fprintf(stderr, "%s\n", err.text);
    gi_image_free(img);
    return ok;
}

/* A diffuse plane (albedo rho) under the environment map `env` (scale,
 * rotation about +Y in degrees), seen straight down from above (eye_x,
 * eye_z), rendered with each of the three direct-light strategies at its
 * own sample count and held against the expected radiance. */
static void plane_under_env(const char *name, float rho, float eye_x, float eye_z, const char *env,
                            float scale, float rotation, const uint32_t spp[3], double expected)
{
    static const gi_ref_strategy strategies[3] = {GI_REF_STRATEGY_MIS, GI_REF_STRATEGY_LIGHT,
                                                  GI_REF_STRATEGY_BSDF};
    for (int k = 0; k < 3; k++) {
        tg_scene b;
        tg_init(&b);
        float alb[3], em[3];
        grey(rho, alb);
        grey(0.0f, em);
        tg_plane(&b, 100.0f, 0.0f, tg_material(&b, alb, em, 0));
        const float eye[3] = {eye_x, 1.0f, eye_z}, at[3] = {eye_x, 0.0f, eye_z};
        tg_camera(&b, eye, at, 60.0f, 0.01f);
        tg_environment(&b, env, scale, rotation);
        gi_error err;
        gi_scene *s = tg_load(&b, GI_BINARY_DIR "/tests", &err);
        CHECK_MSG(s != NULL, "%s", err.text);
        if (!s)
            return;
        estimate e;
        CHECK(render(s, 8, 8, spp[k], strategies[k], &e));
        char what[96];
        snprintf(what, sizeof what, "%s (%s)", name, gi_ref_strategy_name(strategies[k]));
        check_value(what, &e, expected);
        gi_scene_free(s);
    }
}

/* Plane under a uniform sky: irradiance pi L, radiance rho L. */
static void test_plane_under_sky(void)
{
    const float rho = 0.6f, L = 1.5f;
    CHECK(write_sky(GI_BINARY_DIR "/tests/reference_sky_const.exr", 1.0f, 8, 4));
    /* Cosine-weighted BSDF sampling of a constant sky has no variance;
     * light sampling (uniform over the sphere) needs many samples. */
    static const uint32_t spp[3] = {1024, 16384, 64};
    plane_under_env("plane under uniform sky", rho, 0.3f, -0.2f, "reference_sky_const.exr", L, 0.0f,
                    spp, rho * L);
}

/* Plane under a 16x8 map with a gradient and one very bright texel,
 * rotated 30 degrees about +Y (which leaves the irradiance of a horizontal
 * plane unchanged). The map is piecewise constant (nearest texel), so
 * L = rho / pi Int L cos dw is a sum over the upper-hemisphere texels of
 * L_ij pi du (sin^2(pi v1) - sin^2(pi v0)), from dw = 2 pi^2 sin(pi v) du dv
 * and cos = cos(pi v). */
static void test_plane_under_map(void)
{
    const float rho = 0.7f;
    const uint32_t w = 16, h = 8;
    CHECK(write_sky(GI_BINARY_DIR "/tests/reference_sky_map.exr", 0.0f, w, h));
    double sum = 0;
    for (uint32_t j = 0; j < h / 2; j++)
        for (uint32_t i = 0; i < w; i++) {
            double s0 = sin(TG_PI * j / h), s1 = sin(TG_PI * (j + 1) / h);
            sum += map_texel(i, j) * (1.0 / w) * (s1 * s1 - s0 * s0);
        }
    static const uint32_t spp[3] = {4096, 4096, 32768};
    plane_under_env("plane under a bright texel", rho, -0.4f, 0.1f, "reference_sky_map.exr", 1.0f,
                    30.0f, spp, rho * sum);
}

/* One punctual light over a diffuse plane; a narrow camera looks at
 * `target` on the plane, whose radiance is rho / pi x irradiance. */
static void punctual_case(const char *what, const char *light_json, const float pos[3],
                          const float dir[3], const float target[3], double irradiance)
{
    const float rho = 0.5f;
    tg_scene b;
    tg_init(&b);
    float alb[3], em[3];
    grey(rho, alb);
    grey(0.0f, em);
    tg_plane(&b, 50.0f, 0.0f, tg_material(&b, alb, em, 0));
    tg_light(&b, light_json, pos, dir);
    const float eye[3] = {target[0] + 1.0f, 1.5f, target[2] + 2.0f};
    tg_camera(&b, eye, target, 0.2f, 0.01f);
    gi_error err;
    gi_scene *s = tg_load(&b, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    estimate e;
    CHECK(render(s, 2, 2, 16, GI_REF_STRATEGY_MIS, &e));
    check_value(what, &e, rho / GI_PI * irradiance);
    gi_scene_free(s);
}

static void test_punctual(void)
{
    /* Spot: I = 8 at height 2 pointing down, cones 0.3 / 0.5 rad. On the
     * axis E = I / h^2; at 0.4 rad off the axis E = I f cos^3 / h^2 with
     * the ramp f = ((cos 0.4 - cos 0.5) / (cos 0.3 - cos 0.5))^2. */
    const char *spot = "\"type\":\"spot\",\"intensity\":8,\"spot\":{\"innerConeAngle\":0.3,"
                       "\"outerConeAngle\":0.5}";
    const float top[3] = {0, 2, 0}, down[3] = {0, -1, 0}, foot[3] = {0, 0, 0};
    punctual_case("spot light, on its axis", spot, top, down, foot, 8.0 / 4.0);
    double th = 0.4, t = (cos(th) - cos(0.5)) / (cos(0.3) - cos(0.5));
    const float ramp[3] = {(float)(2.0 * tan(th)), 0, 0};
    punctual_case("spot light, in its falloff ramp", spot, top, down, ramp,
                  8.0 * t * t * pow(cos(th), 3) / 4.0);
    const float beyond[3] = {(float)(2.0 * tan(0.55)), 0, 0};
    punctual_case("spot light, outside its cone", spot, top, down, beyond, 0.0);
    /* Directional: E = 3 arriving 30 degrees off the vertical. */
    const float sun_dir[3] = {0.5f, -0.8660254f, 0.0f};
    punctual_case("directional light at 30 degrees", "\"type\":\"directional\",\"intensity\":3",
                  top, sun_dir, foot, 3.0 * cos(30.0 * TG_PI / 180.0));
}

/* Irradiance at the origin (normal +Y) from a unit-radiance polygon, by
 * Lambert's formula E = 1/2 sum_i theta_i (gamma_i . N): the exact value
 * for the polygonal disk, independent of any sampling. */
static double polygon_irradiance(const double (*v)[3], int n)
{
    double sum = 0;
    for (int i = 0; i < n; i++) {
        const double *a = v[i], *b = v[(i + 1) % n];
        double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]),
               lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        double c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
        double g[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0]};
        double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        sum += acos(fmin(1.0, fmax(-1.0, c))) * g[1] / gl;
    }
    return 0.5 * fabs(sum);
}

/* Disk light (emitting downwards, black) of radius r at height h over a
 * diffuse plane; a narrow camera looks at the foot of the axis. */
static void test_disk_light(void)
{
    const float rho = 0.5f, Le = 5.0f, r = 1.0f, h = 2.0f;
    const uint32_t segments = 256;
    double disk = rho * Le * r * r / (h * h + r * r);
    double(*poly)[3] = malloc(segments * sizeof *poly);
    for (uint32_t i = 0; i < segments; i++) {
        double a = 2.0 * TG_PI * i / segments;
        poly[i][0] = r * cos(a);
        poly[i][1] = h;
        poly[i][2] = r * sin(a);
    }
    double polygon = rho / GI_PI * Le * polygon_irradiance((const double(*)[3])poly, (int)segments);
    free(poly);
    printf("disk light: closed form %.6f, the %u-gon %.6f (%.4f%% less)\n", disk, segments, polygon,
           100.0 * (1.0 - polygon / disk));
    CHECK(polygon < disk && polygon > 0.999 * disk);

    static const gi_ref_strategy strategies[3] = {GI_REF_STRATEGY_MIS, GI_REF_STRATEGY_LIGHT,
                                                  GI_REF_STRATEGY_BSDF};
    static const uint32_t spp[3] = {2048, 2048, 131072};
    for (int k = 0; k < 3; k++) {
        tg_scene b;
        tg_init(&b);
        float alb[3], em[3], black[3] = {0, 0, 0};
        grey(rho, alb);
        grey(Le, em);
        tg_plane(&b, 50.0f, 0.0f, tg_material(&b, alb, black, 0));
        tg_disk(&b, r, h, segments, tg_material(&b, black, em, 0));
        const float eye[3] = {3.0f, 1.0f, 0.5f}, at[3] = {0, 0, 0};
        tg_camera(&b, eye, at, 0.2f, 0.01f);
        gi_error err;
        gi_scene *s = tg_load(&b, NULL, &err);
        CHECK_MSG(s != NULL, "%s", err.text);
        if (!s)
            return;
        CHECK(s->emitter_count == segments);
        estimate e;
        CHECK(render(s, 4, 4, spp[k], strategies[k], &e));
        char what[64];
        snprintf(what, sizeof what, "disk light on axis (%s)", gi_ref_strategy_name(strategies[k]));
        check_value(what, &e, disk);
        CHECK_MSG(fabs(e.mean[1] - polygon) <= 5.0 * e.se[1] + 1e-4 * polygon,
                  "%s: %.6f vs polygon %.6f", what, e.mean[1], polygon);
        gi_scene_free(s);
    }
}

/* A point light so strong that the irradiance overflows a float: every
 * sample is Inf, and each is discarded and counted, never averaged in. */
static void test_nonfinite_samples(void)
{
    tg_scene b;
    tg_init(&b);
    float alb[3], em[3];
    grey(0.5f, alb);
    grey(0.0f, em);
    tg_plane(&b, 10.0f, 0.0f, tg_material(&b, alb, em, 0));
    const float p[3] = {0, 0.01f, 0}, eye[3] = {0, 1, 0}, at[3] = {0, 0, 0};
    tg_point_light(&b, p, 3e38f);
    tg_camera(&b, eye, at, 1.0f, 0.01f);
    gi_error err;
    gi_scene *s = tg_load(&b, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = s;
    d.width = 3;
    d.height = 2;
    gi_ref *r;
    CHECK(gi_ref_create(&d, &r, &err) == GI_OK);
    CHECK(gi_ref_render(r, 5, &err) == GI_OK);
    gi_ref_stats st;
    gi_ref_get_stats(r, &st);
    printf("overflowing light: %llu of %d samples non-finite\n", (unsigned long long)st.nonfinite,
           3 * 2 * 5);
    CHECK(st.nonfinite == 3 * 2 * 5);
    gi_image *m = gi_ref_mean_image(r);
    CHECK(m && gi_image_count_nonfinite(m) == 0 && m->rgba[0] == 0.0f);
    CHECK(gi_ref_mean_rel_se(r) == INFINITY);
    gi_image_free(m);
    gi_ref_free(r);
    gi_scene_free(s);
}

int main(void)
{
    test_emitting_sphere();
    test_point_in_sphere();
    test_plane_under_sky();
    test_plane_under_map();
    test_disk_light();
    test_punctual();
    test_nonfinite_samples();
    return gi_test_finish();
}

/* Environment map (envmap.h): the direction <-> (u, v) mapping and its
 * rotation, the pdf integrating to 1 over the sphere, the sampler's texel
 * histogram against weights computed here from the image (chi-square),
 * pdf(sampled direction) == returned pdf, nearest-texel eval, black maps. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gi/envmap.h"
#include "gi/rng.h"

/* Rotation by +a about +Y (right-handed), independent of envmap.c. */
static gi_vec3 rot_y(gi_vec3 d, float a)
{
    double c = cos(a), s = sin(a);
    return gi_v3((float)(c * d.x + s * d.z), d.y, (float)(-s * d.x + c * d.z));
}

static float *random_map(uint32_t w, uint32_t h, uint32_t seed)
{
    float *rgba = malloc((size_t)w * h * 4 * sizeof(float));
    uint32_t s = gi_rng_init(0, 0, seed);
    for (uint32_t k = 0; k < w * h; k++) {
        float scale = gi_rng_next_float(&s) < 0.1f ? 20.0f : 1.0f; /* a few hot texels */
        for (int c = 0; c < 3; c++)
            rgba[k * 4 + c] = scale * gi_rng_next_float(&s);
        rgba[k * 4 + 3] = 1.0f;
    }
    return rgba;
}

static void test_mapping(void)
{
    float rgba[4 * 8 * 4] = {0};
    gi_envmap *env = gi_envmap_create(rgba, 8, 4, 1.0f, 0.0f);
    float u, v;
    /* Fixed points of the convention: -Z is the centre, +X at u = 3/4, +Y top. */
    gi_envmap_dir_to_uv(env, gi_v3(0, 0, -1), &u, &v);
    CHECK_NEAR(u, 0.5, 1e-6);
    CHECK_NEAR(v, 0.5, 1e-6);
    gi_envmap_dir_to_uv(env, gi_v3(1, 0, 0), &u, &v);
    CHECK_NEAR(u, 0.75, 1e-6);
    gi_envmap_dir_to_uv(env, gi_v3(-1, 0, 0), &u, &v);
    CHECK_NEAR(u, 0.25, 1e-6);
    gi_envmap_dir_to_uv(env, gi_v3(0, 1, 0), &u, &v);
    CHECK_NEAR(v, 0.0, 1e-6);
    gi_envmap_dir_to_uv(env, gi_v3(0, -1, 0), &u, &v);
    CHECK(v < 1.0f && v > 0.9999f);
    /* +Z sits on the seam: u wraps into [0, 1). */
    gi_envmap_dir_to_uv(env, gi_v3(0, 0, 1), &u, &v);
    CHECK(u >= 0.0f && u < 1.0f && (u < 1e-6f || u > 1.0f - 1e-6f));
    gi_envmap_free(env);

    /* Round trips at random rotations. */
    uint32_t s = gi_rng_init(1, 2, 3);
    double worst_dir = 0, worst_uv = 0, worst_len = 0;
    for (int k = 0; k < 20000; k++) {
        float rot = 360.0f * gi_rng_next_float(&s) - 180.0f;
        env = gi_envmap_create(rgba, 8, 4, 1.0f, rot);
        float u0 = gi_rng_next_float(&s), v0 = 0.001f + 0.998f * gi_rng_next_float(&s);
        gi_vec3 d = gi_envmap_uv_to_dir(env, u0, v0);
        worst_len = fmax(worst_len, fabs(gi_v3_length(d) - 1.0));
        gi_envmap_dir_to_uv(env, d, &u, &v);
        double du = fabs(u - u0);
        du = fmin(du, 1.0 - du); /* across the seam */
        worst_uv = fmax(worst_uv, fmax(du, fabs(v - v0)));
        gi_vec3 d2 = gi_envmap_uv_to_dir(env, u, v);
        worst_dir = fmax(worst_dir, gi_v3_length(gi_v3_sub(d, d2)));
        gi_envmap_free(env);
    }
    CHECK_MSG(worst_len < 1e-5, "|d| - 1 up to %g", worst_len);
    CHECK_MSG(worst_uv < 2e-5, "uv round trip error %g", worst_uv);
    CHECK_MSG(worst_dir < 2e-5, "direction round trip error %g", worst_dir);
}

static void test_rotation_and_eval(void)
{
    const uint32_t w = 16, h = 8;
    float *rgba = random_map(w, h, 7);
    gi_envmap *env0 = gi_envmap_create(rgba, w, h, 2.5f, 0.0f);
    const float deg = 57.0f;
    gi_envmap *envr = gi_envmap_create(rgba, w, h, 2.5f, deg);
    const float a = deg * GI_PI / 180.0f;

    /* Nearest texel with intensity applied, at every texel centre. */
    int eval_ok = 1;
    for (uint32_t j = 0; j < h; j++)
        for (uint32_t i = 0; i < w; i++) {
            gi_vec3 d = gi_envmap_uv_to_dir(env0, (i + 0.5f) / w, (j + 0.5f) / h);
            float L[3];
            gi_envmap_eval(env0, d, L);
            for (int c = 0; c < 3; c++)
                eval_ok &= L[c] == rgba[(j * w + i) * 4 + c] * 2.5f;
        }
    CHECK(eval_ok);

    /* The rotated map shows the unrotated one turned by +rotation about +Y:
     * same radiance, uv and pdf at R(a) d as the original at d. */
    uint32_t s = gi_rng_init(5, 5, 5);
    int rot_ok = 1;
    for (int k = 0; k < 5000; k++) {
        gi_vec3 d =
            gi_envmap_uv_to_dir(env0, gi_rng_next_float(&s), 0.01f + 0.98f * gi_rng_next_float(&s));
        float u0, v0, u1, v1;
        gi_envmap_dir_to_uv(env0, d, &u0, &v0);
        gi_envmap_dir_to_uv(envr, rot_y(d, a), &u1, &v1);
        float du = fabsf(u0 - u1);
        du = fminf(du, 1.0f - du);
        rot_ok &= du < 1e-5f && fabsf(v0 - v1) < 1e-5f;
        /* Away from texel edges the texel (and so radiance and pdf) match. */
        float fu = u0 * w - floorf(u0 * w), fv = v0 * h - floorf(v0 * h);
        if (fu > 1e-3f && fu < 1 - 1e-3f && fv > 1e-3f && fv < 1 - 1e-3f) {
            float L0[3], L1[3];
            gi_envmap_eval(env0, d, L0);
            gi_envmap_eval(envr, rot_y(d, a), L1);
            rot_ok &= memcmp(L0, L1, sizeof L0) == 0;
            float p0 = gi_envmap_pdf(env0, d), p1 = gi_envmap_pdf(envr, rot_y(d, a));
            rot_ok &= fabsf(p0 - p1) <= 1e-4f * p0;
        }
    }
    CHECK(rot_ok);
    /* A quarter turn sends the map's centre (-Z) to -X. */
    gi_envmap *env90 = gi_envmap_create(rgba, w, h, 1.0f, 90.0f);
    float u, v;
    gi_envmap_dir_to_uv(env90, gi_v3(-1, 0, 0), &u, &v);
    CHECK_NEAR(u, 0.5, 1e-6);
    gi_envmap_free(env90);
    gi_envmap_free(env0);
    gi_envmap_free(envr);
    free(rgba);
}

/* Int pdf dw over the sphere by the midpoint rule on a (theta, phi) grid. */
static double integrate_pdf(const gi_envmap *env, int nt, int np)
{
    double sum = 0;
    for (int t = 0; t < nt; t++) {
        double theta = (t + 0.5) * GI_PI / nt;
        for (int p = 0; p < np; p++) {
            double phi = (p + 0.5) * 2.0 * GI_PI / np;
            gi_vec3 d = gi_v3((float)(sin(theta) * cos(phi)), (float)cos(theta),
                              (float)(sin(theta) * sin(phi)));
            sum += gi_envmap_pdf(env, d) * sin(theta);
        }
    }
    return sum * (GI_PI / nt) * (2.0 * GI_PI / np);
}

static void test_pdf_normalised(void)
{
    const uint32_t w = 16, h = 8;
    float *rgba = random_map(w, h, 11);
    gi_envmap *env = gi_envmap_create(rgba, w, h, 1.0f, 0.0f);
    gi_envmap *envr = gi_envmap_create(rgba, w, h, 1.0f, 33.0f);
    CHECK_NEAR(integrate_pdf(env, 512, 1024), 1.0, 2e-3);
    CHECK_NEAR(integrate_pdf(envr, 512, 1024), 1.0, 2e-3);

    /* Mean luminance over the sphere against the exact texel solid angles. */
    double exact = 0;
    for (uint32_t j = 0; j < h; j++)
        for (uint32_t i = 0; i < w; i++) {
            double solid = (2.0 * GI_PI / w) * (cos(j * GI_PI / h) - cos((j + 1) * GI_PI / h));
            const float *p = rgba + (j * w + i) * 4;
            exact += (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) * solid;
        }
    exact /= 4.0 * GI_PI;
    CHECK_NEAR(gi_envmap_average_radiance(env) / exact, 1.0, 0.01);

    /* A constant map is (close to) uniform over the sphere. */
    float *flat = malloc(64 * 32 * 4 * sizeof(float));
    for (int k = 0; k < 64 * 32 * 4; k++)
        flat[k] = 0.5f;
    gi_envmap *envf = gi_envmap_create(flat, 64, 32, 2.0f, 0.0f);
    for (int j = 0; j < 32; j++) {
        gi_vec3 d = gi_envmap_uv_to_dir(envf, 0.3f, (j + 0.5f) / 32.0f);
        CHECK_NEAR(gi_envmap_pdf(envf, d) * 4.0 * GI_PI, 1.0, 2e-3);
    }
    CHECK_NEAR(gi_envmap_average_radiance(envf), 1.0, 2e-3);
    gi_envmap_free(envf);
    free(flat);
    gi_envmap_free(env);
    gi_envmap_free(envr);
    free(rgba);
}

/* Upper 0.1% point of chi-square with k degrees of freedom (Wilson-Hilferty). */
static double chi2_critical(int k)
{
    const double z = 3.090; /* standard normal, p = 0.001 */
    double a = 2.0 / (9.0 * k);
    double t = 1.0 - a + z * sqrt(a);
    return k * t * t * t;
}

static void test_sampling(void)
{
    const uint32_t w = 16, h = 8;
    float *rgba = random_map(w, h, 23);
    /* A black row and a few black texels must never be drawn. */
    for (uint32_t i = 0; i < w; i++)
        for (int c = 0; c < 3; c++)
            rgba[(5 * w + i) * 4 + c] = 0.0f;
    for (int c = 0; c < 3; c++) {
        rgba[(2 * w + 3) * 4 + c] = 0.0f;
        rgba[(0 * w + 15) * 4 + c] = 0.0f;
    }
    rgba[(6 * w + 6) * 4 + 1] = -50.0f; /* negative luminance: not sampled */

    for (int pass = 0; pass < 2; pass++) {
        float rot = pass == 0 ? 0.0f : -71.0f;
        gi_envmap *env = gi_envmap_create(rgba, w, h, 1.0f, rot);

        /* Expected texel probabilities straight from the image. */
        double prob[16 * 8], total = 0;
        for (uint32_t j = 0; j < h; j++)
            for (uint32_t i = 0; i < w; i++) {
                const float *p = rgba + (j * w + i) * 4;
                double lum = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
                prob[j * w + i] = lum > 0 ? lum * sin((j + 0.5) * GI_PI / h) : 0.0;
                total += prob[j * w + i];
            }
        for (uint32_t k = 0; k < w * h; k++)
            prob[k] /= total;

        const int n = 400000;
        long count[16 * 8] = {0};
        uint32_t s = gi_rng_init(9, 9, 9 + pass);
        int pdf_checked = 0, pdf_ok = 0, texel_ok = 1;
        double worst = 0;
        for (int k = 0; k < n; k++) {
            float u1 = gi_rng_next_float(&s), u2 = gi_rng_next_float(&s);
            gi_vec3 d;
            float pdf = gi_envmap_sample(env, u1, u2, &d);
            float u, v;
            gi_envmap_dir_to_uv(env, d, &u, &v);
            uint32_t i = (uint32_t)(u * w), j = (uint32_t)(v * h);
            i = i < w ? i : w - 1;
            j = j < h ? j : h - 1;
            count[j * w + i]++;
            texel_ok &= pdf > 0.0f;
            /* pdf(d) == returned pdf, except where a float direction cannot
             * tell the texel (edges) or theta (poles). */
            float fu = u * w - (float)i, fv = v * h - (float)j;
            float sin_t = sqrtf(fmaxf(0.0f, 1.0f - d.y * d.y));
            if (fu > 1e-4f && fu < 1 - 1e-4f && fv > 1e-4f && fv < 1 - 1e-4f && sin_t > 0.02f) {
                float p2 = gi_envmap_pdf(env, d);
                double rel = fabs(p2 - pdf) / pdf;
                worst = fmax(worst, rel);
                pdf_checked++;
                pdf_ok += rel < 1e-3;
            }
        }
        CHECK(texel_ok);
        CHECK_MSG(pdf_ok == pdf_checked && pdf_checked > n * 9 / 10,
                  "%d of %d pdfs agree, worst relative error %g", pdf_ok, pdf_checked, worst);

        double chi2 = 0;
        int dof = -1, never_ok = 1;
        for (uint32_t k = 0; k < w * h; k++) {
            double e = prob[k] * n;
            if (prob[k] == 0.0) {
                never_ok &= count[k] == 0;
                continue;
            }
            chi2 += (count[k] - e) * (count[k] - e) / e;
            dof++;
        }
        printf("pass %d: chi2 %.1f, dof %d, 0.1%% critical %.1f; pdf worst rel. error %.2g\n", pass,
               chi2, dof, chi2_critical(dof), worst);
        CHECK_MSG(never_ok, "a black texel was sampled (pass %d)", pass);
        CHECK_MSG(chi2 < chi2_critical(dof), "chi2 %.1f > %.1f (dof %d, pass %d)", chi2,
                  chi2_critical(dof), dof, pass);
        gi_envmap_free(env);
    }
    free(rgba);
}

static void test_black(void)
{
    float rgba[8 * 4 * 4];
    for (int k = 0; k < 8 * 4 * 4; k++)
        rgba[k] = (k % 4 == 3) ? 1.0f : ((k & 1) ? 0.0f : -1.0f); /* black or negative */
    gi_envmap *env = gi_envmap_create(rgba, 8, 4, 3.0f, 10.0f);
    CHECK(env != NULL);
    gi_vec3 d = gi_v3(0.3f, 0.4f, 0.5f);
    CHECK(gi_envmap_sample(env, 0.3f, 0.6f, &d) == 0.0f);
    CHECK(d.x == 0.0f && d.y == 1.0f && d.z == 0.0f);
    CHECK(gi_envmap_pdf(env, gi_v3(0.0f, 0.0f, -1.0f)) == 0.0f);
    CHECK(env->marg_cdf[4] == 0.0f);
    CHECK(gi_envmap_average_radiance(env) == 0.0f);
    gi_envmap_free(env);

    CHECK(gi_envmap_create(rgba, 0, 4, 1.0f, 0.0f) == NULL);
    CHECK(gi_envmap_create(NULL, 8, 4, 1.0f, 0.0f) == NULL);
    gi_envmap_free(NULL);
}

static void test_cdf_layout(void)
{
    const uint32_t w = 16, h = 8;
    float *rgba = random_map(w, h, 3);
    gi_envmap *env = gi_envmap_create(rgba, w, h, 1.0f, 0.0f);
    int ok = env->marg_cdf[0] == 0.0f && env->marg_cdf[h] == 1.0f;
    for (uint32_t j = 0; j < h; j++) {
        const float *c = env->cond_cdf + j * (w + 1);
        ok &= c[0] == 0.0f && c[w] == 1.0f && env->marg_cdf[j] <= env->marg_cdf[j + 1];
        for (uint32_t i = 0; i < w; i++)
            ok &= c[i] <= c[i + 1];
    }
    CHECK(ok);
    gi_envmap_free(env);
    free(rgba);
}

int main(void)
{
    test_mapping();
    test_rotation_and_eval();
    test_pdf_normalised();
    test_cdf_layout();
    test_sampling();
    test_black();
    return gi_test_finish();
}

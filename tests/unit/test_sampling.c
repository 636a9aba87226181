/* CPU side of the shared sampling code: rng.h (known PCG values), sequences.h
 * (known points, (0,m,2)-net property), sampling.h (pdf normalisation,
 * moments, frames) and brdf.h (Phong lobe pdf integral and chi-square of its
 * sampler, sample weight = f cos / pdf, white furnace, BRDF sampling against
 * an independent uniform-hemisphere estimate of the albedo). */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gi/brdf.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/sequences.h"

/* Upper 0.1% point of chi-square with k degrees of freedom (Wilson-Hilferty). */
static double chi2_critical(int k)
{
    const double z = 3.090;
    double a = 2.0 / (9.0 * k);
    double t = 1.0 - a + z * sqrt(a);
    return k * t * t * t;
}

/* Chi-square of observed counts against expected probabilities; bins with
 * an expected count below 5 are pooled. Returns the statistic, *dof set. */
static double chi2_stat(const long *count, const double *prob, int bins, long n, int *dof)
{
    double chi2 = 0, pool_e = 0, pool_o = 0;
    int k = 0;
    for (int b = 0; b < bins; b++) {
        double e = prob[b] * n;
        if (e < 5.0) {
            pool_e += e;
            pool_o += count[b];
            continue;
        }
        chi2 += (count[b] - e) * (count[b] - e) / e;
        k++;
    }
    if (pool_e >= 5.0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        k++;
    } else if (pool_o > 10.0 + 10.0 * pool_e) {
        chi2 += 1e9; /* samples where the pdf says there are (almost) none */
    }
    *dof = k - 1;
    return chi2;
}

static gi_vec3 random_unit(uint32_t *s)
{
    return gi_sample_uniform_sphere(gi_rng_next_float(s), gi_rng_next_float(s));
}

static void test_rng(void)
{
    /* Values computed independently (Python) from the published constants. */
    CHECK(gi_pcg_hash(0) == 129708002u);
    CHECK(gi_pcg_hash(1) == 2831084092u);
    CHECK(gi_pcg_hash(12345) == 4099845390u);
    CHECK(gi_pcg_hash(0xffffffffu) == 3861530882u);
    uint32_t s = gi_rng_init(3, 5, 7);
    CHECK(s == 2686087347u);
    CHECK(gi_rng_next_u32(&s) == 4226808718u);
    CHECK(gi_rng_next_u32(&s) == 1738256761u);
    CHECK(gi_rng_next_u32(&s) == 3291756216u);

    /* Floats in [0, 1) with mean 1/2 and variance 1/12. */
    s = gi_rng_init(0, 0, 1);
    double sum = 0, sum2 = 0;
    int in_range = 1;
    const int n = 1000000;
    for (int k = 0; k < n; k++) {
        float u = gi_rng_next_float(&s);
        in_range &= u >= 0.0f && u < 1.0f;
        sum += u;
        sum2 += (double)u * u;
    }
    CHECK(in_range);
    CHECK_NEAR(sum / n, 0.5, 2e-3);
    CHECK_NEAR(sum2 / n - (sum / n) * (sum / n), 1.0 / 12.0, 1e-3);
    s = 0xffffffffu; /* the top value maps below 1 */
    CHECK(gi_u32_to_unit(0xffffffffu) < 1.0f);

    /* Neighbouring streams do not start alike. */
    int distinct = 1;
    uint32_t first[256];
    for (uint32_t p = 0; p < 256; p++) {
        uint32_t st = gi_rng_init(p, 0, 42);
        first[p] = gi_rng_next_u32(&st);
        for (uint32_t q = 0; q < p; q++)
            distinct &= first[q] != first[p];
    }
    CHECK(distinct);
    uint32_t a = gi_rng_init(1, 2, 3), b = gi_rng_init(1, 3, 3), c = gi_rng_init(1, 2, 4);
    CHECK(a != b && a != c && b != c);
}

/* Every elementary interval [a 2^-k, (a+1) 2^-k) x [b 2^-(m-k), ...) of the
 * first 2^m points holds exactly one point. */
static int is_02_net(const float (*pts)[2], int m)
{
    int n = 1 << m;
    int *cell = malloc(sizeof(int) * n);
    int ok = 1;
    for (int k = 0; k <= m; k++) {
        memset(cell, 0, sizeof(int) * n);
        for (int i = 0; i < n; i++) {
            int x = (int)(pts[i][0] * (float)(1 << k));
            int y = (int)(pts[i][1] * (float)(1 << (m - k)));
            cell[(x << (m - k)) | y]++;
        }
        for (int i = 0; i < n; i++)
            ok &= cell[i] == 1;
    }
    free(cell);
    return ok;
}

static void test_sequences(void)
{
    CHECK(gi_radical_inverse2(0) == 0.0f);
    CHECK(gi_radical_inverse2(1) == 0.5f);
    CHECK(gi_radical_inverse2(2) == 0.25f);
    CHECK(gi_radical_inverse2(3) == 0.75f);
    CHECK(gi_radical_inverse2(0xffffffffu) < 1.0f);
    CHECK(gi_reverse_bits32(1u) == 0x80000000u);
    CHECK(gi_reverse_bits32(0x12345678u) == 0x1e6a2c48u);
    CHECK_NEAR(gi_halton(1, 1), 1.0 / 3.0, 1e-7);
    CHECK_NEAR(gi_halton(1, 2), 2.0 / 3.0, 1e-7);
    CHECK_NEAR(gi_halton(1, 3), 1.0 / 9.0, 1e-7);
    CHECK_NEAR(gi_halton(2, 7), 2.0 / 5.0 + 1.0 / 25.0, 1e-7);
    CHECK_NEAR(gi_halton(7, 20), 1.0 / 19.0 + 1.0 / 361.0, 1e-7);
    CHECK(gi_halton(0, 6) == gi_radical_inverse2(6));
    int in_range = 1;
    for (uint32_t d = 0; d < 8; d++)
        for (uint32_t i = 0; i < 5000; i++) {
            float h = gi_halton(d, i * 7919u + 1u);
            in_range &= h >= 0.0f && h < 1.0f;
        }
    CHECK(in_range);
    /* Base-3 digits pile up to just below 1: still below. */
    CHECK(gi_radical_inverse(3, 3486784400u) < 1.0f);

    CHECK(gi_sobol2(0) == 0.0f && gi_sobol2(1) == 0.5f && gi_sobol2(2) == 0.75f &&
          gi_sobol2(3) == 0.25f);
    enum { M = 10, N = 1 << M };
    float pts[N][2];
    for (int i = 0; i < N; i++)
        gi_sobol02((uint32_t)i, pts[i]);
    CHECK(is_02_net((const float(*)[2])pts, M));
    for (int i = 0; i < N; i++)
        gi_hammersley((uint32_t)i, N, pts[i]);
    CHECK(is_02_net((const float(*)[2])pts, M));
    float hm[2];
    gi_hammersley(3, 4, hm);
    CHECK(hm[0] == 0.75f && hm[1] == 0.75f);
    /* Sobol points 2^m .. 2^(m+1)-1 are again a net. */
    for (int i = 0; i < N; i++)
        gi_sobol02((uint32_t)(N + i), pts[i]);
    CHECK(is_02_net((const float(*)[2])pts, M));

    float r2[2];
    gi_r2(0, r2);
    CHECK(r2[0] == 0.5f && r2[1] == 0.5f);
    gi_r2(1, r2);
    CHECK_NEAR(r2[0], 0.2548776662466927, 1e-6);
    CHECK_NEAR(r2[1], 0.0698402909980532, 1e-6);
    /* Far out the points follow the 0.32 fixed-point alphas exactly. */
    gi_r2(1000003, r2);
    CHECK_NEAR(r2[0], fmod(0.5 + 1000003 * (3242174889.0 / 4294967296.0), 1.0), 1e-7);
    CHECK_NEAR(r2[1], fmod(0.5 + 1000003 * (2447445414.0 / 4294967296.0), 1.0), 1e-7);

    CHECK_NEAR(gi_cp_rotate(0.7f, 0.5f), 0.2, 1e-7);
    CHECK_NEAR(gi_cp_rotate(0.25f, 0.5f), 0.75, 1e-7);
    CHECK(gi_cp_rotate(0.5f, 0.5f) == 0.0f);
    CHECK(gi_cp_rotate(GI_ONE_MINUS_EPSILON, GI_ONE_MINUS_EPSILON) < 1.0f);
}

static void test_warps(void)
{
    const int n = 400000;
    uint32_t s = gi_rng_init(0, 0, 77);
    /* Histograms of quantities that each warp makes uniform. */
    enum { B = 20 };
    long h_cos[B] = {0}, h_sph[B] = {0}, h_hemi[B] = {0}, h_cone[B] = {0}, h_disk[B] = {0};
    long h_phi[B] = {0};
    double m_cos = 0, m_sph[3] = {0}, m_tri[3] = {0}, m_tri2 = 0;
    int ok = 1;
    const float cos_max = 0.8f;
    for (int k = 0; k < n; k++) {
        float u1 = gi_rng_next_float(&s), u2 = gi_rng_next_float(&s);
        gi_vec3 d = gi_sample_cosine_hemisphere(u1, u2);
        ok &= d.z >= 0.0f && fabsf(gi_v3_length(d) - 1.0f) < 1e-5f;
        h_cos[(int)(d.z * d.z * B) < B ? (int)(d.z * d.z * B) : B - 1]++; /* z^2 ~ U(0,1) */
        double phi = atan2(d.y, d.x) + GI_PI;
        h_phi[(int)(phi / (2 * GI_PI) * B) % B]++;
        m_cos += d.z;

        gi_vec3 e = gi_sample_uniform_sphere(u1, u2);
        ok &= fabsf(gi_v3_length(e) - 1.0f) < 1e-5f;
        h_sph[(int)((e.z + 1.0f) * 0.5f * B) < B ? (int)((e.z + 1.0f) * 0.5f * B) : B - 1]++;
        m_sph[0] += e.x, m_sph[1] += e.y, m_sph[2] += (double)e.z * e.z;

        gi_vec3 f = gi_sample_uniform_hemisphere(u1, u2);
        ok &= f.z >= 0.0f && fabsf(gi_v3_length(f) - 1.0f) < 1e-5f;
        h_hemi[(int)(f.z * B) < B ? (int)(f.z * B) : B - 1]++;

        gi_vec3 g = gi_sample_uniform_cone(u1, u2, cos_max);
        ok &= g.z >= cos_max - 1e-6f && fabsf(gi_v3_length(g) - 1.0f) < 1e-5f;
        int cb = (int)((g.z - cos_max) / (1.0f - cos_max) * B);
        h_cone[cb < 0 ? 0 : (cb < B ? cb : B - 1)]++;

        float x, y;
        gi_sample_concentric_disk(u1, u2, &x, &y);
        float r2 = x * x + y * y;
        ok &= r2 <= 1.0f + 1e-6f;
        h_disk[(int)(r2 * B) < B ? (int)(r2 * B) : B - 1]++;

        float b[3];
        gi_sample_uniform_triangle(u1, u2, b);
        ok &= b[0] >= 0.0f && b[1] >= 0.0f && b[2] >= -1e-7f &&
              fabsf(b[0] + b[1] + b[2] - 1.0f) < 1e-6f;
        for (int c = 0; c < 3; c++)
            m_tri[c] += b[c];
        m_tri2 += (double)b[0] * b[0];
    }
    CHECK(ok);
    double uni[B];
    for (int b = 0; b < B; b++)
        uni[b] = 1.0 / B;
    const long *hists[6] = {h_cos, h_phi, h_sph, h_hemi, h_cone, h_disk};
    const char *names[6] = {"cosine z^2",   "cosine phi", "sphere z",
                            "hemisphere z", "cone z",     "disk r^2"};
    for (int i = 0; i < 6; i++) {
        int dof;
        double chi2 = chi2_stat(hists[i], uni, B, n, &dof);
        CHECK_MSG(chi2 < chi2_critical(dof), "%s: chi2 %.1f", names[i], chi2);
    }
    /* Moments: E[cos] = 2/3 under cos/pi; sphere mean 0, E[z^2] = 1/3;
     * triangle E[b] = 1/3, E[b^2] = 1/6. */
    CHECK_NEAR(m_cos / n, 2.0 / 3.0, 2e-3);
    CHECK_NEAR(m_sph[0] / n, 0.0, 4e-3);
    CHECK_NEAR(m_sph[1] / n, 0.0, 4e-3);
    CHECK_NEAR(m_sph[2] / n, 1.0 / 3.0, 2e-3);
    for (int c = 0; c < 3; c++)
        CHECK_NEAR(m_tri[c] / n, 1.0 / 3.0, 2e-3);
    CHECK_NEAR(m_tri2 / n, 1.0 / 6.0, 2e-3);

    /* pdfs integrate to 1: Int pdf dw estimated with uniform sphere samples. */
    double i_cos = 0, i_cone = 0, i_hemi = 0;
    for (int k = 0; k < n; k++) {
        gi_vec3 d = random_unit(&s);
        i_cos += gi_cosine_hemisphere_pdf(d.z);
        i_cone += d.z >= cos_max ? gi_uniform_cone_pdf(cos_max) : 0.0f;
        i_hemi += d.z >= 0.0f ? gi_uniform_hemisphere_pdf() : 0.0f;
    }
    double sphere = 4.0 * GI_PI / n;
    CHECK_NEAR(i_cos * sphere, 1.0, 1e-2);
    CHECK_NEAR(i_cone * sphere, 1.0, 2e-2);
    CHECK_NEAR(i_hemi * sphere, 1.0, 1e-2);
    CHECK_NEAR(gi_uniform_sphere_pdf() * 4.0 * GI_PI, 1.0, 1e-6);
    CHECK_NEAR(gi_cosine_hemisphere_pdf(-0.5f), 0.0, 0.0);

    CHECK_NEAR(gi_power_heuristic(1, 2.0f, 1, 1.0f), 0.8, 1e-6);
    CHECK_NEAR(gi_power_heuristic(1, 0.0f, 1, 1.0f), 0.0, 0.0);
    CHECK_NEAR(gi_power_heuristic(1, 1.0f, 1, 0.0f), 1.0, 0.0);
    CHECK_NEAR(gi_power_heuristic(1, 1e30f, 1, 1.0f), 1.0, 1e-6);
    CHECK_NEAR(gi_power_heuristic(1, 1.0f, 1, INFINITY), 0.0, 0.0);
    CHECK_NEAR(gi_power_heuristic(1, 1.0f, 1, 1.0f) + gi_power_heuristic(1, 1.0f, 1, 1.0f), 1.0,
               1e-6);
}

static void test_frames(void)
{
    uint32_t s = gi_rng_init(4, 4, 4);
    gi_vec3 normals[6] = {gi_v3(0, 0, 1),  gi_v3(0, 0, -1),    gi_v3(1, 0, 0),
                          gi_v3(0, -1, 0), gi_v3(0, 0, -0.0f), gi_v3(0, 1, 0)};
    normals[4] = gi_v3(0.0f, 0.0f, 1.0f);
    double worst = 0;
    for (int k = 0; k < 10000; k++) {
        gi_vec3 n = k < 6 ? normals[k] : random_unit(&s);
        gi_vec3 t, b;
        gi_onb(n, &t, &b);
        worst = fmax(worst, fabs(gi_v3_dot(t, b)) + fabs(gi_v3_dot(t, n)) + fabs(gi_v3_dot(b, n)) +
                                fabs(gi_v3_length(t) - 1) + fabs(gi_v3_length(b) - 1));
        /* Right-handed: t x b = n. */
        worst = fmax(worst, gi_v3_length(gi_v3_sub(gi_v3_cross(t, b), n)));
        gi_vec3 l = random_unit(&s);
        gi_vec3 w = gi_to_world(l, n);
        gi_vec3 back = gi_to_local(w, n);
        worst = fmax(worst, gi_v3_length(gi_v3_sub(back, l)));
        worst = fmax(worst, fabs(gi_v3_dot(w, n) - l.z));
        gi_vec3 z = gi_to_world(gi_v3(0, 0, 1), n);
        worst = fmax(worst, gi_v3_length(gi_v3_sub(z, n)));
    }
    CHECK_MSG(worst < 1e-5, "frame error %g", worst);
}

/* Direction at angles (theta, phi) in the frame of unit axis r. */
static gi_vec3 dir_about(gi_vec3 r, double theta, double phi)
{
    return gi_to_world(
        gi_v3((float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)), (float)cos(theta)),
        r);
}

static void test_phong_lobe(void)
{
    uint32_t s = gi_rng_init(8, 8, 8);
    const float ns[6] = {0, 1, 10, 100, 1000, 9000};
    for (int k = 0; k < 6; k++) {
        gi_vec3 r = random_unit(&s);
        /* 2 pi Int pdf sin(theta) dtheta over the half-sphere about r. */
        const int steps = 200000;
        double sum = 0;
        for (int t = 0; t < steps; t++) {
            double theta = (t + 0.5) * (GI_PI / 2) / steps;
            sum += gi_phong_lobe_pdf(r, ns[k], dir_about(r, theta, 1.0)) * sin(theta);
        }
        CHECK_MSG(fabs(sum * 2 * GI_PI * (GI_PI / 2) / steps - 1.0) < 2e-3, "n %g: %.6f", ns[k],
                  sum * 2 * GI_PI * (GI_PI / 2) / steps);
        CHECK(gi_phong_lobe_pdf(r, ns[k], gi_v3_scale(r, -1.0f)) == 0.0f);
    }

    /* Chi-square of the sampler against the pdf on a (theta, phi) grid about
     * r; bin probabilities integrated from gi_phong_lobe_pdf. */
    const float chi_ns[4] = {1, 10, 100, 1000};
    enum { NT = 24, NP = 12 };
    for (int k = 0; k < 4; k++) {
        float n = chi_ns[k];
        gi_vec3 r = random_unit(&s);
        /* Most of the lobe lies within a few 1/sqrt(n) of r. */
        double tmax = fmin(GI_PI / 2, 6.0 / sqrt(n + 1.0));
        double prob[NT * NP + 1];
        double covered = 0;
        for (int t = 0; t < NT; t++) {
            double t0 = t * tmax / NT, t1 = (t + 1) * tmax / NT, acc = 0;
            for (int q = 0; q < 256; q++) {
                double th = t0 + (q + 0.5) * (t1 - t0) / 256;
                acc += gi_phong_lobe_pdf(r, n, dir_about(r, th, 0.3)) * sin(th);
            }
            acc *= (t1 - t0) / 256 * (2 * GI_PI / NP);
            for (int p = 0; p < NP; p++)
                prob[t * NP + p] = acc;
            covered += acc * NP;
        }
        prob[NT * NP] = fmax(0.0, 1.0 - covered); /* beyond tmax */
        const long total = 300000;
        long count[NT * NP + 1] = {0};
        int above = 1;
        for (long m = 0; m < total; m++) {
            gi_vec3 wi = gi_phong_lobe_sample(r, n, gi_rng_next_float(&s), gi_rng_next_float(&s));
            gi_vec3 l = gi_to_local(wi, r);
            above &= l.z >= -1e-6f;
            double theta = acos(fmin(1.0, fmax(-1.0, l.z)));
            double phi = atan2(l.y, l.x);
            phi = phi < 0 ? phi + 2 * GI_PI : phi;
            int tb = (int)(theta / tmax * NT), pb = (int)(phi / (2 * GI_PI) * NP) % NP;
            count[tb >= NT ? NT * NP : tb * NP + pb]++;
        }
        CHECK(above);
        int dof;
        double chi2 = chi2_stat(count, prob, NT * NP + 1, total, &dof);
        printf("phong lobe n=%g: chi2 %.1f, dof %d, 0.1%% critical %.1f\n", n, chi2, dof,
               chi2_critical(dof));
        CHECK_MSG(chi2 < chi2_critical(dof), "phong n=%g chi2 %.1f (dof %d)", n, chi2, dof);
    }
}

/* Chi-square of the whole BRDF sampler (lobe choice, both lobes, clipping
 * at the surface) against gi_brdf_pdf, on a (cos theta, phi) grid about N;
 * what the reference path tracer draws. Bin probabilities come from a
 * midpoint rule over each bin (dw = dcos dphi); samples that fail (wi below
 * the surface) go to one more bin of probability 1 - sum. */
static void test_brdf_chi2(void)
{
    enum { NC = 20, NP = 24, Q = 24 };
    struct {
        gi_brdf b;
        double theta_o;
    } cases[] = {
        {{{0.6f, 0.6f, 0.6f}, {0, 0, 0}, 0, 0}, 0.7},           /* Lambert */
        {{{0.3f, 0.3f, 0.3f}, {0.5f, 0.5f, 0.5f}, 20, 0}, 0.5}, /* mixture */
        {{{0.2f, 0.2f, 0.2f}, {0.6f, 0.6f, 0.6f}, 8, 0}, 1.25}, /* lobe clipped by the surface */
        {{{0, 0, 0}, {0.9f, 0.9f, 0.9f}, 60, 0}, 1.0},          /* Phong only */
    };
    uint32_t s = gi_rng_init(9, 9, 9);
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const gi_brdf *b = &cases[k].b;
        gi_vec3 N = random_unit(&s);
        gi_vec3 wo = dir_about(N, cases[k].theta_o, 0.4);
        static double prob[NC * NP + 1];
        double covered = 0;
        for (int c = 0; c < NC; c++)
            for (int p = 0; p < NP; p++) {
                double acc = 0;
                for (int qc = 0; qc < Q; qc++)
                    for (int qp = 0; qp < Q; qp++) {
                        double cth = (c + (qc + 0.5) / Q) / NC,
                               phi = (p + (qp + 0.5) / Q) * 2 * GI_PI / NP;
                        acc += gi_brdf_pdf(b, N, wo, dir_about(N, acos(cth), phi));
                    }
                prob[c * NP + p] = acc / (Q * Q) * (1.0 / NC) * (2 * GI_PI / NP);
                covered += prob[c * NP + p];
            }
        prob[NC * NP] = fmax(0.0, 1.0 - covered);
        const long total = 400000;
        static long count[NC * NP + 1];
        memset(count, 0, sizeof count);
        for (long m = 0; m < total; m++) {
            gi_vec3 wi;
            float pdf, w[3];
            int delta;
            gi_brdf_sample(b, N, wo, gi_rng_next_float(&s), gi_rng_next_float(&s),
                           gi_rng_next_float(&s), &wi, &pdf, w, &delta);
            if (pdf == 0.0f) {
                count[NC * NP]++;
                continue;
            }
            gi_vec3 l = gi_to_local(wi, N);
            double phi = atan2(l.y, l.x);
            phi = phi < 0 ? phi + 2 * GI_PI : phi;
            int cb = (int)(l.z * NC), pb = (int)(phi / (2 * GI_PI) * NP) % NP;
            cb = cb < 0 ? 0 : (cb >= NC ? NC - 1 : cb);
            count[cb * NP + pb]++;
        }
        int dof;
        double chi2 = chi2_stat(count, prob, NC * NP + 1, total, &dof);
        printf("brdf sampler case %zu: chi2 %.1f, dof %d, 0.1%% critical %.1f, failed %.4f (pdf "
               "says %.4f)\n",
               k, chi2, dof, chi2_critical(dof), (double)count[NC * NP] / total, prob[NC * NP]);
        CHECK_MSG(chi2 < chi2_critical(dof), "brdf case %zu chi2 %.1f (dof %d)", k, chi2, dof);
    }
}

static gi_brdf make_brdf(float kd, float ks, float n, int mirror)
{
    gi_brdf b = {{kd, kd, kd}, {ks, ks, ks}, n, mirror};
    return b;
}

/* wo at polar angle theta from N (in N's frame, phi fixed). */
static gi_vec3 wo_at(gi_vec3 N, double theta)
{
    return dir_about(N, theta, 0.7);
}

static void test_brdf_sample_consistency(void)
{
    uint32_t s = gi_rng_init(6, 6, 6);
    int ok_weight = 1, ok_pdf = 1, ok_delta = 1, ok_zero = 1, nonzero = 0;
    for (int k = 0; k < 200000; k++) {
        gi_brdf b = {{gi_rng_next_float(&s), gi_rng_next_float(&s), gi_rng_next_float(&s)},
                     {0, 0, 0},
                     1.0f + 200.0f * gi_rng_next_float(&s),
                     0};
        if (k % 3 != 0)
            for (int c = 0; c < 3; c++)
                b.ks[c] = 0.5f * gi_rng_next_float(&s);
        if (k % 7 == 0)
            b.mirror = 1;
        if (k % 11 == 0)
            b.n = 20000.0f; /* mirror by exponent */
        gi_vec3 N = random_unit(&s);
        gi_vec3 wo = random_unit(&s);
        float u1 = gi_rng_next_float(&s), u2 = gi_rng_next_float(&s), u3 = gi_rng_next_float(&s);
        gi_vec3 wi;
        float pdf, w[3];
        int delta;
        gi_brdf_sample(&b, N, wo, u1, u2, u3, &wi, &pdf, w, &delta);
        if (gi_v3_dot(N, wo) <= 0.0f) {
            ok_zero &= pdf == 0.0f && w[0] == 0.0f && w[1] == 0.0f && w[2] == 0.0f;
            continue;
        }
        if (delta) {
            gi_vec3 r = gi_reflect(wo, N);
            float ps = gi_brdf_spec_prob(&b);
            ok_delta &= gi_brdf_is_mirror(&b) && gi_v3_length(gi_v3_sub(wi, r)) < 1e-6f &&
                        pdf == ps && fabsf(w[0] - b.ks[0] / ps) < 1e-6f;
            continue;
        }
        if (pdf == 0.0f) {
            ok_zero &= w[0] == 0.0f && w[1] == 0.0f && w[2] == 0.0f;
            continue;
        }
        nonzero++;
        float f[3];
        gi_brdf_eval(&b, N, wo, wi, f);
        float p = gi_brdf_pdf(&b, N, wo, wi);
        float cos_i = gi_v3_dot(N, wi);
        ok_pdf &= fabsf(p - pdf) <= 1e-6f * pdf;
        for (int c = 0; c < 3; c++)
            ok_weight &= fabsf(w[c] - f[c] * cos_i / p) <= 1e-5f * fmaxf(1.0f, w[c]);
    }
    CHECK(ok_weight);
    CHECK(ok_pdf);
    CHECK(ok_delta);
    CHECK(ok_zero);
    CHECK(nonzero > 50000);

    /* Eval and pdf vanish below the surface; mirror lobe excluded from eval. */
    gi_vec3 N = gi_v3(0, 1, 0), wo = gi_v3_normalize(gi_v3(1, 1, 0));
    gi_brdf b = make_brdf(0.5f, 0.5f, 10.0f, 0);
    float f[3];
    gi_brdf_eval(&b, N, wo, gi_v3(0, -1, 0), f);
    CHECK(f[0] == 0.0f && f[1] == 0.0f && f[2] == 0.0f);
    CHECK(gi_brdf_pdf(&b, N, wo, gi_v3(0, -1, 0)) == 0.0f);
    gi_brdf_eval(&b, N, gi_v3(0, -1, 0), gi_v3(0, 1, 0), f);
    CHECK(f[0] == 0.0f);
    gi_brdf m = make_brdf(0.0f, 1.0f, 10.0f, 1);
    gi_brdf_eval(&m, N, wo, gi_reflect(wo, N), f);
    CHECK(f[0] == 0.0f);
    CHECK(gi_brdf_pdf(&m, N, wo, gi_reflect(wo, N)) == 0.0f);
    /* Analytic values: Lambert kd/pi; Phong peak ks (n+2)/(2 pi) + kd/pi. */
    gi_brdf_eval(&b, N, wo, gi_v3(0, 1, 0), f);
    gi_vec3 r = gi_reflect(wo, N);
    double c = gi_v3_dot(r, gi_v3(0, 1, 0));
    CHECK_NEAR(f[0], 0.5 / GI_PI + 0.5 * 12.0 / (2 * GI_PI) * pow(c, 10.0), 1e-6);
    gi_brdf_eval(&b, N, wo, r, f);
    CHECK_NEAR(f[0], 0.5 / GI_PI + 0.5 * 12.0 / (2 * GI_PI), 1e-5);
    CHECK_NEAR(gi_brdf_spec_prob(&b), 0.5, 1e-7);
    gi_brdf d = make_brdf(0.8f, 0.0f, 0.0f, 0);
    CHECK(gi_brdf_spec_prob(&d) == 0.0f);
    CHECK(!gi_brdf_is_mirror(&b) && gi_brdf_is_mirror(&m));
    gi_brdf big = make_brdf(0.0f, 1.0f, GI_MIRROR_EXPONENT, 0);
    CHECK(gi_brdf_is_mirror(&big));
}

/* Albedo by BRDF sampling (mean weight) and by uniform hemisphere sampling
 * (mean of f cos 2 pi): independent estimators that must agree. */
static void albedo(const gi_brdf *b, gi_vec3 N, gi_vec3 wo, int n, uint32_t *s, double out[2],
                   double err[2])
{
    double m[2] = {0, 0}, m2[2] = {0, 0};
    for (int k = 0; k < n; k++) {
        gi_vec3 wi;
        float pdf, w[3], f[3];
        int delta;
        gi_brdf_sample(b, N, wo, gi_rng_next_float(s), gi_rng_next_float(s), gi_rng_next_float(s),
                       &wi, &pdf, w, &delta);
        m[0] += w[1];
        m2[0] += (double)w[1] * w[1];
        gi_vec3 h = gi_to_world(
            gi_sample_uniform_hemisphere(gi_rng_next_float(s), gi_rng_next_float(s)), N);
        gi_brdf_eval(b, N, wo, h, f);
        double e = f[1] * gi_v3_dot(N, h) * 2.0 * GI_PI;
        m[1] += e;
        m2[1] += e * e;
    }
    for (int i = 0; i < 2; i++) {
        out[i] = m[i] / n;
        err[i] = sqrt(fmax(0.0, m2[i] / n - out[i] * out[i]) / n);
    }
}

static void test_furnace(void)
{
    uint32_t s = gi_rng_init(2, 2, 2);
    gi_vec3 N = gi_v3_normalize(gi_v3(0.3f, 0.9f, -0.2f));
    double a[2], e[2];

    /* Lambert kd = 1 reflects everything: every weight is exactly 1. */
    gi_brdf lam = make_brdf(1.0f, 0.0f, 0.0f, 0);
    albedo(&lam, N, wo_at(N, 1.0), 100000, &s, a, e);
    CHECK_NEAR(a[0], 1.0, 1e-4);
    CHECK_NEAR(a[1], 1.0, 5 * e[1] + 1e-3);

    /* Mirror ks = 1: albedo exactly 1 at any angle. */
    gi_brdf mir = make_brdf(0.0f, 1.0f, 0.0f, 1);
    albedo(&mir, N, wo_at(N, 1.3), 1000, &s, a, e);
    CHECK_NEAR(a[0], 1.0, 1e-6);

    /* Phong ks = 1: albedo 1 at normal incidence, below 1 elsewhere; BRDF
     * sampling agrees with the independent uniform estimate. */
    const float ns[4] = {1, 10, 100, 1000};
    const double angles[4] = {0.0, 0.6, 1.2, 1.5};
    for (int k = 0; k < 4; k++) {
        gi_brdf ph = make_brdf(0.0f, 1.0f, ns[k], 0);
        for (int t = 0; t < 4; t++) {
            gi_vec3 wo = t == 0 ? N : wo_at(N, angles[t]);
            albedo(&ph, N, wo, 200000, &s, a, e);
            if (t == 0)
                CHECK_MSG(fabs(a[0] - 1.0) < 4 * e[0] + 1e-3, "n %g: albedo %.5f +- %.5f", ns[k],
                          a[0], e[0]);
            CHECK_MSG(a[0] <= 1.0 + 4 * e[0] + 1e-4, "n %g angle %g: albedo %.5f", ns[k], angles[t],
                      a[0]);
            if (ns[k] <= 100) /* uniform sampling is too noisy for sharper lobes */
                CHECK_MSG(fabs(a[0] - a[1]) < 5 * sqrt(e[0] * e[0] + e[1] * e[1]) + 1e-3,
                          "n %g angle %g: brdf sampling %.5f +- %.5f, uniform %.5f +- %.5f", ns[k],
                          angles[t], a[0], e[0], a[1], e[1]);
        }
    }

    /* Mixed lobe, kd + ks = 1: energy <= 1, and both estimators agree. */
    gi_brdf mix = {{0.6f, 0.5f, 0.4f}, {0.4f, 0.5f, 0.6f}, 30.0f, 0};
    for (int t = 0; t < 4; t++) {
        albedo(&mix, N, wo_at(N, angles[t]), 200000, &s, a, e);
        CHECK(a[0] <= 1.0 + 4 * e[0]);
        CHECK_MSG(fabs(a[0] - a[1]) < 5 * sqrt(e[0] * e[0] + e[1] * e[1]) + 1e-3,
                  "mix angle %g: %.5f vs %.5f", angles[t], a[0], a[1]);
    }
}

int main(void)
{
    test_rng();
    test_sequences();
    test_warps();
    test_frames();
    test_phong_lobe();
    test_brdf_sample_consistency();
    test_brdf_chi2();
    test_furnace();
    return gi_test_finish();
}

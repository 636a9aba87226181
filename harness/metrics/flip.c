/* LDR-FLIP (Andersson et al., HPG 2020): colour pipeline (§3 of the paper:
 * CSF filtering in YCxCz, Hunt-adjusted CIELAB, HyAB, compression), feature
 * pipeline (§4: edge and point detectors) and their combination. See flip.h. */
#include "flip.h"

#include "filter.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

const gi_flip_csf gi_flip_csf_params[3] = {
    {1.0, 0.0047, 0.0, 1e-5},  /* A  */
    {1.0, 0.0053, 0.0, 1e-5},  /* RG */
    {34.1, 0.04, 13.5, 0.025}, /* BY */
};

/* ---- colorimetry: sRGB primaries, D65 ---- */

static const double RGB2XYZ[3][3] = {
    {0.4124564, 0.3575761, 0.1804375},
    {0.2126729, 0.7151522, 0.0721750},
    {0.0193339, 0.1191920, 0.9503041},
};
static const double XYZ2RGB[3][3] = {
    {3.2404542, -1.5371385, -0.4985314},
    {-0.9692660, 1.8760108, 0.0415560},
    {0.0556434, -0.2040259, 1.0572252},
};
/* White = RGB2XYZ * (1, 1, 1), so linear RGB white has L* = 100, a* = b* = 0. */
#define WX (0.4124564 + 0.3575761 + 0.1804375)
#define WY (0.2126729 + 0.7151522 + 0.0721750)
#define WZ (0.0193339 + 0.1191920 + 0.9503041)

static void mul3(const double m[3][3], const double v[3], double o[3])
{
    double r[3];
    for (int i = 0; i < 3; i++)
        r[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    o[0] = r[0];
    o[1] = r[1];
    o[2] = r[2];
}

void gi_flip_linrgb_to_xyz(const double rgb[3], double xyz[3])
{
    mul3(RGB2XYZ, rgb, xyz);
}

void gi_flip_xyz_to_linrgb(const double xyz[3], double rgb[3])
{
    mul3(XYZ2RGB, xyz, rgb);
}

void gi_flip_xyz_to_ycxcz(const double xyz[3], double o[3])
{
    double x = xyz[0] / WX, y = xyz[1] / WY, z = xyz[2] / WZ;
    o[0] = 116.0 * y - 16.0;
    o[1] = 500.0 * (x - y);
    o[2] = 200.0 * (y - z);
}

void gi_flip_ycxcz_to_xyz(const double c[3], double xyz[3])
{
    double y = (c[0] + 16.0) / 116.0;
    double x = y + c[1] / 500.0;
    double z = y - c[2] / 200.0;
    xyz[0] = x * WX;
    xyz[1] = y * WY;
    xyz[2] = z * WZ;
}

/* CIELAB's f(t): cube root above (6/29)^3, its tangent line below. */
static double lab_f(double t)
{
    const double d = 6.0 / 29.0;
    return t > d * d * d ? cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
}

void gi_flip_xyz_to_lab(const double xyz[3], double lab[3])
{
    double fx = lab_f(xyz[0] / WX), fy = lab_f(xyz[1] / WY), fz = lab_f(xyz[2] / WZ);
    lab[0] = 116.0 * fy - 16.0;
    lab[1] = 500.0 * (fx - fy);
    lab[2] = 200.0 * (fy - fz);
}

void gi_flip_linrgb_to_hunt_lab(const double rgb[3], double h[3])
{
    double xyz[3];
    gi_flip_linrgb_to_xyz(rgb, xyz);
    gi_flip_xyz_to_lab(xyz, h);
    /* Hunt effect: chroma appears weaker at low luminance. */
    h[1] *= 0.01 * h[0];
    h[2] *= 0.01 * h[0];
}

double gi_flip_hyab(const double x[3], const double y[3])
{
    double da = x[1] - y[1], db = x[2] - y[2];
    return fabs(x[0] - y[0]) + sqrt(da * da + db * db);
}

double gi_flip_cmax(void)
{
    const double green[3] = {0, 1, 0}, blue[3] = {0, 0, 1};
    double hg[3], hb[3];
    gi_flip_linrgb_to_hunt_lab(green, hg);
    gi_flip_linrgb_to_hunt_lab(blue, hb);
    return pow(gi_flip_hyab(hg, hb), GI_FLIP_QC);
}

double gi_flip_compress(double e, double cmax)
{
    double knee = GI_FLIP_PC * cmax;
    if (e < knee)
        return (GI_FLIP_PT / knee) * e;
    return GI_FLIP_PT + (e - knee) / (cmax - knee) * (1.0 - GI_FLIP_PT);
}

/* ---- kernels ---- */

int gi_flip_csf_radius(double ppd)
{
    double bmax = 0.0;
    for (int c = 0; c < 3; c++) {
        bmax = fmax(bmax, fmax(gi_flip_csf_params[c].b1, gi_flip_csf_params[c].b2));
    }
    return (int)ceil(3.0 * sqrt(bmax / (2.0 * M_PI * M_PI)) * ppd);
}

/* The CSF kernel of a channel as at most two separable Gaussian terms:
 * S = sum_k weight[k] * (g_k(x) g_k(y)), each g_k normalised to sum 1, the
 * weights summing to 1 (the 2-D normalisation of the paper's kernel). */
typedef struct csf_terms {
    int count, r;
    double weight[2];
    double *g[2]; /* 2r+1 taps each */
} csf_terms;

static int csf_terms_make(double ppd, int channel, csf_terms *t)
{
    const gi_flip_csf *p = &gi_flip_csf_params[channel];
    const double a[2] = {p->a1, p->a2}, b[2] = {p->b1, p->b2};
    memset(t, 0, sizeof *t);
    t->r = gi_flip_csf_radius(ppd);
    int n = 2 * t->r + 1;
    double total = 0.0, mass[2] = {0, 0};
    for (int k = 0; k < 2; k++) {
        if (a[k] == 0.0)
            continue; /* the A and RG channels are single Gaussians */
        double *g = malloc((size_t)n * sizeof *g);
        if (!g)
            return 0;
        double s = 0.0;
        for (int i = -t->r; i <= t->r; i++) {
            double xd = i / ppd; /* degrees */
            g[i + t->r] = exp(-M_PI * M_PI * xd * xd / b[k]);
            s += g[i + t->r];
        }
        for (int i = 0; i < n; i++)
            g[i] /= s;
        /* This term's share of the 2-D sum: a sqrt(pi/b) (sum_x g)^2. */
        mass[t->count] = a[k] * sqrt(M_PI / b[k]) * s * s;
        total += mass[t->count];
        t->g[t->count++] = g;
    }
    for (int k = 0; k < t->count; k++)
        t->weight[k] = mass[k] / total;
    return 1;
}

static void csf_terms_free(csf_terms *t)
{
    for (int k = 0; k < t->count; k++)
        free(t->g[k]);
}

void gi_flip_csf_kernel(double ppd, int channel, double *out)
{
    csf_terms t;
    int r = gi_flip_csf_radius(ppd), n = 2 * r + 1;
    memset(out, 0, (size_t)n * (size_t)n * sizeof *out);
    if (!csf_terms_make(ppd, channel, &t)) {
        csf_terms_free(&t);
        return;
    }
    for (int k = 0; k < t.count; k++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++)
                out[y * n + x] += t.weight[k] * t.g[k][y] * t.g[k][x];
    csf_terms_free(&t);
}

int gi_flip_feature_radius(double ppd)
{
    double sd = 0.5 * GI_FLIP_W * ppd;
    return (int)ceil(3.0 * sd);
}

void gi_flip_feature_kernels(double ppd, double *edge, double *point, double *gauss)
{
    double sd = 0.5 * GI_FLIP_W * ppd;
    int r = gi_flip_feature_radius(ppd), n = 2 * r + 1;
    double gsum = 0.0, epos = 0.0, eneg = 0.0, ppos = 0.0, pneg = 0.0;
    for (int i = -r; i <= r; i++) {
        double g = exp(-(double)(i * i) / (2.0 * sd * sd));
        double e = -i * g;
        double p = ((double)(i * i) / (sd * sd) - 1.0) * g;
        gauss[i + r] = g;
        edge[i + r] = e;
        point[i + r] = p;
        gsum += g;
        if (e > 0)
            epos += e;
        else
            eneg -= e;
        if (p > 0)
            ppos += p;
        else
            pneg -= p;
    }
    /* The 2-D kernels are edge(x) g(y) and point(x) g(y); the sign of a tap
     * is the sign of its x factor, so normalising the 2-D positive and
     * negative sums to +1 and -1 splits into this x factor and a g(y) of
     * sum 1. */
    for (int i = 0; i < n; i++) {
        gauss[i] /= gsum;
        edge[i] /= edge[i] > 0 ? epos : eneg;
        point[i] /= point[i] > 0 ? ppos : pneg;
    }
}

/* ---- the evaluator ---- */

typedef struct work {
    uint32_t w, h;
    size_t n;
    double *plane[3]; /* opponent, then Hunt-Lab */
    double *yn;       /* Y / Yn of the unfiltered image */
    double *edge, *point;
    double *a, *b, *tmp;
} work;

static void work_free(work *k)
{
    for (int c = 0; c < 3; c++)
        free(k->plane[c]);
    free(k->yn);
    free(k->edge);
    free(k->point);
    free(k->a);
    free(k->b);
    free(k->tmp);
}

static int work_alloc(work *k, uint32_t w, uint32_t h)
{
    memset(k, 0, sizeof *k);
    k->w = w;
    k->h = h;
    k->n = (size_t)w * h;
    for (int c = 0; c < 3; c++)
        k->plane[c] = malloc(k->n * sizeof(double));
    k->yn = malloc(k->n * sizeof(double));
    k->edge = malloc(k->n * sizeof(double));
    k->point = malloc(k->n * sizeof(double));
    k->a = malloc(k->n * sizeof(double));
    k->b = malloc(k->n * sizeof(double));
    k->tmp = malloc(k->n * sizeof(double));
    int ok = k->yn && k->edge && k->point && k->a && k->b && k->tmp;
    for (int c = 0; c < 3; c++)
        ok = ok && k->plane[c];
    return ok;
}

static double clamp01(double v)
{
    return v > 0.0 ? (v < 1.0 ? v : 1.0) : 0.0;
}

static double srgb_to_linear(double v)
{
    v = clamp01(v);
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

typedef struct kernels {
    csf_terms csf[3];
    int fr;
    double *edge, *point, *gauss;
} kernels;

/* Hunt-Lab planes after CSF filtering, and the edge and point magnitudes,
 * of one image. */
static void prepare(const float *srgb, const kernels *K, work *k)
{
    for (size_t i = 0; i < k->n; i++) {
        double rgb[3], xyz[3], opp[3];
        for (int c = 0; c < 3; c++)
            rgb[c] = srgb_to_linear(srgb[i * 3 + c]);
        gi_flip_linrgb_to_xyz(rgb, xyz);
        gi_flip_xyz_to_ycxcz(xyz, opp);
        for (int c = 0; c < 3; c++)
            k->plane[c][i] = opp[c];
        k->yn[i] = xyz[1] / WY;
    }

    /* Colour: each opponent channel through its CSF kernel. */
    for (int c = 0; c < 3; c++) {
        const csf_terms *t = &K->csf[c];
        if (t->count == 1) {
            gi_filter_separable(k->plane[c], k->plane[c], k->tmp, k->w, k->h, t->g[0], t->r,
                                t->g[0], t->r, GI_BORDER_CLAMP);
        } else {
            gi_filter_separable(k->plane[c], k->a, k->tmp, k->w, k->h, t->g[0], t->r, t->g[0], t->r,
                                GI_BORDER_CLAMP);
            gi_filter_separable(k->plane[c], k->b, k->tmp, k->w, k->h, t->g[1], t->r, t->g[1], t->r,
                                GI_BORDER_CLAMP);
            for (size_t i = 0; i < k->n; i++)
                k->plane[c][i] = t->weight[0] * k->a[i] + t->weight[1] * k->b[i];
        }
    }
    for (size_t i = 0; i < k->n; i++) {
        double opp[3] = {k->plane[0][i], k->plane[1][i], k->plane[2][i]}, xyz[3], rgb[3], h[3];
        gi_flip_ycxcz_to_xyz(opp, xyz);
        gi_flip_xyz_to_linrgb(xyz, rgb);
        for (int c = 0; c < 3; c++)
            rgb[c] = clamp01(rgb[c]); /* back into the RGB cube */
        gi_flip_linrgb_to_hunt_lab(rgb, h);
        for (int c = 0; c < 3; c++)
            k->plane[c][i] = h[c];
    }

    /* Features: gradient and point responses in x and y. */
    gi_filter_separable(k->yn, k->a, k->tmp, k->w, k->h, K->edge, K->fr, K->gauss, K->fr,
                        GI_BORDER_CLAMP);
    gi_filter_separable(k->yn, k->b, k->tmp, k->w, k->h, K->gauss, K->fr, K->edge, K->fr,
                        GI_BORDER_CLAMP);
    for (size_t i = 0; i < k->n; i++)
        k->edge[i] = sqrt(k->a[i] * k->a[i] + k->b[i] * k->b[i]);
    gi_filter_separable(k->yn, k->a, k->tmp, k->w, k->h, K->point, K->fr, K->gauss, K->fr,
                        GI_BORDER_CLAMP);
    gi_filter_separable(k->yn, k->b, k->tmp, k->w, k->h, K->gauss, K->fr, K->point, K->fr,
                        GI_BORDER_CLAMP);
    for (size_t i = 0; i < k->n; i++)
        k->point[i] = sqrt(k->a[i] * k->a[i] + k->b[i] * k->b[i]);
}

gi_result gi_flip_map(const float *test_srgb, const float *ref_srgb, uint32_t w, uint32_t h,
                      double ppd, float *out, gi_error *err)
{
    if (!(ppd > 0.0) || !isfinite(ppd) || ppd > 1e4)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "FLIP: pixels per degree %g is not in (0, 10000]", ppd);
    if (w == 0 || h == 0)
        return GI_OK;

    gi_result res = GI_OK;
    kernels K;
    memset(&K, 0, sizeof K);
    work kt, kr;
    int ok_t = work_alloc(&kt, w, h), ok_r = work_alloc(&kr, w, h);
    int ok = ok_t && ok_r;
    for (int c = 0; c < 3 && ok; c++)
        ok = csf_terms_make(ppd, c, &K.csf[c]);
    if (ok) {
        K.fr = gi_flip_feature_radius(ppd);
        size_t nf = (size_t)(2 * K.fr + 1);
        K.edge = malloc(nf * sizeof(double));
        K.point = malloc(nf * sizeof(double));
        K.gauss = malloc(nf * sizeof(double));
        ok = K.edge && K.point && K.gauss;
    }
    if (!ok) {
        res =
            gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "FLIP: out of memory for a %ux%u image", w, h);
        goto done;
    }
    gi_flip_feature_kernels(ppd, K.edge, K.point, K.gauss);

    prepare(test_srgb, &K, &kt);
    prepare(ref_srgb, &K, &kr);

    const double cmax = gi_flip_cmax();
    for (size_t i = 0; i < kt.n; i++) {
        const double ht[3] = {kt.plane[0][i], kt.plane[1][i], kt.plane[2][i]};
        const double hr[3] = {kr.plane[0][i], kr.plane[1][i], kr.plane[2][i]};
        double dec = gi_flip_compress(pow(gi_flip_hyab(hr, ht), GI_FLIP_QC), cmax);
        double dedge = fabs(kr.edge[i] - kt.edge[i]), dpoint = fabs(kr.point[i] - kt.point[i]);
        double def = pow(fmax(dedge, dpoint) / sqrt(2.0), GI_FLIP_QF);
        out[i] = (float)pow(dec, 1.0 - def);
    }

done:
    for (int c = 0; c < 3; c++)
        csf_terms_free(&K.csf[c]);
    free(K.edge);
    free(K.point);
    free(K.gauss);
    work_free(&kt);
    work_free(&kr);
    return res;
}

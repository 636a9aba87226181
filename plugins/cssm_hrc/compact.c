/* The compact node encoding of §4.2.1 (cssm.h "compact nodes"): each
 * hierarchy node in 128 bits, 24 bits for the centre, the mean normal and
 * the radiant intensity, 8 bits for the radius, the normal cone angle and
 * the area, 16 bits for each pointer; the pull of §4.1.1 on packed nodes.
 * The codes and why (README "Compact nodes"):
 *  - centre: 8 bits per axis of the box of the scene's texels (24-bit
 *    Morton order would hold the same points); rounding error at most half
 *    a step per axis, added to the radius;
 *  - radius, area: 8 bits, logarithmic between the tree's smallest and
 *    largest value (a node's radius spans 2^8 to 2^10 from leaf to root,
 *    where a linear code would have no step below a leaf's size);
 *    the radius rounded up;
 *  - normal: octahedral, 12 + 12 bits, the best of the four codes around
 *    the point; the cone angle linear in [0, pi], rounded up after adding
 *    the normal's rounding;
 *  - intensity: a shared exponent (6 bits) and three 6-bit mantissas
 *    relative to the light set's scale, rounded with a per-node dither
 *    (unbiased): every channel within 1/31.5 of the largest, 2^-60 to 8
 *    times the scale. */
#include "cssm.h"

#include "gi/rng.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NULL16 0xFFFFu
#define EBIAS 60 /* exponent code of 2^0 x iscale */

static float clampf(float x, float lo, float hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

/* 256 values from lo to hi, equal ratios (the last exactly hi). */
static void log_table(float *tab, float lo, float hi)
{
    if (!(lo > 0.0f))
        lo = hi > 0.0f ? hi * 1e-9f : 1e-30f;
    if (!(hi >= lo))
        hi = lo;
    double ratio = (double)hi / (double)lo;
    for (int q = 0; q < 256; q++)
        tab[q] = (float)(lo * pow(ratio, q / 255.0));
    tab[255] = hi;
}

/* Smallest code whose value is at least x (255 when none is). */
static uint32_t code_up(const float *tab, float x)
{
    uint32_t lo = 0, hi = 255;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (tab[mid] >= x)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* Nearest code in the log domain. */
static uint32_t code_near(const float *tab, float x)
{
    uint32_t q = code_up(tab, x);
    if (q > 0 && (!(x > 0.0f) || logf(tab[q] / x) > logf(x / tab[q - 1])))
        q--;
    return q;
}

/* ----------------------------------------------------- octahedral normal */

static float sgn(float x)
{
    return x < 0.0f ? -1.0f : 1.0f;
}

static gi_vec3 oct_decode(uint32_t code)
{
    float u = (float)(code & 0xFFFu) / 4095.0f * 2.0f - 1.0f,
          v = (float)(code >> 12) / 4095.0f * 2.0f - 1.0f;
    gi_vec3 n = gi_v3(u, v, 1.0f - fabsf(u) - fabsf(v));
    if (n.z < 0.0f) {
        float x = n.x;
        n.x = (1.0f - fabsf(n.y)) * sgn(x);
        n.y = (1.0f - fabsf(x)) * sgn(n.y);
    }
    return gi_v3_normalize(n);
}

static uint32_t oct_encode(gi_vec3 n)
{
    float s = fabsf(n.x) + fabsf(n.y) + fabsf(n.z);
    if (!(s > 0.0f))
        return oct_encode(gi_v3(0, 0, 1));
    float u = n.x / s, v = n.y / s;
    if (n.z < 0.0f) {
        float x = u;
        u = (1.0f - fabsf(v)) * sgn(x);
        v = (1.0f - fabsf(x)) * sgn(v);
    }
    float fu = (clampf(u, -1.0f, 1.0f) + 1.0f) * 0.5f * 4095.0f,
          fv = (clampf(v, -1.0f, 1.0f) + 1.0f) * 0.5f * 4095.0f;
    uint32_t best = 0;
    float bd = -2.0f;
    for (int k = 0; k < 4; k++) { /* the four codes around (u, v): the nearest direction */
        uint32_t qu = (uint32_t)clampf((k & 1) ? ceilf(fu) : floorf(fu), 0.0f, 4095.0f);
        uint32_t qv = (uint32_t)clampf((k & 2) ? ceilf(fv) : floorf(fv), 0.0f, 4095.0f);
        uint32_t code = qu | qv << 12;
        float d = gi_v3_dot(oct_decode(code), n);
        if (d > bd)
            bd = d, best = code;
    }
    return best;
}

/* Angle between unit vectors, accurate near 0 (acos of the dot is not). */
static float angle_unit(gi_vec3 a, gi_vec3 b)
{
    return 2.0f * atan2f(gi_v3_length(gi_v3_sub(a, b)), gi_v3_length(gi_v3_add(a, b)));
}

/* --------------------------------------------------------- intensity */

/* Rounds with a dither fixed per node and channel (seed: the node), so
 * that nodes of equal intensity (a uniform emitter's texels) do not all
 * round the same way: the error is below one mantissa step, and zero on
 * average over nodes, where rounding to nearest would be half a step but
 * shared by every such node (measured: +0.4 % mean luminance on the
 * Cornell box from its light's texels). */
static uint32_t rgb_encode(const float I[3], float scale, uint32_t seed)
{
    float v[3];
    float mx = 0.0f;
    for (int k = 0; k < 3; k++) {
        v[k] = scale > 0.0f && I[k] > 0.0f ? I[k] / scale : 0.0f;
        mx = fmaxf(mx, v[k]);
    }
    if (!(mx > 0.0f) || !isfinite(mx))
        return 0;
    int E;
    frexpf(mx, &E); /* mx = f 2^E, f in [0.5, 1) */
    if (E > 63 - EBIAS)
        E = 63 - EBIAS; /* beyond 8 x the scale: saturates */
    if (E < -EBIAS)     /* below 2^-60 of the scale: black */
        return 0;
    for (;;) {
        float unit = ldexpf(1.0f, E - 6);
        uint32_t m[3];
        int over = 0;
        for (int k = 0; k < 3; k++) {
            float dither =
                (float)(gi_pcg_hash(seed * 3u + (uint32_t)k) >> 8) * (1.0f / 16777216.0f);
            float q = floorf(v[k] / unit + dither);
            over |= q > 63.0f;
            m[k] = (uint32_t)fminf(q, 63.0f);
        }
        if (over && E < 63 - EBIAS) { /* rounding reached 64: next exponent */
            E++;
            continue;
        }
        return m[0] | m[1] << 6 | m[2] << 12 | (uint32_t)(E + EBIAS) << 18;
    }
}

static void rgb_decode(uint32_t code, float scale, float I[3])
{
    int e = (int)(code >> 18 & 63u) - EBIAS;
    float unit = scale * ldexpf(1.0f, e - 6);
    for (int k = 0; k < 3; k++)
        I[k] = (float)(code >> (6 * k) & 63u) * unit;
}

/* ------------------------------------------------------------- nodes */

static uint32_t centre_q(const cssm_ctree *ct, gi_vec3 c, gi_vec3 *dec)
{
    float x[3] = {c.x, c.y, c.z}, d[3];
    uint32_t code = 0;
    for (int k = 0; k < 3; k++) {
        uint32_t q = ct->step[k] > 0.0f
                         ? (uint32_t)clampf(rintf((x[k] - ct->lo[k]) / ct->step[k]), 0.0f, 255.0f)
                         : 0u;
        d[k] = ct->lo[k] + (float)q * ct->step[k];
        code |= q << (8 * k);
    }
    *dec = gi_v3(d[0], d[1], d[2]);
    return code;
}

/* The radius a node needs when its centre is stored as rounded. */
static float radius_needed(const cssm_ctree *ct, gi_vec3 c, float r)
{
    gi_vec3 dec;
    centre_q(ct, c, &dec);
    /* one part in 10^6 more: float rounding of the distances must not make the
     * decoded sphere smaller than the true one */
    return (r + gi_v3_length(gi_v3_sub(c, dec))) * 1.000001f;
}

static uint16_t ptr16(int32_t p)
{
    return p < 0 ? (uint16_t)NULL16 : (uint16_t)p;
}

gi_result cssm_ctree_check(uint32_t texels, gi_error *err)
{
    uint64_t count = texels ? 2ull * texels - 1 : 0;
    if (count <= CSSM_COMPACT_MAX_NODES)
        return GI_OK;
    return gi_error_set(
        err, GI_ERR_INVALID_ARGUMENT,
        "cssm_hrc: nodes=compact holds at most %u nodes (16-bit pointers, Sec. "
        "4.2.1), this hierarchy has %llu (%u texels): lower atlas or use nodes=float",
        CSSM_COMPACT_MAX_NODES, (unsigned long long)count, texels);
}

gi_result cssm_ctree_setup(cssm_ctree *ct, uint32_t count, const float lo[3], const float hi[3],
                           float r_lo, float r_hi, float a_lo, float a_hi, gi_error *err)
{
    memset(ct, 0, sizeof *ct);
    if (count > CSSM_COMPACT_MAX_NODES)
        return cssm_ctree_check((count + 1) / 2, err);
    ct->nodes = calloc(count ? count : 1, sizeof *ct->nodes);
    ct->side = calloc(2 * (size_t)(count ? count : 1), sizeof *ct->side);
    ct->leaves = calloc((size_t)count / 2 + 1, sizeof *ct->leaves);
    if (!ct->nodes || !ct->side || !ct->leaves) {
        cssm_ctree_free(ct);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "cssm_hrc: out of memory for the compact hierarchy");
    }
    ct->count = count;
    for (int k = 0; k < 3; k++) {
        ct->lo[k] = lo[k];
        ct->step[k] = hi[k] > lo[k] ? (hi[k] - lo[k]) / 255.0f : 0.0f;
    }
    log_table(ct->rtab, r_lo, r_hi);
    log_table(ct->atab, a_lo, a_hi);
    for (int q = 0; q < 256; q++)
        ct->ctab[q] = cosf((float)GI_PI * (float)q / 255.0f);
    ct->ctab[0] = 1.0f;
    ct->ctab[255] = -1.0f;
    ct->iscale = 1.0f;
    return GI_OK;
}

void cssm_ctree_free(cssm_ctree *ct)
{
    if (!ct)
        return;
    free(ct->nodes);
    free(ct->side);
    free(ct->leaves);
    memset(ct, 0, sizeof *ct);
}

void cssm_ctree_set_intensity(cssm_ctree *ct, uint32_t i, const float I[3])
{
    uint32_t *w = &ct->nodes[i].w[2];
    *w = (*w & 0xFF000000u) | rgb_encode(I, ct->iscale, i);
}

void cssm_ctree_encode(cssm_ctree *ct, uint32_t i, const cssm_node_view *v)
{
    cssm_pnode *p = &ct->nodes[i];
    gi_vec3 cdec;
    uint32_t cq = centre_q(ct, v->c, &cdec);
    uint32_t rq = code_up(ct->rtab, radius_needed(ct, v->c, v->r));
    uint32_t nq = oct_encode(v->n);
    /* the cone about the stored normal holds the true cone: the angle grows
     * by the normal's rounding, then rounds up to the next code */
    uint32_t kq = 255;
    if (v->cos_cone > -1.0f) {
        float dn = angle_unit(oct_decode(nq), gi_v3_normalize(v->n));
        float need = acosf(clampf(v->cos_cone, -1.0f, 1.0f)) + dn;
        need = need * 1.000001f + 1e-6f;
        kq = need >= (float)GI_PI
                 ? 255u
                 : (uint32_t)clampf(ceilf(need / (float)GI_PI * 255.0f), 0.0f, 255.0f);
    }
    uint32_t aq = code_near(ct->atab, v->area);
    p->w[0] = cq | rq << 24;
    p->w[1] = nq | kq << 24;
    p->w[2] = rgb_encode(v->I, ct->iscale, i) | aq << 24;
    p->w[3] = (uint32_t)ptr16(v->child) | (uint32_t)ptr16(v->skip) << 16;
}

void cssm_ctree_view(const cssm_ctree *ct, uint32_t i, cssm_node_view *v)
{
    const cssm_pnode *p = &ct->nodes[i];
    float x[3];
    for (int k = 0; k < 3; k++)
        x[k] = ct->lo[k] + (float)(p->w[0] >> (8 * k) & 255u) * ct->step[k];
    v->c = v->p = gi_v3(x[0], x[1], x[2]);
    v->r = ct->rtab[p->w[0] >> 24];
    v->n = oct_decode(p->w[1] & 0xFFFFFFu);
    v->cos_cone = ct->ctab[p->w[1] >> 24];
    v->area = ct->atab[p->w[2] >> 24];
    rgb_decode(p->w[2] & 0xFFFFFFu, ct->iscale, v->I);
    uint32_t child = p->w[3] & 0xFFFFu, skip = p->w[3] >> 16;
    v->child = child == NULL16 ? -1 : (int32_t)child;
    v->skip = skip == NULL16 ? -1 : (int32_t)skip;
    /* a full binary subtree of k leaves is 2k - 1 nodes in [i, skip) */
    uint32_t end = v->skip < 0 ? ct->count : (uint32_t)v->skip;
    v->count = (end - i + 1) / 2;
    v->first = ct->side[2 * i];
    v->rep = ct->side[2 * i + 1];
}

gi_result cssm_ctree_build(const cssm_tree *t, const cssm_atlas *a, cssm_ctree *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    if (t->count > CSSM_COMPACT_MAX_NODES) /* refused before anything is computed */
        return cssm_ctree_setup(out, t->count, (float[3]){0, 0, 0}, (float[3]){0, 0, 0}, 1, 1, 1, 1,
                                err);
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t i = 0; i < a->count; i++) {
        float q[3] = {a->texels[i].p.x, a->texels[i].p.y, a->texels[i].p.z};
        for (int k = 0; k < 3; k++)
            lo[k] = fminf(lo[k], q[k]), hi[k] = fmaxf(hi[k], q[k]);
    }
    float amin = FLT_MAX, amax = 0.0f;
    for (uint32_t i = 0; i < t->count; i++)
        if (t->nodes[i].area > 0.0f)
            amin = fminf(amin, t->nodes[i].area), amax = fmaxf(amax, t->nodes[i].area);
    gi_result res = cssm_ctree_setup(out, t->count, lo, hi, 1.0f, 1.0f, amin, amax, err);
    if (res != GI_OK)
        return res;
    float rmin = FLT_MAX, rmax = 0.0f;
    for (uint32_t i = 0; i < t->count; i++) {
        float r = radius_needed(out, t->nodes[i].c, t->nodes[i].r);
        if (r > 0.0f)
            rmin = fminf(rmin, r);
        rmax = fmaxf(rmax, r);
    }
    log_table(out->rtab, rmin, rmax);
    for (uint32_t i = 0; i < t->count; i++) {
        const cssm_node *nd = &t->nodes[i];
        cssm_node_view v = {.c = nd->c,
                            .r = nd->r,
                            .n = nd->n,
                            .cos_cone = nd->cos_cone,
                            .area = nd->area,
                            .child = nd->child,
                            .skip = nd->skip};
        cssm_ctree_encode(out, i, &v);
        out->side[2 * i] = nd->first;
        out->side[2 * i + 1] = nd->rep;
    }
    memcpy(out->leaves, t->leaves, (size_t)a->count * sizeof *out->leaves);
    return GI_OK;
}

void cssm_ctree_pull(cssm_ctree *ct, const cssm_atlas *a, const float *texel_L)
{
    /* the scale: the root's intensity, summed in double */
    double sum[3] = {0, 0, 0};
    for (uint32_t i = 0; i < a->count; i++)
        for (int k = 0; k < 3; k++)
            sum[k] += (double)texel_L[3 * i + k] * a->texels[i].area;
    double mx = fmax(sum[0], fmax(sum[1], sum[2]));
    ct->iscale = mx > 0.0 && mx < FLT_MAX ? (float)mx : 1.0f;
    /* children follow their parent in pre-order: walk backwards */
    for (int32_t i = (int32_t)ct->count - 1; i >= 0; i--) {
        cssm_node_view v;
        cssm_ctree_view(ct, (uint32_t)i, &v);
        float I[3];
        if (v.child < 0) {
            uint32_t x = ct->leaves[v.first];
            for (int k = 0; k < 3; k++)
                I[k] = texel_L[3 * x + k] * a->texels[x].area;
        } else {
            cssm_node_view l, r;
            cssm_ctree_view(ct, (uint32_t)v.child, &l);
            cssm_ctree_view(ct, (uint32_t)l.skip, &r);
            for (int k = 0; k < 3; k++)
                I[k] = l.I[k] + r.I[k];
        }
        cssm_ctree_set_intensity(ct, (uint32_t)i, I);
    }
}

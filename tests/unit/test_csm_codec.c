/* Unit test of the Coherent Shadow Maps codec and map orders (Ritschel et al.
 * 2007 §3.1 compression, §3.2 query, §4.4 enumeration): losslessness and
 * greedy minimality on random depth sequences, the shadow test against the
 * uncompressed one, serialisation and rejection of damaged data, the orders
 * as bijections with neighbour steps, and the compression of an analytic
 * scene (spheres under a lat-long grid of distant-light directions) for
 * scan-line, zig-zag and Hilbert order. */
#include "check.h"
#include "gi/algo/csm_codec.h"
#include "gi/algo/csm_order.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct rng {
    uint64_t s;
} rng;

static uint64_t next_u64(rng *r)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double unit(rng *r)
{
    return (double)(next_u64(r) >> 11) * (1.0 / 9007199254740992.0);
}

/* ---- random dual-depth sequences ---- */

typedef struct seq {
    uint32_t M, N;
    float *z1, *z2; /* [i * M*M + t] */
} seq;

/* Per texel: a random walk of z1 with occasional jumps, a gap to z2 that
 * walks too; sometimes z2 none, z1 == z2, z2 the next float above z1, or an
 * empty texel (both none). */
static seq make_seq(uint32_t M, uint32_t N, uint64_t seed)
{
    seq s = {M, N, NULL, NULL};
    size_t texels = (size_t)M * M;
    s.z1 = malloc(sizeof(float) * texels * N);
    s.z2 = malloc(sizeof(float) * texels * N);
    rng r = {seed};
    for (size_t t = 0; t < texels; t++) {
        double z = 1 + 10 * unit(&r), gap = 0.5 * unit(&r);
        double jump_p = 0.02 + 0.1 * unit(&r);
        for (uint32_t i = 0; i < N; i++) {
            z += 0.05 * (unit(&r) - 0.5);
            gap += 0.02 * (unit(&r) - 0.5);
            if (unit(&r) < jump_p) {
                z = 1 + 10 * unit(&r);
                gap = 0.5 * unit(&r);
            }
            if (gap < 0)
                gap = -gap;
            float a = (float)z, b = (float)(z + gap);
            double e = unit(&r);
            if (e < 0.05)
                b = FLT_MAX;
            else if (e < 0.08)
                b = a;
            else if (e < 0.10)
                b = nextafterf(a, INFINITY);
            else if (e < 0.12)
                a = b = FLT_MAX;
            else if (e < 0.13)
                b = INFINITY;
            s.z1[(size_t)i * texels + t] = a;
            s.z2[(size_t)i * texels + t] = b;
        }
    }
    return s;
}

static void free_seq(seq *s)
{
    free(s->z1);
    free(s->z2);
}

static gi_result encode(const seq *s, gi_csm_data *out)
{
    gi_error err = {{0}};
    gi_csm_codec *enc;
    gi_result r = gi_csm_codec_begin(s->M, s->N, &enc, &err);
    if (r)
        return r;
    size_t texels = (size_t)s->M * s->M;
    for (uint32_t i = 0; i < s->N; i++) {
        r = gi_csm_codec_add_map(enc, i, s->z1 + i * texels, s->z2 + i * texels, &err);
        if (r) {
            fprintf(stderr, "%s\n", err.text);
            gi_csm_codec_free(enc);
            return r;
        }
    }
    r = gi_csm_codec_finish(enc, out, &err);
    if (r)
        fprintf(stderr, "%s\n", err.text);
    return r;
}

static float inf_z2(float z)
{
    return z >= FLT_MAX ? INFINITY : z;
}

static float fin_z1(float z)
{
    return z >= FLT_MAX ? FLT_MAX : z;
}

/* Equation 1 over maps [s, e] of texel t. */
static int separable(const seq *q, size_t t, uint32_t s, uint32_t e)
{
    size_t texels = (size_t)q->M * q->M;
    float mx = -INFINITY, mn = INFINITY;
    for (uint32_t i = s; i <= e; i++) {
        mx = fmaxf(mx, fin_z1(q->z1[i * texels + t]));
        mn = fminf(mn, inf_z2(q->z2[i * texels + t]));
    }
    return mx < mn;
}

static void check_lossless(const seq *q, const gi_csm_data *d)
{
    size_t texels = (size_t)q->M * q->M;
    int offsets_ok = d->offsets[0] == 0 && d->offsets[texels] == d->segment_count;
    int lossless = 1, minimal = 1, visible_ok = 1, order_ok = 1;
    rng r = {77};
    for (size_t t = 0; t < texels; t++) {
        uint32_t b = d->offsets[t], e = d->offsets[t + 1];
        if (e <= b) {
            offsets_ok = 0;
            continue;
        }
        if (d->i_end[e - 1] != q->N - 1)
            order_ok = 0;
        for (uint32_t k = b; k < e; k++) {
            uint32_t s = k == b ? 0 : d->i_end[k - 1] + 1, last = d->i_end[k];
            if (k > b && d->i_end[k] <= d->i_end[k - 1])
                order_ok = 0;
            /* Greedy minimal: one more map would break eq. 1. */
            if (last + 1 < q->N && separable(q, t, s, last + 1))
                minimal = 0;
            /* A segment that breaks eq. 1 is one degenerate map. */
            if (!separable(q, t, s, last) &&
                !(s == last && q->z1[s * texels + t] == q->z2[s * texels + t]))
                minimal = 0;
        }
        for (uint32_t i = 0; i < q->N; i++) {
            float z1 = q->z1[i * texels + t], z2 = q->z2[i * texels + t];
            float z = gi_csm_lookup(d, (uint32_t)t, i);
            uint64_t seg = gi_csm_segment(d, (uint32_t)t, i);
            if (seg < b || seg >= e || d->i_end[seg] < i || (seg > b && d->i_end[seg - 1] >= i))
                order_ok = 0;
            int ok = z1 == z2 ? z == fin_z1(z1) : (fin_z1(z1) <= z && z < inf_z2(z2));
            if (!ok) {
                if (lossless)
                    fprintf(stderr, "texel %zu map %u: z1 %.9g z_avg %.9g z2 %.9g\n", t, i,
                            (double)z1, (double)z, (double)z2);
                lossless = 0;
            }
            /* The shadow test agrees with depth <= z1 outside (z1, z2). */
            float tests[6] = {z1, nextafterf(fin_z1(z1), -INFINITY), z1 - 1, (float)(20 * unit(&r)),
                              z2, nextafterf(inf_z2(z2), INFINITY)};
            for (int j = 0; j < 6; j++) {
                float dep = tests[j];
                if (!(dep < FLT_MAX) || (dep > fin_z1(z1) && dep < inf_z2(z2)))
                    continue;
                if (gi_csm_visible(d, (uint32_t)t, i, dep, 0) != (dep <= z1))
                    visible_ok = 0;
            }
        }
    }
    CHECK(offsets_ok);
    CHECK(order_ok);
    CHECK(lossless);
    CHECK(minimal);
    CHECK(visible_ok);
}

static void test_random(void)
{
    struct {
        uint32_t M, N;
    } cases[] = {{1, 1}, {3, 2}, {8, 37}, {16, 300}, {4, 70000}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        seq q = make_seq(cases[c].M, cases[c].N, 1234 + c);
        gi_csm_data d;
        CHECK(encode(&q, &d) == GI_OK);
        if (d.offsets) {
            check_lossless(&q, &d);
            uint64_t texels = (uint64_t)q.M * q.M;
            CHECK(d.bytes_uncompressed == 2 * texels * q.N);
            CHECK(d.bytes_compressed ==
                  4 * (texels + 1) + d.segment_count * (4 + (q.N <= 65536 ? 2 : 4)));
            printf("random M=%u N=%u: %.2f segments/texel\n", q.M, q.N,
                   (double)d.segment_count / (double)texels);
        }
        gi_csm_data_free(&d);
        free_seq(&q);
    }
}

/* Degenerate and boundary inputs with known segments. */
static void test_edges(void)
{
    /* One texel, N = 6: z1 == z2 at map 2 splits; empty maps join z2-none runs. */
    float z1[6] = {1, 2, 3, 1, FLT_MAX, 5};
    float z2[6] = {4, 5, 3, FLT_MAX, FLT_MAX, INFINITY};
    gi_error err = {{0}};
    gi_csm_codec *enc;
    CHECK(gi_csm_codec_begin(1, 6, &enc, &err) == GI_OK);
    for (uint32_t i = 0; i < 6; i++)
        CHECK(gi_csm_codec_add_map(enc, i, &z1[i], &z2[i], &err) == GI_OK);
    gi_csm_data d;
    CHECK(gi_csm_codec_finish(enc, &d, &err) == GI_OK);
    CHECK(d.segment_count == 3);
    if (d.segment_count == 3) {
        CHECK(d.i_end[0] == 1 && d.z_avg[0] == 3.0f); /* (max z1 2 + min z2 4) / 2 */
        CHECK(d.i_end[1] == 2 && d.z_avg[1] == 3.0f); /* degenerate: z1 */
        CHECK(d.i_end[2] == 5 && d.z_avg[2] == FLT_MAX);
    }
    gi_csm_data_free(&d);

    /* Adjacent floats: the average would round onto z2. */
    float a = 1.0f, b = nextafterf(1.0f, 2.0f);
    CHECK(gi_csm_codec_begin(1, 1, &enc, &err) == GI_OK);
    CHECK(gi_csm_codec_add_map(enc, 0, &a, &b, &err) == GI_OK);
    CHECK(gi_csm_codec_finish(enc, &d, &err) == GI_OK);
    CHECK(d.segment_count == 1 && d.z_avg[0] >= a && d.z_avg[0] < b);
    gi_csm_data_free(&d);

    /* z2 none throughout: z_avg is max z1. */
    float c1[3] = {2, 3, 1}, c2[3] = {FLT_MAX, FLT_MAX, FLT_MAX};
    CHECK(gi_csm_codec_begin(1, 3, &enc, &err) == GI_OK);
    for (uint32_t i = 0; i < 3; i++)
        CHECK(gi_csm_codec_add_map(enc, i, &c1[i], &c2[i], &err) == GI_OK);
    CHECK(gi_csm_codec_finish(enc, &d, &err) == GI_OK);
    CHECK(d.segment_count == 1 && d.z_avg[0] == 3.0f);
    gi_csm_data_free(&d);

    /* Bad input is an error, not a crash. */
    float nan = NAN, one = 1, half = 0.5f;
    CHECK(gi_csm_codec_begin(0, 3, &enc, &err) == GI_ERR_INVALID_ARGUMENT && !enc);
    CHECK(gi_csm_codec_begin(1, 2, &enc, &err) == GI_OK);
    CHECK(gi_csm_codec_add_map(enc, 1, &one, &one, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_csm_codec_finish(enc, &d, &err) == GI_ERR_INVALID_ARGUMENT && !d.offsets);
    CHECK(gi_csm_codec_begin(1, 2, &enc, &err) == GI_OK);
    CHECK(gi_csm_codec_add_map(enc, 0, &nan, &one, &err) == GI_ERR_INVALID_ARGUMENT);
    gi_csm_codec_free(enc);
    CHECK(gi_csm_codec_begin(1, 2, &enc, &err) == GI_OK);
    CHECK(gi_csm_codec_add_map(enc, 0, &one, &half, &err) == GI_ERR_INVALID_ARGUMENT);
    gi_csm_codec_free(enc);
    CHECK(gi_csm_codec_begin(1, 2, &enc, &err) == GI_OK);
    CHECK(gi_csm_codec_add_map(enc, 0, &one, &one, &err) == GI_OK);
    CHECK(gi_csm_codec_finish(enc, &d, &err) == GI_ERR_INVALID_ARGUMENT); /* 1 of 2 maps */
}

static int same_data(const gi_csm_data *a, const gi_csm_data *b)
{
    size_t texels = (size_t)a->M * a->M;
    return a->M == b->M && a->N == b->N && a->segment_count == b->segment_count &&
           a->bytes_compressed == b->bytes_compressed &&
           a->bytes_uncompressed == b->bytes_uncompressed &&
           memcmp(a->offsets, b->offsets, (texels + 1) * 4) == 0 &&
           memcmp(a->z_avg, b->z_avg, a->segment_count * 4) == 0 &&
           memcmp(a->i_end, b->i_end, a->segment_count * 4) == 0;
}

static void test_serialise(uint32_t M, uint32_t N)
{
    seq q = make_seq(M, N, 99 + N);
    gi_csm_data d, back;
    gi_error err = {{0}};
    CHECK(encode(&q, &d) == GI_OK);
    void *bytes;
    size_t size;
    CHECK(gi_csm_data_write(&d, &bytes, &size, &err) == GI_OK);
    CHECK(size == 32 + 4 * ((size_t)M * M + 1) + d.segment_count * (4 + gi_csm_i_end_bytes(N)) + 8);
    CHECK(gi_csm_data_read(bytes, size, &back, &err) == GI_OK);
    CHECK(same_data(&d, &back));
    gi_csm_data_free(&back);

    /* Every truncation, and a single flipped bit anywhere, is rejected. */
    int truncated_ok = 1, flipped_ok = 1;
    unsigned char *copy = malloc(size);
    for (size_t n = 0; n < size; n++) {
        memcpy(copy, bytes, n); /* exact size: ASan sees any over-read */
        if (gi_csm_data_read(copy, n, &back, &err) != GI_ERR_INVALID_ARGUMENT || back.offsets)
            truncated_ok = 0;
    }
    rng r = {5};
    for (int k = 0; k < 2000; k++) {
        memcpy(copy, bytes, size);
        size_t at = (size_t)(next_u64(&r) % size);
        copy[at] ^= (unsigned char)(1u << (next_u64(&r) % 8));
        if (gi_csm_data_read(copy, size, &back, &err) != GI_ERR_INVALID_ARGUMENT) {
            flipped_ok = 0;
            gi_csm_data_free(&back);
        }
    }
    CHECK(truncated_ok);
    CHECK(flipped_ok);
    CHECK(gi_csm_data_read(NULL, 0, &back, &err) == GI_ERR_INVALID_ARGUMENT);
    free(copy);
    free(bytes);
    gi_csm_data_free(&d);
    free_seq(&q);
}

/* ---- orders ---- */

/* The classic Hilbert d -> (x, y) on an n x n square, n = 2^k (Wikipedia,
 * after Hacker's Delight), to hold the gilbert order against. */
static void hilbert_d2xy(uint32_t n, uint32_t d, uint32_t *x, uint32_t *y)
{
    *x = *y = 0;
    for (uint32_t s = 1; s < n; s *= 2, d /= 4) {
        uint32_t rx = 1 & (d / 2), ry = 1 & (d ^ rx);
        if (ry == 0) {
            if (rx == 1) {
                *x = s - 1 - *x;
                *y = s - 1 - *y;
            }
            uint32_t t = *x;
            *x = *y;
            *y = t;
        }
        *x += s * rx;
        *y += s * ry;
    }
}

static void test_orders(void)
{
    uint32_t sizes[][2] = {{1, 1},  {2, 3},   {3, 2},  {8, 8}, {13, 7},
                           {7, 13}, {32, 32}, {16, 4}, {5, 5}, {64, 64}};
    gi_csm_order orders[] = {GI_CSM_ORDER_SCANLINE, GI_CSM_ORDER_ZIGZAG, GI_CSM_ORDER_HILBERT,
                             GI_CSM_ORDER_DIAGONAL};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        uint32_t na = sizes[s][0], nb = sizes[s][1], n = na * nb;
        for (size_t o = 0; o < 4; o++) {
            unsigned char *seen = calloc(n, 1);
            int bijective = 1;
            uint32_t adjacent = 0, pa = 0, pb = 0;
            for (uint32_t k = 0; k < n; k++) {
                uint32_t a = na, b = nb;
                gi_csm_order_cell(orders[o], na, nb, k, &a, &b);
                if (a >= na || b >= nb || seen[b * na + a] ||
                    gi_csm_order_index(orders[o], na, nb, a, b) != k) {
                    bijective = 0;
                    break;
                }
                seen[b * na + a] = 1;
                if (k > 0 && (uint32_t)(abs((int)a - (int)pa) + abs((int)b - (int)pb)) == 1)
                    adjacent++;
                pa = a;
                pb = b;
            }
            CHECK_MSG(bijective, "%s %ux%u", gi_csm_order_name(orders[o]), na, nb);
            double frac = n > 1 ? (double)adjacent / (n - 1) : 1.0;
            if (orders[o] == GI_CSM_ORDER_ZIGZAG)
                CHECK(adjacent == n - 1);
            if (orders[o] == GI_CSM_ORDER_HILBERT) {
                int pow2_square = na == nb && (na & (na - 1)) == 0;
                if (pow2_square)
                    CHECK_MSG(adjacent == n - 1, "hilbert %ux%u", na, nb);
                printf("hilbert %ux%u: %.4f of steps between grid neighbours\n", na, nb, frac);
            }
            free(seen);
        }
    }
    /* The diagonal zig-zag (§4.4, Fig. 8 right): a bijection on every size
     * up to 40 x 40 whose every step goes to one of the 8 neighbours
     * (coherent), and on 8 x 8 the JPEG zig-zag scan. */
    static const uint8_t jpeg[16] = {0, 1, 8, 16, 9, 2, 3, 10, 17, 24, 32, 25, 18, 11, 4, 5};
    for (uint32_t k = 0; k < 16; k++) {
        uint32_t a, b;
        gi_csm_order_cell(GI_CSM_ORDER_DIAGONAL, 8, 8, k, &a, &b);
        CHECK_MSG(b * 8 + a == jpeg[k], "diagonal 8x8 step %u: (%u, %u)", k, a, b);
    }
    int diagonal_ok = 1;
    for (uint32_t na = 1; na <= 40 && diagonal_ok; na++) {
        for (uint32_t nb = 1; nb <= 40 && diagonal_ok; nb++) {
            unsigned char *seen = calloc((size_t)na * nb, 1);
            uint32_t pa = 0, pb = 0;
            for (uint32_t k = 0; k < na * nb; k++) {
                uint32_t a = na, b = nb;
                gi_csm_order_cell(GI_CSM_ORDER_DIAGONAL, na, nb, k, &a, &b);
                int da = abs((int)a - (int)pa), db = abs((int)b - (int)pb);
                if (a >= na || b >= nb || seen[b * na + a] ||
                    gi_csm_order_index(GI_CSM_ORDER_DIAGONAL, na, nb, a, b) != k ||
                    (k > 0 && (da > 1 || db > 1 || da + db == 0)) || (k == 0 && (a || b))) {
                    diagonal_ok = 0;
                    printf("diagonal %ux%u fails at step %u: (%u, %u)\n", na, nb, k, a, b);
                    break;
                }
                seen[b * na + a] = 1;
                pa = a;
                pb = b;
            }
            free(seen);
        }
    }
    CHECK(diagonal_ok);
    gi_csm_order parsed;
    CHECK(gi_csm_order_parse("diagonal", &parsed) && parsed == GI_CSM_ORDER_DIAGONAL);
    /* Every size up to 40 x 40: Hilbert steps are between neighbours except
     * at most one diagonal step, and only where the longer side is odd and
     * the shorter even. */
    int diag_rule = 1;
    uint32_t with_diag = 0;
    for (uint32_t na = 1; na <= 40; na++) {
        for (uint32_t nb = 1; nb <= 40; nb++) {
            uint32_t pa = 0, pb = 0, non = 0;
            for (uint32_t k = 0; k < na * nb; k++) {
                uint32_t a, b;
                gi_csm_order_cell(GI_CSM_ORDER_HILBERT, na, nb, k, &a, &b);
                int da = abs((int)a - (int)pa), db = abs((int)b - (int)pb);
                if (k > 0 && da + db != 1) {
                    non++;
                    if (da != 1 || db != 1)
                        diag_rule = 0;
                }
                if (gi_csm_order_index(GI_CSM_ORDER_HILBERT, na, nb, a, b) != k)
                    diag_rule = 0;
                pa = a;
                pb = b;
            }
            uint32_t lo = na < nb ? na : nb, hi = na < nb ? nb : na;
            if (non > 1 || (non == 1 && !((hi & 1) && !(lo & 1))))
                diag_rule = 0;
            with_diag += non;
        }
    }
    CHECK(diag_rule);
    printf("hilbert, all 1600 sizes up to 40x40: %u with one diagonal step\n", with_diag);

    /* On 2^k squares the order is exactly the classic Hilbert curve. */
    int classic = 1;
    for (uint32_t n = 1; n <= 64; n *= 2) {
        for (uint32_t k = 0; k < n * n; k++) {
            uint32_t a, b, x, y;
            gi_csm_order_cell(GI_CSM_ORDER_HILBERT, n, n, k, &a, &b);
            hilbert_d2xy(n, k, &x, &y);
            if (a != x || b != y)
                classic = 0;
        }
    }
    CHECK(classic);

    /* Hilbert on 2^k squares starts at a corner and ends at the adjacent one. */
    uint32_t a, b;
    gi_csm_order_cell(GI_CSM_ORDER_HILBERT, 8, 8, 0, &a, &b);
    CHECK(a == 0 && b == 0);
    gi_csm_order_cell(GI_CSM_ORDER_HILBERT, 8, 8, 63, &a, &b);
    CHECK(b == 0 && a == 7);
    gi_csm_order o;
    CHECK(gi_csm_order_parse("hilbert", &o) && o == GI_CSM_ORDER_HILBERT);
    CHECK(!gi_csm_order_parse("peano", &o));
}

/* ---- an analytic coherent input ---- */

/* Orthographic dual-depth maps of three disjoint spheres seen from
 * directions d on a lat-long grid (distant light, §4.1): camera plane at
 * distance 2 along d, looking along -d, M x M texels over [-1.2, 1.2]². */
typedef struct sphere {
    double c[3], r;
} sphere;

static const sphere SPHERES[3] = {
    {{0.0, 0.0, 0.0}, 0.5}, {{0.75, 0.2, 0.1}, 0.2}, {{-0.3, -0.7, 0.35}, 0.25}};

static void render_map(uint32_t M, double theta, double phi, float *z1, float *z2)
{
    double d[3] = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
    double u[3] = {-sin(phi), cos(phi), 0};
    double v[3] = {d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]};
    for (uint32_t y = 0; y < M; y++) {
        for (uint32_t x = 0; x < M; x++) {
            double sx = -1.2 + 2.4 * (x + 0.5) / M, sy = -1.2 + 2.4 * (y + 0.5) / M;
            double o[3], hits[6];
            int nh = 0;
            for (int k = 0; k < 3; k++)
                o[k] = 2 * d[k] + sx * u[k] + sy * v[k];
            for (int s = 0; s < 3; s++) { /* ray o - t d */
                double oc[3], bq = 0, cq = -SPHERES[s].r * SPHERES[s].r;
                for (int k = 0; k < 3; k++) {
                    oc[k] = o[k] - SPHERES[s].c[k];
                    bq -= oc[k] * d[k];
                    cq += oc[k] * oc[k];
                }
                double disc = bq * bq - cq;
                if (disc <= 0)
                    continue;
                hits[nh++] = -bq - sqrt(disc);
                hits[nh++] = -bq + sqrt(disc);
            }
            for (int i = 1; i < nh; i++) /* insertion sort */
                for (int j = i; j > 0 && hits[j] < hits[j - 1]; j--) {
                    double t = hits[j];
                    hits[j] = hits[j - 1];
                    hits[j - 1] = t;
                }
            z1[y * M + x] = nh > 0 ? (float)hits[0] : FLT_MAX;
            z2[y * M + x] = nh > 1 ? (float)hits[1] : FLT_MAX;
        }
    }
}

static double spheres_ratio(gi_csm_order order, uint32_t M, uint32_t na, uint32_t nb,
                            double *segs_per_texel)
{
    const double pi = 3.14159265358979323846;
    gi_error err = {{0}};
    gi_csm_codec *enc;
    gi_csm_data d;
    size_t texels = (size_t)M * M;
    float *z1 = malloc(texels * sizeof *z1), *z2 = malloc(texels * sizeof *z2);
    CHECK(gi_csm_codec_begin(M, na * nb, &enc, &err) == GI_OK);
    for (uint32_t i = 0; i < na * nb; i++) {
        uint32_t a, b;
        gi_csm_order_cell(order, na, nb, i, &a, &b);
        render_map(M, pi * (b + 0.5) / nb, 2 * pi * (a + 0.5) / na, z1, z2);
        CHECK(gi_csm_codec_add_map(enc, i, z1, z2, &err) == GI_OK);
    }
    CHECK(gi_csm_codec_finish(enc, &d, &err) == GI_OK);
    double ratio = (double)d.bytes_uncompressed / (double)d.bytes_compressed;
    *segs_per_texel = (double)d.segment_count / (double)texels;
    gi_csm_data_free(&d);
    free(z1);
    free(z2);
    return ratio;
}

static void test_spheres(void)
{
    uint32_t grids[] = {8, 32};
    for (size_t g = 0; g < 2; g++) {
        uint32_t n = grids[g];
        double seg[3], ratio[3];
        gi_csm_order orders[] = {GI_CSM_ORDER_SCANLINE, GI_CSM_ORDER_ZIGZAG, GI_CSM_ORDER_HILBERT};
        for (int o = 0; o < 3; o++) {
            ratio[o] = spheres_ratio(orders[o], 64, n, n, &seg[o]);
            printf("spheres M=64 N=%ux%u %-8s: ratio %.2f:1, %.3f segments/texel\n", n, n,
                   gi_csm_order_name(orders[o]), ratio[o], seg[o]);
        }
        /* Hilbert keeps more successive maps coherent than scan-line. */
        CHECK_MSG(seg[2] <= seg[0] * 1.02, "%ux%u: hilbert %.3f vs scanline %.3f", n, n, seg[2],
                  seg[0]);
    }
}

int main(void)
{
    test_edges();
    test_random();
    test_serialise(5, 40);
    test_serialise(2, 70000);
    test_orders();
    test_spheres();
    return gi_test_finish();
}

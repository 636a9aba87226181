/* CSM compression, Ritschel et al. 2007 §3.1 (greedy dual-depth segments,
 * z_avg, i_end) and §3.2 (binary search for the segment of map i), plus the
 * cache serialisation of the result. Conventions in gi/algo/csm_codec.h. */
#include "gi/algo/csm_codec.h"
#include "gi/cache.h"

#include <assert.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Per texel: the open run [start, ...] with its max z1 and min z2 (z2 none
 * as +inf). open == 0 after a degenerate map closed its own segment. */
typedef struct run {
    uint32_t start;
    uint32_t open;
    float max_z1, min_z2;
} run;

/* Closed segments in the order they were emitted; finish sorts them by texel
 * (each texel's own segments are already in order of i). */
typedef struct seg_rec {
    uint32_t texel, i_end;
    float z_avg;
} seg_rec;

struct gi_csm_codec {
    uint32_t M, N, next;
    int failed;
    run *runs;
    seg_rec *log;
    size_t log_count, log_cap;
};

static float norm_z1(float z)
{
    return z >= FLT_MAX ? FLT_MAX : z;
}

static float norm_z2(float z)
{
    return z >= FLT_MAX ? INFINITY : z;
}

/* z_avg of a run with max z1 = a < min z2 = b (b may be +inf). */
static float z_avg_of(float a, float b)
{
    if (isinf(b))
        return a;
    float m = (float)(0.5 * ((double)a + (double)b));
    return m < b && m >= a ? m : a;
}

gi_result gi_csm_codec_begin(uint32_t M, uint32_t N, gi_csm_codec **out, gi_error *err)
{
    assert(out);
    *out = NULL;
    if (M < 1 || M > GI_CSM_MAX_M || N < 1 || N > GI_CSM_MAX_N)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "csm codec: M = %u, N = %u out of range (1..%u, 1..%u)", M, N,
                            GI_CSM_MAX_M, GI_CSM_MAX_N);
    gi_csm_codec *enc = calloc(1, sizeof *enc);
    if (!enc)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm codec: out of memory");
    enc->M = M;
    enc->N = N;
    enc->runs = calloc((size_t)M * M, sizeof *enc->runs);
    if (!enc->runs) {
        free(enc);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm codec: out of memory");
    }
    *out = enc;
    return GI_OK;
}

void gi_csm_codec_free(gi_csm_codec *enc)
{
    if (!enc)
        return;
    free(enc->runs);
    free(enc->log);
    free(enc);
}

static int emit(gi_csm_codec *enc, uint32_t texel, uint32_t i_end, float z_avg)
{
    if (enc->log_count == enc->log_cap) {
        size_t cap = enc->log_cap ? enc->log_cap * 2 : (size_t)enc->M * enc->M * 2;
        seg_rec *p = realloc(enc->log, cap * sizeof *p);
        if (!p)
            return 0;
        enc->log = p;
        enc->log_cap = cap;
    }
    enc->log[enc->log_count++] = (seg_rec){texel, i_end, z_avg};
    return 1;
}

gi_result gi_csm_codec_add_map(gi_csm_codec *enc, uint32_t i, const float *z1, const float *z2,
                               gi_error *err)
{
    assert(enc && z1 && z2);
    if (enc->failed)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "csm codec: encoder failed earlier");
    if (i != enc->next || i >= enc->N) {
        enc->failed = 1;
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "csm codec: map %u added, expected map %u of %u", i, enc->next, enc->N);
    }
    size_t texels = (size_t)enc->M * enc->M;
    /* Validate the whole map first so that a bad map leaves no half update. */
    for (size_t t = 0; t < texels; t++) {
        float a = norm_z1(z1[t]), b = norm_z2(z2[t]);
        if (isnan(a) || isnan(b) || b < a || (a == FLT_MAX && !isinf(b))) {
            enc->failed = 1;
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "csm codec: map %u texel %zu: z1 = %g, z2 = %g (need z1 <= z2, "
                                "no NaN, z2 none where z1 is)",
                                i, t, (double)z1[t], (double)z2[t]);
        }
    }
    for (size_t t = 0; t < texels; t++) {
        run *r = &enc->runs[t];
        float a = norm_z1(z1[t]), b = norm_z2(z2[t]);
        if (r->open) {
            float mx = fmaxf(r->max_z1, a), mn = fminf(r->min_z2, b);
            if (mx < mn) { /* eq. 1 still holds: extend */
                r->max_z1 = mx;
                r->min_z2 = mn;
                continue;
            }
            if (!emit(enc, (uint32_t)t, i - 1, z_avg_of(r->max_z1, r->min_z2)))
                goto oom;
        }
        if (a < b) {
            *r = (run){i, 1, a, b};
        } else { /* degenerate z1 == z2: a segment of its own */
            r->open = 0;
            if (!emit(enc, (uint32_t)t, i, a))
                goto oom;
        }
    }
    enc->next++;
    return GI_OK;
oom:
    enc->failed = 1;
    return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm codec: out of memory");
}

static void set_sizes(gi_csm_data *d)
{
    uint64_t texels = (uint64_t)d->M * d->M;
    d->bytes_uncompressed = 2u * (uint64_t)d->N * texels;
    d->bytes_compressed = 4u * (texels + 1) + d->segment_count * (4u + gi_csm_i_end_bytes(d->N));
}

static gi_result alloc_data(gi_csm_data *d, uint32_t M, uint32_t N, uint64_t count)
{
    memset(d, 0, sizeof *d);
    d->M = M;
    d->N = N;
    d->segment_count = count;
    size_t texels = (size_t)M * M;
    d->offsets = malloc((texels + 1) * sizeof *d->offsets);
    d->z_avg = malloc((count ? (size_t)count : 1) * sizeof *d->z_avg);
    d->i_end = malloc((count ? (size_t)count : 1) * sizeof *d->i_end);
    if (!d->offsets || !d->z_avg || !d->i_end) {
        gi_csm_data_free(d);
        return GI_ERR_OUT_OF_MEMORY;
    }
    set_sizes(d);
    return GI_OK;
}

gi_result gi_csm_codec_finish(gi_csm_codec *enc, gi_csm_data *out, gi_error *err)
{
    assert(enc && out);
    memset(out, 0, sizeof *out);
    gi_result r = GI_OK;
    if (enc->failed) {
        r = gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "csm codec: encoder failed earlier");
        goto done;
    }
    if (enc->next != enc->N) {
        r = gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "csm codec: %u of %u maps added", enc->next,
                         enc->N);
        goto done;
    }
    size_t texels = (size_t)enc->M * enc->M;
    for (size_t t = 0; t < texels; t++) {
        run *ru = &enc->runs[t];
        if (ru->open && !emit(enc, (uint32_t)t, enc->N - 1, z_avg_of(ru->max_z1, ru->min_z2))) {
            r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm codec: out of memory");
            goto done;
        }
    }
    if (enc->log_count > UINT32_MAX) { /* offsets are uint32 */
        r = gi_error_set(err, GI_ERR_UNSUPPORTED, "csm codec: %zu segments, more than 2^32 - 1",
                         enc->log_count);
        goto done;
    }
    if (alloc_data(out, enc->M, enc->N, enc->log_count) != GI_OK) {
        r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm codec: out of memory");
        goto done;
    }
    /* Counting sort by texel; stable, so each list stays in order of i. */
    memset(out->offsets, 0, (texels + 1) * sizeof *out->offsets);
    for (size_t k = 0; k < enc->log_count; k++)
        out->offsets[enc->log[k].texel + 1]++;
    for (size_t t = 0; t < texels; t++)
        out->offsets[t + 1] += out->offsets[t];
    /* Reuse the run array's start field as the per-texel write cursor. */
    for (size_t t = 0; t < texels; t++)
        enc->runs[t].start = out->offsets[t];
    for (size_t k = 0; k < enc->log_count; k++) {
        uint32_t at = enc->runs[enc->log[k].texel].start++;
        out->z_avg[at] = enc->log[k].z_avg;
        out->i_end[at] = enc->log[k].i_end;
    }
done:
    gi_csm_codec_free(enc);
    return r;
}

void gi_csm_data_free(gi_csm_data *data)
{
    if (!data)
        return;
    free(data->offsets);
    free(data->z_avg);
    free(data->i_end);
    memset(data, 0, sizeof *data);
}

uint64_t gi_csm_segment(const gi_csm_data *data, uint32_t texel, uint32_t i)
{
    assert(data && (uint64_t)texel < (uint64_t)data->M * data->M && i < data->N);
    /* First segment with i_end >= i; the texel's last i_end is N-1. */
    uint32_t lo = data->offsets[texel], hi = data->offsets[texel + 1] - 1;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (data->i_end[mid] < i)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

float gi_csm_lookup(const gi_csm_data *data, uint32_t texel, uint32_t i)
{
    return data->z_avg[gi_csm_segment(data, texel, i)];
}

int gi_csm_visible(const gi_csm_data *data, uint32_t texel, uint32_t i, float depth, float bias)
{
    return depth <= gi_csm_lookup(data, texel, i) + bias;
}

/* ---- serialisation ---- */

static const char CSM_MAGIC[8] = {'G', 'I', 'C', 'S', 'M', 'Z', '\r', '\n'};
enum { CSM_VERSION = 1, CSM_HEADER = 8 + 4 * 4 + 8 };

static void put32(unsigned char *p, uint32_t v)
{
    for (int k = 0; k < 4; k++)
        p[k] = (unsigned char)(v >> (8 * k));
}

static void put64(unsigned char *p, uint64_t v)
{
    for (int k = 0; k < 8; k++)
        p[k] = (unsigned char)(v >> (8 * k));
}

static uint32_t get32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t get64(const unsigned char *p)
{
    return (uint64_t)get32(p) | (uint64_t)get32(p + 4) << 32;
}

static uint32_t f2u(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

static float u2f(uint32_t u)
{
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* Serialised size, or 0 if it would not fit in size_t. */
static size_t file_size(uint32_t M, uint32_t N, uint64_t count)
{
    uint64_t texels = (uint64_t)M * M;
    uint64_t n = CSM_HEADER + 4 * (texels + 1) + 8;
    uint64_t per = 4u + gi_csm_i_end_bytes(N);
    if (count > (UINT64_MAX - n) / per)
        return 0;
    n += count * per;
    return n > SIZE_MAX ? 0 : (size_t)n;
}

gi_result gi_csm_data_write(const gi_csm_data *d, void **bytes, size_t *size, gi_error *err)
{
    assert(d && bytes && size);
    *bytes = NULL;
    *size = 0;
    size_t n = file_size(d->M, d->N, d->segment_count);
    unsigned char *p = n ? malloc(n) : NULL;
    if (!p)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm codec: out of memory");
    uint32_t ib = gi_csm_i_end_bytes(d->N);
    memcpy(p, CSM_MAGIC, 8);
    put32(p + 8, CSM_VERSION);
    put32(p + 12, d->M);
    put32(p + 16, d->N);
    put32(p + 20, ib);
    put64(p + 24, d->segment_count);
    unsigned char *q = p + CSM_HEADER;
    size_t texels = (size_t)d->M * d->M;
    for (size_t t = 0; t <= texels; t++, q += 4)
        put32(q, d->offsets[t]);
    for (uint64_t k = 0; k < d->segment_count; k++, q += 4)
        put32(q, f2u(d->z_avg[k]));
    for (uint64_t k = 0; k < d->segment_count; k++, q += ib) {
        if (ib == 2) {
            q[0] = (unsigned char)d->i_end[k];
            q[1] = (unsigned char)(d->i_end[k] >> 8);
        } else {
            put32(q, d->i_end[k]);
        }
    }
    put64(q, gi_hash64(p, (size_t)(q - p), 0));
    *bytes = p;
    *size = n;
    return GI_OK;
}

gi_result gi_csm_data_read(const void *bytes, size_t size, gi_csm_data *out, gi_error *err)
{
    assert(out);
    memset(out, 0, sizeof *out);
    const unsigned char *p = bytes;
    if (!p || size < CSM_HEADER + 8 || memcmp(p, CSM_MAGIC, 8) != 0)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "csm data: not a CSM file");
    uint32_t version = get32(p + 8), M = get32(p + 12), N = get32(p + 16), ib = get32(p + 20);
    uint64_t count = get64(p + 24);
    if (version != CSM_VERSION)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "csm data: version %u, expected %u",
                            version, CSM_VERSION);
    if (M < 1 || M > GI_CSM_MAX_M || N < 1 || N > GI_CSM_MAX_N || ib != gi_csm_i_end_bytes(N) ||
        count < (uint64_t)M * M || count > (uint64_t)M * M * N || count > UINT32_MAX)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "csm data: bad header (M %u, N %u, i_end bytes %u, %llu segments)", M,
                            N, ib, (unsigned long long)count);
    size_t want = file_size(M, N, count);
    if (want != size)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "csm data: %zu bytes, the header implies %zu", size, want);
    if (gi_hash64(p, size - 8, 0) != get64(p + size - 8))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "csm data: checksum mismatch");
    if (alloc_data(out, M, N, count) != GI_OK)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm data: out of memory");
    const unsigned char *q = p + CSM_HEADER;
    size_t texels = (size_t)M * M;
    for (size_t t = 0; t <= texels; t++, q += 4)
        out->offsets[t] = get32(q);
    for (uint64_t k = 0; k < count; k++, q += 4)
        out->z_avg[k] = u2f(get32(q));
    for (uint64_t k = 0; k < count; k++, q += ib)
        out->i_end[k] = ib == 2 ? (uint32_t)q[0] | (uint32_t)q[1] << 8 : get32(q);
    /* Structure: every texel has >= 1 segment, i_end strictly increasing up
     * to N-1, no NaN z_avg; so lookups stay in bounds. */
    const char *why = NULL;
    if (out->offsets[0] != 0 || out->offsets[texels] != count)
        why = "offsets do not span the segments";
    for (size_t t = 0; !why && t < texels; t++) {
        uint32_t b = out->offsets[t], e = out->offsets[t + 1];
        if (e <= b || e > count) {
            why = "offsets not increasing";
            break;
        }
        for (uint32_t k = b; k < e; k++) {
            if (isnan(out->z_avg[k]) || out->i_end[k] >= N ||
                (k > b && out->i_end[k] <= out->i_end[k - 1])) {
                why = "segment list out of order";
                break;
            }
        }
        if (!why && out->i_end[e - 1] != N - 1)
            why = "segment list does not end at map N-1";
    }
    if (why) {
        gi_csm_data_free(out);
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "csm data: %s", why);
    }
    return GI_OK;
}

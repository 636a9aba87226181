/* Coherent Shadow Maps codec (Ritschel et al., EGSR 2007, §3.1 compression,
 * §3.2 query, §4.4 for the order of the maps): N dual-depth maps of M x M
 * texels, compressed losslessly per texel into piecewise-constant segments.
 * Used by the csm and cssm_hrc plugins (their precomputation loop is
 * gi/algo/csm_precompute.h). No GPU code here.
 *
 * Use:
 *   gi_csm_codec *enc;
 *   gi_csm_codec_begin(M, N, &enc, &err);
 *   for (i = 0; i < N; i++)            // maps in enumeration order (csm_order.h)
 *       gi_csm_codec_add_map(enc, i, z1, z2, &err);
 *   gi_csm_codec_finish(enc, &data, &err);   // frees enc whatever it returns
 *   ... gi_csm_lookup / gi_csm_visible, or upload data.offsets/z_avg/i_end ...
 *   gi_csm_data_free(&data);
 * gi_csm_codec_free(enc) abandons an encoder before finish. The encoder
 * streams: it keeps per texel only the open run (start, max z1, min z2), so
 * the N x M² depths never have to be in memory at once.
 *
 * Input, per map i = 0..N-1 and texel t = y * M + x: linear depths z1 (first
 * surface) and z2 (second surface; the closed-manifold option of §3.1
 * "Details on depth values" passes z3 instead, the codec does not care).
 *   - "no surface" is any value >= FLT_MAX (FLT_MAX or +inf). z2 none means
 *     nothing of the object lies behind z1; z1 none means the texel is empty
 *     (then z2 must be none too) and every depth there is lit.
 *   - z1 == z2 is allowed (a degenerate map: thin surface, depth precision).
 *   - NaN, or z2 < z1, is rejected with GI_ERR_INVALID_ARGUMENT.
 *
 * Segments (greedy, as §3.1 eq. 1, with 0-based map indices): a run of maps
 * [s, e] is one segment while max z1 < min z2 over the run, taking z2 none as
 * +infinity; the run is extended map by map and closed at the first map that
 * would break that, which starts the next run. Then, per segment:
 *   - z_avg = (max z1 + min z2) / 2, the paper's choice, computed in double
 *     and rounded to float; if that rounds up onto min z2 (two adjacent
 *     floats) it becomes max z1, so max z1 <= z_avg < min z2 always holds;
 *   - if min z2 is none over the whole run, z_avg = max z1 (the tightest
 *     value, so receivers of other objects behind it stay shadowed, §4.6;
 *     clip z2 to a spherical far plane before calling to get a middle value);
 *     an empty map in the run makes that FLT_MAX;
 *   - a degenerate map (z1 == z2 finite) cannot satisfy eq. 1 even alone: it
 *     is a segment of its own with z_avg = z1 (the classic shadow-map value,
 *     exact for depths outside (z1, z2) = {}; such texels need the depth bias,
 *     as the paper notes in §6 "Quality").
 * Lossless means: for every texel and map i, with z = gi_csm_lookup(i),
 * z1 <= z < z2 (z2 none: z finite-or-FLT_MAX), or z == z1 for a degenerate
 * map; hence depth <= z agrees with depth <= z1 for every depth outside
 * (z1, z2), the interval where no surface point of the object can lie.
 *
 * Storage (gi_csm_data, and the GPU buffers a plugin uploads as-is):
 *   offsets[M*M + 1]  uint32  texel t owns segments [offsets[t], offsets[t+1])
 *   z_avg[count]      float32 (float16 would break the strict z_avg < z2 for
 *                             close z1, z2: the codec is lossless only in float32)
 *   i_end[count]      uint32 in memory; last map index of the segment,
 *                             strictly increasing per texel, the last one N-1
 * Serialised (gi_csm_data_write) and counted in bytes_compressed, i_end is
 * uint16 when N <= 65536 and uint32 otherwise; the offsets are the M x M
 * lookup texture of §5 plus one end entry:
 *   bytes_compressed   = 4 (M² + 1) + count (4 + 2 or 4)
 *   bytes_uncompressed = 2 N M²: the paper's Table 1 convention of 2 bytes
 *                        per depth pixel (32x32 maps of 128² = 32.0 MB).
 * The format-free figure is the mean number of segments per texel,
 * count / M².
 */
#ifndef GI_CSM_CODEC_H
#define GI_CSM_CODEC_H

#include "gi/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Limits: M in [1, GI_CSM_MAX_M], N in [1, GI_CSM_MAX_N]. */
#define GI_CSM_MAX_M 8192u
#define GI_CSM_MAX_N (1u << 30)

/* Compressed maps. Owned by the caller after finish/read; gi_csm_data_free. */
typedef struct gi_csm_data {
    uint32_t M, N;
    uint32_t *offsets; /* M*M + 1 */
    float *z_avg;      /* segment_count */
    uint32_t *i_end;   /* segment_count */
    uint64_t segment_count;
    uint64_t bytes_uncompressed; /* 2 N M² (Table 1 convention) */
    uint64_t bytes_compressed;   /* 4 (M² + 1) + count (4 + i_end bytes) */
} gi_csm_data;

typedef struct gi_csm_codec gi_csm_codec;

/* Starts an encoder for N maps of M x M texels. */
gi_result gi_csm_codec_begin(uint32_t M, uint32_t N, gi_csm_codec **out, gi_error *err);
/* Adds map i (must be the next one: 0, 1, ..., N-1). z1, z2: M*M depths,
 * row-major. On an error the encoder is unusable (finish reports it). */
gi_result gi_csm_codec_add_map(gi_csm_codec *enc, uint32_t i, const float *z1, const float *z2,
                               gi_error *err);
/* Closes the open runs and fills *out (zeroed on failure). Frees enc in every
 * case. Fails if fewer than N maps were added. */
gi_result gi_csm_codec_finish(gi_csm_codec *enc, gi_csm_data *out, gi_error *err);
/* Abandons an encoder (NULL is fine). */
void gi_csm_codec_free(gi_csm_codec *enc);

/* Frees the arrays and zeroes *data (NULL is fine). */
void gi_csm_data_free(gi_csm_data *data);

/* Bytes per serialised i_end for N maps: 2 or 4. */
static inline uint32_t gi_csm_i_end_bytes(uint32_t N)
{
    return N <= 65536u ? 2u : 4u;
}

/* Index of the segment of texel t that holds map i (§3.2: i_end(j-1) < i <=
 * i_end(j)), by binary search over the texel's list. t < M*M, i < N. */
uint64_t gi_csm_segment(const gi_csm_data *data, uint32_t texel, uint32_t i);
/* z_avg of that segment. */
float gi_csm_lookup(const gi_csm_data *data, uint32_t texel, uint32_t i);
/* Shadow test of §3.2: depth <= z_avg + bias (1 = lit by map i's light). */
int gi_csm_visible(const gi_csm_data *data, uint32_t texel, uint32_t i, float depth, float bias);

/* Serialises to a malloc'd little-endian buffer for the on-disk cache:
 * magic "GICSMZ\r\n", uint32 version (1), M, N, i_end bytes, uint64 count,
 * offsets[M*M + 1] u32, z_avg f32, i_end u16/u32, then the XXH64 of all the
 * preceding bytes. */
gi_result gi_csm_data_write(const gi_csm_data *data, void **bytes, size_t *size, gi_error *err);
/* Parses what gi_csm_data_write wrote. Anything else (wrong magic, version,
 * size, checksum, or inconsistent offsets/i_end) is GI_ERR_INVALID_ARGUMENT
 * with a message, never a crash; *out is zeroed on failure. */
gi_result gi_csm_data_read(const void *bytes, size_t size, gi_csm_data *out, gi_error *err);

#ifdef __cplusplus
}
#endif
#endif

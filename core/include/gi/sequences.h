/* Low-discrepancy sequences for the reference and the GPU methods: radical
 * inverse (van der Corput), Halton, Hammersley, Sobol (0,2) in 2D, the R2
 * sequence (Roberts 2018, "The unreasonable effectiveness of quasirandom
 * sequences") and Cranley-Patterson rotation. C twin of
 * core/shaders/sequences.glsl (vec2 results there are float[2] here).
 *
 * Every function returns values in [0, 1). Base-2 constructions (radical
 * inverse 2, Sobol, R2) work on 32-bit integers and keep the top 24 bits, so
 * they are exact and identical on CPU and GPU; Halton in bases > 2
 * accumulates digits in float (about 1 ulp per digit).
 */
#ifndef GI_SEQUENCES_H
#define GI_SEQUENCES_H

#include <assert.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Largest float below 1. */
#define GI_ONE_MINUS_EPSILON 0x1.fffffep-1f

/* 32-bit integer -> [0, 1) from its top 24 bits. */
static inline float gi_u32_to_unit(uint32_t x)
{
    return (float)(x >> 8) * (1.0f / 16777216.0f);
}

static inline uint32_t gi_reverse_bits32(uint32_t v)
{
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0F0F0F0Fu) | ((v & 0x0F0F0F0Fu) << 4);
    v = ((v >> 8) & 0x00FF00FFu) | ((v & 0x00FF00FFu) << 8);
    return (v >> 16) | (v << 16);
}

/* Van der Corput: radical inverse of i in base 2 (bit reversal). */
static inline float gi_radical_inverse2(uint32_t i)
{
    return gi_u32_to_unit(gi_reverse_bits32(i));
}

/* Radical inverse of i in any base >= 2. */
static inline float gi_radical_inverse(uint32_t base, uint32_t i)
{
    float inv_base = 1.0f / (float)base;
    float f = inv_base, r = 0.0f;
    while (i > 0u) {
        uint32_t next = i / base;
        r += f * (float)(i - next * base);
        f *= inv_base;
        i = next;
    }
    return r < GI_ONE_MINUS_EPSILON ? r : GI_ONE_MINUS_EPSILON;
}

/* Halton point i, dimension dim in [0, 8) (bases 2, 3, 5, ..., 19). */
static inline float gi_halton(uint32_t dim, uint32_t i)
{
    static const uint32_t primes[8] = {2, 3, 5, 7, 11, 13, 17, 19};
    assert(dim < 8);
    return dim == 0 ? gi_radical_inverse2(i) : gi_radical_inverse(primes[dim], i);
}

/* Hammersley point i of n: (i / n, radical inverse 2 of i). */
static inline void gi_hammersley(uint32_t i, uint32_t n, float out[2])
{
    float x = (float)i / (float)n;
    out[0] = x < GI_ONE_MINUS_EPSILON ? x : GI_ONE_MINUS_EPSILON;
    out[1] = gi_radical_inverse2(i);
}

/* Second dimension of the Sobol (0,2)-sequence (Kollig and Keller 2002);
 * the first dimension is gi_radical_inverse2. */
static inline float gi_sobol2(uint32_t i)
{
    uint32_t r = 0u;
    for (uint32_t v = 1u << 31; i != 0u; i >>= 1, v ^= v >> 1)
        if (i & 1u)
            r ^= v;
    return gi_u32_to_unit(r);
}

/* Point i of the Sobol (0,2)-sequence in 2D. */
static inline void gi_sobol02(uint32_t i, float out[2])
{
    out[0] = gi_radical_inverse2(i);
    out[1] = gi_sobol2(i);
}

/* Cranley-Patterson rotation: (x + offset) mod 1, kept below 1. */
static inline float gi_cp_rotate(float x, float offset)
{
    float r = x + offset;
    r = r >= 1.0f ? r - 1.0f : r;
    return r < GI_ONE_MINUS_EPSILON ? r : GI_ONE_MINUS_EPSILON;
}

/* R2 point i: fract(0.5 + i * (1/g, 1/g^2)), g the plastic number, in 0.32
 * fixed point (2^32/g = 3242174889, 2^32/g^2 = 2447445414): exact and
 * wrap-free, with alphas within 2^-33 of the real ones (so for large i the
 * points drift from the real-valued sequence by i x 2^-33, harmlessly). */
static inline void gi_r2(uint32_t i, float out[2])
{
    out[0] = gi_u32_to_unit(0x80000000u + i * 3242174889u);
    out[1] = gi_u32_to_unit(0x80000000u + i * 2447445414u);
}

#ifdef __cplusplus
}
#endif
#endif

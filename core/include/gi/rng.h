/* Random numbers: a 32-bit PCG (RXS-M-XS output) as in Jarzynski and Olano,
 * "Hash Functions for GPU Rendering", JCGT 9(3), 2020. C twin of
 * core/shaders/rng.glsl; both give bit-identical streams.
 *
 * Use:
 *     uint32_t s = gi_rng_init(pixel_index, sample_index, seed);
 *     float u = gi_rng_next_float(&s);       // [0, 1), 24 random bits
 *
 * The state is one uint32_t owned by the caller (no global state). A stream
 * is fixed by (pixel, sample, seed), so a render is the same whatever the
 * thread count or the order in which pixels are done.
 */
#ifndef GI_RNG_H
#define GI_RNG_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* One LCG step followed by the RXS-M-XS output permutation. */
static inline uint32_t gi_pcg_hash(uint32_t v)
{
    uint32_t state = v * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

/* Initial state of the stream for (pixel, sample, seed): a hash chain, so
 * that neighbouring pixels and samples start far apart. */
static inline uint32_t gi_rng_init(uint32_t pixel_index, uint32_t sample_index, uint32_t seed)
{
    return gi_pcg_hash(pixel_index + gi_pcg_hash(sample_index + gi_pcg_hash(seed)));
}

/* Advances the LCG state and returns the permuted new state. */
static inline uint32_t gi_rng_next_u32(uint32_t *state)
{
    uint32_t s = *state * 747796405u + 2891336453u;
    *state = s;
    uint32_t word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (word >> 22u) ^ word;
}

/* Uniform float in [0, 1) from the top 24 bits (exact in float). */
static inline float gi_rng_next_float(uint32_t *state)
{
    return (float)(gi_rng_next_u32(state) >> 8) * (1.0f / 16777216.0f);
}

#ifdef __cplusplus
}
#endif
#endif

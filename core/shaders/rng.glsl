// Random numbers: 32-bit PCG with RXS-M-XS output (Jarzynski and Olano,
// "Hash Functions for GPU Rendering", JCGT 2020). GLSL twin of
// core/include/gi/rng.h; streams are bit-identical to the C ones.
//     uint s = gi_rng_init(pixel_index, sample_index, seed);
//     float u = gi_rng_next_float(s);   // [0, 1), 24 random bits
#ifndef GI_RNG_GLSL
#define GI_RNG_GLSL

// One LCG step followed by the RXS-M-XS output permutation.
uint gi_pcg_hash(uint v)
{
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Initial state for (pixel, sample, seed): a hash chain.
uint gi_rng_init(uint pixel_index, uint sample_index, uint seed)
{
    return gi_pcg_hash(pixel_index + gi_pcg_hash(sample_index + gi_pcg_hash(seed)));
}

// Advances the LCG state and returns the permuted new state.
uint gi_rng_next_u32(inout uint state)
{
    uint s = state * 747796405u + 2891336453u;
    state = s;
    uint word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform float in [0, 1) from the top 24 bits (exact).
float gi_rng_next_float(inout uint state)
{
    return float(gi_rng_next_u32(state) >> 8u) * (1.0 / 16777216.0);
}
#endif

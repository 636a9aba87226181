// Low-discrepancy sequences: radical inverse, Halton, Hammersley, Sobol
// (0,2), R2 (Roberts 2018) and Cranley-Patterson rotation. GLSL twin of
// core/include/gi/sequences.h (its float[2] results are vec2 here). All
// values lie in [0, 1); the base-2 ones are exact and equal to the C ones.
#ifndef GI_SEQUENCES_GLSL
#define GI_SEQUENCES_GLSL
#include "common.glsl"

// 32-bit integer -> [0, 1) from its top 24 bits.
float gi_u32_to_unit(uint x)
{
    return float(x >> 8u) * (1.0 / 16777216.0);
}

uint gi_reverse_bits32(uint v)
{
    return bitfieldReverse(v);
}

// Van der Corput: radical inverse of i in base 2.
float gi_radical_inverse2(uint i)
{
    return gi_u32_to_unit(bitfieldReverse(i));
}

// Radical inverse of i in any base >= 2 (digits summed in float).
float gi_radical_inverse(uint base, uint i)
{
    float inv_base = 1.0 / float(base);
    float f = inv_base, r = 0.0;
    while (i > 0u) {
        uint next = i / base;
        r += f * float(i - next * base);
        f *= inv_base;
        i = next;
    }
    return min(r, GI_ONE_MINUS_EPSILON);
}

// Halton point i, dimension dim in [0, 8) (bases 2, 3, 5, ..., 19).
float gi_halton(uint dim, uint i)
{
    const uint primes[8] = uint[8](2u, 3u, 5u, 7u, 11u, 13u, 17u, 19u);
    return dim == 0u ? gi_radical_inverse2(i) : gi_radical_inverse(primes[min(dim, 7u)], i);
}

// Hammersley point i of n: (i / n, radical inverse 2 of i).
vec2 gi_hammersley(uint i, uint n)
{
    return vec2(min(float(i) / float(n), GI_ONE_MINUS_EPSILON), gi_radical_inverse2(i));
}

// Second dimension of the Sobol (0,2)-sequence (Kollig and Keller 2002).
float gi_sobol2(uint i)
{
    uint r = 0u;
    for (uint v = 1u << 31; i != 0u; i >>= 1, v ^= v >> 1)
        if ((i & 1u) != 0u)
            r ^= v;
    return gi_u32_to_unit(r);
}

vec2 gi_sobol02(uint i)
{
    return vec2(gi_radical_inverse2(i), gi_sobol2(i));
}

// Cranley-Patterson rotation: (x + offset) mod 1, kept below 1.
float gi_cp_rotate(float x, float offset)
{
    float r = x + offset;
    r = r >= 1.0 ? r - 1.0 : r;
    return min(r, GI_ONE_MINUS_EPSILON);
}
vec2 gi_cp_rotate(vec2 x, vec2 offset)
{
    return vec2(gi_cp_rotate(x.x, offset.x), gi_cp_rotate(x.y, offset.y));
}

// R2 point i in 0.32 fixed point: fract(0.5 + i (1/g, 1/g^2)).
vec2 gi_r2(uint i)
{
    return vec2(gi_u32_to_unit(0x80000000u + i * 3242174889u),
                gi_u32_to_unit(0x80000000u + i * 2447445414u));
}
#endif

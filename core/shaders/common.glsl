// Constants and tiny helpers every core shader shares; GLSL side of the
// constants in vecmath.h / sequences.h / brdf.h. No #version: the shader
// builder adds it.
#ifndef GI_COMMON_GLSL
#define GI_COMMON_GLSL

const float GI_PI = 3.14159265358979323846;
const float GI_INV_PI = 0.31830988618379067154;
const float GI_TWO_PI = 6.28318530717958647692;
// Largest float below 1 (0x1.fffffep-1).
const float GI_ONE_MINUS_EPSILON = 0.99999994;
// Phong exponents at or above this mean an ideal mirror (scene.h).
const float GI_MIRROR_EXPONENT = 10000.0;

// Luminance of linear Rec.709 RGB, in the C operation order (vecmath.h).
float gi_luminance(vec3 rgb)
{
    return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b;
}
#endif

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

// The face of the core's cube maps a direction d from the centre falls into
// (+x, -x, +y, -y, +z, -z = 0..5; the lowest axis on a tie, so every
// direction belongs to exactly one face). C twin: gi_cube_face, gi/algo/cubemap.h.
int gi_cube_face(vec3 d)
{
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z)
        return d.x >= 0.0 ? 0 : 1;
    if (a.y >= a.z)
        return d.y >= 0.0 ? 2 : 3;
    return d.z >= 0.0 ? 4 : 5;
}
#endif

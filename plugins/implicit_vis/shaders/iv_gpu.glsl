// Records of the implicit_vis GPU illumination (Sec. 4.3.1), the layouts
// iv_gpu.c uploads; the passes declare the blocks they use.
#ifndef IV_GPU_GLSL
#define IV_GPU_GLSL
#include "common.glsl"
#include "glsl_shared.h"
#include "iv_bindings.h"

struct IvElem {
    vec4 albedo; // rgb
    vec4 emit;   // rgb emitted radiance
    uvec4 info;  // x: the element's leaf node, y: 1 when it emits on both sides
};
struct IvNode {
    vec4 pos; // xyz position, w area
    vec4 nrm; // xyz area-weighted mean normal (unit at a leaf)
};
struct IvBin {
    vec4 dir; // xyz centre direction, w solid angle
    vec4 env; // rgb the environment's radiance through the bin's centre
};
struct IvRad {
    vec4 front; // radiance leaving the side the normal faces
    vec4 back;  // and the other side
};
// Which side of a node sends toward a receiver (iv_weights.comp).
const uint IV_SIDE_FRONT = 0u, IV_SIDE_BACK = 1u, IV_SIDE_BOTH = 2u;

struct IvElemLight {
    vec4 e_front; // irradiance on the side the element's normal faces
    vec4 e_back;  // on the other side
    vec4 normal;  // xyz the element's normal, w the normalisation of its bins (a hemisphere sums to pi)
};
#endif

// The CSSM visibility query of §3.2.2 (Fig. 4) on the GPU: the receiver
// projected into texel j's depth cube map, the face's compressed depth
// looked up by the core's CSM codec (binary search over the texel's
// segments for the map's sequence index), nearest or 2 x 2 PCF.
// GLSL twin of cssm_visible (cssm.c), of gi_csm_segment / gi_csm_visible
// (core/algo/csm_codec.c) and of gi_cube_basis / gi_cube_project
// (gi/algo/cubemap.h), in the C operation order; the gather test of
// plugins/cssm_hrc/tests (integration.cssm_gpu_gather) holds the two paths
// equal. Buffers: gpu_gather.c uploads the codec data as-is.
#ifndef CSSM_LOOKUP_GLSL
#define CSSM_LOOKUP_GLSL
#include "common.glsl"
#include "cssm_bindings.h"

// Buffer textures read as images, not SSBOs (issue 29, cssm_bindings.h). Per texel
// three texels: world position and area, unit normal, cube-map
// centre with the sequence index (uint bits) in w.
layout(binding = CSSM_IMG_TEXELS, rgba32ui) readonly restrict uniform uimageBuffer cssm_texels;
layout(binding = CSSM_IMG_OFFSETS, r32ui) readonly restrict uniform uimageBuffer cssm_offsets;
layout(binding = CSSM_IMG_Z_AVG, r32ui) readonly restrict uniform uimageBuffer cssm_z_avg;
layout(binding = CSSM_IMG_I_END, r32ui) readonly restrict uniform uimageBuffer cssm_i_end;

vec4 cssm_texel_p_area(uint j)
{
    return uintBitsToFloat(imageLoad(cssm_texels, int(3u * j)));
}
vec4 cssm_texel_n(uint j)
{
    return uintBitsToFloat(imageLoad(cssm_texels, int(3u * j + 1u)));
}
uvec4 cssm_texel_eye(uint j) // bits
{
    return imageLoad(cssm_texels, int(3u * j + 2u));
}

uniform uint u_M;           // cube faces M x M
uniform uint u_off_base[6]; // face f's offsets start at u_off_base[f]
uniform uint u_seg_base[6]; // and its segments at u_seg_base[f]

// gi_csm_lookup: z_avg of the first segment of texel `texel` with i_end >= i.
float cssm_csm_lookup(int face, uint texel, uint i)
{
    uint ob = u_off_base[face] + texel, sb = u_seg_base[face];
    uint lo = imageLoad(cssm_offsets, int(ob)).x, hi = imageLoad(cssm_offsets, int(ob + 1u)).x - 1u;
    while (lo < hi) {
        uint mid = lo + (hi - lo) / 2u;
        if (imageLoad(cssm_i_end, int(sb + mid)).x < i)
            lo = mid + 1u;
        else
            hi = mid;
    }
    return uintBitsToFloat(imageLoad(cssm_z_avg, int(sb + lo)).x);
}

// gi_csm_visible at texel (tx, ty) of face `face`, clamped to the face.
float cssm_face_test(int face, int tx, int ty, uint i, float depth, float bias)
{
    int M = int(u_M);
    tx = tx < 0 ? 0 : tx >= M ? M - 1 : tx;
    ty = ty < 0 ? 0 : ty >= M ? M - 1 : ty;
    return depth <= cssm_csm_lookup(face, uint(ty) * u_M + uint(tx), i) + bias ? 1.0 : 0.0;
}

// gi_cube_basis: the face's right s, up t and forward f.
void cssm_cube_basis(int face, out vec3 s, out vec3 t, out vec3 f)
{
    // selects, not constant arrays indexed per lane (issue 29): the same
    // unit vectors, +x, -x, +y, -y, +z, -z, up -y but for +y (+z), -y (-z)
    float sg = (face & 1) == 0 ? 1.0 : -1.0;
    f = vec3(face < 2 ? sg : 0.0, face == 2 || face == 3 ? sg : 0.0, face > 3 ? sg : 0.0);
    vec3 up = face == 2 || face == 3 ? vec3(0.0, 0.0, sg) : vec3(0.0, -1.0, 0.0);
    s = cross(f, up);
    t = cross(s, f);
}

// cssm_visible: 1 lit, 0 occluded (fractions with PCF) between texel j and
// world point x.
float cssm_visible(uint j, vec3 x, float bias, bool pcf)
{
    uvec4 eye = cssm_texel_eye(j);
    vec3 d = x - uintBitsToFloat(eye.xyz);
    float depth = length(d);
    if (!(depth > 0.0))
        return 1.0;
    int face = gi_cube_face(d);
    vec3 s, t, f;
    cssm_cube_basis(face, s, t, f);
    float z = dot(f, d);
    float sx = dot(s, d) / z, sy = dot(t, d) / z;
    uint i = eye.w;
    float M = float(u_M);
    float fx = (sx * 0.5 + 0.5) * M, fy = (sy * 0.5 + 0.5) * M;
    if (!pcf)
        return cssm_face_test(face, int(fx), int(fy), i, depth, bias);
    // 2 x 2 texels around the projection, bilinear weights, clamped to the face
    float gx = fx - 0.5, gy = fy - 0.5;
    int x0 = int(floor(gx)), y0 = int(floor(gy));
    float wx = gx - float(x0), wy = gy - float(y0), v = 0.0;
    for (int k = 0; k < 4; k++) {
        float w = ((k & 1) != 0 ? wx : 1.0 - wx) * ((k >> 1) != 0 ? wy : 1.0 - wy);
        if (w > 0.0)
            v += w * cssm_face_test(face, x0 + (k & 1), y0 + (k >> 1), i, depth, bias);
    }
    return v;
}
#endif

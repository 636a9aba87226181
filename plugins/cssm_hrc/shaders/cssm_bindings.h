/* Binding points of the cssm_hrc plugin's GPU final gather (gather=gpu)
 * and bounces (bounces_on=gpu), read by its C code (gpu_gather.c) and its
 * shaders alike (only #define lines). The read-only data are buffer
 * textures read as images (imageLoad), from GI_IMAGE_PLUGIN_FIRST (2): on
 * llvmpipe an SSBO read is a loop over the eight lanes of a vector with a
 * branch and a bounds check each, a texelFetch a call of the sampler's
 * function, an imageLoad a gather in line, the fastest of the three
 * (issue 29, measured in the README). Floats travel as their bits. */
#ifndef CSSM_BINDINGS_H
#define CSSM_BINDINGS_H
/* per node (§4.2), 7 RGBA32UI texels: sphere, gather position and area,
 * normal and cone, radiant intensity, child / skip / first leaf / leaf
 * count, representative, the representative's walk */
#define CSSM_IMG_NODES 2
#define CSSM_IMG_LEAVES 3 /* R32UI: leaf rank -> texel (the median-cut order) */
/* per texel, 3 RGBA32UI texels: position and area, normal, cube-map eye
 * and sequence index */
#define CSSM_IMG_TEXELS 4
#define CSSM_IMG_OFFSETS 5 /* R32UI: the six faces' codec offsets[M^2 + 1], concatenated */
#define CSSM_IMG_Z_AVG 6   /* R32UI: the six faces' segments, concatenated */
#define CSSM_IMG_I_END 7   /* R32UI */
#define CSSM_IMG_ALBEDO 8  /* RGBA32UI: per texel its albedo, then Phong ks and exponent */
/* written: SSBOs from GI_SSBO_PLUGIN_FIRST (8) */
#define CSSM_SSBO_STATS 14 /* gathered nodes, receivers, clamped gathers (one frame) */
#define CSSM_SSBO_OUT 16   /* bounces_on=gpu: per texel the gathered radiance, 3 floats */
#endif

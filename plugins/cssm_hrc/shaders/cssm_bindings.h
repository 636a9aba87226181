/* Binding points of the cssm_hrc plugin's GPU final gather (gather=gpu),
 * read by its C code (gpu_gather.c) and its shaders alike (only #define
 * lines). SSBOs from GI_SSBO_PLUGIN_FIRST (8). */
#ifndef CSSM_BINDINGS_H
#define CSSM_BINDINGS_H
/* per node (§4.2): sphere, gather position and area, normal and cone,
 * radiant intensity, child / skip / first leaf / leaf count, representative */
#define CSSM_SSBO_NODES 8
#define CSSM_SSBO_LEAVES 9 /* leaf rank -> texel (the median-cut order) */
/* per texel: position and area, normal, cube-map eye and sequence index */
#define CSSM_SSBO_TEXELS 10
#define CSSM_SSBO_OFFSETS 11 /* the six faces' codec offsets[M^2 + 1], concatenated */
#define CSSM_SSBO_Z_AVG 12   /* the six faces' segments, concatenated */
#define CSSM_SSBO_I_END 13
#define CSSM_SSBO_STATS 14 /* gathered nodes, receivers, clamped gathers (one frame) */
/* the HRC bounces' per-texel gather (bounces_on=gpu, cssm_bounce.comp) */
#define CSSM_SSBO_ALBEDO 15 /* per texel: albedo (rgb) */
#define CSSM_SSBO_OUT 16    /* per texel: the gathered radiance, 3 floats */
#endif

/* Binding points of the avg plugin, read by its C code and its shaders
 * alike (only #define lines: both preprocessors read it). Texture units
 * from GI_TEX_PLUGIN_FIRST (14) and SSBOs from GI_SSBO_PLUGIN_FIRST (8),
 * as gi/glsl_shared.h leaves them to plugins; the G-buffer is at the
 * kit's units 8-13. Units are per dispatch, so passes reuse them. */
#ifndef AVG_BINDINGS_H
#define AVG_BINDINGS_H

/* avg_trace.comp: the AVG's two 3D textures. */
#define AVG_TEX_GRID_NORMAL 14
#define AVG_TEX_GRID_COLOUR 15
/* avg_shade.comp: the split G-buffer and the VPLs' shadow-map atlas. */
#define AVG_TEX_SPLIT_POS 14
#define AVG_TEX_SPLIT_NRM 15
#define AVG_TEX_ATLAS 16
/* avg_assemble.comp: the shaded sub-images. */
#define AVG_TEX_SPLIT_OUT 14
#define AVG_TEX_SPLIT_WHOLE 15
/* avg_final.comp: the reassembled indirect light S. */
#define AVG_TEX_INDIRECT 14
#define AVG_TEX_WHOLE 15

/* SSBOs. */
#define AVG_SSBO_SLOTS 8        /* avg_trace.comp: one VPL per slot */
#define AVG_SSBO_VPLS 9         /* avg_shade.comp: the compacted live VPLs */
#define AVG_SSBO_ATLAS_VIEWS 10 /* avg_shade.comp: the atlas' views (depth_atlas.glsl) */
#define AVG_SSBO_COLOURS 8      /* avg_vox.geom, avg_vox1.geom: per-material voxel colour */
#define AVG_SSBO_VOX_SUMS                                                                          \
    9 /* avg_vox1.frag, avg_vox_resolve.comp: fixed-point sums, 8 ints a voxel */

/* Fixed-point unit of the single-pass voxeliser's sums: a normal component
 * or colour channel c is added as round(c x AVG_VOX_FIXED), so a sum is
 * off by at most count / (2 AVG_VOX_FIXED); 2^31 / AVG_VOX_FIXED = 32768
 * unit vectors fit in one voxel. */
#define AVG_VOX_FIXED 65536.0

#endif

/* Binding points of the implicit_vis plugin, read by its C code and its
 * shaders alike (only #define lines). SSBOs from GI_SSBO_PLUGIN_FIRST (8). */
#ifndef IV_BINDINGS_H
#define IV_BINDINGS_H
/* iv_display.comp, and the output of iv_gather.comp */
/* per element: irradiance on both sides, normal (w: the bins' normalisation) */
#define IV_SSBO_ELEM_LIGHT 8
#define IV_SSBO_TRI 9   /* per triangle: subdivisions k, its first grid point */
#define IV_SSBO_GRID 10 /* per grid point: its element */
/* the GPU illumination (iv_emit.comp, iv_gather.comp, iv_pull.comp; iv_gpu.c) */
/* per element: albedo, emission, its leaf and whether it emits on both sides */
#define IV_SSBO_ELEM 11
#define IV_SSBO_CHILDREN 12 /* per node: first child, number of children */
/* per bin: centre direction and solid angle, the environment's radiance */
#define IV_SSBO_BINS 13
#define IV_SSBO_GEOM 14     /* per node, per frame: position and area, mean normal */
#define IV_SSBO_RAD_SRC 15  /* per node: outgoing radiance on both sides, the previous bounce's */
#define IV_SSBO_RAD_DST 16  /* per node: outgoing radiance on both sides, this bounce's */
#define IV_SSBO_LINKS 17    /* per receiving link: bin, other end, covered share, length */
#define IV_SSBO_LINK_OFF 18 /* per element + 1: its first receiving link, its first light link */
/* per receiving link, per frame: node at the other end and its side, Eq. 5's weight */
#define IV_SSBO_WLINKS 19
/* per element: the traced direct irradiance on both sides (direct=traced; iv_gather.comp) */
#define IV_SSBO_DIRECT 20
/* per pixel: the traced direct irradiance (direct=traced; iv_display.comp) */
#define IV_SSBO_PIXEL_DIRECT 21
#define IV_SSBO_PUNCTUAL 3 /* the scene's punctual lights (GI_SSBO_LIGHTS) */
/* work-group width of the three passes */
#define IV_GROUP 64
#endif

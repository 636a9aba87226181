/* Binding points of the implicit_vis plugin, read by its C code and its
 * shader alike (only #define lines). SSBOs from GI_SSBO_PLUGIN_FIRST (8). */
#ifndef IV_BINDINGS_H
#define IV_BINDINGS_H
/* iv_display.comp */
#define IV_SSBO_ELEM_LIGHT 8 /* per element: irradiance on both sides, normal */
#define IV_SSBO_TRI 9        /* per triangle: subdivisions k, its first grid point */
#define IV_SSBO_GRID 10      /* per grid point: its element */
#endif

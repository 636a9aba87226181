/* Binding points of the implicit_vis plugin, read by its C code and its
 * shader alike (only #define lines). SSBOs from GI_SSBO_PLUGIN_FIRST (8). */
#ifndef IV_BINDINGS_H
#define IV_BINDINGS_H
#define IV_SSBO_VERTEX_LIGHT 8 /* iv_display.comp: per scene vertex, its element's irradiance (both sides) and normal */
#endif

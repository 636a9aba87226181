/* Constants that C and GLSL both use, in ONE file compiled by both: the C
 * headers include it, and shaders `#include "glsl_shared.h"` (the build
 * embeds it with the core's shaders). So a binding point, a flag bit or a
 * capacity cannot drift between the host and a shader.
 *
 * Only `#define NAME literal` lines and comments belong here: both
 * preprocessors read it. Integers without a suffix are binding points and
 * sizes (int in both languages); flag bits and type codes carry `u` (GLSL
 * uint, C unsigned).
 *
 * Who owns which binding point (the scene's are bound by
 * gi_gpu_scene_bind, the G-buffer's by gi_kit_bind_gbuffer):
 *   texture units   0-3 scene, 4-7 core passes (private), 8-13 G-buffer,
 *                   GI_TEX_PLUGIN_FIRST (14) and up: the plugin's own
 *   image units     0 accumulation, 1 the target (gi_kit), 2+ the plugin's
 *   SSBOs           0-5 scene and depth atlas, GI_SSBO_PLUGIN_FIRST (8)+ plugin
 *   UBOs            0-1 scene, GI_UBO_PLUGIN_FIRST (2)+ plugin
 */
#ifndef GI_GLSL_SHARED_H
#define GI_GLSL_SHARED_H

/* Capacity of the object-transform UBO (gi_objects[] in scene.glsl). */
#define GI_MAX_OBJECTS 256

/* gi_gpu_material.flags / GiMaterial.flags bits. */
#define GI_MATERIAL_FLAG_MIRROR 1u
#define GI_MATERIAL_FLAG_DOUBLE_SIDED 2u

/* gi_light_type / GiLight.type codes. */
#define GI_LIGHT_TYPE_POINT 0u
#define GI_LIGHT_TYPE_SPOT 1u
#define GI_LIGHT_TYPE_DIRECTIONAL 2u

/* No object / material / triangle (G-buffer ids where nothing was hit). */
#define GI_NO_ID 0xFFFFFFFFu

/* SSBO binding points of the scene (scene.glsl) and the depth atlas. */
#define GI_SSBO_VERTICES 0
#define GI_SSBO_INDICES 1
#define GI_SSBO_MATERIALS 2
#define GI_SSBO_LIGHTS 3
#define GI_SSBO_EMITTERS 4
#define GI_SSBO_DEPTH_ATLAS 5
#define GI_SSBO_PLUGIN_FIRST 8

/* UBO binding points of the scene. */
#define GI_UBO_OBJECTS 0
#define GI_UBO_FRAME 1
#define GI_UBO_PLUGIN_FIRST 2

/* Texture units of the scene. */
#define GI_TEX_ENV 0      /* sampler2D: RGBA32F radiance, intensity applied */
#define GI_TEX_ENV_COND 1 /* sampler2D: R32F, (width+1) x height conditional CDF */
#define GI_TEX_ENV_MARG 2 /* sampler2D: R32F, (height+1) x 1 marginal CDF */
#define GI_TEX_ALBEDO 3   /* sampler2DArray: material textures, one layer each */

/* Texture units the core's own passes use while they draw (not for plugins). */
#define GI_TEX_CORE_DEPTH_PEEL 4  /* depth peeling: the previous layer */
#define GI_TEX_CORE_ATLAS_VIEWS 5 /* depth atlas: its views as a buffer texture */

/* Texture units of the G-buffer (gbuffer_read.glsl, gi_kit_bind_gbuffer). */
#define GI_TEX_GBUFFER_POSITION 8
#define GI_TEX_GBUFFER_NORMAL 9
#define GI_TEX_GBUFFER_ALBEDO 10
#define GI_TEX_GBUFFER_PHONG 11
#define GI_TEX_GBUFFER_EMISSION 12
#define GI_TEX_GBUFFER_IDS 13

/* The first texture unit a plugin may use for its own textures. */
#define GI_TEX_PLUGIN_FIRST 14

/* Image units of the kit's progressive accumulation (accumulate.glsl). */
#define GI_IMAGE_ACCUM 0
#define GI_IMAGE_TARGET 1
#define GI_IMAGE_PLUGIN_FIRST 2

#endif

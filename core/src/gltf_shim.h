/* Internal: the glTF 2.0 parser behind gi_scene_load (gltf_shim.cpp, the only
 * code that sees tinygltf). It validates the whole file and builds every part
 * of a gi_scene except the two that need the rest of the core: scene->bounds
 * (needs the transforms, scene.c) and scene->envmap (needs the image reader,
 * scene.c). Callable from C; no C++ type crosses this header.
 */
#ifndef GI_GLTF_SHIM_H
#define GI_GLTF_SHIM_H

#include "gi/common.h"
#include "gi/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_gltf_source {
    const void *data;
    size_t size;
    int binary;           /* GLB container instead of JSON text */
    const char *base_dir; /* directory relative URIs resolve in; NULL forbids them */
    const char *name;     /* prefix of every message ("cornell.gltf") */
} gi_gltf_source;

/* Room for the JSON pointer of the environment's uri. */
#define GI_GLTF_POINTER_MAX 96

/* Parses and validates; NULL + "name: /json/pointer: reason" in err on
 * failure. On success the scene is complete except bounds and envmap; when
 * scene->has_environment, env_pointer holds the uri's JSON pointer
 * ("/scenes/0/extras/gibench/environment/uri") for the message scene.c
 * writes if the map turns out unreadable. Never lets an exception escape. */
gi_scene *gi_gltf_parse(const gi_gltf_source *src, char env_pointer[GI_GLTF_POINTER_MAX],
                        gi_error *err);

#ifdef __cplusplus
}
#endif
#endif

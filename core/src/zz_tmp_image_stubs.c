/* TEMPORARY stand-ins for scene functions that gpu_scene.c calls and that
 * the glTF loader (branch scene-loader, not yet on main) defines, so that
 * gicore links and the image/envmap/BRDF tests run. None of these tests
 * loads a scene, so the stubs are never called; they abort if they are.
 * Removed before this branch is done. */
#include <stdio.h>
#include <stdlib.h>

#include "gi/scene.h"

static void not_here(const char *fn)
{
    fprintf(stderr, "%s: the scene loader is not merged into this build\n", fn);
    abort();
}

void gi_scene_object_transform(const gi_scene *s, uint32_t object, float t, float out[16])
{
    not_here(__func__);
}

gi_light_frame gi_scene_light_at(const gi_scene *s, uint32_t light, float t)
{
    not_here(__func__);
    gi_light_frame f = {0};
    return f;
}

void gi_scene_triangle_world(const gi_scene *s, uint32_t tri, float t, gi_vec3 p[3])
{
    not_here(__func__);
}

void gi_scene_bounds_at(const gi_scene *s, float t, float out[6])
{
    not_here(__func__);
}

const float *gi_scene_triangle_emission(const gi_scene *s, uint32_t tri)
{
    not_here(__func__);
    return NULL;
}

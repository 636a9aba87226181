/* Shared set-up of the GL tests (test_passes.c, test_depth_atlas.c,
 * plugins/cssm_hrc/tests/csm_direct_tests.c and cssm_tests.c):
 * the GL context and a scene uploaded to it, each step a CHECK of check.h. */
#ifndef GI_TEST_GPU_FIXTURE_H
#define GI_TEST_GPU_FIXTURE_H

#include "check.h"

#include "gi/gpu.h"
#include "gi/scene.h"

/* Creates the context, loads the scene at `path` and uploads it. Returns 0
 * when the context or the scene is missing (*gs is then NULL); *gs is also
 * NULL when the upload failed, which is counted but returns 1. */
static inline int gpu_fixture_load(const char *path, gi_gpu **gpu, gi_scene **s, gi_gpu_scene **gs)
{
    gi_error err;
    *gpu = gi_gpu_create(NULL, &err);
    CHECK_MSG(*gpu != NULL, "%s", err.text);
    *s = gi_scene_load(path, &err);
    CHECK_MSG(*s != NULL, "%s", err.text);
    *gs = NULL;
    if (!*gpu || !*s)
        return 0;
    *gs = gi_gpu_scene_upload(*gpu, *s, &err);
    CHECK_MSG(*gs != NULL, "%s", err.text);
    return 1;
}

#endif

/* libFuzzer target for the glTF loader: any bytes (GLB when they start with
 * the 'glTF' magic, JSON otherwise) must load or fail with a message, never
 * crash, leak or trip a sanitizer. Loaded scenes are then pushed through the
 * functions that read them, so a scene that passes validation but breaks a
 * consumer is found too. External URIs resolve in GI_FUZZ_BASE_DIR
 * (tests/data/valid), read-only. */
#include "gi/cache.h"
#include "gi/mesh.h"
#include "gi/scene.h"

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void exercise(const gi_scene *s)
{
    float b[6], t = s->animation_length * 0.37f;
    gi_scene_bounds_at(s, t, b);
    gi_camera_frame f = gi_scene_camera_at(s, -1, t);
    for (uint32_t i = 0; i < s->camera_count; i++)
        f = gi_scene_camera_at(s, (int)i, t);
    (void)f;
    for (uint32_t i = 0; i < s->light_count; i++)
        (void)gi_scene_light_at(s, i, t);
    for (uint32_t i = 0; i < s->triangle_count && i < 64; i++) {
        gi_vec3 p[3];
        gi_scene_triangle_world(s, i, t, p);
        (void)gi_scene_triangle_emission(s, i);
    }
    for (uint32_t m = 0; m < s->material_count; m++) {
        float out[3], uv[2] = {0.3f, -7.6f};
        gi_scene_albedo(s, m, uv, out);
    }
    for (uint32_t o = 0; o < s->object_count; o++) {
        float sp[4];
        gi_mesh_object_sphere(s, o, sp);
        (void)gi_scene_object_hash(s, o);
    }
    float *areas = malloc((s->triangle_count + 1) * sizeof(float));
    if (areas)
        gi_mesh_triangle_areas(s, t, areas);
    free(areas);
    gi_welded_free(gi_mesh_weld(s, 1e-4f));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    int binary = size >= 4 && memcmp(data, "glTF", 4) == 0;
    gi_error err;
    gi_scene *s = gi_scene_load_memory(data, size, binary, GI_FUZZ_BASE_DIR, "fuzz.gltf", &err);
    if (s)
        exercise(s);
    gi_scene_free(s);
    return 0;
}

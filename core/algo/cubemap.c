/* Cube-map face geometry of the core's depth renderer (cubemap.h). */
#include "gi/algo/cubemap.h"

#include <math.h>

/* The small face functions are inline in cubemap.h: they run per node and
 * per sample in the plugins' gathers, across the library boundary. */
gi_vec3 gi_cube_texel_dir(int face, uint32_t M, uint32_t x, uint32_t y)
{
    gi_vec3 s, t, f;
    gi_cube_basis(face, &s, &t, &f);
    float sx = ((float)x + 0.5f) / (float)M * 2.0f - 1.0f,
          sy = ((float)y + 0.5f) / (float)M * 2.0f - 1.0f;
    return gi_v3_normalize(gi_v3_add(f, gi_v3_add(gi_v3_scale(s, sx), gi_v3_scale(t, sy))));
}

/* Cube-map face geometry of the core's depth renderer (cubemap.h). */
#include "gi/algo/cubemap.h"

#include <math.h>

int gi_cube_face(gi_vec3 d)
{
    float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
    if (ax >= ay && ax >= az)
        return d.x >= 0.0f ? 0 : 1;
    if (ay >= az)
        return d.y >= 0.0f ? 2 : 3;
    return d.z >= 0.0f ? 4 : 5;
}

void gi_cube_basis(int face, gi_vec3 *s, gi_vec3 *t, gi_vec3 *f)
{
    /* as gi_mat4_cube_face_view: forward and the "up" it passes to look_at */
    static const float dir[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                    {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    static const float up[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1},
                                   {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
    *f = gi_v3_load(dir[face]);
    *s = gi_v3_cross(*f, gi_v3_load(up[face]));
    *t = gi_v3_cross(*s, *f);
}

void gi_cube_project(int face, gi_vec3 d, float *sx, float *sy)
{
    gi_vec3 s, t, f;
    gi_cube_basis(face, &s, &t, &f);
    float z = gi_v3_dot(f, d);
    *sx = gi_v3_dot(s, d) / z;
    *sy = gi_v3_dot(t, d) / z;
}

gi_vec3 gi_cube_texel_dir(int face, uint32_t M, uint32_t x, uint32_t y)
{
    gi_vec3 s, t, f;
    gi_cube_basis(face, &s, &t, &f);
    float sx = ((float)x + 0.5f) / (float)M * 2.0f - 1.0f,
          sy = ((float)y + 0.5f) / (float)M * 2.0f - 1.0f;
    return gi_v3_normalize(gi_v3_add(f, gi_v3_add(gi_v3_scale(s, sx), gi_v3_scale(t, sy))));
}

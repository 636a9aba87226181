/* Small vector and matrix helpers shared by core, plugins and the reference.
 *
 * Vectors are float[3] arrays wrapped in gi_vec3 for value semantics;
 * matrices are float[16] in column-major order, as OpenGL reads them:
 * element (row r, column c) is m[c * 4 + r]. Transforms act on column
 * vectors: p' = M p.
 */
#ifndef GI_VECMATH_H
#define GI_VECMATH_H

#include <math.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

#define GI_PI 3.14159265358979323846f
#define GI_INV_PI 0.31830988618379067154f

typedef struct gi_vec3 {
    float x, y, z;
} gi_vec3;

static inline gi_vec3 gi_v3(float x, float y, float z)
{
    gi_vec3 v = {x, y, z};
    return v;
}
static inline gi_vec3 gi_v3_load(const float *p)
{
    return gi_v3(p[0], p[1], p[2]);
}
static inline void gi_v3_store(gi_vec3 v, float *p)
{
    p[0] = v.x;
    p[1] = v.y;
    p[2] = v.z;
}
static inline gi_vec3 gi_v3_add(gi_vec3 a, gi_vec3 b)
{
    return gi_v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline gi_vec3 gi_v3_sub(gi_vec3 a, gi_vec3 b)
{
    return gi_v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline gi_vec3 gi_v3_mul(gi_vec3 a, gi_vec3 b)
{
    return gi_v3(a.x * b.x, a.y * b.y, a.z * b.z);
}
static inline gi_vec3 gi_v3_scale(gi_vec3 a, float s)
{
    return gi_v3(a.x * s, a.y * s, a.z * s);
}
static inline float gi_v3_dot(gi_vec3 a, gi_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline gi_vec3 gi_v3_cross(gi_vec3 a, gi_vec3 b)
{
    return gi_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float gi_v3_length(gi_vec3 a)
{
    return sqrtf(gi_v3_dot(a, a));
}
static inline gi_vec3 gi_v3_normalize(gi_vec3 a)
{
    float l = gi_v3_length(a);
    return l > 0.0f ? gi_v3_scale(a, 1.0f / l) : a;
}
static inline float gi_v3_max_comp(gi_vec3 a)
{
    return fmaxf(a.x, fmaxf(a.y, a.z));
}
/* Luminance of linear Rec.709 RGB. */
static inline float gi_luminance(const float *rgb)
{
    return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

/* Orthonormal basis around unit n (Duff et al. 2017, branchless). */
static inline void gi_onb(gi_vec3 n, gi_vec3 *t, gi_vec3 *b)
{
    float s = copysignf(1.0f, n.z);
    float a = -1.0f / (s + n.z);
    float c = n.x * n.y * a;
    *t = gi_v3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = gi_v3(c, s + n.y * n.y * a, -n.y);
}

static inline void gi_mat4_identity(float m[16])
{
    memset(m, 0, 16 * sizeof(float));
    m[0] = m[5] = m[10] = m[15] = 1.0f;
}
/* out = a * b (out may alias a or b). */
void gi_mat4_mul(float out[16], const float a[16], const float b[16]);
/* General inverse; returns 0 and leaves out untouched when singular. */
int gi_mat4_invert(float out[16], const float m[16]);
void gi_mat4_transpose(float out[16], const float m[16]);
/* Rigid/affine transform of a point (w = 1) and of a direction (w = 0). */
gi_vec3 gi_mat4_point(const float m[16], gi_vec3 p);
gi_vec3 gi_mat4_dir(const float m[16], gi_vec3 d);
/* Translation, rotation (unit quaternion x,y,z,w) and scale composed as T R S. */
void gi_mat4_trs(float out[16], const float t[3], const float q[4], const float s[3]);
/* View matrix: world -> eye, eye looks down -Z with +Y up. */
void gi_mat4_look_at(float out[16], gi_vec3 eye, gi_vec3 target, gi_vec3 up);
/* Clip-space projections with depth z/w in [0, 1] from near to far: the
 * core sets glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE) on its context, so
 * these are NOT the classic glFrustum/glOrtho matrices (z in [-1, 1]). */
void gi_mat4_perspective(float out[16], float yfov_rad, float aspect, float znear, float zfar);
void gi_mat4_ortho(float out[16], float l, float r, float b, float t, float n, float f);
/* View matrix of cube face i (GL order +X, -X, +Y, -Y, +Z, -Z) at `eye`,
 * matching GL_TEXTURE_CUBE_MAP_POSITIVE_X + i with a 90 degree projection. */
void gi_mat4_cube_face_view(float out[16], gi_vec3 eye, int face);
/* Quaternion helpers (x, y, z, w). */
void gi_quat_slerp(float out[4], const float a[4], const float b[4], float t);
void gi_quat_normalize(float q[4]);

#ifdef __cplusplus
}
#endif
#endif

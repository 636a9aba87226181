/* Matrix and quaternion helpers declared in vecmath.h (column-major). */
#include "gi/vecmath.h"

void gi_mat4_mul(float out[16], const float a[16], const float b[16])
{
    float r[16];
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float s = 0.0f;
            for (int k = 0; k < 4; k++)
                s += a[k * 4 + row] * b[c * 4 + k];
            r[c * 4 + row] = s;
        }
    memcpy(out, r, sizeof r);
}

void gi_mat4_transpose(float out[16], const float m[16])
{
    float r[16];
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++)
            r[row * 4 + c] = m[c * 4 + row];
    memcpy(out, r, sizeof r);
}

int gi_mat4_invert(float out[16], const float m[16])
{
    double inv[16], det;
    const float *a = m;
    inv[0] = (double)a[5] * a[10] * a[15] - (double)a[5] * a[11] * a[14] -
             (double)a[9] * a[6] * a[15] + (double)a[9] * a[7] * a[14] +
             (double)a[13] * a[6] * a[11] - (double)a[13] * a[7] * a[10];
    inv[4] = -(double)a[4] * a[10] * a[15] + (double)a[4] * a[11] * a[14] +
             (double)a[8] * a[6] * a[15] - (double)a[8] * a[7] * a[14] -
             (double)a[12] * a[6] * a[11] + (double)a[12] * a[7] * a[10];
    inv[8] = (double)a[4] * a[9] * a[15] - (double)a[4] * a[11] * a[13] -
             (double)a[8] * a[5] * a[15] + (double)a[8] * a[7] * a[13] +
             (double)a[12] * a[5] * a[11] - (double)a[12] * a[7] * a[9];
    inv[12] = -(double)a[4] * a[9] * a[14] + (double)a[4] * a[10] * a[13] +
              (double)a[8] * a[5] * a[14] - (double)a[8] * a[6] * a[13] -
              (double)a[12] * a[5] * a[10] + (double)a[12] * a[6] * a[9];
    inv[1] = -(double)a[1] * a[10] * a[15] + (double)a[1] * a[11] * a[14] +
             (double)a[9] * a[2] * a[15] - (double)a[9] * a[3] * a[14] -
             (double)a[13] * a[2] * a[11] + (double)a[13] * a[3] * a[10];
    inv[5] = (double)a[0] * a[10] * a[15] - (double)a[0] * a[11] * a[14] -
             (double)a[8] * a[2] * a[15] + (double)a[8] * a[3] * a[14] +
             (double)a[12] * a[2] * a[11] - (double)a[12] * a[3] * a[10];
    inv[9] = -(double)a[0] * a[9] * a[15] + (double)a[0] * a[11] * a[13] +
             (double)a[8] * a[1] * a[15] - (double)a[8] * a[3] * a[13] -
             (double)a[12] * a[1] * a[11] + (double)a[12] * a[3] * a[9];
    inv[13] = (double)a[0] * a[9] * a[14] - (double)a[0] * a[10] * a[13] -
              (double)a[8] * a[1] * a[14] + (double)a[8] * a[2] * a[13] +
              (double)a[12] * a[1] * a[10] - (double)a[12] * a[2] * a[9];
    inv[2] = (double)a[1] * a[6] * a[15] - (double)a[1] * a[7] * a[14] -
             (double)a[5] * a[2] * a[15] + (double)a[5] * a[3] * a[14] +
             (double)a[13] * a[2] * a[7] - (double)a[13] * a[3] * a[6];
    inv[6] = -(double)a[0] * a[6] * a[15] + (double)a[0] * a[7] * a[14] +
             (double)a[4] * a[2] * a[15] - (double)a[4] * a[3] * a[14] -
             (double)a[12] * a[2] * a[7] + (double)a[12] * a[3] * a[6];
    inv[10] = (double)a[0] * a[5] * a[15] - (double)a[0] * a[7] * a[13] -
              (double)a[4] * a[1] * a[15] + (double)a[4] * a[3] * a[13] +
              (double)a[12] * a[1] * a[7] - (double)a[12] * a[3] * a[5];
    inv[14] = -(double)a[0] * a[5] * a[14] + (double)a[0] * a[6] * a[13] +
              (double)a[4] * a[1] * a[14] - (double)a[4] * a[2] * a[13] -
              (double)a[12] * a[1] * a[6] + (double)a[12] * a[2] * a[5];
    inv[3] = -(double)a[1] * a[6] * a[11] + (double)a[1] * a[7] * a[10] +
             (double)a[5] * a[2] * a[11] - (double)a[5] * a[3] * a[10] -
             (double)a[9] * a[2] * a[7] + (double)a[9] * a[3] * a[6];
    inv[7] = (double)a[0] * a[6] * a[11] - (double)a[0] * a[7] * a[10] -
             (double)a[4] * a[2] * a[11] + (double)a[4] * a[3] * a[10] +
             (double)a[8] * a[2] * a[7] - (double)a[8] * a[3] * a[6];
    inv[11] = -(double)a[0] * a[5] * a[11] + (double)a[0] * a[7] * a[9] +
              (double)a[4] * a[1] * a[11] - (double)a[4] * a[3] * a[9] -
              (double)a[8] * a[1] * a[7] + (double)a[8] * a[3] * a[5];
    inv[15] = (double)a[0] * a[5] * a[10] - (double)a[0] * a[6] * a[9] -
              (double)a[4] * a[1] * a[10] + (double)a[4] * a[2] * a[9] +
              (double)a[8] * a[1] * a[6] - (double)a[8] * a[2] * a[5];
    det = a[0] * inv[0] + a[1] * inv[4] + a[2] * inv[8] + a[3] * inv[12];
    if (det == 0.0 || !isfinite(det))
        return 0;
    for (int i = 0; i < 16; i++)
        out[i] = (float)(inv[i] / det);
    return 1;
}

gi_vec3 gi_mat4_point(const float m[16], gi_vec3 p)
{
    float x = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12];
    float y = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13];
    float z = m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14];
    float w = m[3] * p.x + m[7] * p.y + m[11] * p.z + m[15];
    if (w != 1.0f && w != 0.0f)
        return gi_v3(x / w, y / w, z / w);
    return gi_v3(x, y, z);
}

gi_vec3 gi_mat4_dir(const float m[16], gi_vec3 d)
{
    return gi_v3(m[0] * d.x + m[4] * d.y + m[8] * d.z, m[1] * d.x + m[5] * d.y + m[9] * d.z,
                 m[2] * d.x + m[6] * d.y + m[10] * d.z);
}

void gi_mat4_trs(float out[16], const float t[3], const float q[4], const float s[3])
{
    float x = q[0], y = q[1], z = q[2], w = q[3];
    float r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                  2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                  2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++) {
        for (int row = 0; row < 3; row++)
            out[c * 4 + row] = r[c * 3 + row] * s[c];
        out[c * 4 + 3] = 0.0f;
    }
    out[12] = t[0];
    out[13] = t[1];
    out[14] = t[2];
    out[15] = 1.0f;
}

void gi_mat4_look_at(float out[16], gi_vec3 eye, gi_vec3 target, gi_vec3 up)
{
    gi_vec3 f = gi_v3_normalize(gi_v3_sub(target, eye));
    gi_vec3 s = gi_v3_cross(f, up);
    if (gi_v3_length(s) < 1e-6f) /* up parallel to the view: pick another */
        s = gi_v3_cross(f, fabsf(f.y) < 0.9f ? gi_v3(0, 1, 0) : gi_v3(1, 0, 0));
    s = gi_v3_normalize(s);
    gi_vec3 u = gi_v3_cross(s, f);
    gi_mat4_identity(out);
    out[0] = s.x;
    out[4] = s.y;
    out[8] = s.z;
    out[1] = u.x;
    out[5] = u.y;
    out[9] = u.z;
    out[2] = -f.x;
    out[6] = -f.y;
    out[10] = -f.z;
    out[12] = -gi_v3_dot(s, eye);
    out[13] = -gi_v3_dot(u, eye);
    out[14] = gi_v3_dot(f, eye);
}

void gi_mat4_perspective(float out[16], float yfov, float aspect, float n, float f)
{
    float t = 1.0f / tanf(yfov * 0.5f);
    memset(out, 0, 16 * sizeof(float));
    out[0] = t / aspect;
    out[5] = t;
    out[10] = f / (n - f);
    out[11] = -1.0f;
    out[14] = f * n / (n - f);
}

void gi_mat4_ortho(float out[16], float l, float r, float b, float t, float n, float f)
{
    gi_mat4_identity(out);
    out[0] = 2.0f / (r - l);
    out[5] = 2.0f / (t - b);
    out[10] = -1.0f / (f - n);
    out[12] = -(r + l) / (r - l);
    out[13] = -(t + b) / (t - b);
    out[14] = -n / (f - n);
}

void gi_mat4_cube_face_view(float out[16], gi_vec3 eye, int face)
{
    /* GL cube map face directions and their "up" (-t axis) vectors. */
    static const float dir[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                    {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    static const float up[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1},
                                   {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
    gi_vec3 d = gi_v3_load(dir[face]);
    gi_mat4_look_at(out, eye, gi_v3_add(eye, d), gi_v3_load(up[face]));
}

void gi_quat_normalize(float q[4])
{
    float l = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (l > 0.0f)
        for (int i = 0; i < 4; i++)
            q[i] /= l;
}

void gi_quat_slerp(float out[4], const float a[4], const float b[4], float t)
{
    float bb[4] = {b[0], b[1], b[2], b[3]};
    float d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    if (d < 0.0f) { /* take the short way round */
        d = -d;
        for (int i = 0; i < 4; i++)
            bb[i] = -bb[i];
    }
    float wa, wb;
    if (d > 0.9995f) {
        wa = 1.0f - t;
        wb = t;
    } else {
        float th = acosf(d), s = sinf(th);
        wa = sinf((1.0f - t) * th) / s;
        wb = sinf(t * th) / s;
    }
    for (int i = 0; i < 4; i++)
        out[i] = wa * a[i] + wb * bb[i];
    gi_quat_normalize(out);
}

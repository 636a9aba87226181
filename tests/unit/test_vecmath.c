/* Matrix helpers: inverse, projections with depth in [0, 1], cube faces in
 * GL order, TRS and slerp. */
#include "check.h"
#include "gi/vecmath.h"

static float clip_depth(const float proj[16], float z_eye)
{
    float z = proj[10] * z_eye + proj[14];
    float w = proj[11] * z_eye + proj[15];
    return z / w;
}

int main(void)
{
    float p[16], inv[16], id[16];
    gi_mat4_perspective(p, 1.0f, 1.5f, 0.1f, 100.0f);
    CHECK_NEAR(clip_depth(p, -0.1f), 0.0, 1e-6);
    CHECK_NEAR(clip_depth(p, -100.0f), 1.0, 1e-5);
    gi_mat4_ortho(p, -1, 1, -2, 2, 1, 5);
    CHECK_NEAR(clip_depth(p, -1.0f), 0.0, 1e-6);
    CHECK_NEAR(clip_depth(p, -5.0f), 1.0, 1e-6);
    CHECK(gi_mat4_invert(inv, p));
    gi_mat4_mul(id, p, inv);
    for (int i = 0; i < 16; i++)
        CHECK_NEAR(id[i], (i % 5 == 0) ? 1.0 : 0.0, 1e-5);

    /* Cube face f looks along its axis: the axis point maps to the centre of
     * the face in front of the eye (z_eye < 0); GL's +Y face has "up" +Z
     * seen as -t, so a point at +Z lands at the top (t < 0 means v up). */
    static const float axes[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    for (int f = 0; f < 6; f++) {
        float v[16];
        gi_mat4_cube_face_view(v, gi_v3(1, 2, 3), f);
        gi_vec3 q = gi_mat4_point(v, gi_v3(1 + axes[f][0], 2 + axes[f][1], 3 + axes[f][2]));
        CHECK_NEAR(q.x, 0, 1e-5);
        CHECK_NEAR(q.y, 0, 1e-5);
        CHECK_NEAR(q.z, -1, 1e-5);
    }
    /* Rendered faces must agree with GL's cube sampling: for +X, sc = -rz and
     * tc = -ry, and a rendered image has eye x along s and eye y along t. */
    float v[16];
    gi_mat4_cube_face_view(v, gi_v3(0, 0, 0), 0);
    gi_vec3 q = gi_mat4_point(v, gi_v3(1, 0, -0.5f)); /* sc = +0.5 */
    CHECK(q.x > 0);
    q = gi_mat4_point(v, gi_v3(1, 0.5f, 0)); /* tc = -0.5 */
    CHECK(q.y < 0);
    gi_mat4_cube_face_view(v, gi_v3(0, 0, 0), 2); /* +Y: sc = rx, tc = rz */
    q = gi_mat4_point(v, gi_v3(0.5f, 1, 0.25f));
    CHECK(q.x > 0 && q.y > 0);

    float t[3] = {1, 2, 3}, r[4] = {0, 0.70710678f, 0, 0.70710678f}, s[3] = {2, 2, 2}, m[16];
    gi_mat4_trs(m, t, r, s); /* 90 degrees about +Y: +X -> -Z */
    q = gi_mat4_point(m, gi_v3(1, 0, 0));
    CHECK_NEAR(q.x, 1, 1e-5);
    CHECK_NEAR(q.y, 2, 1e-5);
    CHECK_NEAR(q.z, 1, 1e-5);
    float a[4] = {0, 0, 0, 1}, h[4];
    gi_quat_slerp(h, a, r, 0.5f); /* 45 degrees */
    CHECK_NEAR(h[1], sinf(GI_PI / 8), 1e-5);
    CHECK_NEAR(h[3], cosf(GI_PI / 8), 1e-5);

    float look[16];
    gi_mat4_look_at(look, gi_v3(0, 0, 5), gi_v3(0, 0, 0), gi_v3(0, 1, 0));
    q = gi_mat4_point(look, gi_v3(0, 0, 0));
    CHECK_NEAR(q.z, -5, 1e-5);
    return gi_test_finish();
}

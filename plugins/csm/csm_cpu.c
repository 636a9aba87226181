/* CPU side of the csm plugin (csm_cpu.h). */
#include "csm_cpu.h"

#include <float.h>
#include <math.h>

void csm_cell_angles(uint32_t n_theta, uint32_t n_phi, uint32_t a, uint32_t b, float *theta,
                     float *phi)
{
    *theta = GI_PI * ((float)b + 0.5f) / (float)n_theta;
    *phi = 2.0f * GI_PI * ((float)a + 0.5f) / (float)n_phi;
}

gi_vec3 csm_dir(float theta, float phi)
{
    float st = sinf(theta);
    return gi_v3(st * cosf(phi), cosf(theta), st * sinf(phi));
}

void csm_grid_coords(gi_vec3 w, uint32_t n_theta, uint32_t n_phi, float *u, float *v)
{
    float theta = atan2f(sqrtf(w.x * w.x + w.z * w.z), w.y);
    float phi = atan2f(w.z, w.x);
    if (phi < 0.0f)
        phi += 2.0f * GI_PI;
    *u = phi * (0.5f * GI_INV_PI) * (float)n_phi - 0.5f;
    *v = theta * GI_INV_PI * (float)n_theta - 0.5f;
}

void csm_basis(float theta, float phi, gi_vec3 *t, gi_vec3 *b, gi_vec3 *d)
{
    *d = csm_dir(theta, phi);
    *t = gi_v3(-sinf(phi), 0.0f, cosf(phi));
    *b = gi_v3_cross(*d, *t);
}

gi_vec3 csm_project(const float sphere[4], float theta, float phi, gi_vec3 x)
{
    gi_vec3 t, b, d;
    csm_basis(theta, phi, &t, &b, &d);
    gi_vec3 p = gi_v3_sub(x, gi_v3(sphere[0], sphere[1], sphere[2]));
    float R = sphere[3];
    return gi_v3(gi_v3_dot(p, t) / R, gi_v3_dot(p, b) / R, CSM_EYE * R - gi_v3_dot(p, d));
}

void csm_map_view(const float sphere[4], float theta, float phi, gi_depth_view *out)
{
    gi_vec3 t, b, d;
    csm_basis(theta, phi, &t, &b, &d);
    float R = sphere[3];
    gi_vec3 eye = gi_v3_add(gi_v3(sphere[0], sphere[1], sphere[2]), gi_v3_scale(d, CSM_EYE * R));
    memset(out, 0, sizeof *out);
    float *m = out->view; /* column-major, rows t, b, d */
    m[0] = t.x, m[4] = t.y, m[8] = t.z, m[12] = -gi_v3_dot(t, eye);
    m[1] = b.x, m[5] = b.y, m[9] = b.z, m[13] = -gi_v3_dot(b, eye);
    m[2] = d.x, m[6] = d.y, m[10] = d.z, m[14] = -gi_v3_dot(d, eye);
    m[15] = 1.0f;
    /* Everything of the object lies at eye depths in [(EYE-1) R, (EYE+1) R]. */
    gi_mat4_ortho(out->proj, -R, R, -R, R, 0.5f * (CSM_EYE - 1.0f) * R, (CSM_EYE + 1.5f) * R);
    out->projection = GI_PROJ_ORTHOGRAPHIC;
}

void csm_texel_depths(const float *map, size_t texels, int mode, float shell, const float *far,
                      float *z1, float *z2)
{
    for (size_t t = 0; t < texels; t++) {
        float a = map[4 * t], b = map[4 * t + 1];
        if (mode != CSM_DEPTH_Z2 && b < FLT_MAX) {
            if (map[4 * t + 2] < FLT_MAX)
                b = map[4 * t + 2];
            else if (mode == CSM_DEPTH_SPHERE && far[t] > b && far[t] < FLT_MAX)
                b = far[t];
        }
        if (shell > 0.0f && a < FLT_MAX && b >= FLT_MAX)
            b = a + shell;
        z1[t] = a;
        z2[t] = b;
    }
}

void csm_sphere_far(const gi_depth_view *v, gi_depth_metric metric, const float sphere[4],
                    uint32_t M, float *far)
{
    float vp[16], inv[16];
    gi_mat4_mul(vp, v->proj, v->view);
    if (!gi_mat4_invert(inv, vp)) {
        for (size_t t = 0; t < (size_t)M * M; t++)
            far[t] = FLT_MAX;
        return;
    }
    const gi_vec3 c = gi_v3(sphere[0], sphere[1], sphere[2]);
    const double R = sphere[3];
    for (uint32_t j = 0; j < M; j++)
        for (uint32_t i = 0; i < M; i++) {
            float x = ((float)i + 0.5f) / (float)M * 2.0f - 1.0f,
                  y = ((float)j + 0.5f) / (float)M * 2.0f - 1.0f;
            /* the texel's ray: from its point on the near plane (clip z 0) toward the far plane (z
             * 1) */
            gi_vec3 p0 = gi_mat4_point(inv, gi_v3(x, y, 0.0f)),
                    p1 = gi_mat4_point(inv, gi_v3(x, y, 1.0f));
            gi_vec3 d = gi_v3_normalize(gi_v3_sub(p1, p0)), oc = gi_v3_sub(p0, c);
            double b = gi_v3_dot(oc, d), disc = b * b - ((double)gi_v3_dot(oc, oc) - R * R);
            float *out = &far[(size_t)j * M + i];
            if (disc < 0.0) {
                *out = FLT_MAX;
                continue;
            }
            gi_vec3 exit_point = gi_v3_add(p0, gi_v3_scale(d, (float)(-b + sqrt(disc))));
            gi_vec3 e = gi_mat4_point(v->view, exit_point);
            *out = metric == GI_DEPTH_EYE_Z ? -e.z : gi_v3_length(e);
        }
}

/* TEMPORARY stand-ins for functions other branches implement (common.c,
 * vecmath.c, image_oiio.cpp, envmap.c), so that the scene loader and its
 * tests link on the scene-loader branch. Deleted before the merge; nothing
 * here is meant to survive it. */
#include "gi/common.h"
#include "gi/envmap.h"
#include "gi/image.h"
#include "gi/vecmath.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

gi_result gi_error_set(gi_error *err, gi_result code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->text, sizeof err->text, fmt, ap);
        va_end(ap);
    }
    return code;
}

void gi_mat4_mul(float out[16], const float a[16], const float b[16])
{
    float r[16];
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float v = 0.0f;
            for (int k = 0; k < 4; k++)
                v += a[k * 4 + row] * b[c * 4 + k];
            r[c * 4 + row] = v;
        }
    memcpy(out, r, sizeof r);
}

gi_vec3 gi_mat4_point(const float m[16], gi_vec3 p)
{
    return gi_v3(m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12],
                 m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
                 m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]);
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
    gi_mat4_identity(out);
    for (int c = 0; c < 3; c++)
        for (int row = 0; row < 3; row++)
            out[c * 4 + row] = r[c * 3 + row] * s[c];
    out[12] = t[0];
    out[13] = t[1];
    out[14] = t[2];
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
    float d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    float bb[4] = {b[0], b[1], b[2], b[3]};
    if (d < 0.0f) {
        d = -d;
        for (int i = 0; i < 4; i++)
            bb[i] = -bb[i];
    }
    float wa = 1.0f - t, wb = t;
    if (d < 0.9995f) {
        float th = acosf(d), s = sinf(th);
        wa = sinf((1.0f - t) * th) / s;
        wb = sinf(t * th) / s;
    }
    for (int i = 0; i < 4; i++)
        out[i] = wa * a[i] + wb * bb[i];
    gi_quat_normalize(out);
}

void gi_image_free(gi_image *img)
{
    if (img) {
        free(img->rgba);
        free(img);
    }
}

/* Little-endian colour PFM ("PF", negative scale) only: enough for tests. */
gi_image *gi_image_read(const char *path, gi_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        gi_error_set(err, GI_ERR_IO, "%s: cannot open", path);
        return NULL;
    }
    char magic[3] = {0};
    unsigned w = 0, h = 0;
    float scale = 0.0f;
    gi_image *img = NULL;
    if (fscanf(f, "%2s %u %u %f", magic, &w, &h, &scale) == 4 && strcmp(magic, "PF") == 0 &&
        scale < 0.0f && w > 0 && h > 0 && w <= 4096 && h <= 4096 && fgetc(f) != EOF) {
        float *rgb = malloc((size_t)w * h * 3 * sizeof(float));
        img = calloc(1, sizeof *img);
        if (img && rgb && fread(rgb, sizeof(float) * 3, (size_t)w * h, f) == (size_t)w * h) {
            img->width = w;
            img->height = h;
            img->rgba = malloc((size_t)w * h * 4 * sizeof(float));
            for (size_t i = 0; img->rgba && i < (size_t)w * h; i++) {
                size_t src = ((h - 1 - i / w) * w + i % w) * 3; /* PFM is bottom-up */
                memcpy(img->rgba + i * 4, rgb + src, 3 * sizeof(float));
                img->rgba[i * 4 + 3] = 1.0f;
            }
        }
        free(rgb);
        if (img && !img->rgba) {
            gi_image_free(img);
            img = NULL;
        }
    }
    fclose(f);
    if (!img)
        gi_error_set(err, GI_ERR_IO, "%s: not a readable PFM file", path);
    return img;
}

gi_envmap *gi_envmap_create(const float *rgba, uint32_t width, uint32_t height, float intensity,
                            float rotation_deg)
{
    gi_envmap *env = calloc(1, sizeof *env);
    if (!env)
        return NULL;
    env->width = width;
    env->height = height;
    env->rotation = rotation_deg * GI_PI / 180.0f;
    env->rgb = malloc((size_t)width * height * 3 * sizeof(float));
    if (!env->rgb) {
        free(env);
        return NULL;
    }
    for (size_t i = 0; i < (size_t)width * height; i++)
        for (int c = 0; c < 3; c++)
            env->rgb[i * 3 + c] = rgba[i * 4 + c] * intensity;
    return env;
}

void gi_envmap_free(gi_envmap *env)
{
    if (env) {
        free(env->rgb);
        free(env->cond_cdf);
        free(env->marg_cdf);
        free(env->row_weight);
        free(env);
    }
}

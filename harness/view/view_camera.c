/* gibench view: the orbit camera (docs/commands.md "gibench view"): the eye at a
 * distance from a centre, at a yaw and a pitch, placed from the scene's
 * cameras; any change restarts the accumulation and the reference. */
#include "view.h"

#include "gi/vecmath.h"

#include <math.h>
#include <string.h>

gi_vec3 view_eye(const viewer *v)
{
    float cp = cosf(v->pitch), sp = sinf(v->pitch);
    gi_vec3 dir = gi_v3(cp * sinf(v->yaw), sp, cp * cosf(v->yaw));
    return gi_v3_add(v->center, gi_v3_scale(dir, v->dist));
}

gi_camera_frame view_camera(const viewer *v)
{
    view_file f;
    memset(&f, 0, sizeof f);
    f.eye = view_eye(v);
    f.forward = gi_v3_normalize(gi_v3_sub(v->center, f.eye));
    f.up = gi_v3(0, 1, 0);
    f.yfov = v->yfov;
    f.znear = v->znear;
    f.zfar = v->zfar;
    return view_file_camera(&f);
}

/* The orbit camera placed as the scene's camera `index` (-1: the default view). */
void view_camera_from_scene(viewer *v, int index)
{
    gi_camera_frame cf = gi_scene_camera_at(v->scene, index, v->time);
    gi_vec3 f = gi_v3_normalize(cf.forward);
    gi_vec3 mid = gi_v3(0.5f * (v->gs->bounds[0] + v->gs->bounds[3]),
                        0.5f * (v->gs->bounds[1] + v->gs->bounds[4]),
                        0.5f * (v->gs->bounds[2] + v->gs->bounds[5]));
    float d = gi_v3_dot(gi_v3_sub(mid, cf.eye), f);
    if (!(d > 1e-3f))
        d = fmaxf(gi_v3_length(gi_v3_sub(mid, cf.eye)), 1.0f);
    v->dist = d;
    v->center = gi_v3_add(cf.eye, gi_v3_scale(f, d));
    v->pitch = asinf(fmaxf(-1.0f, fminf(1.0f, -f.y)));
    v->yaw = atan2f(-f.x, -f.z);
    v->yfov = cf.yfov;
    v->znear = cf.znear;
    v->zfar = cf.zfar;
    v->scene_camera = index;
    view_changed(v);
}

void view_changed(viewer *v)
{
    v->pitch = fmaxf(-1.55f, fminf(1.55f, v->pitch));
    v->dist = fmaxf(v->dist, 1e-3f);
    v->frame_index = 0;
    v->need_render = 1;
    v->need_display = 1;
    view_second_changed(v);
    gi_image_free(v->ref_img); /* of the old view: no error against it */
    v->ref_img = NULL;
    v->err_dirty = 1;
    if (view_needs_reference(v)) {
        gi_camera_frame cf = view_camera(v);
        view_ref_request(&v->ref, &cf, v->time, v->width, v->height, v->seed);
        v->ref_spp = 0;
        const float black[4] = {0, 0, 0, 1};
        glClearTexImage(v->ref_tex, 0, GL_RGBA, GL_FLOAT, black);
    }
}

int view_needs_reference(const viewer *v)
{
    return v->method_index < 0 || v->split == 1 || v->split == 2 || v->show_panels ||
           v->source == VIEW_SRC_ERROR || v->source == VIEW_SRC_REFERENCE;
}

/* The reference runs while it is shown (alone, in split view, as the error,
 * or for the panels' live error) and idles otherwise. */
void view_reference_as_needed(viewer *v)
{
    int need = view_needs_reference(v);
    if (need && !view_ref_running(&v->ref))
        view_changed(v);
    else if (!need)
        view_ref_pause(&v->ref);
}

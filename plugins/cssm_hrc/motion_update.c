/* Moving rigid objects in cssm_hrc (Ritschel et al. 2008, §3.3), the
 * plugin's side of motion.c: prepare() makes the static CSSM (the scene
 * without the movers, their texels "don't care"), each mover's own CSSM
 * and CSM in its frame and, with two or more movers, the static objects'
 * CSMs (not cached); update() places the movers (D T^-1: no map is made
 * again) and makes the hierarchy again; both check the hulls. */
#include "cssm_hrc.h"

#include "gi/log.h"

/* Reports the hull check of §3.3 at time t: stats hull_overlap and
 * hull_intrusion, and a warning when the look-ups are not valid. */
static void check_hulls(cssm_hrc *c, const gi_scene *s, float t)
{
    const gi_host *host = c->kit.host;
    host->stage_begin(host, "hull");
    uint32_t bad = cssm_motion_check(&c->motion, s, t);
    host->stage_end(host, "hull");
    if (bad)
        host->log(
            host, GI_LOG_WARN,
            "t = %.3f s: %s; the visibility through the moving object is wrong there (Sec. 3.3)", t,
            c->motion.what);
}

gi_result cssm_build_moving(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    const gi_host *host = c->kit.host;
    gi_result r = cssm_motion_init(gs->scene, gs->time, &c->atlas, &c->motion, err);
    if (r != GI_OK)
        return r;
    cssm_build_opts o = {.skip_objects = c->motion.object_moves, .dont_care = c->motion.on_moving};
    r = cssm_maps_build_ex(gs, &c->atlas, c->order, (uint32_t)c->M, &o, host, &c->maps, err);
    if (r == GI_OK)
        r = cssm_motion_build_maps(&c->motion, gs, &c->atlas, c->order, (uint32_t)c->M, host, err);
    if (r != GI_OK)
        return r;
    c->maps.motion = &c->motion;
    host->stat(host, "cache_hit", 0.0);
    cssm_stats_moving(c);
    check_hulls(c, gs->scene, gs->time);
    return GI_OK;
}

gi_result cssm_place_movers(cssm_hrc *c, const gi_gpu_scene *gs)
{
    /* §3.3: A's texels placed by T, the hierarchy made again over the
     * moved texels (a median cut of a few thousand points: what a fresh
     * prepare would make), the atlas lit again; the CSSMs and the CSMs
     * are not made again (D T^-1) */
    const gi_host *host = c->kit.host;
    gi_error err;
    host->stage_begin(host, "motion");
    cssm_motion_place(&c->motion, gs->scene, gs->time, &c->atlas);
    host->stage_end(host, "motion");
    host->stage_begin(host, "hierarchy");
    cssm_tree_free(&c->tree);
    gi_result r = cssm_tree_build(&c->atlas, &c->tree, &err);
    if (r == GI_OK)
        r = cssm_make_compact(c, &err);
    host->stage_end(host, "hierarchy");
    if (r != GI_OK) { /* what was made before is gone: render refuses until the next prepare */
        c->prepared = 0;
        return gi_kit_fail_with(&c->kit, r, &err);
    }
    check_hulls(c, gs->scene, gs->time);
    return GI_OK;
}

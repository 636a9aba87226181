/* Progressive rendering until a sample count, a time, a standard error or
 * an estimated relMSE
 * (reference.h, gi_ref_progressive): the loop of gibench reference and of
 * the Python API's Scene.reference. */
#include "reference.h"

#include "gi/timer.h"

#include <math.h>

/* Passes between progress updates and stop checks last about this long. */
#define PASS_SECONDS 0.5

/* Next sample count at which target_se is checked: a function of the
 * image alone (never of timing), so that the stopping point and the image
 * are reproducible. Aim 10% past the count the 1/sqrt(spp) law predicts,
 * at most doubling. */
static uint64_t next_checkpoint(uint64_t spp, double se, double target)
{
    if (spp < 4)
        return 4;
    double want =
        isfinite(se) ? 1.1 * (double)spp * (se / target) * (se / target) : 2.0 * (double)spp;
    uint64_t n = want > 2.0 * (double)spp ? 2 * spp : (uint64_t)ceil(want);
    return n > spp ? n : spp + 1;
}

/* Samples of the next pass: about PASS_SECONDS of work, never past the
 * checkpoint or the sample limit, nor (much) past the time budget. */
static uint64_t pass_size(const gi_ref_until *u, uint64_t spp, uint64_t checkpoint, double per_spp,
                          double elapsed)
{
    double budget = PASS_SECONDS;
    if (u->seconds > 0.0)
        budget = fmin(budget, u->seconds - elapsed);
    uint64_t k = per_spp > 0.0 ? (uint64_t)(budget / per_spp) : 1;
    k = k < 1 ? 1 : k;
    if (checkpoint && k > checkpoint - spp)
        k = checkpoint - spp;
    if (k > 0xFFFFFFFFull - spp)
        k = 0xFFFFFFFFull - spp;
    return k;
}

/* The first checkpoint; 0 with neither target (then u->spp decides). */
static uint64_t first_checkpoint(const gi_ref_until *u)
{
    uint64_t c = u->target_se > 0.0 || u->target_relmse > 0.0 ? next_checkpoint(0, 0, 1) : 0;
    return u->spp && (!c || c > u->spp) ? u->spp : c;
}

/* At a checkpoint: the targets' statistics taken (*se, the --target-se
 * one), *stop set when one is reached, else the next checkpoint (relMSE
 * falls as 1/spp: its square root goes as the standard error). */
static uint64_t check_targets(const gi_ref *r, const gi_ref_until *u, uint64_t spp, double *se,
                              const char **stop)
{
    uint64_t next = 0;
    if (u->target_se > 0.0) {
        *se = gi_ref_mean_rel_se(r);
        if (*se <= u->target_se)
            *stop = "target-se";
        next = next_checkpoint(spp, *se, u->target_se);
    }
    if (u->target_relmse > 0.0) {
        double rm = gi_ref_mean_relmse(r);
        if (!*stop && rm <= u->target_relmse)
            *stop = "target-relmse";
        uint64_t n = next_checkpoint(spp, sqrt(rm), sqrt(u->target_relmse));
        next = next && next < n ? next : n;
    }
    return u->spp && next > u->spp ? u->spp : next;
}

gi_result gi_ref_progressive(gi_ref *r, const gi_ref_until *u, gi_ref_pass_fn fn, void *user,
                             const char **stop, gi_error *err)
{
    *stop = NULL;
    const double t_render = gi_now();
    double se = INFINITY, per_spp = 0.0; /* seconds a sample per pixel takes */
    uint64_t se_spp = 0;
    uint64_t checkpoint = first_checkpoint(u);
    const int targets = u->target_se > 0.0 || u->target_relmse > 0.0;
    while (!*stop) {
        uint64_t spp = gi_ref_spp(r);
        uint64_t k = pass_size(u, spp, checkpoint, per_spp, gi_now() - t_render);
        double t0 = gi_now();
        gi_result res = gi_ref_render(r, (uint32_t)k, err);
        if (res != GI_OK)
            return res;
        per_spp = (gi_now() - t0) / (double)k;
        spp = gi_ref_spp(r);
        double elapsed = gi_now() - t_render;
        if (targets && spp == checkpoint) {
            checkpoint = check_targets(r, u, spp, &se, stop);
            se_spp = spp;
        }
        if (!*stop && u->spp && spp >= u->spp)
            *stop = "spp";
        if (!*stop && u->seconds > 0.0 && elapsed >= u->seconds)
            *stop = "time";
        if (!*stop && spp >= 0xFFFFFFFFull)
            *stop = "spp";
        if (fn && fn(user, spp, u->target_se > 0.0 ? se : gi_ref_mean_rel_se(r),
                     u->target_se > 0.0 ? se_spp : spp, elapsed))
            return gi_error_set(err, GI_ERR_CANCELLED, "reference: interrupted after %llu spp",
                                (unsigned long long)spp);
    }
    return GI_OK;
}

/* The metrics of one comparison as JSON under the names of `gibench diff
 * --json` (runner.h), shared by the diff command and the Python API. */
#include "runner.h"

#include "metrics.h"

#include <math.h>

static json_object *metric_num(double v)
{
    return isfinite(v) ? json_object_new_double(v) : NULL; /* null: infinite or undefined */
}

void runner_metrics_json_add(json_object *j, const gi_metrics *m)
{
    json_object_object_add(j, "pixels_compared", json_object_new_int64((int64_t)m->pixels));
    json_object_object_add(j, "pixels_excluded", json_object_new_int64((int64_t)m->excluded));
    json_object_object_add(j, "exposure", json_object_new_double(m->exposure));
    json_object_object_add(j, "flip_ppd", json_object_new_double(m->flip_ppd));
    json_object_object_add(j, "rmse", metric_num(m->rmse));
    json_object_object_add(j, "mse", metric_num(m->mse));
    json_object_object_add(j, "relmse", metric_num(m->relmse));
    json_object_object_add(j, "mae", metric_num(m->mae));
    json_object_object_add(j, "psnr", metric_num(m->psnr));
    json_object_object_add(j, "ssim", metric_num(m->ssim));
    json_object_object_add(j, "mean_lum_test", metric_num(m->mean_lum_test));
    json_object_object_add(j, "mean_lum_ref", metric_num(m->mean_lum_ref));
    json_object_object_add(j, "mean_lum_diff_pct", metric_num(m->mean_lum_diff_pct));
    json_object_object_add(j, "flip", metric_num(m->flip));
    /* HDR-FLIP of the linear images, and the exposures (stops) it swept */
    json_object_object_add(j, "hdr_flip", metric_num(m->hdr_flip));
    json_object_object_add(j, "hdr_flip_start", metric_num(m->hdr_flip_start));
    json_object_object_add(j, "hdr_flip_stop", metric_num(m->hdr_flip_stop));
    json_object_object_add(j, "hdr_flip_exposures",
                           isfinite(m->hdr_flip) ? json_object_new_int(m->hdr_flip_exposures)
                                                 : NULL);
    json_object_object_add(j, "leaked_energy", metric_num(m->leaked_energy));
    json_object_object_add(j, "dark_fraction", metric_num(m->dark_fraction));
    json_object_object_add(j, "dark_energy_ref", metric_num(m->dark_energy_ref));
    json_object_object_add(j, "dark_threshold", json_object_new_double(m->dark_threshold));
}

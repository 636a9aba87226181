/* The report viewer's image labels (report_viewer.c): repeats of one
 * setting are numbered among themselves, "#2" for the second run of that
 * setting, whatever other settings share a prefix of its label (issue 33:
 * the second run of light_samples=1 was labelled "#3" because the label
 * of light_samples=16 begins with it). */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "report_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static json_object *record(const char *run, const char *params)
{
    json_object *o = json_object_new_object();
    json_object_object_add(o, "run", json_object_new_string(run));
    json_object_object_add(o, "method", json_object_new_string("direct"));
    json_object_object_add(o, "params", json_object_new_string(params));
    json_object_object_add(o, "status", json_object_new_string("ok"));
    json_object_object_add(o, "png", json_object_new_string("image.png"));
    return o;
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    char buf[1024], png[1100];
    snprintf(buf, sizeof buf, "%s/gibench-report-labels-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    char *d = mkdtemp(buf);
    CHECK(d != NULL);
    if (!d)
        return gi_test_finish();
    /* the viewer lists a run only when its picture exists */
    snprintf(png, sizeof png, "%s/image.png", d);
    FILE *f = fopen(png, "wb");
    CHECK(f != NULL);
    if (f)
        fclose(f);

    /* a sweep of light_samples, twice, in the study's order */
    const char *params[] = {"light_samples=1", "light_samples=4", "light_samples=16",
                            "light_samples=1", "light_samples=4", "light_samples=16"};
    const char *want[] = {"direct light_samples=1",    "direct light_samples=4",
                          "direct light_samples=16",   "direct light_samples=1 #2",
                          "direct light_samples=4 #2", "direct light_samples=16 #2"};
    json_object *runs = json_object_new_array();
    for (int i = 0; i < 6; i++) {
        char id[16];
        snprintf(id, sizeof id, "run%d", i);
        json_object_array_add(runs, record(id, params[i]));
    }
    json_object *meta = json_object_new_object();
    json_object *sets = report_viewer_sets(d, runs, meta);
    json_object *images = NULL;
    CHECK(json_object_array_length(sets) == 1);
    json_object_object_get_ex(json_object_array_get_idx(sets, 0), "images", &images);
    CHECK_MSG(json_object_array_length(images) == 6, "%zu images",
              images ? json_object_array_length(images) : 0);
    for (size_t i = 0; images && i < json_object_array_length(images) && i < 6; i++) {
        const char *l = report_raw(json_object_array_get_idx(images, i), "label");
        CHECK_MSG(!strcmp(l, want[i]), "image %zu labelled '%s', not '%s'", i, l, want[i]);
    }
    json_object_put(sets);
    json_object_put(meta);
    json_object_put(runs);
    unlink(png);
    rmdir(d);
    return gi_test_finish();
}

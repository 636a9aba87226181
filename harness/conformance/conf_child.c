/* gibench conformance --run-items, the child process (docs/conformance.md): runs a method's items
 * from --from on, each in its own session under an alarm, and prints the lines that the parent
 * reads back. */
#define _POSIX_C_SOURCE 200809L
#include "conf.h"

#include "gi/timer.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* The child: items from..count-1, one line when each starts and one with
 * its result; an alarm ends a hung item (and the process). */
int conf_run_items(const conf_opts *o, uint32_t from)
{
    gi_plugins *reg = cli_load_plugins(1);
    const gi_method *m = reg ? gi_plugins_find(reg, o->method) : NULL;
    if (!m) {
        gi_plugins_free(reg);
        return cli_fail(EXIT_USAGE, "conformance: no method '%s'", o->method);
    }
    static conf_item items[CONF_MAX_ITEMS];
    uint32_t n = conf_build_items(m, items);
    for (uint32_t k = from; k < n; k++) {
        printf("ITEM-START %u %s %s\n", k, items[k].group, items[k].arg);
        fflush(stdout);
        alarm((unsigned)ceil(conf_item_limit(m, &items[k], o->item_timeout)));
        double t0 = gi_now();
        conf_session S;
        memset(&S, 0, sizeof S);
        S.m = m;
        conf_result r = {R_FAIL, ""};
        gi_error err;
        if (!strcmp(items[k].group, "unknown_params")) {
            conf_run_item(&S, o, &items[k], &r);
        } else if (!(S.gpu = gi_gpu_create(NULL, &err))) {
            conf_set(&r, R_FAIL, "%s", err.text);
        } else {
            conf_run_item(&S, o, &items[k], &r);
            conf_instance_free(&S);
            if (S.fbo)
                glDeleteFramebuffers(1, &S.fbo);
            if (S.tex)
                glDeleteTextures(1, &S.tex);
            gi_gpu_destroy(S.gpu);
        }
        alarm(0);
        for (char *c = r.detail; *c; c++) /* one line */
            if (*c == '\n' || *c == '\t')
                *c = ' ';
        printf("ITEM-RESULT %u %s %.3f\t%s\n", k, conf_status_name[r.status], gi_now() - t0,
               r.detail);
        fflush(stdout);
    }
    gi_plugins_free(reg);
    return EXIT_OK;
}

/* gibench conformance --held-out SEED|DIR, the parent (docs/conformance.md "The held-out
 * family"): makes the family of a seed with scripts/held_out.py (or takes a folder it made),
 * runs every method on both furnace orientations and on every variant in a child process each
 * (`gibench conformance --held-out-item DIR FILE --method M`, conf_heldout_run.c), so that a
 * crash or a hang costs one (method, variant) pair, and prints the table of method x variant x
 * check with the numbers (or its JSON). */
#define _XOPEN_SOURCE 700 /* nftw */
#include "conf.h"
#include "proc.h"

#include <errno.h>
#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define HO_MAX_VARIANTS 32
#define HO_MAX_ROWS 4096

typedef struct ho_row {
    char method[64], variant[64], check[96];
    conf_status status;
    double value, limit, seconds;
    char detail[1024];
} ho_row;

typedef struct ho_run {
    char dir[1024];
    int made; /* the folder is ours, removed at the end */
    char name[HO_MAX_VARIANTS][64], file[HO_MAX_VARIANTS][256];
    uint32_t count;
    ho_row *rows;
    uint32_t nrows;
} ho_run;

static int is_dir(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

static int remove_entry(const char *p, const struct stat *st, int flag, struct FTW *f)
{
    return remove(p);
}

/* The family's folder: DIR as given when it holds a manifest, else SEED's family made into a
 * temporary folder. EXIT_OK, or an exit code after one line saying why. */
static int family_folder(const char *arg, ho_run *h)
{
    char mf[1100];
    snprintf(mf, sizeof mf, "%s/manifest.json", arg);
    if (is_dir(arg)) {
        if (access(mf, R_OK) != 0)
            return cli_fail(EXIT_USAGE,
                            "conformance: --held-out folder '%s' has no manifest.json (make one "
                            "with scripts/held_out.py --seed N --out DIR)",
                            arg);
        snprintf(h->dir, sizeof h->dir, "%s", arg);
        return EXIT_OK;
    }
    unsigned long seed;
    if (!cli_parse_uint(arg, 0, 4294967295ul, &seed))
        return cli_fail(EXIT_USAGE,
                        "conformance: --held-out '%s' is neither a seed (an integer in "
                        "0..4294967295) nor a folder made by scripts/held_out.py",
                        arg);
    if (!cli_temp_dir("gibench-held-out", h->dir, sizeof h->dir))
        return cli_fail(EXIT_RUN, "conformance: cannot make a temporary folder %s: %s", h->dir,
                        strerror(errno));
    h->made = 1;
    char seed_s[32], log[1100];
    snprintf(seed_s, sizeof seed_s, "%lu", seed);
    snprintf(log, sizeof log, "%s/held_out.log", h->dir);
    char *argv[] = {
        "/usr/bin/python3", CONF_HELD_OUT_SCRIPT, "--seed", seed_s, "--out", h->dir, NULL};
    cli_proc_result pr;
    if (cli_run(argv, 120.0, log, log, &pr) != 0 || pr.signaled || pr.timed_out ||
        pr.exit_code != 0) {
        char d[700];
        cli_proc_describe(&pr, d, sizeof d);
        return cli_fail(EXIT_RUN, "conformance: scripts/held_out.py --seed %s failed: %s", seed_s,
                        pr.last_line[0] ? pr.last_line : d);
    }
    return EXIT_OK;
}

static int wanted(const char *list, const char *name)
{
    if (!list)
        return 1;
    size_t n = strlen(name);
    for (const char *p = list; *p;) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        if (len == n && !strncmp(p, name, n))
            return 1;
        p = end ? end + 1 : p + len;
    }
    return 0;
}

/* The variants of the manifest (those --variants names). */
static int read_manifest(const conf_opts *o, ho_run *h)
{
    char mf[1100];
    snprintf(mf, sizeof mf, "%s/manifest.json", h->dir);
    json_object *root = json_object_from_file(mf), *vs;
    if (!root || !json_object_object_get_ex(root, "variants", &vs) ||
        !json_object_is_type(vs, json_type_array)) {
        json_object_put(root);
        return cli_fail(EXIT_USAGE, "conformance: %s is not a held-out manifest (no variants)", mf);
    }
    for (size_t i = 0; i < json_object_array_length(vs) && h->count < HO_MAX_VARIANTS; i++) {
        json_object *v = json_object_array_get_idx(vs, i), *nm, *fl;
        if (!json_object_object_get_ex(v, "name", &nm) ||
            !json_object_object_get_ex(v, "file", &fl))
            continue;
        if (!wanted(o->variants, json_object_get_string(nm)))
            continue;
        snprintf(h->name[h->count], 64, "%s", json_object_get_string(nm));
        snprintf(h->file[h->count], 256, "%s", json_object_get_string(fl));
        h->count++;
    }
    json_object_put(root);
    if (h->count == 0 && !wanted(o->variants, "furnace_in") && !wanted(o->variants, "furnace_out"))
        return cli_fail(EXIT_USAGE, "conformance: no variant of %s matches --variants '%s'", mf,
                        o->variants ? o->variants : "");
    return EXIT_OK;
}

static ho_row *new_row(ho_run *h, const char *method, const char *variant, const char *check)
{
    if (h->nrows >= HO_MAX_ROWS)
        return NULL;
    ho_row *r = &h->rows[h->nrows++];
    memset(r, 0, sizeof *r);
    snprintf(r->method, sizeof r->method, "%s", method);
    snprintf(r->variant, sizeof r->variant, "%s", variant);
    snprintf(r->check, sizeof r->check, "%s", check);
    r->status = R_FAIL;
    r->value = r->limit = NAN;
    return r;
}

/* Reads the child's lines into rows; a check it started and did not finish fails with `why`. */
static void read_child(ho_run *h, const char *log, const char *method, const char *variant,
                       double seconds, const char *why)
{
    FILE *f = fopen(log, "r");
    char line[2048];
    ho_row *open_row = NULL;
    uint32_t first = h->nrows;
    while (f && fgets(line, sizeof line, f)) {
        char check[96], st[16];
        double v, l;
        if (sscanf(line, "HO-START %95s", check) == 1) {
            open_row = new_row(h, method, variant, check);
            if (open_row)
                snprintf(open_row->detail, sizeof open_row->detail, "%s", why);
        } else if (open_row &&
                   sscanf(line, "HO-RESULT %95s %15s %lf %lf", check, st, &v, &l) == 4) {
            char *tab = strchr(line, '\t');
            open_row->status = !strcmp(st, "pass") ? R_PASS : !strcmp(st, "n/a") ? R_NA : R_FAIL;
            open_row->value = v;
            open_row->limit = l;
            snprintf(open_row->detail, sizeof open_row->detail, "%s", tab ? tab + 1 : "");
            open_row->detail[strcspn(open_row->detail, "\n")] = '\0';
            open_row = NULL;
        }
    }
    if (f)
        fclose(f);
    if (h->nrows == first) { /* nothing started: the child failed before its first check */
        ho_row *r = new_row(h, method, variant, "trivial");
        if (r)
            snprintf(r->detail, sizeof r->detail, "%s", why);
    }
    for (uint32_t k = first; k < h->nrows; k++)
        h->rows[k].seconds = seconds / (double)(h->nrows - first);
}

/* One child: method m on `file` (a variant's glTF, or furnace_in / furnace_out). */
static void run_child(const conf_opts *o, ho_run *h, const gi_method *m, const char *variant,
                      const char *file)
{
    char size[32], log[1400];
    snprintf(size, sizeof size, "%u", o->size);
    snprintf(log, sizeof log, "%s/%s-%s.log", h->dir, m->id, variant);
    char *argv[] = {(char *)cli_self_exe(),
                    "conformance",
                    "--held-out-item",
                    h->dir,
                    (char *)file,
                    "--method",
                    (char *)m->id,
                    "--size",
                    size,
                    o->no_converge ? "--no-converge" : NULL,
                    NULL};
    /* A knob sweep renders up to 1 + 1 + 3 per knob images; a method that precomputes gets five
     * times the item limit for each, as the parameter items of the shipped suite do. */
    uint32_t knobs = 0;
    for (const gi_param_desc *d = m->params; d && d->name; d++)
        knobs += gi_param_quality_of(d, NULL) != 0;
    double per = o->item_timeout * ((m->caps & GI_CAP_PRECOMPUTE) ? 5.0 : 1.0);
    double limit = 60.0 + per * (3.0 + 3.0 * (o->no_converge ? 0 : knobs));
    cli_proc_result pr;
    double t0 = gi_now();
    int ok = cli_run(argv, limit, log, log, &pr) == 0;
    char why[700] = "not finished";
    if (!ok || pr.signaled || pr.timed_out || pr.exit_code != 0)
        cli_proc_describe(&pr, why, sizeof why);
    if (!ok)
        snprintf(why, sizeof why, "%s", pr.last_line);
    read_child(h, log, m->id, variant, gi_now() - t0, why);
    if (!o->json)
        fprintf(stderr, "conformance: %s %s (%.1f s)\n", m->id, variant, gi_now() - t0);
}

/* Per method: the counts and the worst ratio of error to its limit over the trivial checks. */
static void print_summary(const ho_run *h, const gi_method *const *ms, uint32_t count)
{
    printf("\n%-14s %5s %5s %5s  %-s\n", "method", "pass", "fail", "n/a",
           "worst relMSE / limit (trivial check)");
    for (uint32_t i = 0; i < count; i++) {
        uint32_t c[3] = {0, 0, 0};
        double worst = NAN;
        char at[80] = "-";
        for (uint32_t k = 0; k < h->nrows; k++) {
            const ho_row *r = &h->rows[k];
            if (strcmp(r->method, ms[i]->id))
                continue;
            c[r->status]++;
            double q = r->value / r->limit;
            if (!strcmp(r->check, "trivial") && r->status != R_NA && isfinite(r->limit) &&
                (isnan(worst) || q > worst)) {
                worst = q;
                snprintf(at, sizeof at, "%s", r->variant);
            }
        }
        printf("%-14s %5u %5u %5u  %.3g (%s)\n", ms[i]->id, c[R_PASS], c[R_FAIL], c[R_NA], worst,
               at);
    }
}

static void print_rows(const ho_run *h, const gi_method *const *ms, uint32_t count)
{
    printf("%-14s %-12s %-22s %-5s %10s %10s  %s\n", "method", "variant", "check", "", "value",
           "limit", "detail");
    for (uint32_t k = 0; k < h->nrows; k++) {
        const ho_row *r = &h->rows[k];
        char st[16]; /* "*": a declared departure, scored at its remedy (the detail says) */
        snprintf(st, sizeof st, "%s%s", conf_status_name[r->status],
                 strncmp(r->detail, "declared departure: ", 20) ? "" : "*");
        printf("%-14s %-12s %-22s %-5s %10.4g %10.4g  %s\n", r->method, r->variant, r->check, st,
               r->value, r->limit, r->detail);
    }
    print_summary(h, ms, count);
}

static json_object *num(double v)
{
    return isfinite(v) ? json_object_new_double(v) : NULL;
}

static json_object *rows_json(const ho_run *h, const conf_opts *o, int failed)
{
    json_object *root = json_object_new_object(), *arr = json_object_new_array();
    json_object_object_add(root, "status", json_object_new_string(failed ? "fail" : "pass"));
    json_object_object_add(root, "held_out", json_object_new_string(o->held_out));
    json_object_object_add(root, "size", json_object_new_int((int32_t)o->size));
    for (uint32_t k = 0; k < h->nrows; k++) {
        const ho_row *r = &h->rows[k];
        json_object *jo = json_object_new_object();
        json_object_object_add(jo, "method", json_object_new_string(r->method));
        json_object_object_add(jo, "variant", json_object_new_string(r->variant));
        json_object_object_add(jo, "check", json_object_new_string(r->check));
        json_object_object_add(jo, "status", json_object_new_string(conf_status_name[r->status]));
        json_object_object_add(jo, "value", num(r->value));
        json_object_object_add(jo, "limit", num(r->limit));
        json_object_object_add(jo, "seconds", json_object_new_double(r->seconds));
        json_object_object_add(jo, "detail", json_object_new_string(r->detail));
        json_object_object_add(
            jo, "departure",
            json_object_new_boolean(!strncmp(r->detail, "declared departure: ", 20)));
        json_object_array_add(arr, jo);
    }
    json_object_object_add(root, "rows", arr);
    return root;
}

int conf_held_out(const conf_opts *o, const gi_method *const *ms, uint32_t count)
{
    static ho_run h;
    memset(&h, 0, sizeof h);
    int rc = family_folder(o->held_out, &h);
    if (rc == EXIT_OK)
        rc = read_manifest(o, &h);
    if (rc == EXIT_OK && !(h.rows = calloc(HO_MAX_ROWS, sizeof *h.rows)))
        rc = cli_fail(EXIT_RUN, "out of memory");
    if (rc != EXIT_OK) {
        if (h.made)
            nftw(h.dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
        return rc;
    }
    cli_install_signal_handlers();
    for (uint32_t i = 0; i < count; i++) {
        /* the furnaces belong to no seed: --variants names them to run them */
        if (wanted(o->variants, "furnace_in"))
            run_child(o, &h, ms[i], "furnace_in", "furnace_in");
        if (wanted(o->variants, "furnace_out"))
            run_child(o, &h, ms[i], "furnace_out", "furnace_out");
        for (uint32_t v = 0; v < h.count; v++)
            run_child(o, &h, ms[i], h.name[v], h.file[v]);
    }
    int failed = 0;
    for (uint32_t k = 0; k < h.nrows; k++)
        failed |= h.rows[k].status == R_FAIL;
    if (o->json) {
        json_object *j = rows_json(&h, o, failed);
        puts(json_object_to_json_string_ext(j, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED |
                                                   JSON_C_TO_STRING_NOSLASHESCAPE));
        json_object_put(j);
    } else {
        print_rows(&h, ms, count);
    }
    if (h.made && !failed)
        nftw(h.dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    else if (h.made)
        fprintf(stderr, "conformance: the family, references and children's logs are in %s\n",
                h.dir);
    free(h.rows);
    return failed ? EXIT_RUN : EXIT_OK;
}

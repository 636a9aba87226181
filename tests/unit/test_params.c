/* Method parameters: defaults, types, ranges, enums, unknown names, and a
 * plugin that reads a name its table does not declare (refused by
 * gi_method_create in release builds as in debug ones). */
#include "check.h"
#include "gi/params.h"
#include "gi/plugin.h"

#include <stdlib.h>
#include <string.h>

static const gi_param_desc desc[] = {
    {"N", GI_PARAM_INT, 32, 1, 512, NULL, "N (Sec. 4.1)", "maps per dimension"},
    {"bias", GI_PARAM_FLOAT, 0.01, 0, 1, NULL, NULL, "depth bias"},
    {"jitter", GI_PARAM_BOOL, 1, 0, 1, NULL, NULL, "jitter VPLs"},
    {"filter", GI_PARAM_ENUM, 1, 0, 0, "nearest|pcf|rr", "Sec. 4.5", "visibility filter"},
    {0},
};

static gi_params *parse(const char *a, const char *b, gi_error *err)
{
    const char *kv[2] = {a, b};
    uint32_t n = a ? (b ? 2 : 1) : 0;
    return gi_params_parse("csm", desc, kv, n, err);
}

/* A method whose create() reads a misspelt parameter ("bais" for "bias")
 * when `misspelt` is set, and counts its destroys. */
static int misspelt, destroyed;
static int instance_token;

static gi_result misspelt_create(const gi_host *host, const gi_params *params, void **out)
{
    (void)host;
    float bias = gi_params_float(params, misspelt ? "bais" : "bias");
    (void)gi_params_int(params, "N");
    *out = bias >= 0.0f ? &instance_token : NULL;
    return GI_OK;
}
static void misspelt_destroy(void *inst)
{
    destroyed += inst == &instance_token;
}

static void check_undeclared(void)
{
    gi_method m = {.id = "csm", .create = misspelt_create, .destroy = misspelt_destroy};
    gi_error err = {{0}};
    void *inst = NULL;
    gi_params *p = parse(NULL, NULL, &err);
    CHECK(p && gi_params_check(p, "csm", &err) == GI_OK);
    CHECK(gi_method_create(&m, NULL, p, &inst, &err) == GI_OK && inst == &instance_token);
    gi_params_free(p);

    misspelt = 1;
    destroyed = 0;
    p = parse(NULL, NULL, &err);
    /* the getter gives 0 for the undeclared name and keeps the first one */
    CHECK(gi_params_float(p, "bais") == 0.0f && gi_params_int(p, "nn") == 0);
    CHECK(gi_params_check(p, "csm", &err) == GI_ERR_INVALID_ARGUMENT && strstr(err.text, "'bais'"));
    gi_params_free(p);
    p = parse(NULL, NULL, &err);
    inst = NULL;
    gi_result r = gi_method_create(&m, NULL, p, &inst, &err);
    CHECK_MSG(r == GI_ERR_INVALID_ARGUMENT && inst == NULL && destroyed == 1,
              "result %d, destroyed %d", (int)r, destroyed);
    CHECK_MSG(
        strcmp(err.text,
               "method 'csm' read parameter 'bais', which its parameter table does not declare (a "
               "bug in the plugin)") == 0,
        "'%s'", err.text);
    gi_params_free(p);
}

/* Quality marks (params.h): direction and factor read back, three steps
 * rounded and clamped, an int step at least one, a malformed mark refused,
 * and a marked row still parses as before. */
static void check_quality(void)
{
    static const gi_param_desc q[] = {
        {"N", GI_PARAM_INT, 12, 1, 32, GI_QUALITY_UP(1.5), NULL, "bins"},
        {"subdiv", GI_PARAM_FLOAT, 1.0, 0.01, 100.0, GI_QUALITY_DOWN(2), NULL, "threshold"},
        {"k", GI_PARAM_INT, 1, 1, 64, GI_QUALITY_UP(1.2), NULL, "small"},
        {"bad", GI_PARAM_INT, 1, 1, 64, "quality:up:1", NULL, "factor 1"},
        {"odd", GI_PARAM_FLOAT, 1, 1, 64, "more", NULL, "no mark"},
        {"filter", GI_PARAM_ENUM, 0, 0, 0, "quality:up:2", NULL, "an enum's choices"},
        {"r", GI_PARAM_INT, 4, 1, 64, GI_QUALITY_NONE("bias grows with r"), NULL, "no converge"},
        {"r2", GI_PARAM_INT, 4, 1, 64, "quality:none:", NULL, "no reason"},
        {0},
    };
    gi_param_quality m;
    CHECK(gi_param_quality_of(&q[0], &m) == 1 && m.dir == 1 && m.factor == 1.5);
    CHECK(gi_param_quality_step(&q[0], 12, 1) == 18 && gi_param_quality_step(&q[0], 12, 2) == 27);
    CHECK(gi_param_quality_step(&q[0], 12, 3) == 32); /* 40.5 clamped to max */
    CHECK(gi_param_quality_of(&q[1], &m) == 1 && m.dir == -1 && m.factor == 2.0);
    CHECK_NEAR(gi_param_quality_step(&q[1], 1.0, 3), 0.125, 1e-12);
    CHECK(gi_param_quality_step(&q[2], 1, 3) == 4); /* 1.2 rounds to 1: one more a step */
    CHECK(gi_param_quality_of(&q[3], &m) == -1 && gi_param_quality_step(&q[3], 5, 2) == 5);
    CHECK(gi_param_quality_of(&q[4], &m) == -1);
    CHECK(gi_param_quality_of(&q[5], &m) == 0 && gi_param_quality_of(&desc[0], &m) == 0);
    CHECK(gi_param_quality_of(&q[6], &m) == 1 && m.dir == 0 &&
          !strcmp(m.reason, "bias grows with r"));
    CHECK(gi_param_quality_step(&q[6], 4, 3) == 4 && gi_param_quality_of(&q[7], &m) == -1);
    gi_error err;
    const char *kv[1] = {"N=20"};
    gi_params *p = gi_params_parse("iv", q, kv, 1, &err);
    CHECK(p && gi_params_int(p, "N") == 20);
    gi_params_free(p);
}

int main(void)
{
    check_undeclared();
    check_quality();
    gi_error err;
    gi_params *p = parse(NULL, NULL, &err);
    CHECK(p != NULL);
    CHECK(gi_params_int(p, "N") == 32);
    CHECK_NEAR(gi_params_float(p, "bias"), 0.01, 1e-7);
    CHECK(gi_params_bool(p, "jitter") == 1);
    CHECK(gi_params_enum(p, "filter") == 1);
    char *s = gi_params_to_string(p);
    /* canonical text: every parameter in table order, defaults included */
    CHECK_MSG(s && strcmp(s, "N=32,bias=0.01,jitter=true,filter=pcf") == 0, "'%s'",
              s ? s : "(null)");
    free(s);
    gi_params_free(p);

    p = parse("N=128", "filter=rr", &err);
    CHECK(p && gi_params_int(p, "N") == 128 && gi_params_enum(p, "filter") == 2);
    gi_params_free(p);
    p = parse("jitter=off", "bias=0.5", &err);
    CHECK(p && gi_params_bool(p, "jitter") == 0 && gi_params_float(p, "bias") == 0.5f);
    gi_params_free(p);

    struct {
        const char *kv, *msg;
    } bad[] = {
        {"M=3", "csm: unknown parameter 'M' (known: N, bias, jitter, filter)"},
        {"N=0", "csm: N=0 is outside [1, 512]"},
        {"N=1000", "csm: N=1000 is outside [1, 512]"},
        {"N=1.5", "csm: N='1.5' is not an integer"},
        {"bias=abc", "csm: bias='abc' is not a number"},
        {"bias=nan", "csm: bias='nan' is not a number"},
        {"jitter=maybe", "csm: jitter='maybe' is not true or false"},
        {"filter=box", "csm: filter='box' is not one of nearest|pcf|rr"},
        {"N", "csm: parameter 'N' is not name=value"},
        {"=3", "csm: parameter '=3' is not name=value"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err.text[0] = '\0';
        p = parse(bad[i].kv, NULL, &err);
        CHECK_MSG(p == NULL && strcmp(err.text, bad[i].msg) == 0, "%s -> '%s'", bad[i].kv,
                  err.text);
        gi_params_free(p);
    }
    p = parse("N=4", "N=5", &err);
    CHECK(p == NULL && strstr(err.text, "given twice"));
    CHECK(gi_param_desc_count(desc) == 4);
    /* A value is exactly its text: no blanks around it, not empty (strtol
     * and strtod would skip leading blanks and take " 5" as 5). */
    const char *blank[] = {"N= 5", "N=5 ", "N=\t5", "N=", "bias= 0.5", "bias=0.5\n", "bias="};
    for (size_t i = 0; i < sizeof blank / sizeof blank[0]; i++) {
        p = parse(blank[i], NULL, &err);
        CHECK_MSG(p == NULL && strstr(err.text, "is not"), "'%s' was taken", blank[i]);
        gi_params_free(p);
    }
    p = parse("N=5", "bias=0.5", &err);
    CHECK(p && gi_params_int(p, "N") == 5);
    gi_params_free(p);
    return gi_test_finish();
}

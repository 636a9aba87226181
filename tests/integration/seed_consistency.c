/* `gibench diff` of two references made with independent seeds must report
 * an error consistent with their variance layers: E[(a - b)^2] equals
 * var(a) + var(b) per pixel and channel (variances of the means), so the
 * MSE that diff prints, divided by the mean of var(a) + var(b), is 1 up to
 * sampling noise. Also: a reference against itself has zero error.
 *
 *   seed_consistency A.exr B.exr DIFF_AB.json DIFF_AA.json */
#include "gi/image.h"

#include <json-c/json.h>
#include <math.h>
#include <stdio.h>

static double field(const char *path, const char *key)
{
    json_object *o = json_object_from_file(path), *v;
    double x = NAN;
    if (o && json_object_object_get_ex(o, key, &v) && !json_object_is_type(v, json_type_null))
        x = json_object_get_double(v);
    json_object_put(o);
    return x;
}

int main(int argc, char **argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: seed_consistency A.exr B.exr DIFF_AB.json DIFF_AA.json\n");
        return 2;
    }
    gi_error err;
    gi_image *va = gi_image_read_layer(argv[1], "variance", &err);
    gi_image *vb = va ? gi_image_read_layer(argv[2], "variance", &err) : NULL;
    if (!va || !vb) {
        fprintf(stderr, "%s\n", err.text);
        return 1;
    }
    double sum = 0.0;
    size_t n = (size_t)va->width * va->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            sum += va->rgba[4 * i + (size_t)c] + vb->rgba[4 * i + (size_t)c];
    double expected = sum / (3.0 * (double)n);
    double mse = field(argv[3], "mse"), self_mse = field(argv[4], "mse"),
           self_flip = field(argv[4], "flip");
    double ratio = mse / expected;
    printf("diff MSE of two seeds %.6g, mean var(a)+var(b) %.6g, ratio %.3f; self MSE %g, self "
           "FLIP %g\n",
           mse, expected, ratio, self_mse, self_flip);
    gi_image_free(va);
    gi_image_free(vb);
    /* 16x16x3 values at 64 spp: the ratio's own spread is a few percent;
     * heavy-tailed pixels (light edges) widen it, so allow 0.7..1.4. */
    int ok = ratio > 0.7 && ratio < 1.4 && self_mse == 0.0 && self_flip == 0.0;
    printf("%s\n", ok ? "ok" : "FAIL");
    return ok ? 0 : 1;
}

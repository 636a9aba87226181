/* The vlf plugin's lights other than emission and sky (not in the paper)
 * against independent computations (the plugin's CPU sources are compiled
 * in; see plugins/vlf/README.md "Tests"):
 *
 *   vlf_lights_tests sun    a directional light: open floor lit by
 *                           E cos theta, an occluder's shadow where it
 *                           falls;
 *   vlf_lights_tests point  point and spot lights: inverse square law,
 *                           shadow, spot cone; a point light's reflection
 *                           in a mirror. */
#include "vlf_field.h"
#include "vlf_test_util.h"

#include "gi/lights.h"
#include "gi/scene.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Mean irradiance (channel 0) of the whole elements of face fi whose
 * centres (world x, y) lie in the box [x0, x1] x [y0, y1]; -1 if none. */
static double mean_E_in(const vlf_field *f, uint32_t fi, float x0, float x1, float y0, float y1)
{
    const vlf_face *fc = &f->faces[fi];
    double sum = 0.0;
    uint32_t n = 0;
    float texel = 1.0f / (f->prm.density * f->prm.density);
    for (uint32_t iy = 0; iy < fc->H; iy++)
        for (uint32_t ix = 0; ix < fc->W; ix++) {
            uint32_t e = fc->first_elem + iy * fc->W + ix;
            if (f->elem_area[e] < 0.99f * texel)
                continue;
            gi_vec3 q = gi_v3_add(
                fc->origin, gi_v3_add(gi_v3_scale(fc->t, ((float)ix + 0.5f) / f->prm.density),
                                      gi_v3_scale(fc->b, ((float)iy + 0.5f) / f->prm.density)));
            gi_vec3 w = gi_v3_add(f->centre, gi_v3_scale(q, f->radius));
            if (w.x < x0 || w.x > x1 || w.y < y0 || w.y > y1)
                continue;
            sum += f->E_tot[3 * (size_t)e];
            n++;
        }
    return n ? sum / n : -1.0;
}

/* Directional light: a floor (z = 0, [-1, 1]^2) under a square occluder
 * (z = 0.5, half size 0.25), a sun of irradiance 2 straight down and 30
 * degrees off: after one iteration the open floor's irradiance is within
 * 5 % of 2 cos(theta), and the floor around the shadow's centre (0, 0.5 tan
 * theta) gets under 5 % of it while the same spot mirrored (where the
 * shadow would fall were the light reversed) is lit; the always-lit and the
 * never-lit answers each fail one of these. */
static void test_sun(void)
{
    for (int k = 0; k < 2; k++) {
        float a = k ? GI_PI / 6.0f : 0.0f;
        gi_scene *s = bare_scene(4, 8, 1, 2);
        s->materials[0].albedo[0] = s->materials[0].albedo[1] = s->materials[0].albedo[2] = 0.5f;
        /* the light's node: turned by a about x, its -z pointing along (0, sin a, -cos a) */
        s->nodes[1].rotation[0] = sinf(0.5f * a);
        s->nodes[1].rotation[3] = cosf(0.5f * a);
        add_quad(s, 0, gi_v3(-1, -1, 0), gi_v3(1, -1, 0), gi_v3(1, 1, 0), gi_v3(-1, 1, 0), 0);
        /* the occluder faces the floor: a ray from the floor toward the sun
         * meets its front (the rule for sides, gi/scene.h) */
        add_quad(s, 1, gi_v3(-0.25f, -0.25f, 0.5f), gi_v3(-0.25f, 0.25f, 0.5f),
                 gi_v3(0.25f, 0.25f, 0.5f), gi_v3(0.25f, -0.25f, 0.5f), 0);
        float bounds[6] = {-1, -1, 0, 1, 1, 0.5f};
        memcpy(s->objects[0].local_bounds, bounds, sizeof bounds);
        s->light_count = 1;
        s->lights = calloc(1, sizeof *s->lights);
        s->lights[0].type = GI_LIGHT_DIRECTIONAL;
        s->lights[0].node = 1;
        s->lights[0].intensity[0] = s->lights[0].intensity[1] = s->lights[0].intensity[2] = 2.0f;
        vlf_settings p = defaults();
        p.iterations = 1;
        p.density = 16;
        vlf_field f;
        gi_error err;
        gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
        EXPECT(rc == GI_OK, "%s", err.text);
        if (rc == GI_OK) {
            vlf_field_propagate(&f, NULL, NULL, NULL);
            uint32_t floor = f.tri_face[0];
            double want = 2.0 * cos(a), ys = 0.5 * tan(a);
            double open = mean_E_in(&f, floor, 0.55f, 0.9f, -0.9f, 0.9f);
            double shadow = mean_E_in(&f, floor, -0.1f, 0.1f, (float)ys - 0.1f, (float)ys + 0.1f);
            double mirror = mean_E_in(&f, floor, -0.1f, 0.1f, (float)-ys - 0.1f, (float)-ys + 0.1f);
            printf("sun %2.0f deg: open floor E = %.4f (due %.4f), shadow centre (0, %.3f) E = "
                   "%.4f, %s E = %.4f\n",
                   a * 180.0 / GI_PI, open, want, ys, shadow,
                   k ? "the mirrored spot" : "(same spot)", mirror);
            EXPECT(fabs(open / want - 1.0) < 0.05, "sun: open floor %.4f, due %.4f", open, want);
            EXPECT(shadow >= 0.0 && shadow < 0.05 * want, "sun: the shadow gets %.4f", shadow);
            if (k)
                EXPECT(mirror > 0.9 * want, "sun: the spot opposite the shadow gets %.4f", mirror);
            EXPECT(f.sun_count == 1, "sun: %u directional lights seen", f.sun_count);
            vlf_field_free(&f);
        }
        gi_scene_free(s);
    }
}

/* Point and spot lights: the floor and occluder of test_sun, a point
 * light (intensity 3) at (0, 0, 1.5) (the occluder turned to face the
 * floor): after one iteration every whole
 * floor element outside the shadow's rim gets I h / d^3 at its centre
 * (1 %), the elements inside the shadow (|x|, |y| < 0.3; the occluder's
 * shadow reaches 0.375) nothing; a spot there pointing down (cones 0.3 and
 * 0.35 rad) the same times the glTF falloff, and nothing beyond its outer
 * cone. The unshadowed and the black answers each fail. */
static void test_point(void)
{
    for (int k = 0; k < 2; k++) {
        gi_scene *s = bare_scene(4, 8, 1, 2);
        s->materials[0].albedo[0] = s->materials[0].albedo[1] = s->materials[0].albedo[2] = 0.5f;
        s->nodes[1].translation[2] = 1.5f; /* -z of the node points down */
        add_quad(s, 0, gi_v3(-1, -1, 0), gi_v3(1, -1, 0), gi_v3(1, 1, 0), gi_v3(-1, 1, 0), 0);
        /* the occluder's front faces the floor: the shadow ray goes from the
         * floor to the light, as the reference casts it, and by the rule for
         * sides (gi/scene.h) passes through a single-sided face's back */
        add_quad(s, 1, gi_v3(-0.25f, -0.25f, 0.5f), gi_v3(-0.25f, 0.25f, 0.5f),
                 gi_v3(0.25f, 0.25f, 0.5f), gi_v3(0.25f, -0.25f, 0.5f), 0);
        for (uint32_t v = 4; v < 8; v++)
            s->vertices[v].normal[2] = -1.0f;
        float bounds[6] = {-1, -1, 0, 1, 1, 0.5f};
        memcpy(s->objects[0].local_bounds, bounds, sizeof bounds);
        s->light_count = 1;
        s->lights = calloc(1, sizeof *s->lights);
        s->lights[0].type = k ? GI_LIGHT_SPOT : GI_LIGHT_POINT;
        s->lights[0].node = 1;
        s->lights[0].inner_cone = 0.3f;
        s->lights[0].outer_cone = 0.35f;
        s->lights[0].intensity[0] = s->lights[0].intensity[1] = s->lights[0].intensity[2] = 3.0f;
        vlf_settings p = defaults();
        p.iterations = 1;
        p.density = 16;
        vlf_field f;
        gi_error err;
        gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
        EXPECT(rc == GI_OK, "%s", err.text);
        if (rc == GI_OK) {
            vlf_field_propagate(&f, NULL, NULL, NULL);
            const vlf_face *fc = &f.faces[f.tri_face[0]];
            float texel = 1.0f / (p.density * p.density);
            double worst = 0.0, shadow = 0.0, beyond = 0.0, lit = 0.0;
            uint32_t n_lit = 0, n_shadow = 0, n_beyond = 0;
            float cos_i = cosf(0.3f), cos_o = cosf(0.35f);
            for (uint32_t iy = 0; iy < fc->H; iy++)
                for (uint32_t ix = 0; ix < fc->W; ix++) {
                    uint32_t e = fc->first_elem + iy * fc->W + ix;
                    if (f.elem_area[e] < 0.99f * texel)
                        continue;
                    gi_vec3 q = gi_v3_add(
                        fc->origin, gi_v3_add(gi_v3_scale(fc->t, ((float)ix + 0.5f) / p.density),
                                              gi_v3_scale(fc->b, ((float)iy + 0.5f) / p.density)));
                    gi_vec3 w = gi_v3_add(f.centre, gi_v3_scale(q, f.radius));
                    double d2 = (double)w.x * w.x + (double)w.y * w.y + 1.5 * 1.5, d = sqrt(d2);
                    double want = 3.0 * 1.5 / (d2 * d);
                    double ca = 1.5 / d;
                    if (k)
                        want *= gi_spot_falloff((float)ca, cos_i, cos_o);
                    double got = f.E_tot[3 * (size_t)e];
                    float rim = fmaxf(fabsf(w.x), fabsf(w.y));
                    if (rim < 0.3f) {
                        shadow = fmax(shadow, got);
                        n_shadow++;
                    } else if (rim > 0.45f && want > 0.05) {
                        worst = fmax(worst, fabs(got / want - 1.0));
                        lit += got;
                        n_lit++;
                    } else if (k && ca < cos_o - 0.01) {
                        beyond = fmax(beyond, got);
                        n_beyond++;
                    }
                }
            printf("%s: %u lit elements, worst %.3f %% off I h / d^3%s; %u in the shadow, at most "
                   "%.5f; %u beyond the cone, "
                   "at most %.5f\n",
                   k ? "spot" : "point", n_lit, 100.0 * worst, k ? " x falloff" : "", n_shadow,
                   shadow, n_beyond, beyond);
            EXPECT(n_lit > (k ? 8u : 100u) && n_shadow > 20,
                   "point: too few elements lit (%u) or shadowed (%u)", n_lit, n_shadow);
            EXPECT(worst < 0.01, "point: lit floor off the inverse square law by %.3g", worst);
            EXPECT(shadow < 1e-3, "point: the shadow gets %.4g", shadow);
            if (k)
                EXPECT(n_beyond > 50 && beyond < 1e-4,
                       "spot: %u elements beyond the cone get up to %.4g", n_beyond, beyond);
            vlf_field_free(&f);
        }
        gi_scene_free(s);
    }
}

/* A point light's reflection by a mirror (the first shot into non-diffuse
 * tiles): the tilted mirror of test_mirror (ks 0.8, 0.6 wide) under a
 * point light (3 W/sr) at (0, 0, 1): the flux the tiles send out (sum of
 * L x cell area x dOmega over every direction and covered cell) is within
 * 5 % of ks times the flux the light brings onto the mirror (I cos / d^2
 * integrated over it), the most of it goes out along one of the three
 * directions around the centre's reflection (sin 45, 0, cos 45), and none
 * along a direction more than 1 rad from it. */
static void test_point_mirror(void)
{
    gi_scene *s = bare_scene(2, 4, 1, 2);
    s->materials[0].ks[0] = s->materials[0].ks[1] = s->materials[0].ks[2] = 0.8f;
    s->materials[0].mirror = 1;
    s->materials[0].exponent = GI_MIRROR_EXPONENT;
    s->nodes[1].translation[2] = 1.0f;
    float c = cosf(GI_PI / 8), sn = sinf(GI_PI / 8);
    gi_vec3 tx = gi_v3(c, 0, -sn), ty = gi_v3(0, 1, 0);
    gi_vec3 P[4];
    float uv[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++)
        P[k] = gi_v3_add(gi_v3_scale(tx, 0.3f * uv[k][0]), gi_v3_scale(ty, 0.3f * uv[k][1]));
    add_quad(s, 0, P[0], P[1], P[2], P[3], 0);
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t v = 0; v < 4; v++)
        for (int a = 0; a < 3; a++)
            lo[a] = fminf(lo[a], s->vertices[v].position[a]),
            hi[a] = fmaxf(hi[a], s->vertices[v].position[a]);
    for (int a = 0; a < 3; a++)
        s->objects[0].local_bounds[a] = lo[a], s->objects[0].local_bounds[3 + a] = hi[a];
    s->light_count = 1;
    s->lights = calloc(1, sizeof *s->lights);
    s->lights[0].type = GI_LIGHT_POINT;
    s->lights[0].node = 1;
    s->lights[0].intensity[0] = s->lights[0].intensity[1] = s->lights[0].intensity[2] = 3.0f;
    vlf_settings p = defaults();
    p.iterations = 1;
    vlf_field f;
    gi_error err;
    gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
    EXPECT(rc == GI_OK, "%s", err.text);
    if (rc == GI_OK) {
        vlf_field_propagate(&f, NULL, NULL, NULL);
        const vlf_face *fc = &f.faces[0];
        gi_vec3 refl = gi_v3_normalize(gi_v3(1, 0, 1));
        uint32_t node[3];
        float al[3];
        vlf_dirs_locate(&f.dirs, refl, node, al);
        /* the light's flux onto the mirror, world units: I cos / d^2 over it */
        double in = 0.0;
        gi_vec3 nrm = gi_v3(sn, 0, c);
        for (int a = 0; a < 200; a++)
            for (int b = 0; b < 200; b++) {
                gi_vec3 x = gi_v3_add(gi_v3_scale(tx, 0.3f * (((float)a + 0.5f) / 100.0f - 1.0f)),
                                      gi_v3_scale(ty, 0.3f * (((float)b + 0.5f) / 100.0f - 1.0f)));
                gi_vec3 d = gi_v3_sub(gi_v3(0, 0, 1), x);
                float d2 = gi_v3_dot(d, d);
                in += 3.0 * gi_v3_dot(nrm, gi_v3_normalize(d)) / d2 * (0.6 / 200.0) * (0.6 / 200.0);
            }
        double out = 0.0, best = 0.0, far = 0.0;
        uint32_t best_sd = UINT32_MAX;
        double cell = (2.0 / p.N) * (2.0 / p.N) * (double)f.radius * f.radius;
        for (uint32_t sd = 0; sd < 2 * p.l; sd++) {
            gi_vec3 w = f.dirs.signed_dirs[sd];
            if (gi_v3_dot(w, fc->n) <= 0.0f)
                continue;
            const vlf_rect *r = &f.rects[(size_t)fc->nd * p.l + sd % p.l];
            double sum = 0.0;
            for (uint32_t k = 0; k < r->w * r->h; k++)
                if (f.nd_cover[r->offset + k])
                    sum += f.out_tot[3 * (size_t)(r->offset + k)];
            double flux = sum * cell * f.dirs.solid_angle[sd];
            out += flux;
            if (flux > best)
                best = flux, best_sd = sd;
            if (acosf(fminf(1.0f, gi_v3_dot(w, refl))) > 1.0f)
                far = fmax(far, flux);
        }
        int near = best_sd == node[0] || best_sd == node[1] || best_sd == node[2];
        printf("point light in a mirror: flux out of the tiles %.4f, ks x flux onto the mirror "
               "%.4f (%+.2f %%); the "
               "largest share (%.0f %%) along %s of the reflection's three directions; at most "
               "%.2g beyond 1 rad\n",
               out, 0.8 * in, 100.0 * (out / (0.8 * in) - 1.0), 100.0 * best / (out > 0 ? out : 1),
               near ? "one" : "none", far);
        EXPECT(fabs(out / (0.8 * in) - 1.0) < 0.05, "point light in a mirror: out %.4f, due %.4f",
               out, 0.8 * in);
        EXPECT(near,
               "point light in a mirror: the most light leaves along direction %u, not around the "
               "reflection",
               best_sd);
        EXPECT(far < 1e-6 * out, "point light in a mirror: %.4g away from the reflection", far);
        vlf_field_free(&f);
    }
    gi_scene_free(s);
}

/* Point and spot lights on a floor, then a point light in a mirror. */
static void test_point_lights(void)
{
    test_point();
    test_point_mirror();
}

int main(int argc, char **argv)
{
    static const vlf_test_part parts[] = {{"sun", test_sun}, {"point", test_point_lights}};
    return vlf_test_main("vlf_lights_tests", parts, sizeof parts / sizeof parts[0], argc, argv);
}

/* The vlf plugin's propagation (paper §3.2-§3.5) against independent
 * computations (the plugin's CPU sources are compiled in; see
 * plugins/vlf/README.md "Tests"):
 *
 *   vlf_transport_tests energy   closed box: per iteration everything shot
 *                                is received (nothing escapes, nothing lands
 *                                on a back face), and the emitted flux
 *                                equals the first iteration's shot;
 *                                perturbed directions sorted beside the
 *                                sweeps give the same field on 1, 2 and 5
 *                                threads;
 *   vlf_transport_tests furnace  the closed emitting sphere (conformance
 *                                scene): the mean irradiance of the
 *                                propagated field converges to
 *                                Le (1/(1 - rho) - 1) pi within 2 % as
 *                                iterations grow;
 *   vlf_transport_tests mirror   a mirror facing an emitter: the mirror's
 *                                stored radiance in the subfields around
 *                                the reflected direction shows the emitter
 *                                (ks Le), and nothing where the reflection
 *                                misses it;
 *   vlf_transport_tests albedo   the glossy lobe's albedo over incidence
 *                                (its grazing fall-off) against Monte Carlo
 *                                of core brdf.h's lobe;
 *   vlf_transport_tests texture  a textured floor: each element's albedo
 *                                averages the texture over it, and
 *                                propagation shoots with it;
 *   vlf_transport_tests double   a double-sided panel lit from its back:
 *                                the lit side's irradiance against the
 *                                light's integral, nothing through the
 *                                panel, the per-ray sort and perturbed
 *                                directions agree; single-sided, the same
 *                                light crosses it (its back does not exist);
 *   vlf_transport_tests sides    the inward single-sided ball of
 *                                tests/data/truth/sphere_in_ss.gltf: the
 *                                lamp's light crosses its upper half and
 *                                lights the inside of its lower half. */
#include "vlf_field.h"
#include "vlf_test_util.h"

#include "gi/brdf.h"
#include "gi/scene.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void test_energy(void)
{
    gi_scene *s = load("tests/data/conformance/furnace_050.gltf");
    if (!s)
        return;
    vlf_settings p = defaults();
    p.l = 64;
    p.N = 48;
    p.density = 6;
    p.iterations = 1;
    if (getenv("VLF_N"))
        p.N = (uint32_t)atoi(getenv("VLF_N"));
    vlf_field f;
    gi_error err;
    EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
    vlf_field_propagate(&f, NULL, NULL, NULL);
    const vlf_stats *st = &f.st;
    printf("energy (closed sphere, 1 iteration): emitted %.6f shot %.6f received %.6f back %.6f "
           "escaped %.6f\n",
           st->flux_emitted, st->flux_shot, st->flux_received, st->flux_back, st->flux_escaped);
    /* The rule for sides from the receiver's side (propagate.c): every
     * packet ends at a back or escapes; inside the inward-wound sphere each
     * reaches the far wall once, which takes it and lets it go on (a point
     * outside sees the inside through the walls' backs). */
    CHECK_NEAR(st->flux_shot, st->flux_back + st->flux_escaped, 1e-4 * st->flux_shot);
    EXPECT(fabs(st->flux_received / st->flux_shot - 1.0) < 1e-3,
           "the far wall received %.4g of %.4g shot", st->flux_received, st->flux_shot);
    EXPECT(st->flux_back < 1e-3 * st->flux_shot, "light met back faces in a closed sphere: %.4g",
           st->flux_back);
    /* what is shot in the first iteration is the emission, within the
     * aliasing of the faces' projections onto the rays */
    EXPECT(fabs(st->flux_shot / st->flux_emitted - 1.0) < 0.02, "shot %.5g vs emitted %.5g",
           st->flux_shot, st->flux_emitted);
    /* received = sum of E * area over elements */
    double absorbed = 0.0;
    for (uint32_t e = 0; e < f.elem_count; e++)
        absorbed +=
            (f.E_tot[3 * e] + f.E_tot[3 * e + 1] + f.E_tot[3 * e + 2]) / 3.0 * f.elem_area[e];
    EXPECT(fabs(absorbed / st->flux_received - 1.0) < 0.02,
           "irradiance x area %.5g vs received %.5g", absorbed, st->flux_received);
    vlf_field_free(&f);
    /* the same with every triangle cut into 4 (the tessellation sweep's option) */
    p.subdivide = 2;
    EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
    vlf_field_propagate(&f, NULL, NULL, NULL);
    printf("energy, triangles cut into 4 (%u triangles): emitted %.6f shot %.6f received %.6f back "
           "%.6f escaped %.6f\n",
           f.tri_count, st->flux_emitted, st->flux_shot, st->flux_received, st->flux_back,
           st->flux_escaped);
    CHECK_NEAR(st->flux_shot, st->flux_back + st->flux_escaped, 1e-4 * st->flux_shot);
    EXPECT(fabs(st->flux_received / st->flux_shot - 1.0) < 1e-3 &&
               st->flux_back < 1e-3 * st->flux_shot,
           "subdivided: received %.4g of %.4g shot, %.4g met back faces", st->flux_received,
           st->flux_shot, st->flux_back);
    EXPECT(fabs(st->flux_shot / st->flux_emitted - 1.0) < 0.02,
           "subdivided: shot %.5g vs emitted %.5g", st->flux_shot, st->flux_emitted);
    vlf_field_free(&f);
    p.subdivide = 1;
    /* the same with 3 perturbed directions per fixed one (§3.5) */
    p.perturbed = 3;
    EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
    vlf_field_propagate(&f, NULL, NULL, NULL);
    printf("energy, 3 perturbed directions: emitted %.6f shot %.6f received %.6f back %.6f escaped "
           "%.6f\n",
           st->flux_emitted, st->flux_shot, st->flux_received, st->flux_back, st->flux_escaped);
    CHECK_NEAR(st->flux_shot, st->flux_back + st->flux_escaped, 1e-4 * st->flux_shot);
    EXPECT(fabs(st->flux_received / st->flux_shot - 1.0) < 1e-3 &&
               st->flux_back < 1e-3 * st->flux_shot,
           "perturbed: received %.4g of %.4g shot, %.4g met back faces", st->flux_received,
           st->flux_shot, st->flux_back);
    EXPECT(fabs(st->flux_shot / st->flux_emitted - 1.0) < 0.02,
           "perturbed: shot %.5g vs emitted %.5g", st->flux_shot, st->flux_emitted);
    /* the perturbed lists sorted beside the sweeps on 2 threads (above) or
     * in line on 1, or on 5: the same field, bit for bit */
    uint32_t tc[2] = {1, 5};
    for (int k = 0; k < 2; k++) {
        vlf_settings q = p;
        q.threads = tc[k];
        vlf_field g;
        EXPECT(vlf_field_build(&g, s, 0.0f, &q, &err) == GI_OK, "%s", err.text);
        vlf_field_propagate(&g, NULL, NULL, NULL);
        int same = g.elem_count == f.elem_count &&
                   memcmp(g.E_tot, f.E_tot, (size_t)f.elem_count * 3 * sizeof *f.E_tot) == 0 &&
                   g.st.flux_shot == f.st.flux_shot && g.st.samples == f.st.samples;
        EXPECT(same, "perturbed propagation on %u threads differs from 2 threads", tc[k]);
        vlf_field_free(&g);
    }
    vlf_field_free(&f);
    gi_scene_free(s);
}

static void test_furnace(void)
{
    const char *files[] = {"tests/data/conformance/furnace_050.gltf",
                           "tests/data/conformance/furnace_080.gltf"};
    const double rho[] = {0.5, 0.8};
    for (int k = 0; k < 2; k++) {
        gi_scene *s = load(files[k]);
        if (!s)
            return;
        uint32_t its[] = {1, 8, 16};
        for (int q = 0; q < 3; q++) {
            vlf_settings p = defaults();
            if (!getenv("VLF_FULL"))
                p.l = 64, p.N = 48, p.density = 6;
            p.iterations = its[q];
            vlf_field f;
            gi_error err;
            EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
            vlf_field_propagate(&f, NULL, NULL, NULL);
            /* radiance of the surface = Le + rho E / pi, area-weighted mean */
            double num = 0.0, den = 0.0;
            for (uint32_t e = 0; e < f.elem_count; e++) {
                const vlf_face *fc = &f.faces[f.elem_face[e]];
                double L = fc->emission[0] + fc->kd[0] * f.E_tot[3 * e] / GI_PI;
                num += L * f.elem_area[e];
                den += f.elem_area[e];
            }
            double got = num / den, Le = f.faces[0].emission[0];
            double want = 0.0;
            for (uint32_t b = 0; b <= its[q]; b++)
                want += Le * pow(rho[k], b);
            printf("furnace rho=%.1f iterations %2u: mean radiance %.5f, due Le sum_{k<=%u} rho^k "
                   "= %.5f (limit %.5f)\n",
                   rho[k], its[q], got, its[q], want, Le / (1.0 - rho[k]));
            EXPECT(fabs(got / want - 1.0) < 0.02, "furnace %.4f vs %.4f", got, want);
            vlf_field_free(&f);
        }
        gi_scene_free(s);
    }
}

/* Two quads: an emitter of radiance 1 at height 1 facing down, and below
 * it a mirror (ks 0.8) tilted so that the emitter's light leaves it
 * toward +x. */
static void test_mirror(void)
{
    gi_scene *s = bare_scene(4, 8, 2, 1);
    s->materials[0].emission[0] = s->materials[0].emission[1] = s->materials[0].emission[2] = 1.0f;
    s->materials[1].ks[0] = s->materials[1].ks[1] = s->materials[1].ks[2] = 0.8f;
    s->materials[1].mirror = 1;
    s->materials[1].exponent = GI_MIRROR_EXPONENT;
    /* emitter at z = 1, normal -z (clockwise seen from above) */
    add_quad(s, 0, gi_v3(-0.3f, -0.3f, 1.0f), gi_v3(-0.3f, 0.3f, 1.0f), gi_v3(0.3f, 0.3f, 1.0f),
             gi_v3(0.3f, -0.3f, 1.0f), 0);
    /* mirror around the origin, normal (sin 22.5, 0, cos 22.5): light coming
     * down (-z) leaves along (sin 45, 0, cos 45) */
    float c = cosf(GI_PI / 8), sn = sinf(GI_PI / 8);
    gi_vec3 tx = gi_v3(c, 0, -sn), ty = gi_v3(0, 1, 0);
    gi_vec3 P[4];
    float uv[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++)
        P[k] = gi_v3_add(gi_v3_scale(tx, 0.3f * uv[k][0]), gi_v3_scale(ty, 0.3f * uv[k][1]));
    add_quad(s, 1, P[0], P[1], P[2], P[3], 1);
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t v = 0; v < 8; v++)
        for (int a = 0; a < 3; a++)
            lo[a] = fminf(lo[a], s->vertices[v].position[a]),
            hi[a] = fmaxf(hi[a], s->vertices[v].position[a]);
    for (int a = 0; a < 3; a++)
        s->objects[0].local_bounds[a] = lo[a], s->objects[0].local_bounds[3 + a] = hi[a];
    vlf_settings p = defaults();
    p.iterations = 2;
    vlf_field f;
    gi_error err;
    gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
    EXPECT(rc == GI_OK, "%s", err.text);
    if (rc == GI_OK) {
        vlf_field_propagate(&f, NULL, NULL, NULL);
        int mf = -1;
        for (uint32_t fi = 0; fi < f.face_count; fi++)
            if (f.faces[fi].nd >= 0)
                mf = (int)fi;
        EXPECT(mf >= 0, "no non-diffuse face");
        gi_vec3 refl = gi_v3_normalize(gi_v3(1, 0, 1));
        /* mean stored radiance of the mirror along each signed direction */
        double best_hit = 0.0, far = 0.0;
        float best_ang = 10.0f;
        for (uint32_t sd = 0; mf >= 0 && sd < 2 * p.l; sd++) {
            gi_vec3 w = f.dirs.signed_dirs[sd];
            uint32_t i = sd % p.l;
            if (gi_v3_dot(w, f.faces[mf].n) <= 0.0f)
                continue;
            const vlf_rect *r = &f.rects[(size_t)f.faces[mf].nd * p.l + i];
            double sum = 0.0;
            uint32_t n = 0;
            for (uint32_t k = 0; k < r->w * r->h; k++)
                if (f.nd_cover[r->offset + k])
                    sum += f.out_tot[3 * (size_t)(r->offset + k)], n++;
            double mean = n ? sum / n : 0.0;
            float ang = acosf(fminf(1.0f, gi_v3_dot(w, refl)));
            if (ang < best_ang)
                best_ang = ang, best_hit = mean;
            if (ang > 1.0f)
                far = fmax(far, mean);
        }
        /* the mirror's radiance toward the reflected direction shows the
         * emitter through it: most of ks Le = 0.8 at the direction nearest
         * the reflection (barycentric weights and the emitter's edges take
         * some), and nothing far from it */
        printf("mirror: stored radiance %.3f at the direction nearest the reflection (%.3f rad "
               "from it; ks Le = 0.8), "
               "at most %.4f beyond 1 rad from it (the emitter subtends up to 0.54 rad seen from "
               "the mirror)\n",
               best_hit, best_ang, far);
        EXPECT(best_hit > 0.3 && best_hit < 0.85, "mirror radiance toward the reflection %.3f",
               best_hit);
        EXPECT(far < 0.01, "mirror radiance away from the reflection %.4f", far);
        vlf_field_free(&f);
    }
    gi_scene_free(s);
}

/* The glossy lobe's grazing fall-off: vlf_phong_albedo (a quadrature)
 * against a Monte Carlo estimate of core brdf.h's lobe (gi_brdf_eval, wi
 * drawn from the lobe, 200 000 samples) for n = 10 and 50 at incidence
 * 0, 60, 80 and 88 degrees: within 0.01; 1 at normal incidence (1e-3);
 * the answer without fall-off (1 everywhere) misses at 80 degrees by more
 * than 0.1. */
static void test_albedo(void)
{
    const float ns[2] = {10.0f, 50.0f}, deg[4] = {0.0f, 60.0f, 80.0f, 88.0f};
    uint32_t seed = 31u;
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 4; b++) {
            float th = deg[b] * GI_PI / 180.0f;
            gi_vec3 N = gi_v3(0, 0, 1), wo = gi_v3(sinf(th), 0.0f, cosf(th));
            gi_brdf br = {{0, 0, 0}, {1, 1, 1}, ns[a], 0};
            gi_vec3 r = gi_reflect(wo, N);
            double sum = 0.0;
            const int M = 200000;
            for (int k = 0; k < M; k++) {
                gi_vec3 wi = gi_phong_lobe_sample(r, ns[a], frand(&seed), frand(&seed));
                float fv[3];
                gi_brdf_eval(&br, N, wo, wi, fv);
                float pdf = gi_phong_lobe_pdf(r, ns[a], wi);
                if (pdf > 0.0f)
                    sum += fv[0] * fmax(0.0, gi_v3_dot(N, wi)) / pdf;
            }
            double mc = sum / M, q = vlf_phong_albedo(ns[a], cosf(th));
            printf("albedo n = %2.0f, %2.0f deg: quadrature %.4f, Monte Carlo %.4f\n", ns[a],
                   deg[b], q, mc);
            EXPECT(fabs(q - mc) < 0.01, "n %g at %g deg: quadrature %.4f, Monte Carlo %.4f", ns[a],
                   deg[b], q, mc);
            if (b == 0)
                EXPECT(fabs(q - 1.0) < 1e-3, "albedo at normal incidence %.5f", q);
            if (b == 2 && a == 0)
                EXPECT(fabs(1.0 - mc) > 0.1,
                       "no fall-off at 80 deg (%.4f): the test proves nothing", mc);
        }
}

/* Textured albedo in propagation: a floor (albedo 0.8 x a texture of 8 x 1
 * texels, the left four black, the right four white) under an emitting
 * square facing down, 1 iteration: each floor element's albedo is the
 * texture averaged over it (0 on the black half, 0.8 on the white half,
 * where the bilinear texture is constant), the radiance it shoots on is
 * albedo x E / pi there (1e-5), and the area-weighted mean albedo of the
 * floor is within 2 % of 0.8 x the texture's mean over it; the answer
 * without the texture (0.8 everywhere) fails the black half. */
static void test_texture(void)
{
    /* floor z = 0 over [-1, 1]^2 facing +z; emitter z = 1 over [-0.5, 0.5]^2 facing -z */
    const float tri[4 * 9] = {-1,   -1,    0, 1,     -1,    0, 1,     1,     0, -1,   -1,   0,
                              1,    1,     0, -1,    1,     0, -0.5f, -0.5f, 1, 0.5f, 0.5f, 1,
                              0.5f, -0.5f, 1, -0.5f, -0.5f, 1, -0.5f, 0.5f,  1, 0.5f, 0.5f, 1};
    gi_scene *s = triangle_scene(tri, 4);
    gi_material *m = calloc(2, sizeof *m);
    m[0] = s->materials[0];
    m[0].albedo[0] = m[0].albedo[1] = m[0].albedo[2] = 0.8f;
    m[0].albedo_texture = 0;
    m[1].albedo_texture = -1;
    m[1].emission[0] = m[1].emission[1] = m[1].emission[2] = 1.0f;
    free(s->materials);
    s->materials = m;
    s->material_count = 2;
    gi_texture tex = {NULL, 8, 1, calloc(8 * 4, sizeof(float))};
    for (int i = 4; i < 8; i++)
        for (int c = 0; c < 4; c++)
            tex.rgba[4 * i + c] = 1.0f;
    s->textures = &tex;
    s->texture_count = 1;
    for (uint32_t k = 0; k < 12; k++) {
        gi_vertex *v = &s->vertices[k];
        v->material = k < 6 ? 0 : 1;
        v->uv[0] = 0.5f * (v->position[0] + 1.0f);
        v->uv[1] = 0.5f * (v->position[1] + 1.0f);
    }
    vlf_settings p = defaults();
    p.l = 32, p.N = 32, p.density = 8, p.iterations = 1;
    vlf_field f;
    gi_error err;
    int ok = vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    if (ok) {
        vlf_field_propagate(&f, NULL, NULL, NULL);
        uint32_t nb = 0, nw = 0, bad = 0;
        double akd = 0.0, area = 0.0, worst = 0.0;
        for (uint32_t e = 0; e < f.elem_count; e++) {
            const vlf_face *fc = &f.faces[f.elem_face[e]];
            if (fc->emission[0] > 0.0f || !(f.elem_area[e] > 0.0f))
                continue;
            gi_vec3 q = gi_v3_add(fc->origin,
                                  gi_v3_add(gi_v3_scale(fc->t, f.elem_c[2 * e] / p.density),
                                            gi_v3_scale(fc->b, f.elem_c[2 * e + 1] / p.density)));
            float x = f.centre.x + f.radius * q.x;
            float half = 0.5f / (p.density / f.radius) + 1e-3f; /* half an element, world units */
            float kd = f.elem_kd[3 * e];
            akd += kd * f.elem_area[e], area += f.elem_area[e];
            float want = -1.0f;
            if (x + half < -0.125f && x - half > -0.875f)
                want = 0.0f, nb++;
            else if (x - half > 0.125f && x + half < 0.875f)
                want = 0.8f, nw++;
            if (want < 0.0f)
                continue;
            double shot = f.L_cur[3 * e], due = want * f.E_tot[3 * e] * GI_INV_PI;
            worst = fmax(worst, fabs(shot - due));
            if (fabsf(kd - want) > 1e-4f)
                bad++;
        }
        /* the texture's mean over the floor: u = (x + 1) / 2 over [0, 1] (clamped bilinear or
         * wrapped, the two halves are symmetric): 0.5 */
        double mean = area > 0.0 ? akd / area : 0.0;
        printf("texture: %u elements on the black half, %u on the white, %u with the wrong albedo; "
               "shot radiance off "
               "by at most %.2e; mean albedo %.4f (due 0.8 x 0.5 = 0.4)\n",
               nb, nw, bad, worst, mean);
        EXPECT(nb > 4 && nw > 4,
               "too few elements inside the halves (%u, %u): the test set-up is wrong", nb, nw);
        EXPECT(bad == 0, "%u elements with the wrong albedo", bad);
        EXPECT(worst < 1e-5, "shot radiance differs from albedo E / pi by %.3g", worst);
        EXPECT(fabs(mean - 0.4) < 0.008, "mean albedo %.4f, due 0.4", mean);
        vlf_field_free(&f);
    }
    s->textures = NULL;
    s->texture_count = 0;
    free(tex.rgba);
    gi_scene_free(s);
}

/* Irradiance at world point x on a surface of unit normal n from the
 * panel scene's light (plugins/vlf/data/gen_scenes.py: a 0.5 x 0.5 square at
 * (0, 1.3, 1) facing the panel's centre, Le = 6), by 32 x 32 point patches
 * with both cosines; nothing stands between them. */
static double panel_light_E(gi_vec3 x, gi_vec3 n)
{
    gi_vec3 c = gi_v3(0.0f, 1.3f, 1.0f), ln = gi_v3_normalize(gi_v3(0.0f, -1.3f, -1.0f));
    gi_vec3 e1 = gi_v3(1, 0, 0), e2 = gi_v3_cross(ln, e1);
    double E = 0.0, dA = 0.25 / (32.0 * 32.0);
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 32; i++) {
            float u = ((float)i + 0.5f) / 32.0f - 0.5f, v = ((float)j + 0.5f) / 32.0f - 0.5f;
            gi_vec3 y =
                gi_v3_add(c, gi_v3_add(gi_v3_scale(e1, 0.5f * u), gi_v3_scale(e2, 0.5f * v)));
            gi_vec3 d = gi_v3_sub(y, x);
            double r2 = gi_v3_dot(d, d), r = sqrt(r2);
            double cx = gi_v3_dot(n, d) / r, cy = -gi_v3_dot(ln, d) / r;
            if (cx > 0.0 && cy > 0.0)
                E += 6.0 * cx * cy * dA / r2;
        }
    return E;
}

/* The single-sided panel (faces lit and dark of field f): only the dark
 * side exists. The light meets its back: it receives nothing (glTF
 * doubleSided = false), but a ray from a point behind it back toward the
 * light meets its front (the rule of gi/scene.h as the reference casts it),
 * so the light the double-sided panel's lit side received (recv_double)
 * stops there: it casts its shadow. */
static void check_single_sided(const vlf_field *f, int lit, int dark, double recv_double)
{
    const vlf_stats *st = &f->st;
    EXPECT(lit < 0 && dark >= 0 && f->faces[dark].twin < 0, "single-sided panel: faces %d / %d",
           lit, dark);
    printf("double: single-sided panel: flux shot %.4f, received %.4f, crossed a back side %.4f "
           "(double-sided received %.4f), escaped %.4f\n",
           st->flux_shot, st->flux_received, st->flux_back, recv_double, st->flux_escaped);
    EXPECT(st->flux_received < 1e-3 * st->flux_back, "single-sided: received %.4g, back %.4g",
           st->flux_received, st->flux_back);
    EXPECT(fabs(st->flux_back - recv_double) < 0.02 * recv_double,
           "single-sided back %.4g, double-sided received %.4g", st->flux_back, recv_double);
    EXPECT(fabs(st->flux_escaped - (st->flux_shot - st->flux_back)) < 1e-3 * st->flux_shot,
           "single-sided panel: escaped %.4g of %.4g shot, %.4g stopped at its back",
           st->flux_escaped, st->flux_shot, st->flux_back);
}

/* The double-sided panel's sides (faces lit and dark of field f, built
 * with settings p): each other's twin; the lit side's irradiance against
 * the light's, nothing on the dark side, nothing met a back side. */
static void check_double_sided(const vlf_field *f, const vlf_settings *p, int lit, int dark)
{
    const vlf_stats *st = &f->st;
    const vlf_face *fl = &f->faces[lit], *fd = &f->faces[dark];
    EXPECT(fl->twin == dark && fd->twin == lit && fl->back != fd->back && fl->W == fd->W &&
               fl->H == fd->H,
           "the two sides are not each other's twin");
    /* lit side: the mean irradiance of its upper and lower halves (3x apart)
     * (whole elements) each within 5 % of the light's irradiance at
     * their centres (single elements alias: the small light is seen
     * through a few directions only); dark side: nothing (no light
     * through the panel) */
    double sum[2] = {0, 0}, sum_ref[2] = {0, 0}, dark_max = 0.0;
    uint32_t n = 0;
    float texel = 1.0f / (p->density * p->density);
    for (uint32_t e = 0; e < fl->W * fl->H; e++) {
        uint32_t el = fl->first_elem + e, ed = fd->first_elem + e;
        EXPECT(f->elem_area[el] == f->elem_area[ed], "element areas of the two sides differ");
        dark_max = fmax(dark_max, f->E_tot[3 * (size_t)ed]);
        if (f->elem_area[el] < 0.99f * texel)
            continue;
        gi_vec3 q = gi_v3_add(
            fl->origin, gi_v3_add(gi_v3_scale(fl->t, f->elem_c[2 * (size_t)el] / p->density),
                                  gi_v3_scale(fl->b, f->elem_c[2 * (size_t)el + 1] / p->density)));
        gi_vec3 x = gi_v3_add(f->centre, gi_v3_scale(q, f->radius));
        int h = x.y > 0.0f;
        sum[h] += f->E_tot[3 * (size_t)el];
        sum_ref[h] += panel_light_E(x, fl->n);
        n++;
    }
    printf("double (order %s, perturbed %u): lit side %u whole elements, irradiance lower "
           "half %.4f vs %.4f "
           "(%+.2f %%), upper %.4f vs %.4f (%+.2f %%); dark side max E %.3g; flux received "
           "%.4f, back %.4g\n",
           p->order == VLF_ORDER_RAYS ? "rays" : "faces", p->perturbed, n, sum[0], sum_ref[0],
           100.0 * (sum[0] / sum_ref[0] - 1.0), sum[1], sum_ref[1],
           100.0 * (sum[1] / sum_ref[1] - 1.0), dark_max, st->flux_received, st->flux_back);
    EXPECT(n > 100, "only %u whole elements on the lit side", n);
    for (int h = 0; h < 2; h++)
        EXPECT(fabs(sum[h] / sum_ref[h] - 1.0) < 0.05, "lit side half %d: irradiance %.4f vs %.4f",
               h, sum[h], sum_ref[h]);
    EXPECT(dark_max == 0.0, "light through the panel: %.3g on its dark side", dark_max);
    /* the lit side takes the light and lets it go on; its twin, met on
     * its back, stops it (propagate.c) */
    EXPECT(fabs(st->flux_back / st->flux_received - 1.0) < 0.01,
           "the dark side stopped %.4g of the %.4g the lit side took", st->flux_back,
           st->flux_received);
}

/* Irradiance at world point x (unit normal n) from sphere_in_ss.gltf's
 * lamp (tests/data/truth/gen_truth.py: 0.8 x 0.8 at height 2 facing down,
 * Le = 8) by 32 x 32 point patches with both cosines, unoccluded. */
static double ball_lamp_E(gi_vec3 x, gi_vec3 n)
{
    double E = 0.0, dA = 0.64 / (32.0 * 32.0);
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 32; i++) {
            gi_vec3 y = gi_v3(0.8f * (((float)i + 0.5f) / 32.0f - 0.5f), 2.0f,
                              0.8f * (((float)j + 0.5f) / 32.0f - 0.5f));
            gi_vec3 d = gi_v3_sub(y, x);
            double r2 = gi_v3_dot(d, d), r = sqrt(r2);
            double cx = gi_v3_dot(n, d) / r, cy = d.y / r;
            if (cx > 0.0 && cy > 0.0)
                E += 8.0 * cx * cy * dA / r2;
        }
    return E;
}

/* The one rule for sides (gi/scene.h, glTF doubleSided = false): a
 * single-sided face seen from its back does not exist for any ray. The
 * inward-wound ball of tests/data/truth/sphere_in_ss.gltf under a lamp: a
 * ray from the inside of its lower half (fronts facing up) toward the lamp
 * meets the upper half's front (it faces down, into the ball), so, as in
 * the reference, no direct light lands there, 1 iteration: the irradiance
 * against the lamp's unoccluded one (the light-side sweep of the first
 * issue 28 change let 98.5 % of it through). */
static void test_sides(void)
{
    gi_scene *s = load("tests/data/truth/sphere_in_ss.gltf");
    if (!s)
        return;
    vlf_settings p = defaults();
    p.iterations = 1;
    p.density = 24;
    vlf_field f;
    gi_error err;
    gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
    EXPECT(rc == GI_OK, "%s", err.text);
    if (rc == GI_OK) {
        vlf_field_propagate(&f, NULL, NULL, NULL);
        double got = 0.0, want = 0.0;
        uint32_t n = 0;
        for (uint32_t e = 0; e < f.elem_count; e++) {
            const vlf_face *fc = &f.faces[f.elem_face[e]];
            if (fabsf(fc->kd[0] - 0.7f) > 1e-3f || fc->n.y < 0.5f)
                continue; /* the ball's lower half, inside */
            gi_vec3 q = gi_v3_add(
                fc->origin, gi_v3_add(gi_v3_scale(fc->t, f.elem_c[2 * (size_t)e] / p.density),
                                      gi_v3_scale(fc->b, f.elem_c[2 * (size_t)e + 1] / p.density)));
            gi_vec3 x = gi_v3_add(f.centre, gi_v3_scale(q, f.radius));
            got += f.E_tot[3 * (size_t)e] * f.elem_area[e];
            want += ball_lamp_E(x, fc->n) * f.elem_area[e];
            n++;
        }
        printf("sides: inward single-sided ball, inside of its lower half (%u elements): "
               "irradiance x area %.5f, the lamp's unoccluded %.5f (%+.1f %%); "
               "flux across back sides %.4f\n",
               n, got, want, want > 0.0 ? 100.0 * (got / want - 1.0) : 0.0, f.st.flux_back);
        EXPECT(n > 20 && want > 0.0, "ball's lower half: %u elements", n);
        EXPECT(got < 0.01 * want, "inside of the ball: %.4g (unoccluded %.4g)", got, want);
        vlf_field_free(&f);
    }
    gi_scene_free(s);
}

/* Field f (order rays) against the irradiance E_faces of order faces. */
static void check_against_faces(const vlf_field *f, const float *E_faces)
{
    /* the per-ray sort keeps the two sides' fragments in the same order */
    double d = 0.0, tot = 0.0;
    for (size_t k = 0; k < (size_t)f->elem_count * 3; k++)
        d += fabs(f->E_tot[k] - E_faces[k]), tot += fabs(E_faces[k]);
    printf("double: order rays against faces: relative L1 %.3g\n", d / tot);
    EXPECT(d <= 1e-6 * tot, "order rays differs from faces: relative L1 %.3g", d / tot);
}

/* Double-sided materials (§3.1: values for both sides): the thin panel of
 * plugins/vlf/data/panel_double.gltf lit from its back side, 1 iteration. */
static void test_double(void)
{
    const char *names[2] = {"plugins/vlf/data/panel_double.gltf",
                            "plugins/vlf/data/panel_single.gltf"};
    double recv_double = -1.0;
    for (int sc = 0; sc < 2; sc++) {
        gi_scene *s = load(names[sc]);
        if (!s)
            continue;
        uint32_t orders[3] = {VLF_ORDER_FACES, VLF_ORDER_RAYS, VLF_ORDER_FACES},
                 perturbed[3] = {0, 0, 3};
        float *E_faces = NULL;
        for (int run = 0; run < (sc == 0 ? 3 : 1); run++) {
            vlf_settings p = defaults();
            p.iterations = 1;
            p.order = orders[run], p.perturbed = perturbed[run];
            vlf_field f;
            gi_error err;
            gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
            EXPECT(rc == GI_OK, "%s", err.text);
            if (rc != GI_OK)
                continue;
            vlf_field_propagate(&f, NULL, NULL, NULL);
            const vlf_stats *st = &f.st;
            /* every packet stops at a back or escapes (propagate.c) */
            CHECK_NEAR(st->flux_shot, st->flux_back + st->flux_escaped, 1e-4 * st->flux_shot);
            /* the panel's sides: lit (normal toward the light, +z), dark (-z) */
            int lit = -1, dark = -1;
            for (uint32_t fi = 0; fi < f.face_count; fi++)
                if (f.faces[fi].emission[0] == 0.0f)
                    *(f.faces[fi].n.z > 0.0f ? &lit : &dark) = (int)fi;
            if (sc == 1) {
                check_single_sided(&f, lit, dark, recv_double);
                vlf_field_free(&f);
                continue;
            }
            EXPECT(lit >= 0 && dark >= 0, "double-sided panel: faces %d / %d", lit, dark);
            if (lit < 0 || dark < 0) {
                vlf_field_free(&f);
                continue;
            }
            check_double_sided(&f, &p, lit, dark);
            if (run == 0) {
                E_faces = malloc((size_t)f.elem_count * 3 * sizeof *E_faces);
                if (E_faces)
                    memcpy(E_faces, f.E_tot, (size_t)f.elem_count * 3 * sizeof *E_faces);
                recv_double = st->flux_received;
            } else if (run == 1 && E_faces) {
                check_against_faces(&f, E_faces);
            }
            vlf_field_free(&f);
        }
        free(E_faces);
        gi_scene_free(s);
    }
}

int main(int argc, char **argv)
{
    static const vlf_test_part parts[] = {{"energy", test_energy},   {"furnace", test_furnace},
                                          {"mirror", test_mirror},   {"albedo", test_albedo},
                                          {"texture", test_texture}, {"double", test_double},
                                          {"sides", test_sides}};
    return vlf_test_main("vlf_transport_tests", parts, sizeof parts / sizeof parts[0], argc, argv);
}

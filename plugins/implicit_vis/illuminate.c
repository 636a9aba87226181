/* The implicit_vis method's illumination on the CPU (Sec. 4.3, 4.4):
 * gathering at the leaves along their receiving links with Eq. 5, the
 * direct light first (light links, the environment through the bins the
 * links leave open, punctual lights through their bin), then the bounces,
 * each followed by the area-weighted pull-up; and the receiving links
 * flattened for the same computation on the GPU (iv_gpu.c, Sec. 4.3.1).
 * See iv.h. */
#include "iv.h"

#include "gi/lights.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* Solid angle of node y seen from leaf x, Eq. 5's (n_y . -w) A_y / r^2:
 * its area foreshortened by its mean normal (a cluster facing many ways,
 * short mean normal, shows more than its mean normal says; as links.c
 * counts coverage), taken as the solid angle of a disc of that projected
 * area (Sec. 4.1: elements are discs), 2 pi (1 - 1 / sqrt(1 + a / (pi r^2))),
 * which is a / r^2 for the small elements Eq. 5 assumes and stays below a
 * hemisphere for a disc nearer than its size. */
static float node_omega(const iv_hier *h, uint32_t x, uint32_t y)
{
    gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * y]), gi_v3_load(&h->pos[3 * x]));
    float r2 = gi_v3_dot(d, d);
    if (!(r2 > 0.0f))
        return 0.0f;
    gi_vec3 n = gi_v3_load(&h->nrm[3 * y]);
    float c = fabsf(gi_v3_dot(n, d)) / sqrtf(r2), len = gi_v3_length(n);
    return iv_disc_solid_angle((double)h->area[y] * fmaxf(c, 1.0f - len), r2);
}

float iv_link_share(const iv_links *l, const iv_hier *h, uint32_t x, uint32_t b)
{
    size_t i = (size_t)x * l->bins + b;
    int32_t y = l->cell[i].other;
    if (y < 0)
        return 0.0f;
    if (l->coverage > 0.0f) { /* README "Deviations": the share the links' solid angles cover */
        float f = l->cover[i] / (l->coverage * l->bin_omega[b]);
        return f < 1.0f ? f : 1.0f;
    }
    switch (l->weight) {
    case IV_WEIGHT_BIN: /* the nearest covers its bin */
        return 1.0f;
    case IV_WEIGHT_SURFACE: /* Eq. 4 over the nearest surface's nodes in the bin */
        return l->cover[i] / l->bin_omega[b];
    default: /* Eq. 5 as printed: (n_y . -w) A_y / r^2 of the nearest */
        return node_omega(h, x, (uint32_t)y) / l->bin_omega[b];
    }
}

int iv_env_partial(const iv_links *l)
{
    return l->coverage > 0.0f || l->weight == IV_WEIGHT_SURFACE;
}

float iv_env_open(const iv_links *l, const iv_hier *h, uint32_t x, uint32_t b)
{
    if (l->cell[(size_t)x * l->bins + b].other < 0)
        return 1.0f;
    if (!iv_env_partial(l))
        return 0.0f;
    float f = iv_link_share(l, h, x, b);
    return f < 1.0f ? 1.0f - f : 0.0f;
}

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* Elements e0 .. e1 - 1 of iv_links_pack: each writes its own links'
 * words only, so ranges pack side by side on threads. */
typedef struct pack_range {
    const iv_links *l;
    const iv_hier *h;
    uint32_t *links;
    uint32_t e0, e1;
} pack_range;

static void *pack_elements(void *arg)
{
    const pack_range *r = arg;
    const iv_links *l = r->l;
    size_t light_base = l->leaf_off[r->h->elem_count];
    for (uint32_t e = r->e0; e < r->e1; e++) {
        uint32_t x = r->h->elem_node[e];
        for (int light = 0; light < 2; light++) {
            const uint32_t *o = light ? l->light_off : l->leaf_off;
            const uint32_t *bin = light ? l->light_bin : l->leaf_bin;
            const uint32_t *src = light ? l->light_src : l->leaf_src;
            for (uint32_t j = o[e]; j < o[e + 1]; j++) {
                uint32_t *w = &r->links[4 * ((light ? light_base : 0) + j)];
                w[0] = bin[j];
                w[1] = src[j];
                w[2] = float_bits(iv_link_share(l, r->h, x, bin[j]));
                w[3] = float_bits(l->cell[(size_t)x * l->bins + bin[j]].dist);
            }
        }
    }
    return NULL;
}

/* Most threads iv_links_pack starts. */
#define IV_PACK_THREADS 16u

void iv_links_pack(const iv_links *l, const iv_hier *h, uint32_t *links, uint32_t *off)
{
    for (uint32_t e = 0; e <= h->elem_count; e++) {
        off[2 * e] = l->leaf_off[e];
        off[2 * e + 1] = l->light_off[e];
    }
    /* on l->threads threads (the link creation's), in element ranges: the
     * same words; a thread that cannot start packs on this one */
    uint32_t T = l->threads > 1 ? l->threads : 1, n = h->elem_count;
    T = T > IV_PACK_THREADS ? IV_PACK_THREADS : T;
    T = n < 1024u ? 1u : T;
    pack_range r[IV_PACK_THREADS];
    pthread_t tid[IV_PACK_THREADS];
    int made[IV_PACK_THREADS] = {0};
    for (uint32_t i = 0; i < T; i++) {
        r[i] = (pack_range){l, h, links, (uint32_t)((uint64_t)n * i / T),
                            (uint32_t)((uint64_t)n * (i + 1) / T)};
        if (i > 0)
            made[i] = pthread_create(&tid[i], NULL, pack_elements, &r[i]) == 0;
    }
    pack_elements(&r[0]);
    for (uint32_t i = 1; i < T; i++) {
        if (made[i])
            pthread_join(tid[i], NULL);
        else
            pack_elements(&r[i]);
    }
}

/* Radiance a node sends toward point x: the side its mean normal faces x;
 * a cluster whose children face every way (mean normal shorter than 0.3)
 * sends the mean of both sides. */
static void node_radiance(const iv_hier *h, const float *sp, const float *sm, uint32_t src,
                          gi_vec3 x, float out[3])
{
    gi_vec3 ns = gi_v3_load(&h->nrm[3 * src]);
    float len2 = gi_v3_dot(ns, ns);
    if (len2 < 0.09f) {
        for (int c = 0; c < 3; c++)
            out[c] = 0.5f * (sp[3 * src + c] + sm[3 * src + c]);
        return;
    }
    const float *L = gi_v3_dot(ns, gi_v3_sub(x, gi_v3_load(&h->pos[3 * src]))) >= 0.0f ? sp : sm;
    for (int c = 0; c < 3; c++)
        out[c] = L[3 * src + c];
}

/* Area-weighted pull-up of the leaves' radiance to every node (Sec. 4.3). */
static void pull_up(const iv_hier *h, float *sp, float *sm)
{
    for (uint32_t i = h->node_count; i-- > 0;) {
        if (iv_is_leaf(h, i))
            continue;
        double a = 0.0, p[3] = {0, 0, 0}, m[3] = {0, 0, 0};
        for (uint32_t k = 0; k < h->child_count[i]; k++) {
            uint32_t c = h->first_child[i] + k;
            double w = h->area[c];
            a += w;
            for (int j = 0; j < 3; j++) {
                p[j] += w * sp[3 * c + j];
                m[j] += w * sm[3 * c + j];
            }
        }
        for (int j = 0; j < 3; j++) {
            sp[3 * i + j] = a > 0.0 ? (float)(p[j] / a) : 0.0f;
            sm[3 * i + j] = a > 0.0 ? (float)(m[j] / a) : 0.0f;
        }
    }
}

/* Adds radiance L arriving through the fraction `frac` of bin b to the
 * irradiance of the side of the disc (normal n) it falls on: the bin's
 * share of the hemisphere weighted by its cosine. With frac = 1 this is
 * Eq. 5 with the nearest element covering its bin. */
static void add_bin(const iv_links *l, uint32_t b, gi_vec3 n, float norm, float frac,
                    const float L[3], double ep[3], double em[3])
{
    float w = gi_v3_dot(n, gi_v3_load(&l->bin_dir[3 * b])) * l->bin_omega[b] * norm * frac;
    double *e = w >= 0.0f ? ep : em;
    w = fabsf(w);
    for (int c = 0; c < 3; c++)
        e[c] += (double)w * L[c];
}

/* Irradiance from the punctual lights at leaf x, each seen through the bin
 * toward it: blocked where the bin holds a link shorter than the light's
 * distance (a directional light: where the bin holds any link). */
static void punctual(const iv_links *l, const iv_hier *h, const iv_lights *li, uint32_t leaf,
                     double ep[3], double em[3])
{
    const gi_scene *s = li->scene;
    gi_vec3 x = gi_v3_load(&h->pos[3 * leaf]), n = gi_v3_load(&h->nrm[3 * leaf]);
    size_t base = (size_t)leaf * l->bins;
    for (uint32_t i = 0; i < s->light_count; i++) {
        const gi_light *lt = &s->lights[i];
        gi_light_frame f = gi_scene_light_at(s, i, li->t);
        gi_vec3 wl;
        float scale, r;
        if (!gi_punctual_toward(lt, f, x, &wl, &r, &scale))
            continue;
        size_t k = base + iv_bin_of(wl, l->n);
        if (l->cell[k].other >= 0 && l->cell[k].dist < r)
            continue;
        float c = gi_v3_dot(n, wl);
        double *e = c >= 0.0f ? ep : em;
        for (int j = 0; j < 3; j++)
            e[j] += (double)(fabsf(c) * scale * lt->intensity[j]);
    }
}

void iv_illuminate(const iv_links *l, iv_hier *h, const iv_lights *li, uint32_t bounces,
                   float *e_out)
{
    uint32_t nn = h->node_count, ne = h->elem_count;
    float *sp = calloc((size_t)nn * 3, sizeof(float)), *sm = calloc((size_t)nn * 3, sizeof(float));
    float *norm = malloc(ne * sizeof(float));
    double *ek = malloc((size_t)ne * 6 * sizeof(double));
    if (!sp || !sm || !norm || !ek) {
        memset(e_out, 0, (size_t)ne * 6 * sizeof(float));
        free(sp), free(sm), free(norm), free(ek);
        return;
    }
    memset(e_out, 0, (size_t)ne * 6 * sizeof(float));
    /* each disc's bins, cosine-weighted, sum to pi over a hemisphere */
    for (uint32_t e = 0; e < ne; e++) {
        gi_vec3 n = gi_v3_load(&h->nrm[3 * h->elem_node[e]]);
        double s = 0.0;
        for (uint32_t b = 0; b < l->bins; b++)
            s += fabs((double)gi_v3_dot(n, gi_v3_load(&l->bin_dir[3 * b]))) * l->bin_omega[b];
        norm[e] = s > 0.0 ? (float)(2.0 * GI_PI / s) : 0.0f;
    }
    /* bounce 0: emission */
    for (uint32_t e = 0; e < ne; e++) {
        uint32_t x = h->elem_node[e];
        for (int c = 0; c < 3; c++) {
            sp[3 * x + c] = h->elem_emit[3 * e + c];
            sm[3 * x + c] = h->elem_two_sided_emit[e] ? h->elem_emit[3 * e + c] : 0.0f;
        }
    }
    pull_up(h, sp, sm);
    for (uint32_t k = 0; k <= bounces; k++) {
        int direct = k == 0;
        const uint32_t *off = direct ? l->light_off : l->leaf_off;
        const uint32_t *bin = direct ? l->light_bin : l->leaf_bin;
        const uint32_t *src = direct ? l->light_src : l->leaf_src;
        for (uint32_t e = 0; e < ne; e++) {
            uint32_t x = h->elem_node[e];
            gi_vec3 p = gi_v3_load(&h->pos[3 * x]), n = gi_v3_load(&h->nrm[3 * x]);
            double ep[3] = {0, 0, 0}, em[3] = {0, 0, 0};
            if (direct && li->direct) { /* traced (README "Traced direct light") */
                for (int c = 0; c < 3; c++) {
                    ep[c] = li->direct[6 * (size_t)e + (size_t)c];
                    em[c] = li->direct[6 * (size_t)e + 3 + (size_t)c];
                }
            }
            uint32_t j1 = direct && li->direct ? off[e] : off[e + 1];
            for (uint32_t j = off[e]; j < j1; j++) {
                float L[3];
                node_radiance(h, sp, sm, src[j], p, L);
                add_bin(l, bin[j], n, norm[e], iv_link_share(l, h, x, bin[j]), L, ep, em);
            }
            if (direct && !li->direct) {
                if (li->env) { /* Sec. 4.4: an empty bin (or what its links leave uncovered) sees
                                  the environment */
                    for (uint32_t b = 0; b < l->bins; b++) {
                        float open = iv_env_open(l, h, x, b);
                        if (open > 0.0f) {
                            float L[3];
                            gi_envmap_eval(li->env, gi_v3_load(&l->bin_dir[3 * b]), L);
                            add_bin(l, b, n, norm[e], open, L, ep, em);
                        }
                    }
                }
                if (li->scene && li->scene->light_count)
                    punctual(l, h, li, x, ep, em);
            }
            for (int c = 0; c < 3; c++) { /* single-sided: lit on its front only */
                ek[6 * e + c] = ep[c];
                ek[6 * e + 3 + c] = h->elem_two_sided_emit[e] ? em[c] : 0.0;
            }
        }
        /* the gathered light, reflected: the next bounce's source */
        for (uint32_t e = 0; e < ne; e++) {
            uint32_t x = h->elem_node[e];
            for (int c = 0; c < 3; c++) {
                if (!(direct && li->direct)) { /* traced direct light: the display adds its own */
                    e_out[6 * e + c] += (float)ek[6 * e + c];
                    e_out[6 * e + 3 + c] += (float)ek[6 * e + 3 + c];
                }
                float rho = h->elem_albedo[3 * e + c] / (float)GI_PI;
                sp[3 * x + c] = rho * (float)ek[6 * e + c];
                sm[3 * x + c] = rho * (float)ek[6 * e + 3 + c];
            }
        }
        if (k < bounces)
            pull_up(h, sp, sm);
    }
    free(sp), free(sm), free(norm), free(ek);
}

/* Scoring a visibility method against exact ray casting, with the trivial
 * answers as the baseline (shared by the plugins' visibility tests).
 *
 * An agreement percentage alone says little: where most pairs are lit,
 * "always lit" (no shadows at all) agrees on most of them, and where most
 * are shadowed "never lit" does. So every visibility test scores, on the
 * same pairs, the method, the always-lit answer and the never-lit answer,
 * and requires
 *   - at least `min_each` occluded and `min_each` unoccluded pairs, so
 *     that both kinds of mistake can be seen, and
 *   - the method's disagreements to be at most (1 - margin) times those of
 *     the better trivial answer, i.e. the method removes at least the
 *     fraction `margin` of the trivial answer's disagreements.
 * The better trivial answer is wrong on every pair of the smaller class,
 * so the margin says how much of the rarer answer the method gets right,
 * net of the mistakes it makes on the other class.
 *
 * The margin the tests use, VIS_MARGIN (one half), comes from what a
 * discretised shadow test is expected to get wrong: its mistakes lie in a
 * band around each shadow's edge whose width is set by the discretisation
 * (a texel, a map direction's cell, the spacing of the points on a light),
 * while inside a shadow, and away from every shadow, it answers like a
 * ray. For the pairs of these tests (shadows many texels across) that band
 * holds well under half of the smaller class, so a method that is not right
 * on at least half of it is not a working shadow test. A test whose
 * discretisation is coarse by design may state another margin beside its
 * call, with the reason. */
#ifndef GI_TEST_VIS_SCORE_H
#define GI_TEST_VIS_SCORE_H

#include <stdio.h>

#define VIS_MARGIN 0.5

typedef struct vis_score {
    long pairs;    /* pairs scored */
    long occluded; /* of them, blocked according to ray casting */
    long agree;    /* the method gives ray casting's answer */
} vis_score;

/* One pair: ray casting's answer and the method's (non-zero: lit). */
static inline void vis_add(vis_score *s, int exact_lit, int method_lit)
{
    s->pairs++;
    s->occluded += !exact_lit;
    s->agree += (exact_lit != 0) == (method_lit != 0);
}

/* Prints the scores (method, always lit, never lit, pairs) as one line
 * starting with `what` and returns the number of failed requirements
 * (0, 1 or 2), each reported on stderr. */
static inline int vis_check(const vis_score *s, const char *what, double margin, long min_each)
{
    long lit = s->pairs - s->occluded;
    long trivial_wrong =
        lit < s->occluded ? lit : s->occluded; /* the better trivial answer's mistakes */
    long wrong = s->pairs - s->agree;
    double n = s->pairs > 0 ? (double)s->pairs : 1.0;
    double removed = trivial_wrong > 0 ? 1.0 - (double)wrong / (double)trivial_wrong : 0.0;
    printf("%s: %ld pairs (%ld occluded, %ld unoccluded): method %.1f %%, always lit %.1f %%, "
           "never lit %.1f %%; "
           "the method removes %.0f %% of the better trivial answer's %ld disagreements (required "
           "%.0f %%)\n",
           what, s->pairs, s->occluded, lit, 100.0 * (double)s->agree / n, 100.0 * (double)lit / n,
           100.0 * (double)s->occluded / n, 100.0 * removed, trivial_wrong, 100.0 * margin);
    int fails = 0;
    if (s->occluded < min_each || lit < min_each) {
        fprintf(stderr,
                "%s: %ld occluded and %ld unoccluded pairs; at least %ld of each are needed\n",
                what, s->occluded, lit, min_each);
        fails++;
    }
    if ((double)wrong > (1.0 - margin) * (double)trivial_wrong) {
        fprintf(stderr,
                "%s: %ld disagreements, more than %.0f %% of the better trivial answer's %ld\n",
                what, wrong, 100.0 * (1.0 - margin), trivial_wrong);
        fails++;
    }
    return fails;
}

#endif

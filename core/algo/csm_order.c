/* Enumerations of a grid of depth maps for Coherent Shadow Maps, Ritschel et
 * al. 2007 §4.4 (scan-line, zig-zag, Hilbert, diagonal zig-zag). The Hilbert order is the
 * generalised Hilbert curve "gilbert" (Cervený 2019), walked without
 * generating it: both directions descend its recursive split of the
 * rectangle, choosing the sub-rectangle by area (index -> cell) or by
 * containment (cell -> index). See gi/algo/csm_order.h. */
#include "gi/algo/csm_order.h"

#include <assert.h>
#include <string.h>

const char *gi_csm_order_name(gi_csm_order order)
{
    switch (order) {
    case GI_CSM_ORDER_SCANLINE:
        return "scanline";
    case GI_CSM_ORDER_ZIGZAG:
        return "zigzag";
    case GI_CSM_ORDER_HILBERT:
        return "hilbert";
    case GI_CSM_ORDER_DIAGONAL:
        return "diagonal";
    }
    return "?";
}

int gi_csm_order_parse(const char *name, gi_csm_order *out)
{
    static const gi_csm_order all[] = {GI_CSM_ORDER_SCANLINE, GI_CSM_ORDER_ZIGZAG,
                                       GI_CSM_ORDER_HILBERT, GI_CSM_ORDER_DIAGONAL};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++) {
        if (strcmp(name, gi_csm_order_name(all[k])) == 0) {
            *out = all[k];
            return 1;
        }
    }
    return 0;
}

static int64_t sgn(int64_t v)
{
    return (v > 0) - (v < 0);
}

static int64_t abs64(int64_t v)
{
    return v < 0 ? -v : v;
}

/* Python's v // 2 (floor), which the reference generator uses. */
static int64_t half_floor(int64_t v)
{
    return v >= 0 ? v / 2 : -((-v + 1) / 2);
}

/* A gilbert sub-rectangle: origin (x, y), major axis (ax, ay) and minor axis
 * (bx, by), each along one grid axis, lengths |ax + ay| and |bx + by|. */
typedef struct rect {
    int64_t x, y, ax, ay, bx, by;
} rect;

static int64_t area(rect r)
{
    return abs64(r.ax + r.ay) * abs64(r.bx + r.by);
}

static int contains(rect r, int64_t px, int64_t py)
{
    int64_t x1 = r.x + (r.ax - sgn(r.ax)) + (r.bx - sgn(r.bx));
    int64_t y1 = r.y + (r.ay - sgn(r.ay)) + (r.by - sgn(r.by));
    int64_t xl = r.x < x1 ? r.x : x1, xh = r.x < x1 ? x1 : r.x;
    int64_t yl = r.y < y1 ? r.y : y1, yh = r.y < y1 ? y1 : r.y;
    return px >= xl && px <= xh && py >= yl && py <= yh;
}

/* The two or three parts of r in curve order (generate2d of gilbert);
 * returns their count, or 0 if r is a single row or column (a leaf). */
static int split(rect r, rect part[3])
{
    int64_t w = abs64(r.ax + r.ay), h = abs64(r.bx + r.by);
    if (w == 1 || h == 1)
        return 0;
    int64_t dax = sgn(r.ax), day = sgn(r.ay), dbx = sgn(r.bx), dby = sgn(r.by);
    int64_t ax2 = half_floor(r.ax), ay2 = half_floor(r.ay);
    int64_t bx2 = half_floor(r.bx), by2 = half_floor(r.by);
    int64_t w2 = abs64(ax2 + ay2), h2 = abs64(bx2 + by2);
    if (2 * w > 3 * h) {
        if ((w2 & 1) && w > 2) { /* prefer even steps */
            ax2 += dax;
            ay2 += day;
        }
        /* long case: two halves along the major axis */
        part[0] = (rect){r.x, r.y, ax2, ay2, r.bx, r.by};
        part[1] = (rect){r.x + ax2, r.y + ay2, r.ax - ax2, r.ay - ay2, r.bx, r.by};
        return 2;
    }
    if ((h2 & 1) && h > 2) {
        bx2 += dbx;
        by2 += dby;
    }
    /* standard case: up, long across, down */
    part[0] = (rect){r.x, r.y, bx2, by2, ax2, ay2};
    part[1] = (rect){r.x + bx2, r.y + by2, r.ax, r.ay, r.bx - bx2, r.by - by2};
    part[2] = (rect){r.x + (r.ax - dax) + (bx2 - dbx),
                     r.y + (r.ay - day) + (by2 - dby),
                     -bx2,
                     -by2,
                     -(r.ax - ax2),
                     -(r.ay - ay2)};
    return 3;
}

static rect root(uint32_t na, uint32_t nb)
{
    return na >= nb ? (rect){0, 0, na, 0, 0, nb} : (rect){0, 0, 0, nb, na, 0};
}

static void hilbert_cell(uint32_t na, uint32_t nb, uint32_t index, uint32_t *a, uint32_t *b)
{
    rect r = root(na, nb), part[3];
    int64_t k = index;
    for (;;) {
        int n = split(r, part);
        if (n == 0)
            break;
        for (int j = 0; j < n; j++) {
            int64_t s = area(part[j]);
            if (k < s || j == n - 1) {
                r = part[j];
                break;
            }
            k -= s;
        }
    }
    /* Leaf: a row along the major axis or a column along the minor one. */
    int64_t w = abs64(r.ax + r.ay);
    int64_t dx = w > 1 ? sgn(r.ax) : sgn(r.bx), dy = w > 1 ? sgn(r.ay) : sgn(r.by);
    *a = (uint32_t)(r.x + k * dx);
    *b = (uint32_t)(r.y + k * dy);
}

static uint32_t hilbert_index(uint32_t na, uint32_t nb, uint32_t a, uint32_t b)
{
    rect r = root(na, nb), part[3];
    int64_t k = 0;
    for (;;) {
        int n = split(r, part);
        if (n == 0)
            break;
        for (int j = 0; j < n; j++) {
            if (contains(part[j], a, b) || j == n - 1) {
                r = part[j];
                break;
            }
            k += area(part[j]);
        }
    }
    int64_t w = abs64(r.ax + r.ay);
    int64_t dx = w > 1 ? sgn(r.ax) : sgn(r.bx), dy = w > 1 ? sgn(r.ay) : sgn(r.by);
    return (uint32_t)(k + ((int64_t)a - r.x) * dx + ((int64_t)b - r.y) * dy);
}

/* Cells before anti-diagonal s (a + b = s) of an na x nb grid: the sum of
 * the lengths of the diagonals 0 .. s-1, in closed form (the full triangle
 * minus the two corners that stick out past a = na - 1 and b = nb - 1). */
static uint64_t diagonal_start(uint64_t na, uint64_t nb, uint64_t s)
{
    uint64_t n = s * (s + 1) / 2;
    if (s > na)
        n -= (s - na) * (s - na + 1) / 2;
    if (s > nb)
        n -= (s - nb) * (s - nb + 1) / 2;
    return n;
}

/* First and last a on anti-diagonal s. */
static void diagonal_range(uint64_t na, uint64_t nb, uint64_t s, uint64_t *lo, uint64_t *hi)
{
    *lo = s + 1 > nb ? s + 1 - nb : 0;
    *hi = s < na - 1 ? s : na - 1;
}

static void diagonal_cell(uint32_t na, uint32_t nb, uint32_t index, uint32_t *a, uint32_t *b)
{
    /* the largest s with diagonal_start(s) <= index, by bisection */
    uint64_t lo = 0, hi = (uint64_t)na + nb - 1;
    while (hi - lo > 1) {
        uint64_t mid = (lo + hi) / 2;
        if (diagonal_start(na, nb, mid) <= index)
            lo = mid;
        else
            hi = mid;
    }
    uint64_t s = lo, k = index - diagonal_start(na, nb, s), alo, ahi;
    diagonal_range(na, nb, s, &alo, &ahi);
    uint64_t av = (s & 1) ? ahi - k : alo + k;
    *a = (uint32_t)av;
    *b = (uint32_t)(s - av);
}

static uint32_t diagonal_index(uint32_t na, uint32_t nb, uint32_t a, uint32_t b)
{
    uint64_t s = (uint64_t)a + b, alo, ahi;
    diagonal_range(na, nb, s, &alo, &ahi);
    return (uint32_t)(diagonal_start(na, nb, s) + ((s & 1) ? ahi - a : a - alo));
}

void gi_csm_order_cell(gi_csm_order order, uint32_t na, uint32_t nb, uint32_t index, uint32_t *a,
                       uint32_t *b)
{
    assert(na >= 1 && nb >= 1 && (uint64_t)index < (uint64_t)na * nb && a && b);
    switch (order) {
    case GI_CSM_ORDER_SCANLINE:
        *a = index % na;
        *b = index / na;
        return;
    case GI_CSM_ORDER_ZIGZAG:
        *b = index / na;
        *a = (*b & 1) ? na - 1 - index % na : index % na;
        return;
    case GI_CSM_ORDER_HILBERT:
        hilbert_cell(na, nb, index, a, b);
        return;
    case GI_CSM_ORDER_DIAGONAL:
        diagonal_cell(na, nb, index, a, b);
        return;
    }
    assert(!"unknown order");
}

uint32_t gi_csm_order_index(gi_csm_order order, uint32_t na, uint32_t nb, uint32_t a, uint32_t b)
{
    assert(na >= 1 && nb >= 1 && a < na && b < nb);
    switch (order) {
    case GI_CSM_ORDER_SCANLINE:
        return b * na + a;
    case GI_CSM_ORDER_ZIGZAG:
        return b * na + ((b & 1) ? na - 1 - a : a);
    case GI_CSM_ORDER_HILBERT:
        return hilbert_index(na, nb, a, b);
    case GI_CSM_ORDER_DIAGONAL:
        return diagonal_index(na, nb, a, b);
    }
    assert(!"unknown order");
    return 0;
}

/* Enumerations of an N_a x N_b grid of depth maps for Coherent Shadow Maps
 * (Ritschel et al., EGSR 2007, §4.4 "Enumeration and Discretization", Fig. 8):
 * the order in which the maps are fed to the codec (csm_codec.h), so that
 * successive maps are coherent. Grid cells are (a, b), 0 <= a < N_a,
 * 0 <= b < N_b (e.g. a = longitude, b = latitude of a distant light's
 * lat-long grid, or the two parameters of a point on an area light);
 * sequence indices are 0 .. N_a N_b - 1.
 *
 *   SCANLINE  index = b N_a + a: a runs fastest (the paper's scan-line order).
 *   ZIGZAG    boustrophedon: as SCANLINE, but odd rows b run a backwards, so
 *             successive cells are always grid neighbours.
 *   HILBERT   the generalised Hilbert curve "gilbert" (J. Cervený 2019,
 *             github.com/jakubcerveny/gilbert) over the N_a x N_b rectangle,
 *             starting at (0, 0). On 2^k x 2^k squares it is the classic
 *             Hilbert curve (the d2xy of Hacker's Delight; tested). On other
 *             sizes it visits every cell once with no skipped cells, and
 *             every step is between grid neighbours except, when the longer
 *             side is odd and the shorter even (4 x 5, 32 x 33), at most one
 *             diagonal step (the test checks every size up to 40 x 40).
 *   DIAGONAL  the zig-zag area curve (JPEG-style): the anti-diagonals
 *             a + b = s in increasing s, even s with a increasing, odd s
 *             with a decreasing, starting at (0, 0); every step goes to one
 *             of the 8 neighbours (a diagonal step inside an anti-diagonal,
 *             an axis step between two). The paper's Fig. 8 (right) names a
 *             "zig-zag area curve" for area lights without defining it in
 *             the text; ZIGZAG (rows) and DIAGONAL (anti-diagonals) are the
 *             two usual readings, and both are offered.
 * Both directions are O(log(N_a N_b)) (HILBERT descends the same recursive
 * split as the generator; DIAGONAL is closed-form per anti-diagonal), with
 * no tables and no state.
 */
#ifndef GI_CSM_ORDER_H
#define GI_CSM_ORDER_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum gi_csm_order {
    GI_CSM_ORDER_SCANLINE = 0,
    GI_CSM_ORDER_ZIGZAG = 1,
    GI_CSM_ORDER_HILBERT = 2,
    GI_CSM_ORDER_DIAGONAL = 3,
} gi_csm_order;

/* "scanline", "zigzag", "hilbert", "diagonal". */
const char *gi_csm_order_name(gi_csm_order order);
/* Parses a name as above; returns 0 if unknown. */
int gi_csm_order_parse(const char *name, gi_csm_order *out);

/* Sequence index -> grid cell. index < na * nb (asserted), na, nb >= 1. */
void gi_csm_order_cell(gi_csm_order order, uint32_t na, uint32_t nb, uint32_t index, uint32_t *a,
                       uint32_t *b);
/* Grid cell -> sequence index; the inverse of gi_csm_order_cell. */
uint32_t gi_csm_order_index(gi_csm_order order, uint32_t na, uint32_t nb, uint32_t a, uint32_t b);

#ifdef __cplusplus
}
#endif
#endif

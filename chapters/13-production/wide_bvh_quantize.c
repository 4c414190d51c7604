/* wide_bvh_quantize.c -- a wide node's child boxes as bytes on a grid over
 * the node's own box (wide_bvh.h, wide_bvh_qnode), rounded outward. */
#include "13-production/wide_bvh.h"

#include <math.h>
#include <string.h>

enum { GRID_STEPS = 255, EXPONENT_MIN = -126, EXPONENT_MAX = 127 };

/* The smallest exponent whose grid, 255 steps from `origin`, reaches `hi`
 * as the kernels compute it. The estimate from the extent is checked and
 * moved by the very arithmetic of wide_bvh_dequantize, so rounding in the
 * estimate cannot make the grid too short. At EXPONENT_MAX the last plane
 * is 255 x 2^127 = inf, which reaches any hi: the search always ends. */
static int grid_exponent(float origin, float hi)
{
    double extent = (double)hi - (double)origin;
    int e = EXPONENT_MIN;
    if (extent > 0.0) {
        int binary_exponent;
        frexp(extent / GRID_STEPS, &binary_exponent); /* extent / 255 < 2^binary_exponent */
        e = binary_exponent < EXPONENT_MIN ? EXPONENT_MIN : binary_exponent;
    }
    while (e < EXPONENT_MAX && wide_bvh_dequantize(origin, e, GRID_STEPS) < hi)
        e++;
    while (e > EXPONENT_MIN && wide_bvh_dequantize(origin, e - 1, GRID_STEPS) >= hi)
        e--;
    return e;
}

/* The grid plane for x: outward, the highest at or below x (a lower plane)
 * or the lowest at or above it (an upper plane); the twin, the nearest.
 * Planes are non-decreasing in q, so each search starts from the estimate
 * and steps until the grid's own floats say it is right. */
static uint8_t grid_plane(float x, float origin, int e, bool upper, wide_bvh_rounding rounding)
{
    double estimate = ((double)x - (double)origin) / (double)wide_bvh_step(e);
    if (rounding == WIDE_BVH_ROUND_NEAREST)
        return (uint8_t)fmin(GRID_STEPS, fmax(0.0, nearbyint(estimate)));
    int q = (int)fmin(GRID_STEPS, fmax(0.0, upper ? ceil(estimate) : floor(estimate)));
    if (upper) {
        while (q < GRID_STEPS && wide_bvh_dequantize(origin, e, q) < x)
            q++;
        while (q > 0 && wide_bvh_dequantize(origin, e, q - 1) >= x)
            q--;
    } else {
        while (q > 0 && wide_bvh_dequantize(origin, e, q) > x)
            q--;
        while (q < GRID_STEPS && wide_bvh_dequantize(origin, e, q + 1) <= x)
            q++;
    }
    return (uint8_t)q;
}

bool wide_bvh_quantize_node(const wide_bvh_node *node, wide_bvh_rounding rounding, wide_bvh_qnode *q)
{
    const float(*exact)[WIDE_BVH_WIDTH] = node->bounds;
    int children = (int)node->children;
    q->children = (uint8_t)children;
    memcpy(q->child, node->child, sizeof q->child);
    for (int axis = 0; axis < 3; axis++) {
        /* the node's box on this axis: the union of its children's */
        float lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < children; k++) {
            lo = fminf(lo, exact[axis][k]);
            hi = fmaxf(hi, exact[axis + 3][k]);
        }
        if (!isfinite(lo) || !isfinite(hi))
            return false;
        int e = grid_exponent(lo, hi);
        q->origin[axis] = lo;
        q->exponent[axis] = (int8_t)e;
        for (int k = 0; k < WIDE_BVH_WIDTH; k++) {
            bool child = k < children;
            q->bounds[axis][k] = child ? grid_plane(exact[axis][k], lo, e, false, rounding) : GRID_STEPS;
            q->bounds[axis + 3][k] = child ? grid_plane(exact[axis + 3][k], lo, e, true, rounding) : 0;
        }
    }
    return true;
}

aabb wide_bvh_qnode_box(const wide_bvh_qnode *q, int k)
{
    float plane[6];
    for (int p = 0; p < 6; p++)
        plane[p] = wide_bvh_dequantize(q->origin[p % 3], q->exponent[p % 3], q->bounds[p][k]);
    return (aabb){vec3_make(plane[0], plane[1], plane[2]), vec3_make(plane[3], plane[4], plane[5])};
}

/* ---- a node of either layout ----------------------------------------------------- */

uint32_t wide_bvh_child(const wide_bvh *b, int n, int k)
{
    return b->layout == WIDE_BVH_QUANTIZED ? b->qnodes[n].child[k] : b->nodes[n].child[k];
}

aabb wide_bvh_child_box(const wide_bvh *b, int n, int k)
{
    if (b->layout == WIDE_BVH_QUANTIZED)
        return wide_bvh_qnode_box(&b->qnodes[n], k);
    const wide_bvh_node *node = &b->nodes[n];
    return (aabb){vec3_make(node->bounds[0][k], node->bounds[1][k], node->bounds[2][k]),
                  vec3_make(node->bounds[3][k], node->bounds[4][k], node->bounds[5][k])};
}

int wide_bvh_children(const wide_bvh *b, int n)
{
    return b->layout == WIDE_BVH_QUANTIZED ? b->qnodes[n].children : (int)b->nodes[n].children;
}

/* kdtree.c -- building a kd-tree with the surface area heuristic.
 *
 * The lecture's kd-tree splits a box by a plane, sends each object to the
 * side(s) it overlaps, and recurses. Where to put the plane is the whole
 * question. The surface area heuristic (SAH; MacDonald and Booth 1990)
 * answers it with a cost model: a random ray that hits a convex box A also
 * hits a convex box B inside it with probability SA(B) / SA(A), so splitting
 * a node costs, on average,
 *
 *   C(split) = C_traverse + (SA_below / SA) N_below C_isect
 *                         + (SA_above / SA) N_above C_isect
 *
 * against N C_isect for keeping it as a leaf. Only planes at the triangles'
 * box faces can be minima of C (between two such planes N_below and N_above
 * do not change while the areas change linearly), so those are the only
 * candidates: each triangle contributes a "start" and an "end" event on each
 * axis, or one "planar" event when its box is flat on that axis.
 *
 * Wald and Havran ("On building fast kd-trees for ray tracing, and on doing
 * that in O(N log N)", 2006): sort the events once; one sweep along a sorted
 * list gives N_below, N_planar and N_above at every candidate; splitting a
 * node splits its sorted lists into sorted lists for the children, so only
 * the new events of the triangles that straddle the plane need sorting. That
 * is what this file does: O(N log N) overall, not O(N log^2 N).
 *
 * Events come from the box of the part of each triangle inside the node:
 * when a triangle straddles a split, the triangle itself is clipped to each
 * child (Wald and Havran's "perfect splits", see triangle_clip_box), not
 * just its bounding box, so a cell the triangle's box reaches but the
 * triangle does not gets no reference to it.
 */
#include "05-kd-tree/kdtree.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "memory.h"
#include "timer.h"

/* ---- the cost constants ---------------------------------------------------
 * Only their ratio matters for where the splits go: C_isect = 1 is the unit,
 * C_traverse says how many triangle tests one step down the tree costs. On
 * paper a step (load 8 bytes, one subtraction and multiplication, pick a
 * child) is cheaper than a Moller-Trumbore test (two cross products, three
 * dot products, a division). In practice each step depends on the one
 * before (load, compute, load the next node: nothing overlaps), while the
 * tests of one leaf run side by side. Measured on the tori field (100k
 * triangles, perfect splits, the chapter text has the table): C_traverse
 * from 1 to 3 traces within 5-20% of each other, 4 clearly slower, 1 builds
 * 2.6x the nodes of 2, and 2 was as fast as any (1.5 as fast, with 35-40%
 * more bytes). */
static const float KD_TRAVERSAL_COST = 2.0f;
static const float KD_INTERSECTION_COST = 1.0f;
/* A split that leaves one side empty lets every ray that crosses that side
 * skip it for the price of one step; Wald and Havran multiply its cost by
 * 0.8 to prefer cutting off empty space early (the SAH alone already cuts
 * a lot of it). Measured with 1 instead: the teapot in a stadium costs the
 * same per camera ray (within 2%) with a third fewer nodes; on the tori
 * field (100k) rays test 20% more triangles (3.9 -> 4.7) with 32% fewer
 * nodes. */
static const float KD_EMPTY_BONUS = 0.8f;

kdtree_options kdtree_default_options(void)
{
    return (kdtree_options){KD_TRAVERSAL_COST, KD_INTERSECTION_COST, KD_EMPTY_BONUS, 0};
}

int kdtree_depth_limit(int triangle_count)
{
    /* 8 + 1.3 log2 N (Havran's thesis, and pbrt): deep enough for the SAH
     * to finish on real scenes, shallow enough to bound the tree's size
     * and the traversal's stack whatever the SAH decides. */
    double n = triangle_count > 1 ? (double)triangle_count : 1.0;
    int depth = (int)(8.0 + 1.3 * log2(n));
    return depth < KD_MAX_DEPTH ? depth : KD_MAX_DEPTH;
}

/* ---- events -----------------------------------------------------------------
 * An event packs into 64 bits, so that sorting by (position, type) is
 * sorting integers: the position's bits turned into an unsigned integer with
 * the same order (flip the sign bit of positives, all bits of negatives),
 * then the type (end < planar < start at the same position, the order the
 * sweep needs), then the triangle index. */
typedef uint64_t kd_event;
enum { EVENT_END = 0, EVENT_PLANAR = 1, EVENT_START = 2 };
enum { EVENT_TRIANGLE_BITS = 30 };
static const uint32_t EVENT_TRIANGLE_MASK = (1u << EVENT_TRIANGLE_BITS) - 1u;

static inline kd_event event_make(float position, int type, uint32_t triangle)
{
    /* + 0.0f turns -0 into +0: both are the same plane and must sort together. */
    float p = position + 0.0f;
    uint32_t bits;
    memcpy(&bits, &p, sizeof bits);
    bits = (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
    return ((uint64_t)bits << 32) | ((uint64_t)type << EVENT_TRIANGLE_BITS) | triangle;
}

static inline float event_position(kd_event e)
{
    uint32_t bits = (uint32_t)(e >> 32);
    bits = (bits & 0x80000000u) ? (bits & 0x7FFFFFFFu) : ~bits;
    float p;
    memcpy(&p, &bits, sizeof p);
    return p;
}

static inline int event_type(kd_event e) { return (int)((e >> EVENT_TRIANGLE_BITS) & 3u); }
static inline uint32_t event_triangle(kd_event e) { return (uint32_t)e & EVENT_TRIANGLE_MASK; }
/* Events on the same plane have the same upper 32 bits. */
static inline uint32_t event_plane(kd_event e) { return (uint32_t)(e >> 32); }

/* Sort by (position, type): an LSD radix sort on the 34 key bits (above the
 * triangle index), three passes of 11-12 bits; insertion sort for short
 * lists. scratch holds n events. */
static void events_sort(kd_event *events, int n, kd_event *scratch)
{
    if (n < 64) {
        for (int i = 1; i < n; i++) {
            kd_event e = events[i];
            int j = i;
            for (; j > 0 && events[j - 1] > e; j--)
                events[j] = events[j - 1];
            events[j] = e;
        }
        return;
    }
    static const int shifts[3] = {30, 41, 52}, widths[3] = {11, 11, 12};
    kd_event *from = events, *to = scratch;
    for (int pass = 0; pass < 3; pass++) {
        int buckets = 1 << widths[pass];
        uint32_t mask = (uint32_t)buckets - 1u;
        int count[1 << 12] = {0};
        for (int i = 0; i < n; i++)
            count[(from[i] >> shifts[pass]) & mask]++;
        int sum = 0;
        for (int b = 0; b < buckets; b++) {
            int c = count[b];
            count[b] = sum;
            sum += c;
        }
        for (int i = 0; i < n; i++)
            to[count[(from[i] >> shifts[pass]) & mask]++] = from[i];
        kd_event *swap = from;
        from = to;
        to = swap;
    }
    /* three passes: the sorted list is in scratch */
    memcpy(events, from, (size_t)n * sizeof *events);
}

/* ---- the SAH ------------------------------------------------------------------
 * For a split on one axis of a node's box: the area of a child is
 * 2 (cross + length * perimeter), with cross = e_a e_b and perimeter =
 * e_a + e_b over the other two axes' extents, and length along the axis. */
typedef struct {
    float lo, hi;       /* the node's box along the axis */
    float cross, perimeter;
    float inverse_area; /* 1 / SA(node) */
} axis_geometry;

static axis_geometry axis_geometry_make(aabb box, int axis)
{
    vec3 e = aabb_extent(box);
    float ea = vec3_axis(e, (axis + 1) % 3), eb = vec3_axis(e, (axis + 2) % 3);
    return (axis_geometry){vec3_axis(box.lo, axis), vec3_axis(box.hi, axis), ea * eb, ea + eb,
                           1.0f / aabb_surface_area(box)};
}

static inline float sah_cost(const kdtree_options *o, const axis_geometry *g, float split, int n_below, int n_above)
{
    float below_area = 2.0f * (g->cross + (split - g->lo) * g->perimeter);
    float above_area = 2.0f * (g->cross + (g->hi - split) * g->perimeter);
    float cost = o->traversal_cost +
                 o->intersection_cost * (below_area * (float)n_below + above_area * (float)n_above) * g->inverse_area;
    return (n_below == 0 || n_above == 0) ? cost * o->empty_bonus : cost;
}

float kdtree_split_cost(const kdtree_options *o, aabb box, int axis, float split, int n_below, int n_above)
{
    axis_geometry g = axis_geometry_make(box, axis);
    return sah_cost(o, &g, split, n_below, n_above);
}

/* ---- the builder ------------------------------------------------------------- */

enum { SIDE_BOTH = 0, SIDE_BELOW = 1, SIDE_ABOVE = 2 };

typedef struct {
    const triangle_set *set;
    kdtree_options options;
    int depth_limit;
    kd_node *nodes;
    int node_count, node_capacity;
    uint32_t *references;
    int reference_count, reference_capacity;
    uint8_t *side; /* per triangle: which child(ren) of the node being split it goes to */
    /* Per triangle: bit a set if its box is flat on axis a (one planar
     * event there, else a start and an end). Flat stays flat and not-flat
     * stays not-flat in every node (a triangle in a node overlaps it with
     * positive extent on every axis where its box has one), so this is
     * fixed, and the children's lists can be laid out before they are
     * filled. */
    uint8_t *flat_axes;
    /* Room for the straddling triangles' new events and for sorting them,
     * sized for the root and reused by every node (the children are built
     * only after the parent is done with it). */
    kd_event *scratch;
    float root_inverse_area;
    int leaves, empty_leaves, max_depth;
    double sah_cost;
} kd_builder;

/* A node's events: three runs, axis 0, then 1, then 2, each sorted. */
typedef struct {
    kd_event *events; /* owned by the node being built */
    int count[3];
} event_lists;

typedef struct {
    float cost;
    int axis;
    float position;
    bool planar_below; /* triangles lying in the plane go below (else above) */
} split_choice;

static int add_node(kd_builder *b)
{
    if (b->node_count >= (1 << 30))
        abort(); /* the 30-bit child index would overflow */
    b->nodes = memory_grow(b->nodes, &b->node_capacity, b->node_count + 1, sizeof *b->nodes);
    return b->node_count++;
}

static void make_leaf(kd_builder *b, int index, const event_lists *lists, int n, aabb box, int depth)
{
    b->references = memory_grow(b->references, &b->reference_capacity, b->reference_count + n, sizeof *b->references);
    kd_node *node = &b->nodes[index];
    node->first_reference = (uint32_t)b->reference_count;
    node->bits = ((uint32_t)n << 2) | KD_LEAF_TAG;
    /* Each triangle has exactly one start or planar event on axis 0. */
    for (int i = 0; i < lists->count[0]; i++)
        if (event_type(lists->events[i]) != EVENT_END)
            b->references[b->reference_count++] = event_triangle(lists->events[i]);
    b->leaves++;
    b->empty_leaves += n == 0;
    if (depth > b->max_depth)
        b->max_depth = depth;
    b->sah_cost += (double)(b->options.intersection_cost * (float)n * aabb_surface_area(box) * b->root_inverse_area);
}

/* Sweep the sorted events on each axis: N_below, N_planar, N_above at every
 * candidate plane (Wald and Havran's FindPlane). Going along the axis, at a
 * plane p: triangles ending at p are below only, those starting at p are
 * above only, those lying flat in p are "planar" and go to whichever side is
 * cheaper. */
static split_choice find_split(const kd_builder *b, aabb box, const event_lists *lists, int n)
{
    split_choice best = {INFINITY, -1, 0.0f, false};
    const kd_event *run = lists->events;
    for (int axis = 0; axis < 3; axis++) {
        axis_geometry g = axis_geometry_make(box, axis);
        int n_below = 0, n_above = n, count = lists->count[axis];
        for (int i = 0; i < count;) {
            uint32_t plane = event_plane(run[i]);
            float p = event_position(run[i]);
            int ending = 0, lying = 0, starting = 0;
            while (i < count && event_plane(run[i]) == plane && event_type(run[i]) == EVENT_END)
                ending++, i++;
            while (i < count && event_plane(run[i]) == plane && event_type(run[i]) == EVENT_PLANAR)
                lying++, i++;
            while (i < count && event_plane(run[i]) == plane && event_type(run[i]) == EVENT_START)
                starting++, i++;
            n_above -= lying + ending;
            /* Only planes strictly inside the box: a plane on its face would
             * make a child identical to the node, and with the empty bonus
             * such a split would look cheaper than the node, again and again
             * (64 copies of one triangle fill their node's box exactly: no
             * plane is left, and they make one leaf). And a split must take
             * at least one triangle away from one side: if every triangle
             * straddles, both children hold all N and nothing is separated.
             * The SAH never picks that split (SA_below + SA_above > SA, so
             * it costs more than N C_isect), but the rule keeps the build
             * finite and small whatever costs the options give. */
            if (g.lo < p && p < g.hi) {
                if (!(n_below + lying == n && n_above == n)) {
                    float cost = sah_cost(&b->options, &g, p, n_below + lying, n_above);
                    if (cost < best.cost)
                        best = (split_choice){cost, axis, p, true};
                }
                if (lying > 0 && !(n_below == n && n_above + lying == n)) {
                    float cost = sah_cost(&b->options, &g, p, n_below, n_above + lying);
                    if (cost < best.cost)
                        best = (split_choice){cost, axis, p, false};
                }
            }
            n_below += starting + lying;
        }
        run += count;
    }
    return best;
}

static void build_node(kd_builder *b, int index, aabb box, event_lists lists, int n, int depth);

static kd_event *allocate_events(size_t count)
{
    /* malloc, not memory_allocate: no need to zero what is written next */
    kd_event *events = malloc((count > 0 ? count : 1) * sizeof *events);
    if (events == NULL) {
        fputs("kd-tree: out of memory for the build's events\n", stderr);
        exit(1);
    }
    return events;
}

/* The part of box a inside box b (both finite: plain comparisons, no NaN
 * rules to follow, so no calls to fminf and fmaxf). */
static inline aabb box_clip(aabb a, aabb b)
{
    return (aabb){{a.lo.x > b.lo.x ? a.lo.x : b.lo.x, a.lo.y > b.lo.y ? a.lo.y : b.lo.y, a.lo.z > b.lo.z ? a.lo.z : b.lo.z},
                  {a.hi.x < b.hi.x ? a.hi.x : b.hi.x, a.hi.y < b.hi.y ? a.hi.y : b.hi.y, a.hi.z < b.hi.z ? a.hi.z : b.hi.z}};
}

/* ---- perfect splits ---------------------------------------------------------
 * A triangle's box is a poor stand-in for the triangle when it lies
 * slanted: the box reaches into cells the triangle never enters, and each
 * such cell gets a reference that every ray through it tests for nothing.
 * Wald and Havran's "perfect splits": when a triangle straddles a split,
 * clip the triangle itself (Sutherland-Hodgman, plane by plane) to each
 * child's box and give the child the box of what is left, or nothing at
 * all if nothing is left.
 *
 * The clipped corners are rounded, so the clip must never cut away a
 * piece of triangle a ray can still hit in the cell: each child's box is
 * grown by CLIP_SLACK times the size of the coordinates before clipping,
 * and what is left is grown by as much again (then cut back to the
 * child's box). A triangle is dropped from a child only when it misses
 * that grown box, by far more than any rounding. CLIP_SLACK = 2^-18 is 64
 * ulps; each clip rounds a corner by a few ulps of the coordinates, and a
 * corner goes through at most six clips. */
static const float CLIP_SLACK = 0x1.0p-18f;
enum { CLIP_MAX_CORNERS = 9 }; /* a triangle cut by six planes: 3 + 6 corners */

/* Keep the part of polygon in[0 .. n) on the side of the plane x_axis = c
 * given by keep_below; returns the new number of corners in out[]. */
static int polygon_clip(const vec3 *in, int n, int axis, float c, bool keep_below, vec3 *out)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        vec3 a = in[i], b = in[(i + 1) % n];
        float da = vec3_axis(a, axis) - c, db = vec3_axis(b, axis) - c;
        bool a_in = keep_below ? da <= 0.0f : da >= 0.0f;
        bool b_in = keep_below ? db <= 0.0f : db >= 0.0f;
        if (a_in)
            out[m++] = a;
        if (a_in != b_in) {
            /* the edge crosses the plane: a + (b - a) da / (da - db) */
            float s = da / (da - db);
            vec3 p = vec3_add(a, vec3_scale(vec3_sub(b, a), s));
            /* on the plane exactly, whatever the rounding said */
            if (axis == 0)
                p.x = c;
            else if (axis == 1)
                p.y = c;
            else
                p.z = c;
            out[m++] = p;
        }
    }
    return m;
}

/* The box of triangle t clipped to `cell` (already known to overlap the
 * triangle's box), grown as the comment above says; false if the triangle
 * misses the grown cell. On a flat axis the triangle's box is exact and
 * kept as it is. */
static bool triangle_clip_box(const triangle_set *set, uint32_t t, uint8_t flat_axes, aabb cell, aabb *out)
{
    const triangle *tri = &set->triangles[t];
    aabb bbox = box_clip(set->boxes[t], cell);
    float scale = 0.0f;
    for (int a = 0; a < 3; a++) {
        float m[4] = {fabsf(vec3_axis(set->boxes[t].lo, a)), fabsf(vec3_axis(set->boxes[t].hi, a)),
                      fabsf(vec3_axis(cell.lo, a)), fabsf(vec3_axis(cell.hi, a))};
        for (int i = 0; i < 4; i++)
            scale = m[i] > scale ? m[i] : scale;
    }
    float slack = scale * CLIP_SLACK;
    vec3 buffer[2][CLIP_MAX_CORNERS] = {{tri->p0, tri->p1, tri->p2}};
    int n = 3, current = 0;
    for (int a = 0; a < 3 && n > 0; a++) {
        float lo = vec3_axis(cell.lo, a) - slack, hi = vec3_axis(cell.hi, a) + slack;
        /* Clip only by the planes the triangle crosses. */
        if (vec3_axis(set->boxes[t].lo, a) < lo) {
            n = polygon_clip(buffer[current], n, a, lo, false, buffer[1 - current]);
            current = 1 - current;
        }
        if (n > 0 && vec3_axis(set->boxes[t].hi, a) > hi) {
            n = polygon_clip(buffer[current], n, a, hi, true, buffer[1 - current]);
            current = 1 - current;
        }
    }
    if (n == 0)
        return false;
    aabb clipped = aabb_empty();
    for (int i = 0; i < n; i++)
        clipped = aabb_union(clipped, (aabb){buffer[current][i], buffer[current][i]});
    vec3 grow = vec3_make(slack, slack, slack);
    clipped = box_clip((aabb){vec3_sub(clipped.lo, grow), vec3_add(clipped.hi, grow)}, bbox);
    /* Flat axes keep the exact box; and should rounding ever leave an
     * empty interval (it cannot, the growth covers it), the plain box. */
    for (int a = 0; a < 3; a++) {
        float lo = vec3_axis(clipped.lo, a), hi = vec3_axis(clipped.hi, a);
        if (((flat_axes >> a) & 1) || !(lo < hi)) {
            lo = vec3_axis(bbox.lo, a);
            hi = vec3_axis(bbox.hi, a);
        }
        if (a == 0)
            clipped.lo.x = lo, clipped.hi.x = hi;
        else if (a == 1)
            clipped.lo.y = lo, clipped.hi.y = hi;
        else
            clipped.lo.z = lo, clipped.hi.z = hi;
    }
    *out = clipped;
    return true;
}

/* dst[0 .. fresh_count) is free, dst[fresh_count .. fresh_count + kept) holds
 * sorted events; merge the sorted fresh[] into the whole of dst. Writing
 * dst[i + j] while reading dst[fresh_count + j] with i < fresh_count never
 * overwrites an event not yet read. */
static void merge_in_place(kd_event *dst, const kd_event *fresh, int fresh_count, int kept)
{
    const kd_event *held = dst + fresh_count;
    int i = 0, j = 0;
    while (i < fresh_count && j < kept) {
        if (fresh[i] < held[j]) {
            dst[i + j] = fresh[i];
            i++;
        } else {
            dst[i + j] = held[j];
            j++;
        }
    }
    while (i < fresh_count) {
        dst[i + j] = fresh[i];
        i++;
    }
}

/* Split the event lists; clip straddling triangles' boxes to each child and
 * sort their new events; then recurse, below child first. */
static void split_node(kd_builder *b, int index, aabb box, event_lists lists, int n, split_choice s, int depth)
{
    const triangle_set *set = b->set;
    const int k = s.axis;
    const float p = s.position;
    uint8_t *side = b->side;
    const int offset[3] = {0, lists.count[0], lists.count[0] + lists.count[1]};

    /* Classify the triangles: below only, above only, or both (straddling).
     * One pass along axis k, where each triangle has a start before its end,
     * or one planar event: a start at or after p means above only, before p
     * both for now; an end at or before p then makes it below only. Planar
     * triangles lying in p go to the side the SAH chose, the same side for
     * all of them (Wald and Havran). */
    const kd_event *run = lists.events + offset[k];
    for (int i = 0; i < lists.count[k]; i++) {
        kd_event e = run[i];
        float q = event_position(e);
        uint32_t t = event_triangle(e);
        switch (event_type(e)) {
        case EVENT_START:
            side[t] = q >= p ? SIDE_ABOVE : SIDE_BOTH;
            break;
        case EVENT_END:
            if (q <= p)
                side[t] = SIDE_BELOW;
            break;
        default:
            side[t] = q < p ? SIDE_BELOW : q > p ? SIDE_ABOVE : s.planar_below ? SIDE_BELOW : SIDE_ABOVE;
            break;
        }
    }

    /* Count the triangles and events of each side, and make new events for
     * the straddling triangles: each one's box clipped to the node, then to
     * the child, at most 2 per axis per child. */
    aabb below_box = box, above_box = box;
    if (k == 0)
        below_box.hi.x = above_box.lo.x = p;
    else if (k == 1)
        below_box.hi.y = above_box.lo.y = p;
    else
        below_box.hi.z = above_box.lo.z = p;
    int n_below = 0, n_above = 0, kept_below[3] = {0, 0, 0}, kept_above[3] = {0, 0, 0};
    int slots = 2 * n; /* per axis per child: room for all n triangles to straddle */
    kd_event *fresh_below = b->scratch, *fresh_above = b->scratch + 3 * slots, *sort_room = b->scratch + 6 * slots;
    int fresh_below_count[3] = {0, 0, 0}, fresh_above_count[3] = {0, 0, 0};
    for (int i = 0; i < lists.count[0]; i++) {
        kd_event e = lists.events[i];
        uint32_t t = event_triangle(e);
        if (event_type(e) == EVENT_END)
            continue;
        for (int a = 0; a < 3; a++) {
            int events_on_a = 2 - ((b->flat_axes[t] >> a) & 1);
            kept_below[a] += side[t] == SIDE_BELOW ? events_on_a : 0;
            kept_above[a] += side[t] == SIDE_ABOVE ? events_on_a : 0;
        }
        if (side[t] != SIDE_BOTH) {
            n_below += side[t] == SIDE_BELOW;
            n_above += side[t] == SIDE_ABOVE;
            continue;
        }
        /* A straddling triangle: the part of it in each child (perfect
         * splits, above); it may turn out to miss one of them. */
        aabb child[2];
        bool in_child[2] = {triangle_clip_box(set, t, b->flat_axes[t], below_box, &child[0]),
                            triangle_clip_box(set, t, b->flat_axes[t], above_box, &child[1])};
        n_below += in_child[0];
        n_above += in_child[1];
        for (int c = 0; c < 2; c++) {
            if (!in_child[c])
                continue;
            kd_event *out = c == 0 ? fresh_below : fresh_above;
            int *out_count = c == 0 ? fresh_below_count : fresh_above_count;
            for (int a = 0; a < 3; a++) {
                float lo = vec3_axis(child[c].lo, a), hi = vec3_axis(child[c].hi, a);
                kd_event *dst = out + a * slots + out_count[a];
                if (lo == hi) {
                    dst[0] = event_make(lo, EVENT_PLANAR, t);
                    out_count[a] += 1;
                } else {
                    dst[0] = event_make(lo, EVENT_START, t);
                    dst[1] = event_make(hi, EVENT_END, t);
                    out_count[a] += 2;
                }
            }
        }
    }
    for (int a = 0; a < 3; a++) {
        events_sort(fresh_below + a * slots, fresh_below_count[a], sort_room);
        events_sort(fresh_above + a * slots, fresh_above_count[a], sort_room);
    }

    /* Merge, axis by axis: the one-sided triangles' events are already in
     * order (a subsequence of a sorted list), the new ones were sorted. */
    event_lists below, above;
    size_t total_below = 0, total_above = 0;
    for (int a = 0; a < 3; a++) {
        below.count[a] = kept_below[a] + fresh_below_count[a];
        above.count[a] = kept_above[a] + fresh_above_count[a];
        total_below += (size_t)below.count[a];
        total_above += (size_t)above.count[a];
    }
    /* + 1: the partition below writes one slot past what it keeps */
    below.events = allocate_events(total_below + 1);
    above.events = allocate_events(total_above + 1);
    kd_event *region_below = below.events, *region_above = above.events;
    for (int a = 0; a < 3; a++) {
        /* First the one-sided events, into the back of the axis's region
         * (after room for the new ones), without a branch: each event is
         * written to both children and kept by the one it belongs to. */
        const kd_event *src = lists.events + offset[a];
        kd_event *keep_below = region_below + fresh_below_count[a];
        kd_event *keep_above = region_above + fresh_above_count[a];
        for (int i = 0; i < lists.count[a]; i++) {
            kd_event e = src[i];
            int where = side[event_triangle(e)];
            *keep_below = e;
            keep_below += where == SIDE_BELOW;
            *keep_above = e;
            keep_above += where == SIDE_ABOVE;
        }
        /* Then merge the new events in from the front: the merge writes at
         * most as far as it has read, so it can work in place. */
        merge_in_place(region_below, fresh_below + a * slots, fresh_below_count[a], kept_below[a]);
        merge_in_place(region_above, fresh_above + a * slots, fresh_above_count[a], kept_above[a]);
        region_below += below.count[a];
        region_above += above.count[a];
    }
    free(lists.events);

    /* Recurse: the below child is the next node in the array; the above
     * child's index is stored in the node. */
    b->sah_cost += (double)(b->options.traversal_cost * aabb_surface_area(box) * b->root_inverse_area);
    build_node(b, add_node(b), below_box, below, n_below, depth + 1);
    int above_index = add_node(b);
    b->nodes[index].split = p;
    b->nodes[index].bits = ((uint32_t)above_index << 2) | (uint32_t)k;
    build_node(b, above_index, above_box, above, n_above, depth + 1);
}

static void build_node(kd_builder *b, int index, aabb box, event_lists lists, int n, int depth)
{
    /* Make a leaf at the depth limit, or with nothing left to separate. */
    split_choice s = {INFINITY, -1, 0.0f, false};
    float area = aabb_surface_area(box);
    if (n > 0 && depth < b->depth_limit && area > 0.0f)
        s = find_split(b, box, &lists, n);
    /* Stop when the SAH says no split is cheaper than a leaf. */
    if (s.axis < 0 || !(s.cost < b->options.intersection_cost * (float)n)) {
        make_leaf(b, index, &lists, n, box, depth);
        free(lists.events);
        return;
    }
    split_node(b, index, box, lists, n, s, depth);
}

/* ---- the accel interface -------------------------------------------------------- */

/* Defined in kdtree_trace.c. */
extern const accel_ops kdtree_ops;

accel *kdtree_build_with(const triangle_set *set, const kdtree_options *options)
{
    double start = timer_seconds();
    if ((uint32_t)set->count > EVENT_TRIANGLE_MASK)
        abort(); /* more triangles than an event's 30-bit index holds */
    kd_builder b = {0};
    b.set = set;
    b.options = *options;
    b.depth_limit = options->max_depth > 0 ? options->max_depth : kdtree_depth_limit(set->count);
    if (b.depth_limit > KD_MAX_DEPTH)
        b.depth_limit = KD_MAX_DEPTH;
    b.side = memory_allocate((size_t)(set->count > 0 ? set->count : 1), 1);
    b.flat_axes = memory_allocate((size_t)(set->count > 0 ? set->count : 1), 1);

    /* The root's box: of the triangles with finite coordinates. A triangle
     * with a NaN or infinite corner can never be hit by Moller-Trumbore (its
     * products are NaN), so it is left out of the tree altogether. */
    aabb root = aabb_empty();
    int n = 0;
    for (int i = 0; i < set->count; i++)
        if (vec3_is_finite(set->boxes[i].lo) && vec3_is_finite(set->boxes[i].hi)) {
            root = aabb_union(root, set->boxes[i]);
            n++;
        }
    float root_area = aabb_surface_area(root);
    b.root_inverse_area = root_area > 0.0f ? 1.0f / root_area : 0.0f;

    /* Events for every triangle, then one sort per axis. */
    event_lists lists = {allocate_events((size_t)6 * (size_t)n), {0, 0, 0}};
    kd_event *out = lists.events;
    for (int a = 0; a < 3; a++) {
        kd_event *first = out;
        for (int i = 0; i < set->count; i++) {
            aabb box = set->boxes[i];
            if (!(vec3_is_finite(box.lo) && vec3_is_finite(box.hi)))
                continue;
            float lo = vec3_axis(box.lo, a), hi = vec3_axis(box.hi, a);
            b.flat_axes[i] |= (uint8_t)((lo == hi) << a);
            if (lo == hi) {
                *out++ = event_make(lo, EVENT_PLANAR, (uint32_t)i);
            } else {
                *out++ = event_make(lo, EVENT_START, (uint32_t)i);
                *out++ = event_make(hi, EVENT_END, (uint32_t)i);
            }
        }
        lists.count[a] = (int)(out - first);
    }
    /* Scratch for new events: 2 slots per axis per child for each of a
     * node's triangles (all might straddle), plus room to sort one axis. */
    b.scratch = allocate_events((size_t)14 * (size_t)n);
    for (int a = 0, offset = 0; a < 3; offset += lists.count[a], a++)
        events_sort(lists.events + offset, lists.count[a], b.scratch);

    build_node(&b, add_node(&b), root, lists, n, 0);
    free(b.side);
    free(b.flat_axes);
    free(b.scratch);

    kd_tree *tree = memory_allocate(1, sizeof *tree);
    tree->base.ops = &kdtree_ops;
    tree->base.set = set;
    tree->nodes = b.nodes;
    tree->references = b.references;
    tree->bounds = root;
    tree->options = *options;
    tree->depth_limit = b.depth_limit;
    tree->empty_leaves = b.empty_leaves;
    tree->sah_cost = b.sah_cost;
    accel_stats *st = &tree->base.stats;
    st->name = "kd-tree";
    st->nodes = b.node_count;
    st->leaves = b.leaves;
    st->max_depth = b.max_depth;
    st->references = b.reference_count;
    st->bytes = sizeof *tree + (size_t)b.node_count * sizeof(kd_node) + (size_t)b.reference_count * sizeof(uint32_t);
    st->build_seconds = timer_seconds() - start;
    return &tree->base;
}

accel *kdtree_build(const triangle_set *set)
{
    kdtree_options o = kdtree_default_options();
    return kdtree_build_with(set, &o);
}

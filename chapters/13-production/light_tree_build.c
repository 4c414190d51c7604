/* light_tree_build.c -- the light tree's build (light_tree.h): each
 * emitter's bounds, the bounds of a group, the choice of splits, and the
 * nodes written four children to a group. */
#include "13-production/light_tree.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "memory.h"

/* ---- the bounds of a group of emitters ---------------------------------------------- */

/* A cone's spread is widened by this much (radians) where two are merged:
 * the merged axis comes from float rotations, and a normal left a rounding
 * outside the cone would be judged unable to light a point it barely can.
 * A thousandth of a degree costs nothing measurable in the importance. */
static const double CONE_ROUNDING = 2e-5;

/* The angle between two unit vectors, accurate near 0 and pi. */
static double angle_between(vec3 a, vec3 b)
{
    vec3 c = vec3_cross(a, b);
    return atan2((double)vec3_length(c), (double)vec3_dot(a, b));
}

/* The least cone holding two (after pbrt-v4's DirectionCone union): the
 * one that holds the other, else the cone spanning both, its axis turned
 * from a's towards b's; the whole sphere past pi. */
static void cone_union(vec3 axis_a, float cos_a, vec3 axis_b, float cos_b, vec3 *axis, float *cos_out)
{
    if (axis_a.x == axis_b.x && axis_a.y == axis_b.y && axis_a.z == axis_b.z) {
        /* one facing (the lamps of one wall): no trigonometry */
        *axis = axis_a, *cos_out = fminf(cos_a, cos_b);
        return;
    }
    double theta_a = acos(fmin(1.0, fmax(-1.0, (double)cos_a)));
    double theta_b = acos(fmin(1.0, fmax(-1.0, (double)cos_b)));
    double theta_d = angle_between(axis_a, axis_b);
    if (fmin(theta_d + theta_b, PI) <= theta_a) {
        *axis = axis_a, *cos_out = cos_a;
        return;
    }
    if (fmin(theta_d + theta_a, PI) <= theta_b) {
        *axis = axis_b, *cos_out = cos_b;
        return;
    }
    double theta_o = 0.5 * (theta_a + theta_d + theta_b) + CONE_ROUNDING;
    vec3 turn = vec3_cross(axis_a, axis_b);
    if (theta_o >= PI || vec3_length_squared(turn) == 0.0f) {
        *axis = axis_a, *cos_out = -1.0f;
        return;
    }
    /* a's axis turned by theta_o - theta_a about a x b (Rodrigues; the
     * turn axis is perpendicular to a) */
    double theta_r = theta_o - theta_a;
    vec3 k = vec3_normalize(turn);
    *axis = vec3_normalize(vec3_add(vec3_scale(axis_a, (float)cos(theta_r)),
                                    vec3_scale(vec3_cross(k, axis_a), (float)sin(theta_r))));
    *cos_out = (float)cos(theta_o);
}

static light_bounds bounds_union(const light_bounds *a, const light_bounds *b)
{
    if (!(a->power > 0.0f))
        return *b;
    if (!(b->power > 0.0f))
        return *a;
    light_bounds u = {.box = aabb_union(a->box, b->box), .power = a->power + b->power};
    cone_union(a->axis, a->cos_theta_o, b->axis, b->cos_theta_o, &u.axis, &u.cos_theta_o);
    return u;
}

/* The bounds of one emitting triangle: its box, its power, its normal
 * (spread 0), emitting over the hemisphere in front (theta_e = pi/2). */
static light_bounds triangle_bounds(const pt_scene *sc, int slot, float *area)
{
    const triangle *t = &sc->triangles.triangles[sc->emitters[slot]];
    vec3 le = sc->materials[sc->geometry.faces[sc->emitters[slot]].material].emission;
    vec3 cross = vec3_cross(vec3_sub(t->p1, t->p0), vec3_sub(t->p2, t->p0));
    *area = 0.5f * vec3_length(cross);
    light_bounds b = {.box = aabb_add_point(aabb_add_point(aabb_add_point(aabb_empty(), t->p0), t->p1), t->p2),
                      .axis = sc->emitter_normals[slot], .cos_theta_o = 1.0f};
    b.power = *area * ((le.x + le.y + le.z) / 3.0f); /* chapter 09's power: area x mean(L_e) */
    return b;
}

/* ---- the build ----------------------------------------------------------------------
 * Top down, as chapter 06 builds its BVH, one emitter per leaf. A split is
 * chosen among 12 buckets of the emitters' centres along each axis by the
 * cost pbrt-v4 gives a group (its "surface area orientation heuristic"):
 *   Phi x M_omega x A x K_r,
 * its power, the solid angle its cone and theta_e may send light into, its
 * box's area (how often a point is near it) and, against long thin boxes,
 * the box's longest side over its side along the axis. A split of less
 * total cost keeps bright, near, alike-facing emitters together, so that
 * the importance tells the halves apart. */
enum { LIGHT_TREE_BUCKETS = 12 };

/* M_omega: the solid angle, weighted by cosine past theta_o, that a cone
 * of spread theta_o emitting over theta_e lights. */
static double orientation_measure(const light_bounds *b)
{
    double theta_o = acos(fmin(1.0, fmax(-1.0, (double)b->cos_theta_o)));
    double theta_e = PI / 2.0; /* one-sided emitters */
    double theta_w = fmin(theta_o + theta_e, PI), s = sin(theta_o), c = cos(theta_o);
    return 2.0 * PI * (1.0 - c) + PI / 2.0 * (2.0 * theta_w * s - cos(theta_o - 2.0 * theta_w) - 2.0 * theta_o * s + c);
}

static double split_cost(const light_bounds *b, const aabb *parent_box, int axis)
{
    if (!(b->power > 0.0f))
        return 0.0;
    vec3 extent = aabb_extent(*parent_box);
    float along = vec3_axis(extent, axis), longest = vec3_max_component(extent);
    double k_r = along > 0.0f ? (double)longest / along : 1.0;
    return (double)b->power * orientation_measure(b) * (double)aabb_surface_area(b->box) * k_r;
}

typedef struct {
    light_tree *t;
    const light_bounds *leaf; /* each emitter's bounds */
    int *order;               /* the emitters, regrouped as the tree splits them */
} build_state;

static vec3 bounds_centre(const light_bounds *b) { return aabb_centroid(b->box); }

static int bucket_of(float c, float lo, float hi)
{
    int k = hi > lo ? (int)((double)LIGHT_TREE_BUCKETS * (c - lo) / (hi - lo)) : 0;
    return k < 0 ? 0 : k >= LIGHT_TREE_BUCKETS ? LIGHT_TREE_BUCKETS - 1 : k;
}

/* ---- groups of emitters, without trigonometry ----
 * Merging cones one emitter at a time (cone_union) takes inverse
 * trigonometry at each step, and the build merges every emitter a few
 * times per level: for 10,000 lamps most of the build's time. The
 * emitters are leaves, each cone a single normal, so a group's cone is
 * made in two passes instead: its axis the mean of their normals, its
 * spread out to the farthest, cos(theta_o) = min n_i . axis. Not always
 * the narrowest cone, but it holds every normal, and for the lamps of one
 * wall or two it is the narrowest. */

/* A group being gathered: box, power and the sum of normals; then the
 * least cosine to the mean. */
typedef struct {
    light_bounds bounds;
    vec3 normal_sum;
} light_gather;

/* aabb_union() without its NaN-proof fminf and fmaxf (calls into libm
 * here, a fifth of the build's time): the build's boxes hold no NaN. */
static float less_of(float a, float b) { return a < b ? a : b; }
static float more_of(float a, float b) { return a > b ? a : b; }
static aabb box_union(aabb a, aabb b)
{
    aabb u = {{less_of(a.lo.x, b.lo.x), less_of(a.lo.y, b.lo.y), less_of(a.lo.z, b.lo.z)},
              {more_of(a.hi.x, b.hi.x), more_of(a.hi.y, b.hi.y), more_of(a.hi.z, b.hi.z)}};
    return u;
}

static aabb box_add(aabb b, vec3 p) { return box_union(b, (aabb){p, p}); }

static void gather_add(light_gather *g, const light_bounds *leaf)
{
    g->bounds.box = g->bounds.power > 0.0f ? box_union(g->bounds.box, leaf->box) : leaf->box;
    g->bounds.power += leaf->power;
    g->normal_sum = vec3_add(g->normal_sum, leaf->axis);
}

/* The axis from the sum (the first normal where the sum vanishes). */
static void gather_axis(light_gather *g, const light_bounds *first)
{
    float length = vec3_length(g->normal_sum);
    g->bounds.axis = length > 0.0f ? vec3_scale(g->normal_sum, 1.0f / length) : first->axis;
    g->bounds.cos_theta_o = 1.0f;
}

static void gather_spread(light_gather *g, const light_bounds *leaf)
{
    g->bounds.cos_theta_o = less_of(g->bounds.cos_theta_o, more_of(-1.0f, vec3_dot(g->bounds.axis, leaf->axis)));
}

/* The bounds of order[begin, end). */
static light_bounds range_bounds(const build_state *s, int begin, int end)
{
    light_gather g = {0};
    for (int i = begin; i < end; i++)
        gather_add(&g, &s->leaf[s->order[i]]);
    gather_axis(&g, &s->leaf[s->order[begin]]);
    for (int i = begin; i < end; i++)
        gather_spread(&g, &s->leaf[s->order[i]]);
    return g.bounds;
}

/* The bounds a node of order[begin, end) keeps: the narrower of the cone
 * about the mean (range_bounds) and the one cone_union() merges emitter by
 * emitter, which is narrower where the normals are few and far apart
 * (emitters facing every way: a pick refused a tenth as often far from
 * them). Once per node, so the trigonometry costs little. */
static light_bounds node_bounds(const build_state *s, int begin, int end)
{
    light_bounds mean = range_bounds(s, begin, end), merged = {0};
    for (int i = begin; i < end; i++)
        merged = bounds_union(&merged, &s->leaf[s->order[i]]);
    return merged.cos_theta_o > mean.cos_theta_o ? merged : mean;
}

/* The cheapest bucket split of order[begin, end): its axis and the last
 * bucket of the first half in *axis, *last; false if the centres all
 * coincide (nothing to split by place). */
static bool best_split(const build_state *s, int begin, int end, const aabb *box, int *axis, int *last)
{
    aabb centres = aabb_empty();
    for (int i = begin; i < end; i++)
        centres = box_add(centres, bounds_centre(&s->leaf[s->order[i]]));
    double best = INFINITY;
    for (int a = 0; a < 3; a++) {
        float lo = vec3_axis(centres.lo, a), hi = vec3_axis(centres.hi, a);
        if (!(hi > lo))
            continue;
        light_gather gather[LIGHT_TREE_BUCKETS];
        const light_bounds *first[LIGHT_TREE_BUCKETS] = {NULL};
        memset(gather, 0, sizeof gather);
        for (int i = begin; i < end; i++) {
            const light_bounds *b = &s->leaf[s->order[i]];
            int k = bucket_of(vec3_axis(bounds_centre(b), a), lo, hi);
            gather_add(&gather[k], b);
            first[k] = first[k] != NULL ? first[k] : b;
        }
        for (int k = 0; k < LIGHT_TREE_BUCKETS; k++)
            if (first[k] != NULL)
                gather_axis(&gather[k], first[k]);
        for (int i = begin; i < end; i++) {
            const light_bounds *b = &s->leaf[s->order[i]];
            gather_spread(&gather[bucket_of(vec3_axis(bounds_centre(b), a), lo, hi)], b);
        }
        light_bounds bucket[LIGHT_TREE_BUCKETS];
        for (int k = 0; k < LIGHT_TREE_BUCKETS; k++)
            bucket[k] = gather[k].bounds;
        light_bounds below[LIGHT_TREE_BUCKETS];
        below[0] = bucket[0];
        for (int k = 1; k < LIGHT_TREE_BUCKETS; k++)
            below[k] = bounds_union(&below[k - 1], &bucket[k]);
        light_bounds above = bucket[LIGHT_TREE_BUCKETS - 1];
        for (int k = LIGHT_TREE_BUCKETS - 2; k >= 0; k--) {
            double cost = split_cost(&below[k], box, a) + split_cost(&above, box, a);
            if (below[k].power > 0.0f && above.power > 0.0f && cost < best)
                best = cost, *axis = a, *last = k;
            above = bounds_union(&above, &bucket[k]);
        }
    }
    return best < INFINITY;
}

/* An emitter and its centre's coordinate along the axis a split sorts by. */
typedef struct {
    float key;
    int light;
} keyed_light;

static int compare_keys(const void *a, const void *b)
{
    float ka = ((const keyed_light *)a)->key, kb = ((const keyed_light *)b)->key;
    return (ka > kb) - (ka < kb);
}

/* order[begin, end) sorted by their centres along `axis`. */
static void sort_along(build_state *s, int begin, int end, int axis)
{
    int n = end - begin;
    keyed_light *keyed = memory_allocate((size_t)n, sizeof *keyed);
    for (int i = 0; i < n; i++)
        keyed[i] = (keyed_light){vec3_axis(bounds_centre(&s->leaf[s->order[begin + i]]), axis), s->order[begin + i]};
    qsort(keyed, (size_t)n, sizeof *keyed, compare_keys);
    for (int i = 0; i < n; i++)
        s->order[begin + i] = keyed[i].light;
    free(keyed);
}

/* Where order[begin, end) is cut in two: by the cheapest bucket split,
 * or, deep down or where the centres coincide, in half by count along the
 * box's longest axis. */
static int split_point(build_state *s, int begin, int end, const aabb *box, int depth)
{
    int axis, last;
    if (depth < LIGHT_TREE_BALANCED_DEPTH && best_split(s, begin, end, box, &axis, &last)) {
        aabb centres = aabb_empty();
        for (int i = begin; i < end; i++)
            centres = box_add(centres, bounds_centre(&s->leaf[s->order[i]]));
        float lo = vec3_axis(centres.lo, axis), hi = vec3_axis(centres.hi, axis);
        int mid = begin;
        for (int i = begin; i < end; i++)
            if (bucket_of(vec3_axis(bounds_centre(&s->leaf[s->order[i]]), axis), lo, hi) <= last) {
                int swap = s->order[i];
                s->order[i] = s->order[mid];
                s->order[mid++] = swap;
            }
        return mid;
    }
    sort_along(s, begin, end, aabb_longest_axis(*box));
    return begin + (end - begin) / 2;
}

/* A 16-bit fraction of 32767: the nearest, or the one at or below. */
static int16_t snorm16(float x, bool down)
{
    float scaled = fminf(1.0f, fmaxf(-1.0f, x)) * 32767.0f;
    return (int16_t)(down ? floorf(scaled) : lrintf(scaled));
}

/* How much the bounding sphere's radius is widened: the centre and the
 * length of the diagonal each round (a few ulps, parts in 10⁷), and a
 * sphere that rounds short could leave an emitter's corner outside, so the
 * importance would underrate it. A part in a million covers them. */
#define LIGHT_TREE_RADIUS_SLACK 1e-6f

/* The node the walk reads, from the bounds: the box's bounding sphere
 * (its radius widened by LIGHT_TREE_RADIUS_SLACK), the cone packed
 * (light_tree_node). */
static light_tree_node node_from(const light_bounds *b, int32_t index)
{
    vec3 centre = aabb_centroid(b->box);
    light_tree_node node = {.centre = {centre.x, centre.y, centre.z},
                            .radius = 0.5f * vec3_length(aabb_extent(b->box)) * (1.0f + LIGHT_TREE_RADIUS_SLACK),
                            .power = b->power, .cos_theta_o = snorm16(b->cos_theta_o, true), .index = index};
    node.axis[0] = snorm16(b->axis.x, false);
    node.axis[1] = snorm16(b->axis.y, false);
    node.axis[2] = snorm16(b->axis.z, false);
    return node;
}

/* The emitters order[begin, end) cut into at most LIGHT_TREE_WIDTH groups
 * (two cuts of the binary build, then each half cut again): their ends
 * into end_of[], the count returned. */
static int split_four(build_state *s, int begin, int end, const aabb *box, int depth, int end_of[LIGHT_TREE_WIDTH])
{
    int mid = split_point(s, begin, end, box, depth), count = 0;
    int range[2][2] = {{begin, mid}, {mid, end}};
    for (int h = 0; h < 2; h++) {
        int b = range[h][0], e = range[h][1];
        if (e - b == 1) {
            end_of[count++] = e;
            continue;
        }
        light_bounds half = range_bounds(s, b, e);
        end_of[count++] = split_point(s, b, e, &half.box, depth + 1);
        end_of[count++] = e;
    }
    return count;
}

/* Node number `node` of the tree set to `value`. */
static void node_set(light_tree *t, int node, light_tree_node value)
{
    light_tree_group *g = &t->groups[node / LIGHT_TREE_WIDTH];
    int k = node % LIGHT_TREE_WIDTH;
    for (int c = 0; c < 3; c++) {
        g->centre[c][k] = value.centre[c];
        g->axis[c][k] = value.axis[c];
    }
    g->radius[k] = value.radius;
    g->power[k] = value.power;
    g->cos_theta_o[k] = value.cos_theta_o;
    g->index[k] = value.index;
}

/* The group at `first` holds the emitters order[begin, end): one child
 * each if they are few enough, else up to LIGHT_TREE_WIDTH subtrees, each
 * an inner node whose own group is the next free one. */
static void build_group(build_state *s, int begin, int end, int first, int parent, int depth)
{
    light_tree *t = s->t;
    int end_of[LIGHT_TREE_WIDTH], count;
    if (end - begin <= LIGHT_TREE_WIDTH) {
        count = end - begin;
        for (int k = 0; k < count; k++)
            end_of[k] = begin + k + 1;
    } else {
        light_bounds all = range_bounds(s, begin, end);
        count = split_four(s, begin, end, &all.box, depth, end_of);
    }
    for (int k = 0, b = begin; k < count; b = end_of[k++]) {
        int node = first + k, e = end_of[k];
        t->parent[node] = parent;
        if (e - b == 1) {
            node_set(t, node, node_from(&s->leaf[s->order[b]], -1 - s->order[b]));
            t->leaf_of_light[s->order[b]] = node;
            continue;
        }
        light_bounds group = node_bounds(s, b, e);
        int child_group = t->node_count;
        t->node_count += LIGHT_TREE_WIDTH;
        node_set(t, node, node_from(&group, child_group));
        build_group(s, b, e, child_group, node, depth + 2);
    }
}

void light_tree_build(light_tree *t, const pt_scene *sc)
{
    int n = sc->emitter_count;
    memset(t, 0, sizeof *t);
    t->light_count = n;
    t->triangle_count = sc->triangles.count;
    t->light_of_triangle = memory_allocate((size_t)(t->triangle_count > 0 ? t->triangle_count : 1), sizeof(int));
    for (int i = 0; i < t->triangle_count; i++)
        t->light_of_triangle[i] = -1;
    if (n == 0)
        return;
    /* a group per inner node and one for the root's children: fewer than
     * n groups, each on two 64-byte lines of its own */
    size_t slots = (size_t)LIGHT_TREE_WIDTH * (size_t)(n + 1);
    size_t bytes = (size_t)(n + 1) * sizeof *t->groups;
    t->groups = aligned_alloc(64, bytes);
    if (t->groups == NULL) {
        fprintf(stderr, "out of memory (%zu bytes for the light tree)\n", bytes);
        exit(1);
    }
    memset(t->groups, 0, bytes);
    t->parent = memory_allocate(slots, sizeof(int));
    t->leaf_of_light = memory_allocate((size_t)n, sizeof(int));
    t->area = memory_allocate((size_t)n, sizeof(float));
    light_bounds *leaf = memory_allocate((size_t)n, sizeof *leaf);
    build_state s = {.t = t, .leaf = leaf, .order = memory_allocate((size_t)n, sizeof(int))};
    for (int i = 0; i < n; i++) {
        leaf[i] = triangle_bounds(sc, i, &t->area[i]);
        t->light_of_triangle[sc->emitters[i]] = i;
        s.order[i] = i;
    }
    t->node_count = LIGHT_TREE_WIDTH;
    build_group(&s, 0, n, 0, -1, 0);
    free(s.order);
    free(leaf);
}

void light_tree_free(light_tree *t)
{
    free(t->groups);
    free(t->parent);
    free(t->leaf_of_light);
    free(t->light_of_triangle);
    free(t->area);
    memset(t, 0, sizeof *t);
}

/* light_tree.c -- the light tree (light_tree.h): its bounds, its build
 * and its walk. */
#include "13-production/light_tree.h"

#include <float.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "memory.h"

/* ---- the importance of a node at a point -----------------------------------------
 * An emitter of power Phi at distance d, seen at theta' from its normal,
 * lighting a surface at theta_i from its normal, sends it about
 *   Phi cos(theta') cos(theta_i) / d^2.
 * For a node, each factor is bounded over what the node may hold: d from
 * the box's centre (no less than half its diagonal, so that a point inside
 * gets a finite bound); theta' no less than the angle from the cone's axis
 * to p, less the cone's spread theta_o and the angle theta_b the box
 * subtends from p; theta_i no less than the angle from n to the box's
 * centre less theta_b. An angle that cannot go below 0 is taken as 0.
 * The emitters send nothing past theta_e, and the surface receives nothing
 * from below (the light sample adds nothing there), so those bounds give 0. */

/* cos and sin of max(0, a - b), from the cosines and sines of a and b:
 * no inverse trigonometry on the walk. */
static void angle_less(float cos_a, float sin_a, float cos_b, float sin_b, float *cos_out, float *sin_out)
{
    if (cos_a >= cos_b) { /* a <= b */
        *cos_out = 1.0f;
        *sin_out = 0.0f;
        return;
    }
    *cos_out = cos_a * cos_b + sin_a * sin_b;
    *sin_out = sin_a * cos_b - cos_a * sin_b;
}

static float sin_of(float cos_a) { return sqrtf(fmaxf(0.0f, 1.0f - cos_a * cos_a)); }

/* How far past grazing (as a cosine) an emitter's bound may look and
 * still count: the cone's axis is stored to 3e-5 radians and the cosines
 * below round, and an emitter the bound called unable to light a point it
 * barely lights would never be picked there (a bias on the rungs without
 * MIS). 1e-3 radians covers both many times; the emitters it lets in
 * send next to nothing, and get an importance to match. */
static const float LIGHT_TREE_GRAZING = 1e-3f;

static const float SNORM16 = 1.0f / 32767.0f;

float light_node_importance(const light_tree_node *node, vec3 p, vec3 n)
{
    vec3 from_centre = vec3_make(p.x - node->centre[0], p.y - node->centre[1], p.z - node->centre[2]);
    float d2 = vec3_length_squared(from_centre), radius2 = node->radius * node->radius;
    /* Inside the bounding sphere every direction is possible: only the
     * distance bound is left. */
    if (d2 <= radius2)
        return node->power / fmaxf(radius2, FLT_MIN);
    float inverse_d = 1.0f / sqrtf(d2);
    vec3 towards_p = vec3_scale(from_centre, inverse_d);
    float sin_b = node->radius * inverse_d, cos_b = sqrtf(fmaxf(0.0f, 1.0f - sin_b * sin_b));
    /* theta' = theta_w - theta_o - theta_b, at the emitters */
    vec3 axis = vec3_scale(vec3_make(node->axis[0], node->axis[1], node->axis[2]), SNORM16);
    float cos_o = (float)node->cos_theta_o * SNORM16;
    float cos_w = vec3_dot(axis, towards_p), cos_x, sin_x, cos_light, sin_light;
    angle_less(cos_w, sin_of(cos_w), cos_o, sin_of(cos_o), &cos_x, &sin_x);
    angle_less(cos_x, sin_x, cos_b, sin_b, &cos_light, &sin_light);
    if (cos_light < -LIGHT_TREE_GRAZING) /* past theta_e = pi/2 */
        return 0.0f;
    float importance = node->power * fmaxf(cos_light, LIGHT_TREE_GRAZING) / d2;
    /* theta_i' = theta_i - theta_b, at the surface (one-sided: the light
     * sample adds only above it) */
    if (n.x != 0.0f || n.y != 0.0f || n.z != 0.0f) {
        float cos_i = -vec3_dot(n, towards_p), cos_surface, sin_surface;
        angle_less(cos_i, sin_of(cos_i), cos_b, sin_b, &cos_surface, &sin_surface);
        importance = cos_surface > 0.0f ? importance * cos_surface : 0.0f;
    }
    return importance;
}

/* ---- the walk ---------------------------------------------------------------------
 * The nodes come in groups of LIGHT_TREE_WIDTH, the children of one node
 * (an empty place has power 0, so importance 0); the first group is the
 * root's. At each level the walk takes child k of its group with
 * probability I_k / (I_0 + I_1 + I_2 + I_3), the importances at p, and
 * stretches the pick's number u back onto [0, 1) within the part it fell
 * in, so one number serves every level. Four children a level, not two:
 * a level's importances are independent of one another and overlap in the
 * processor, while the levels wait on each other, so half as many levels
 * take about half the time. The sample and the pmf compute each choice by
 * the same expressions, so the pmf is the sample's product, bit for bit. */

#if defined(__SSE2__)
/* light_node_importance() for the four nodes of a group at once, one per
 * SSE lane: the same operations in the same order (sqrtps and divps round
 * as sqrtf and / do; max of two numbers, never NaN here, as fmaxf), so
 * the same bits (test_light_tree_group_is_its_nodes_importance); both
 * branches of each choice computed and one kept per lane. A group's four
 * importances cost about one node's. */
static __m128 select_ps(__m128 mask, __m128 a, __m128 b) { return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b)); }

/* angle_less() in four lanes: cos and sin of max(0, a - b). */
static void angle_less4(__m128 cos_a, __m128 sin_a, __m128 cos_b, __m128 sin_b, __m128 *cos_out, __m128 *sin_out)
{
    __m128 a_within_b = _mm_cmpge_ps(cos_a, cos_b);
    __m128 c = _mm_add_ps(_mm_mul_ps(cos_a, cos_b), _mm_mul_ps(sin_a, sin_b));
    __m128 s = _mm_sub_ps(_mm_mul_ps(sin_a, cos_b), _mm_mul_ps(cos_a, sin_b));
    *cos_out = select_ps(a_within_b, _mm_set1_ps(1.0f), c);
    *sin_out = select_ps(a_within_b, _mm_setzero_ps(), s);
}

static __m128 sin_of4(__m128 cos_a)
{
    return _mm_sqrt_ps(_mm_max_ps(_mm_setzero_ps(), _mm_sub_ps(_mm_set1_ps(1.0f), _mm_mul_ps(cos_a, cos_a))));
}

static __m128 dot4(__m128 ax, __m128 ay, __m128 az, __m128 bx, __m128 by, __m128 bz)
{
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ax, bx), _mm_mul_ps(ay, by)), _mm_mul_ps(az, bz));
}

/* Four 16-bit fractions as floats (sign-extended by a shift). */
static __m128 snorm4(const int16_t *v)
{
    __m128i x = _mm_loadl_epi64((const __m128i *)(const void *)v);
    return _mm_cvtepi32_ps(_mm_srai_epi32(_mm_unpacklo_epi16(x, x), 16));
}

static float group_importances(const light_tree_group *group, vec3 p, vec3 n, float importance[LIGHT_TREE_WIDTH])
{
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f), snorm = _mm_set1_ps(SNORM16);
    __m128 fx = _mm_sub_ps(_mm_set1_ps(p.x), _mm_load_ps(group->centre[0]));
    __m128 fy = _mm_sub_ps(_mm_set1_ps(p.y), _mm_load_ps(group->centre[1]));
    __m128 fz = _mm_sub_ps(_mm_set1_ps(p.z), _mm_load_ps(group->centre[2]));
    __m128 radius = _mm_load_ps(group->radius), power = _mm_load_ps(group->power);
    __m128 d2 = dot4(fx, fy, fz, fx, fy, fz), radius2 = _mm_mul_ps(radius, radius);
    __m128 inside = _mm_cmple_ps(d2, radius2);
    __m128 inside_value = _mm_div_ps(power, _mm_max_ps(radius2, _mm_set1_ps(FLT_MIN)));
    __m128 inverse_d = _mm_div_ps(one, _mm_sqrt_ps(d2));
    __m128 tx = _mm_mul_ps(fx, inverse_d), ty = _mm_mul_ps(fy, inverse_d), tz = _mm_mul_ps(fz, inverse_d);
    __m128 sin_b = _mm_mul_ps(radius, inverse_d);
    __m128 cos_b = _mm_sqrt_ps(_mm_max_ps(zero, _mm_sub_ps(one, _mm_mul_ps(sin_b, sin_b))));
    __m128 ax = _mm_mul_ps(snorm4(group->axis[0]), snorm), ay = _mm_mul_ps(snorm4(group->axis[1]), snorm);
    __m128 az = _mm_mul_ps(snorm4(group->axis[2]), snorm), cos_o = _mm_mul_ps(snorm4(group->cos_theta_o), snorm);
    __m128 cos_w = dot4(ax, ay, az, tx, ty, tz), cos_x, sin_x, cos_light, sin_light;
    angle_less4(cos_w, sin_of4(cos_w), cos_o, sin_of4(cos_o), &cos_x, &sin_x);
    angle_less4(cos_x, sin_x, cos_b, sin_b, &cos_light, &sin_light);
    __m128 facing = _mm_cmpge_ps(cos_light, _mm_set1_ps(-LIGHT_TREE_GRAZING));
    __m128 value = _mm_div_ps(_mm_mul_ps(power, _mm_max_ps(cos_light, _mm_set1_ps(LIGHT_TREE_GRAZING))), d2);
    value = _mm_and_ps(facing, value);
    if (n.x != 0.0f || n.y != 0.0f || n.z != 0.0f) {
        __m128 cos_i = _mm_sub_ps(zero, dot4(_mm_set1_ps(n.x), _mm_set1_ps(n.y), _mm_set1_ps(n.z), tx, ty, tz));
        __m128 cos_surface, sin_surface;
        angle_less4(cos_i, sin_of4(cos_i), cos_b, sin_b, &cos_surface, &sin_surface);
        value = _mm_and_ps(_mm_cmpgt_ps(cos_surface, zero), _mm_mul_ps(value, cos_surface));
    }
    _mm_storeu_ps(importance, select_ps(inside, inside_value, value));
    return (importance[0] + importance[1]) + (importance[2] + importance[3]);
}
#else
#endif

/* Node k of a group, as one struct. */
static light_tree_node group_node(const light_tree_group *g, int k)
{
    light_tree_node node = {.centre = {g->centre[0][k], g->centre[1][k], g->centre[2][k]}, .radius = g->radius[k],
                            .power = g->power[k], .axis = {g->axis[0][k], g->axis[1][k], g->axis[2][k]},
                            .cos_theta_o = g->cos_theta_o[k], .index = g->index[k]};
    return node;
}

light_tree_node light_tree_node_at(const light_tree *t, int node)
{
    return group_node(&t->groups[node / LIGHT_TREE_WIDTH], node % LIGHT_TREE_WIDTH);
}

#if !defined(__SSE2__)
/* The importances of a group at p, and their sum (in one order). */
static float group_importances(const light_tree_group *group, vec3 p, vec3 n, float importance[LIGHT_TREE_WIDTH])
{
    for (int k = 0; k < LIGHT_TREE_WIDTH; k++) {
        light_tree_node node = group_node(group, k);
        importance[k] = light_node_importance(&node, p, n);
    }
    return (importance[0] + importance[1]) + (importance[2] + importance[3]);
}
#endif

float light_tree_group_importances(const light_tree *t, int first, vec3 p, vec3 n, float importance[LIGHT_TREE_WIDTH])
{
    return group_importances(&t->groups[first / LIGHT_TREE_WIDTH], p, n, importance);
}

/* Child k of a group, by u (in [0, 1), in double: it is divided at each
 * level), stretched in place; -1 if no child has any importance. */
static int choose_child(const float importance[LIGHT_TREE_WIDTH], float sum, double *u)
{
    if (!(sum > 0.0f))
        return -1;
    double below = 0.0, target = *u * (double)sum;
    int k = 0, last = 0;
    for (; k < LIGHT_TREE_WIDTH; k++) {
        if (importance[k] > 0.0f)
            last = k;
        if (target < below + (double)importance[k])
            break;
        below += (double)importance[k];
    }
    if (k == LIGHT_TREE_WIDTH) { /* u rounded past the last: the last child that can be picked */
        k = last;
        below -= (double)importance[k];
    }
    *u = fmin(fmax((target - below) / (double)importance[k], 0.0), 0x1.fffffffffffffp-1);
    return k;
}

int light_tree_sample(const light_tree *t, vec3 p, vec3 n, float u, float *pmf)
{
    *pmf = 0.0f;
    if (t->light_count == 0)
        return -1;
    double v = u;
    float product = 1.0f, importance[LIGHT_TREE_WIDTH];
    int first = 0, node;
    for (;;) {
        const light_tree_group *group = &t->groups[first / LIGHT_TREE_WIDTH];
        float sum = group_importances(group, p, n, importance);
        int k = choose_child(importance, sum, &v);
        if (k < 0)
            return -1; /* no child can light p */
        product *= importance[k] / sum;
        node = first + k;
        if (group->index[k] < 0)
            break;
        first = group->index[k];
    }
    if (!(product > 0.0f))
        return -1; /* a choice of probability below float's range: the pmf says 0 too */
    *pmf = product;
    return -1 - t->groups[node / LIGHT_TREE_WIDTH].index[node % LIGHT_TREE_WIDTH];
}

float light_tree_pmf(const light_tree *t, vec3 p, vec3 n, int slot)
{
    if (slot < 0 || slot >= t->light_count)
        return 0.0f;
    /* the way from the top to the leaf, found from the leaf up */
    int way[LIGHT_TREE_MAX_DEPTH + 1], depth = 0;
    for (int node = t->leaf_of_light[slot]; node >= 0; node = t->parent[node])
        way[depth++] = node;
    float product = 1.0f, importance[LIGHT_TREE_WIDTH];
    for (int level = depth - 1; level >= 0; level--) {
        int node = way[level], first = node - node % LIGHT_TREE_WIDTH;
        float sum = group_importances(&t->groups[first / LIGHT_TREE_WIDTH], p, n, importance);
        if (!(sum > 0.0f))
            return 0.0f;
        product *= importance[node - first] / sum;
    }
    return product > 0.0f ? product : 0.0f;
}

bool light_tree_sample_light(const light_tree *t, const pt_scene *sc, vec3 p, vec3 n, float u_pick, float u1, float u2,
                             pt_light_sample *x)
{
    float pmf;
    int slot = light_tree_sample(t, p, n, u_pick, &pmf);
    if (slot < 0)
        return false;
    int material;
    pt_scene_emitter_point(sc, slot, u1, u2, &x->point, &x->point_error, &x->normal, &material);
    x->emission = sc->materials[material].emission;
    x->pdf_light = pmf / t->area[slot];
    return true;
}

float light_tree_pdf_area(const light_tree *t, vec3 p, vec3 n, int triangle)
{
    if (triangle < 0 || triangle >= t->triangle_count || t->light_of_triangle[triangle] < 0)
        return 0.0f;
    int slot = t->light_of_triangle[triangle];
    return light_tree_pmf(t, p, n, slot) / t->area[slot];
}

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

/* The cheapest bucket split of order[begin, end): its axis and the last
 * bucket of the first half in *axis, *last; false if the centres all
 * coincide (nothing to split by place). */
static bool best_split(const build_state *s, int begin, int end, const aabb *box, int *axis, int *last)
{
    aabb centres = aabb_empty();
    for (int i = begin; i < end; i++)
        centres = aabb_add_point(centres, bounds_centre(&s->leaf[s->order[i]]));
    double best = INFINITY;
    for (int a = 0; a < 3; a++) {
        float lo = vec3_axis(centres.lo, a), hi = vec3_axis(centres.hi, a);
        if (!(hi > lo))
            continue;
        light_bounds bucket[LIGHT_TREE_BUCKETS];
        memset(bucket, 0, sizeof bucket);
        for (int i = begin; i < end; i++) {
            const light_bounds *b = &s->leaf[s->order[i]];
            int k = bucket_of(vec3_axis(bounds_centre(b), a), lo, hi);
            bucket[k] = bounds_union(&bucket[k], b);
        }
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
            centres = aabb_add_point(centres, bounds_centre(&s->leaf[s->order[i]]));
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

/* The node the walk reads, from the bounds: the box's bounding sphere
 * (its radius a part in a million over, for the rounding of centre and
 * length), the cone packed (light_tree_node). */
static light_tree_node node_from(const light_bounds *b, int32_t index)
{
    vec3 centre = aabb_centroid(b->box);
    light_tree_node node = {.centre = {centre.x, centre.y, centre.z},
                            .radius = 0.5f * vec3_length(aabb_extent(b->box)) * (1.0f + 1e-6f),
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
        light_bounds half = {0};
        for (int i = b; i < e; i++)
            half = bounds_union(&half, &s->leaf[s->order[i]]);
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
        light_bounds all = {0};
        for (int i = begin; i < end; i++)
            all = bounds_union(&all, &s->leaf[s->order[i]]);
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
        light_bounds group = {0};
        for (int i = b; i < e; i++)
            group = bounds_union(&group, &s->leaf[s->order[i]]);
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

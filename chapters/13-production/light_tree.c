/* light_tree.c -- the light tree (light_tree.h): the importance of a node
 * and the walk down (the build is light_tree_build.c). */
#include "13-production/light_tree.h"

#include <float.h>
#include <math.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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
static __m128 select_ps(__m128 mask, __m128 a, __m128 b)
{
    return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}

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

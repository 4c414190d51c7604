/* light_tree.h -- picking one of many lights by what it can give a point.
 *
 * Chapter 09 picks an emitting triangle in proportion to its power, the
 * same choice at every shading point. With thousands of emitters most of
 * them are far, turned away or below the surface, and a sample spent on
 * one of those adds nothing. The light tree (after pbrt-v4's BVH light
 * sampler and Conty and Kulla's many-lights tree) groups the emitters in
 * a tree of four children per node; each node bounds its emitters' power,
 * place (a box) and facing (a cone of normals). A pick walks from the
 * root, choosing a child
 * in proportion to an importance: the most its emitters could send to the
 * point (power, over the squared distance, times the best cosines the
 * bounds allow at the light and at the surface). The probability of the
 * emitter reached is the product of the choices on its way; the point on
 * it is uniform, as in chapter 09, so its density per unit area is that
 * product over its area.
 *
 * The tree only changes which emitter is picked and with what
 * probability: the light sample's physics stays chapter 09's
 * (light_transport.h). Point lights are summed at every vertex, as
 * chapter 09 does, and are not in the tree; neither are emitting spheres
 * nor the environment, which only rays that meet them count.
 *
 * Usage (pbrt's triad: sample, and the probability of what was sampled):
 *   light_tree t;
 *   light_tree_build(&t, &scene);             after pt_scene_finish
 *   pt_light_sample x;
 *   if (light_tree_sample_light(&t, &scene, p, n, u_pick, u1, u2, &x)) ... x.pdf_light per unit area
 *   float pdf = light_tree_pdf_area(&t, p, n, triangle);   the same, for a point a BSDF ray found
 *   light_tree_free(&t);
 */
#ifndef LIGHT_TREE_H
#define LIGHT_TREE_H

#include <stdbool.h>
#include <stdint.h>

#include "03-aabb-slabs/aabb.h"
#include "09-path-tracing/scene_pt.h"

/* What a node knows of its emitters: their total power (area x mean L_e,
 * chapter 09's measure), a box around them, and a cone around their
 * normals (every normal within theta_o of `axis`). Every emitter here is
 * one-sided (scene_pt.h): each emits within theta_e = pi/2 of its normal.
 * What the build works with; the walk reads the nodes below. */
typedef struct {
    aabb box;
    vec3 axis;
    float cos_theta_o;
    float power;
} light_bounds;

/* A node: its box as its bounding sphere; the cone's axis and cosine as
 * 16-bit fractions of 32767, the cosine rounded down (the cone only
 * widens), the axis to the nearest (off by at most 3e-5 radians, within
 * the importance's LIGHT_TREE_GRAZING). An empty place has power 0. */
typedef struct {
    float centre[3], radius;
    float power;
    int16_t axis[3], cos_theta_o;
    int32_t index; /* an inner node: its children's first node; a leaf: -1 - its emitter */
} light_tree_node;

/* Children per node. */
enum { LIGHT_TREE_WIDTH = 4 };

/* The children of one node as the walk reads them: each field of the four
 * side by side (one SSE load), 128 bytes, two cache lines. Node k of
 * group g is node number LIGHT_TREE_WIDTH g + k. */
typedef struct {
    float centre[3][LIGHT_TREE_WIDTH], radius[LIGHT_TREE_WIDTH], power[LIGHT_TREE_WIDTH];
    int16_t axis[3][LIGHT_TREE_WIDTH], cos_theta_o[LIGHT_TREE_WIDTH];
    int32_t index[LIGHT_TREE_WIDTH];
} light_tree_group;
_Static_assert(sizeof(light_tree_group) == 128, "a group is two 64-byte lines");

typedef struct {
    light_tree_group *groups; /* groups[0]: the root's children */
    int *parent;            /* each node's parent (-1 in the first group) */
    int node_count, light_count; /* node_count: places in groups, empty ones too */
    int *leaf_of_light;     /* an emitter slot's leaf */
    int *light_of_triangle; /* a triangle's emitter slot, -1 if it does not emit */
    float *area;            /* each emitter's area */
    int triangle_count;
} light_tree;

/* Node number `node` of the tree, as one struct. */
light_tree_node light_tree_node_at(const light_tree *t, int node);

/* Chapter 13's renderer picks by the tree from this many emitting
 * triangles on (path_tracer_wide.h); below, by power, as chapter 09.
 * Measured roughly (relative error squared x CPU time, 96 x 96 at 64 spp,
 * one thread, a shared machine): the Cornell box's 2 emitting triangles
 * cost 30 % more with the tree (a walk, where both are alike), Veach's 8
 * tied, the many-lights box's 10,208 won (README). */
enum { LIGHT_TREE_MIN_EMITTERS = 16 };

/* The deepest leaf: splits that balance power, place and facing may be
 * lopsided; past LIGHT_TREE_BALANCED_DEPTH the build halves by count, so
 * a leaf is at most that plus log2(2^31) deep. */
enum { LIGHT_TREE_BALANCED_DEPTH = 40, LIGHT_TREE_MAX_DEPTH = LIGHT_TREE_BALANCED_DEPTH + 32 };

/* The tree over the scene's emitting triangles (sc->emitters, after
 * pt_scene_finish). Empty (node_count 0) if there are none. */
void light_tree_build(light_tree *t, const pt_scene *sc);
void light_tree_free(light_tree *t);

/* The most a node's emitters could send to the point p of normal n (n = 0:
 * a point in space, no surface): power / d^2 x cos(theta') x cos(theta_i'),
 * where theta' is the least angle the cone allows between a normal and the
 * direction to p, and theta_i' the least angle the bounding sphere allows
 * between n and a direction into it. 0 only where no emitter can reach
 * p's front. */
float light_node_importance(const light_tree_node *node, vec3 p, vec3 n);

/* The importances of the group of nodes from `first` at p (four at once,
 * in SSE where the processor has it: the same bits as
 * light_node_importance() of each), and their sum: what the walk reads. */
float light_tree_group_importances(const light_tree *t, int first, vec3 p, vec3 n, float importance[LIGHT_TREE_WIDTH]);

/* One emitter picked for the point p of normal n with the number u in
 * [0, 1): its slot, and its probability in *pmf; -1 (pmf 0) where no
 * emitter can light p. */
int light_tree_sample(const light_tree *t, vec3 p, vec3 n, float u, float *pmf);

/* The probability light_tree_sample() picks emitter `slot` for p and n:
 * the same product, bit for bit. */
float light_tree_pmf(const light_tree *t, vec3 p, vec3 n, int slot);

/* pt_scene_sample_light() with the emitter picked by the tree: a uniform
 * point on it, x->pdf_light = pmf / area. False where no emitter can
 * light p. */
bool light_tree_sample_light(const light_tree *t, const pt_scene *sc, vec3 p, vec3 n, float u_pick, float u1, float u2,
                             pt_light_sample *x);

/* The density per unit area with which light_tree_sample_light() picks a
 * point of triangle `triangle` for p and n: its pmf over its area (0 if
 * the triangle is not an emitter). What MIS weighs emission against. */
float light_tree_pdf_area(const light_tree *t, vec3 p, vec3 n, int triangle);

#endif

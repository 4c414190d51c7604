/* walls.c -- a shortcut that pays on rooms: walls cast no shadows.
 * See walls.h. */
#include "13-production/walls.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "13-production/wide_bvh.h"
#include "13-production/flat.h"
#include "13-production/light_tree.h"
#include "memory.h"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

/* Four wall planes, structure of arrays (one group is tested at once): a
 * point p lies in front of plane j if
 *   normal . p - offset > slack . |p| + slack_constant
 * where the right side bounds the rounding of the left (below). An unused
 * lane has normal 0 and offset -1: every point is in front of it. */
typedef struct {
    float normal[3][4], offset[4];
    float slack[3][4], slack_constant[4];
} wall_planes4;

struct walls_accel {
    accel base;          /* set: every triangle of the scene */
    accel *all;          /* production_accel_build() of every triangle */
    int wall_count;      /* triangles */
    wall_planes4 *wall_planes;
    int wall_plane_count, wall_group_count;
    triangle_set occluder_triangles;
    accel *occluders; /* of every triangle that is not a wall; NULL when the scene has none */
    bool off;         /* walls_accel_build(..., false): every shadow ray meets every triangle */
    char name[64];    /* "walls over <the structure's name>" */
    walls_inner_builder inner; /* what `all` and `occluders` are */
    /* The scene's light tree (light_tree.h), for a scene of at least
     * LIGHT_TREE_MIN_EMITTERS emitting triangles: built once with the
     * structures, before the first sample, not at every render. */
    light_tree lights;
    bool has_lights;
};

/* At most this many triangles: no tree (production_accel_build). */
enum { FLAT_TRIANGLES_MAX = 64 };

accel *production_accel_build(const triangle_set *set)
{
    /* A few dozen triangles: no tree at all, every triangle tested, eight per
     * AVX instruction (flat.h). On the Cornell box (32 and 22 triangles) a
     * closest hit took 64 ns through the 4-wide BVH and the path tracer was
     * 14 % faster flat (README, "The flat set"). A flat test costs about
     * 0.9 ns per triangle, the 4-wide BVH 50-70 ns a ray on small meshes:
     * they cross near 64. */
    if (set->count <= FLAT_TRIANGLES_MAX)
        return flat_build(set);
    /* Four boxes per node tested at once. Inside a room every ray meets the
     * boxes of the walls; a binary tree visits them one level at a time, a
     * 4-wide one in one or two nodes. */
    return wide_bvh_build(set, BVH_SPLIT_SAH);
}

/* ---- walls cast no shadows ----------------------------------------------------
 * A triangle lies in a plane. If both ends of a segment are on the same
 * side of that plane, so is every point between them (a half-space is
 * convex), and the segment cannot meet the triangle. A shadow ray is such
 * a segment, from a surface point to a point on a light. So a triangle
 * with the whole scene in front of it -- a wall of a room -- can never
 * block a shadow ray between two points of the scene: every such ray
 * needs only the other triangles (the occluders). In the Cornell box
 * that leaves the two blocks and the light, 22 of 32 triangles, and the
 * walls, whose boxes every shadow ray in the room overlaps, are not
 * visited at all.
 *
 * The scene is analysed once (find_walls); each ray is then checked
 * (pt_scene_segment_inside_walls): only a ray whose two ends are in front
 * of every wall plane skips the walls. The check, not the analysis, is
 * what makes the answer right, so a ray from anywhere (a camera outside
 * the room, a point of a moving object) still gets the right answer. */

/* Vertex-against-plane tests the analysis may spend (about 0.1 s); on a
 * larger scene the triangles not yet looked at are not walls. */
enum { WALL_TEST_BUDGET = 100000000 };

/* A wall's plane, and how much its test may be off by rounding.
 *
 * The test runs in float, four planes at a time, and must never say "in
 * front" of a point that is not: the margin (slack) bounds every rounding
 * on the way, with room to spare. Two kinds of plane:
 *   - axis-aligned, the three corners sharing one coordinate exactly (the
 *     Cornell box's floor, ceiling, back and green walls): the normal is
 *     exactly +-1 on that axis and the offset that coordinate, so the
 *     distance is one subtraction, off by half a unit in the last place of
 *     |p| + |offset| along that axis at most. The slack is 2^-20 of those:
 *     a point 2^-16 from the plane x = 0 is still judged correctly, and
 *     so is a ray's end ray.h moved off such a wall (by at least 64
 *     roundings of the wall's size, 2^-18 of it: twice the slack of the
 *     back wall, the farthest from 0 for its size).
 *   - any other (the red wall, whose quad is not quite flat): the unit
 *     normal n is rounded to float, each component by at most u |n_k|
 *     (u = 2^-24), and the offset too, so the plane tilts a little about
 *     the corner the offset was taken at, c0. The distance n . p - offset
 *     is off by at most (u = one rounding of each term):
 *       3 for the dot product and 1 for the subtraction, of |n| . |p|;
 *       1 for the tilted normal, of |n| . (|p| + |c0|);
 *       2 for its length not being exactly 1, of |n| . |p| + |offset|;
 *       1 for the offset, and the subtraction's 1, of |offset|;
 *     and 2 more of |n| . |p| where p is a ray's end o + t d, rounded
 *     twice (the test passes |o| + |t d| as |p|): 9 of |n| . |p| and 4 of
 *     |offset| and |n| . |c0|. The slack is 16 of each (TILTED_SLACK, per
 *     axis weighted by |n_k|): on the red wall 1.6e-3, under what ray.h
 *     moves a ray's end off it (2.2e-3), so rays from it skip the walls
 *     too. (It was 2^-19 of every coordinate and corner unweighted, 9.5e-3,
 *     and a quarter of the Cornell box's shadow rays, those from the red
 *     wall, took the full test.)
 * A margin too large only sends a ray down the full test, never gives a
 * wrong answer. */
typedef struct {
    float normal[3], offset, slack[3], slack_constant;
} wall_plane;

static const float AXIS_SLACK = 0x1.0p-20f, TILTED_SLACK = 0x1.0p-20f;

/* The plane of triangle t, facing the side its normal (p1 - p0) x (p2 - p0)
 * points to; false if the triangle has no area. */
static bool wall_plane_of(const triangle *t, wall_plane *out)
{
    float corners[3][3] = {{t->p0.x, t->p0.y, t->p0.z}, {t->p1.x, t->p1.y, t->p1.z}, {t->p2.x, t->p2.y, t->p2.z}};
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)corners[1][k] - corners[0][k];
        e2[k] = (double)corners[2][k] - corners[0][k];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(length > 0.0))
        return false;
    memset(out, 0, sizeof *out);
    for (int axis = 0; axis < 3; axis++) {
        if (corners[0][axis] == corners[1][axis] && corners[0][axis] == corners[2][axis]) {
            float sign = n[axis] > 0.0 ? 1.0f : -1.0f;
            out->normal[axis] = sign;
            out->offset = sign * corners[0][axis];
            out->slack[axis] = AXIS_SLACK;
            out->slack_constant = AXIS_SLACK * fabsf(out->offset);
            return true;
        }
    }
    double offset = 0.0, corner = 0.0;
    for (int k = 0; k < 3; k++) {
        out->normal[k] = (float)(n[k] / length);
        offset += (double)out->normal[k] * corners[0][k];
        corner += fabs((double)out->normal[k]) * fabs((double)corners[0][k]);
        out->slack[k] = TILTED_SLACK * fabsf(out->normal[k]);
    }
    out->offset = (float)offset;
    out->slack_constant = (float)(TILTED_SLACK * (corner + fabs(offset)));
    return true;
}

/* At most this many wall planes: every shadow ray tests them all, so a
 * room's six (and a few for faces that are not quite flat) pay for
 * themselves, but not the hundreds of faces of a closed sphere. */
enum { WALL_PLANES_MAX = 8 };
/* ... and only if the walls are at least this fraction of the scene's area. */
static const double WALL_AREA_MIN = 0.1;

/* Add w to the planes, unless it is already there (the other triangle of a
 * flat quad); false if it is not and there is no room for it. */
static bool add_wall_plane(walls_accel *sc, const wall_plane *w)
{
    for (int k = 0; k < sc->wall_plane_count; k++) {
        const wall_planes4 *g = &sc->wall_planes[k / 4];
        int j = k % 4;
        if (g->normal[0][j] == w->normal[0] && g->normal[1][j] == w->normal[1] && g->normal[2][j] == w->normal[2] &&
            g->offset[j] == w->offset && g->slack_constant[j] == w->slack_constant)
            return true; /* the other triangle of a flat quad: the same plane */
    }
    if (sc->wall_plane_count == WALL_PLANES_MAX)
        return false;
    int k = sc->wall_plane_count++;
    if (k % 4 == 0) {
        wall_planes4 *g = &sc->wall_planes[sc->wall_group_count++];
        memset(g, 0, sizeof *g);
        for (int j = 0; j < 4; j++)
            g->offset[j] = -1.0f;
    }
    wall_planes4 *g = &sc->wall_planes[k / 4];
    int j = k % 4;
    for (int a = 0; a < 3; a++) {
        g->normal[a][j] = w->normal[a];
        g->slack[a][j] = w->slack[a];
    }
    g->offset[j] = w->offset;
    g->slack_constant[j] = w->slack_constant;
    return true;
}

static void find_walls(walls_accel *sc, const pt_scene *scene)
{
    const mesh *m = &scene->geometry;
    int n = sc->base.set->count;
    bool *keep = memory_allocate((size_t)(n > 0 ? n : 1), sizeof *keep);
    long budget = WALL_TEST_BUDGET;
    sc->wall_count = 0;
    sc->wall_plane_count = 0;
    sc->wall_group_count = 0;
    sc->wall_planes = aligned_alloc(64, WALL_PLANES_MAX / 4 * sizeof *sc->wall_planes);
    if (sc->wall_planes == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    for (int i = 0; i < n; i++) {
        keep[i] = true;
        wall_plane w;
        if (budget <= 0 || !wall_plane_of(&sc->base.set->triangles[i], &w))
            continue;
        /* Every vertex and sphere of the scene in front of the plane or on
         * it (to within the slack). A misjudged vertex here would only make
         * the walls skipped less or more often: the test of each ray's two
         * ends decides, and it is exact. */
        bool wall = true;
        int v = 0;
        for (; v < m->position_count && wall; v++) {
            vec3 p = m->positions[v];
            float distance = w.normal[0] * p.x + w.normal[1] * p.y + w.normal[2] * p.z - w.offset;
            float margin = w.slack[0] * fabsf(p.x) + w.slack[1] * fabsf(p.y) + w.slack[2] * fabsf(p.z) + w.slack_constant;
            wall = distance >= -margin;
        }
        budget -= v; /* most triangles of a large mesh stop at an early vertex */
        for (int k = 0; k < scene->sphere_count && wall; k++) {
            const pt_sphere *s = &scene->spheres[k];
            vec3 c = s->center;
            float distance = w.normal[0] * c.x + w.normal[1] * c.y + w.normal[2] * c.z - w.offset;
            wall = distance >= s->radius * vec3_length(vec3_make(w.normal[0], w.normal[1], w.normal[2]));
        }
        if (!wall || !add_wall_plane(sc, &w))
            continue;
        keep[i] = false;
        sc->wall_count++;
    }
    /* Walls pay when they are large: a room's walls are boxes every shadow
     * ray in the room overlaps. A few faces of a closed sphere (eight of
     * hundreds) are not worth testing each ray's ends against. */
    double area = 0.0, wall_area = 0.0;
    for (int i = 0; i < n; i++) {
        const triangle *t = &sc->base.set->triangles[i];
        double a = 0.5 * (double)vec3_length(vec3_cross(vec3_sub(t->p1, t->p0), vec3_sub(t->p2, t->p0)));
        area += a;
        wall_area += keep[i] ? 0.0 : a;
    }
    if (sc->wall_count == 0 || wall_area < WALL_AREA_MIN * area) {
        sc->wall_count = sc->wall_plane_count = sc->wall_group_count = 0;
    } else {
        triangle_set_subset(&sc->occluder_triangles, sc->base.set, keep);
        sc->occluders = sc->inner(&sc->occluder_triangles);
    }
    free(keep);
}

/* Inline: it runs for every shadow ray, and a call (with the ray passed
 * through memory) cost as much as the test. */
static inline bool segment_inside_walls(const walls_accel *sc, const ray *r)
{
    if (sc->wall_group_count == 0 || sc->off || !(r->t_max < INFINITY))
        return false;
    /* The two ends, p = o + t d, rounded twice: each coordinate is off by
     * at most 2^-23 of |o| + |t d|, which is what the slack is taken of
     * (AXIS_SLACK is 8 times that and more). */
    vec3 step_start = vec3_scale(r->direction, r->t_min), step_end = vec3_scale(r->direction, r->t_max);
    vec3 start = vec3_add(r->origin, step_start), end = vec3_add(r->origin, step_end);
    vec3 size_start = vec3_add(vec3_abs(r->origin), vec3_abs(step_start));
    vec3 size_end = vec3_add(vec3_abs(r->origin), vec3_abs(step_end));
    /* Four planes per step, without a branch per plane: each lane's
     * answer is or-ed into `outside`. The SSE version does the same float
     * operations in the same order as the loop. */
    int outside = 0;
#if defined(__SSE2__)
    const __m128 p[2][3] = {{_mm_set1_ps(start.x), _mm_set1_ps(start.y), _mm_set1_ps(start.z)},
                            {_mm_set1_ps(end.x), _mm_set1_ps(end.y), _mm_set1_ps(end.z)}};
    const __m128 size[2][3] = {{_mm_set1_ps(size_start.x), _mm_set1_ps(size_start.y), _mm_set1_ps(size_start.z)},
                               {_mm_set1_ps(size_end.x), _mm_set1_ps(size_end.y), _mm_set1_ps(size_end.z)}};
    for (int g = 0; g < sc->wall_group_count; g++) {
        const wall_planes4 *w = &sc->wall_planes[g];
        for (int e = 0; e < 2; e++) {
            __m128 distance = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_load_ps(w->normal[0]), p[e][0]),
                                                    _mm_mul_ps(_mm_load_ps(w->normal[1]), p[e][1])),
                                         _mm_mul_ps(_mm_load_ps(w->normal[2]), p[e][2]));
            distance = _mm_sub_ps(distance, _mm_load_ps(w->offset));
            __m128 margin = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_load_ps(w->slack[0]), size[e][0]),
                                                  _mm_mul_ps(_mm_load_ps(w->slack[1]), size[e][1])),
                                       _mm_mul_ps(_mm_load_ps(w->slack[2]), size[e][2]));
            margin = _mm_add_ps(margin, _mm_load_ps(w->slack_constant));
            outside |= _mm_movemask_ps(_mm_cmpngt_ps(distance, margin));
        }
    }
#else
    const vec3 p[2] = {start, end}, size[2] = {size_start, size_end};
    for (int g = 0; g < sc->wall_group_count; g++) {
        const wall_planes4 *w = &sc->wall_planes[g];
        for (int e = 0; e < 2; e++)
            for (int j = 0; j < 4; j++) {
                float distance = w->normal[0][j] * p[e].x + w->normal[1][j] * p[e].y + w->normal[2][j] * p[e].z -
                                 w->offset[j];
                float margin = w->slack[0][j] * size[e].x + w->slack[1][j] * size[e].y +
                               w->slack[2][j] * size[e].z + w->slack_constant[j];
                outside |= !(distance > margin);
            }
    }
#endif
    return outside == 0;
}

bool walls_segment_inside(const accel *a, const ray *r) { return walls_is(a) && segment_inside_walls((const walls_accel *)a, r); }

#if defined(__x86_64__) && defined(__GNUC__)
/* segment_inside_walls() for eight rays, one per lane: the same float
 * operations in the same order as its SSE version, so each lane gets the
 * very answer a ray alone gets. */
__attribute__((target("avx"))) static int segments8_inside_walls_avx(const walls_accel *sc, const rays8 *rays)
{
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const __m256 t_min = _mm256_load_ps(rays->t_min), t_max = _mm256_load_ps(rays->t_max);
    __m256 p[2][3], size[2][3];
    for (int c = 0; c < 3; c++) {
        __m256 o = _mm256_load_ps(rays->origin[c]), d = _mm256_load_ps(rays->direction[c]);
        __m256 step_start = _mm256_mul_ps(d, t_min), step_end = _mm256_mul_ps(d, t_max);
        p[0][c] = _mm256_add_ps(o, step_start);
        p[1][c] = _mm256_add_ps(o, step_end);
        size[0][c] = _mm256_add_ps(_mm256_and_ps(o, abs_mask), _mm256_and_ps(step_start, abs_mask));
        size[1][c] = _mm256_add_ps(_mm256_and_ps(o, abs_mask), _mm256_and_ps(step_end, abs_mask));
    }
    __m256 outside = _mm256_cmp_ps(t_max, _mm256_set1_ps(INFINITY), _CMP_NLT_UQ); /* an infinite ray is not inside */
    /* the planes in use only (the SSE version also tests the unused lanes, which pass) */
    for (int k = 0; k < sc->wall_plane_count; k++) {
        const wall_planes4 *w = &sc->wall_planes[k / 4];
        const int j = k % 4;
        const __m256 normal[3] = {_mm256_broadcast_ss(&w->normal[0][j]), _mm256_broadcast_ss(&w->normal[1][j]),
                                  _mm256_broadcast_ss(&w->normal[2][j])};
        const __m256 slack[3] = {_mm256_broadcast_ss(&w->slack[0][j]), _mm256_broadcast_ss(&w->slack[1][j]),
                                 _mm256_broadcast_ss(&w->slack[2][j])};
        for (int e = 0; e < 2; e++) {
            __m256 distance = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(normal[0], p[e][0]),
                                                          _mm256_mul_ps(normal[1], p[e][1])),
                                            _mm256_mul_ps(normal[2], p[e][2]));
            distance = _mm256_sub_ps(distance, _mm256_broadcast_ss(&w->offset[j]));
            __m256 margin = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(slack[0], size[e][0]),
                                                        _mm256_mul_ps(slack[1], size[e][1])),
                                          _mm256_mul_ps(slack[2], size[e][2]));
            margin = _mm256_add_ps(margin, _mm256_broadcast_ss(&w->slack_constant[j]));
            outside = _mm256_or_ps(outside, _mm256_cmp_ps(distance, margin, _CMP_NGT_UQ));
        }
    }
    int inside = ~_mm256_movemask_ps(outside) & 0xff;
    _mm256_zeroupper();
    return inside;
}
#endif

int walls_segments8_inside(const accel *a, const rays8 *rays, int active)
{
    if (!walls_is(a))
        return 0;
    const walls_accel *sc = (const walls_accel *)a;
    if (sc->wall_group_count == 0 || sc->off)
        return 0;
#if defined(__x86_64__) && defined(__GNUC__)
    if (__builtin_cpu_supports("avx"))
        return segments8_inside_walls_avx(sc, rays) & active;
#endif
    int inside = 0;
    for (int k = 0; k < RAYS8_LANES; k++)
        if ((active >> k) & 1) {
            ray r = rays8_get(rays, k);
            inside |= segment_inside_walls(sc, &r) << k;
        }
    return inside;
}



/* ---- the walls as an accelerator ----------------------------------------------
 * Closest hits go to the structure of all triangles; a shadow ray whose two
 * ends lie in front of every wall plane goes to the occluders alone. */
static bool walls_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    const walls_accel *w = (const walls_accel *)a;
    return accel_closest_hit(w->all, r, hit, counters);
}

static bool walls_any_hit(const accel *a, ray r, ray_counters *counters)
{
    const walls_accel *w = (const walls_accel *)a;
    if (segment_inside_walls(w, &r)) {
        counters->shadow_rays_inside_walls++;
        return w->occluder_triangles.count > 0 && accel_any_hit(w->occluders, r, counters);
    }
    return accel_any_hit(w->all, r, counters);
}

static void walls_destroy(accel *a)
{
    walls_accel *w = (walls_accel *)a;
    accel_destroy(w->all);
    accel_destroy(w->occluders);
    triangle_set_free(&w->occluder_triangles);
    free(w->wall_planes);
    if (w->has_lights)
        light_tree_free(&w->lights);
    free(w);
}

/* Both structures inside trace with the test asked for. */
static bool walls_use_triangle_test(accel *a, triangle_test test)
{
    walls_accel *w = (walls_accel *)a;
    bool ok = accel_use_triangle_test(w->all, test);
    if (w->occluders != NULL)
        ok = accel_use_triangle_test(w->occluders, test) && ok;
    a->triangle_test = test;
    return ok;
}

static const accel_ops walls_ops = {walls_closest_hit, walls_any_hit, walls_destroy, walls_use_triangle_test};

bool walls_is(const accel *a) { return a != NULL && a->ops == &walls_ops; }

accel *walls_accel_build(const triangle_set *set, const pt_scene *scene, bool on)
{
    return walls_accel_build_over(set, scene, on, production_accel_build);
}

accel *walls_accel_build_over(const triangle_set *set, const pt_scene *scene, bool on, walls_inner_builder inner)
{
    walls_accel *w = memory_allocate(1, sizeof *w);
    w->base.ops = &walls_ops;
    w->base.set = set;
    w->inner = inner;
    w->all = inner(set);
    if (w->all == NULL) { /* an outside library's builder may fail */
        free(w);
        return NULL;
    }
    w->base.stats = w->all->stats;
    w->off = !on;
    find_walls(w, scene);
    w->has_lights = scene->emitter_count >= LIGHT_TREE_MIN_EMITTERS;
    if (w->has_lights)
        light_tree_build(&w->lights, scene);
    snprintf(w->name, sizeof w->name, "%s%s", w->wall_group_count > 0 && on ? "walls over " : "", w->all->stats.name);
    w->base.stats.name = w->name;
    return &w->base;
}

const accel *walls_all(const accel *a) { return ((const walls_accel *)a)->all; }

const light_tree *walls_light_tree(const accel *a)
{
    const walls_accel *w = (const walls_accel *)a;
    return walls_is(a) && w->has_lights ? &w->lights : NULL;
}

const accel *walls_occluders(const accel *a)
{
    const walls_accel *w = (const walls_accel *)a;
    return w->occluder_triangles.count > 0 ? w->occluders : NULL;
}

bool walls_found(const accel *a)
{
    const walls_accel *w = (const walls_accel *)a;
    return walls_is(a) && w->wall_group_count > 0 && !w->off;
}

int walls_triangle_count(const accel *a) { return walls_is(a) ? ((const walls_accel *)a)->wall_count : 0; }

accel *production_scene_accel(const triangle_set *set, const void *scene)
{
    return walls_accel_build(set, scene, true);
}

accel *production_scene_accel_no_walls(const triangle_set *set, const void *scene)
{
    return walls_accel_build(set, scene, false);
}

int walls_plane_count(const accel *a) { return walls_is(a) ? ((const walls_accel *)a)->wall_plane_count : 0; }

void walls_drop_slack(accel *a)
{
    walls_accel *w = (walls_accel *)a;
    for (int g = 0; g < w->wall_group_count; g++) {
        memset(w->wall_planes[g].slack, 0, sizeof w->wall_planes[g].slack);
        memset(w->wall_planes[g].slack_constant, 0, sizeof w->wall_planes[g].slack_constant);
    }
}

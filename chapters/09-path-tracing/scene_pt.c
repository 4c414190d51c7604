/* scene_pt.c -- the path tracer's scenes. */
#include "scene_pt.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "06-bvh/bvh4.h"
#include "06-bvh/flat.h"
#include "memory.h"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

void pt_scene_init(pt_scene *sc)
{
    memset(sc, 0, sizeof *sc);
    mesh_init(&sc->geometry);
    sc->up = vec3_make(0, 1, 0);
    sc->vertical_fov_degrees = 40.0f;
}

void pt_scene_free(pt_scene *sc)
{
    accel_destroy(sc->bvh);
    accel_destroy(sc->occluders);
    triangle_set_free(&sc->triangles);
    triangle_set_free(&sc->occluder_triangles);
    free(sc->wall_planes);
    mesh_free(&sc->geometry);
    free(sc->spheres);
    free(sc->materials);
    free(sc->point_lights);
    free(sc->emitters);
    free(sc->emitter_normals);
    free(sc->emitter_cdf);
    memset(sc, 0, sizeof *sc);
}

pt_material pt_diffuse(vec3 albedo) { return (pt_material){BSDF_DIFFUSE, albedo, vec3_splat(0.0f), 1.0f, 1.0f}; }

pt_material pt_emitter(vec3 albedo, vec3 emission)
{
    pt_material m = pt_diffuse(albedo);
    m.emission = emission;
    return m;
}

pt_material pt_glossy(vec3 f0, float roughness) { return (pt_material){BSDF_GLOSSY, f0, vec3_splat(0.0f), roughness, 1.0f}; }

pt_material pt_glass(float ior) { return (pt_material){BSDF_GLASS, vec3_splat(1.0f), vec3_splat(0.0f), 0.0f, ior}; }

pt_material pt_mirror(vec3 albedo) { return (pt_material){BSDF_MIRROR, albedo, vec3_splat(0.0f), 0.0f, 1.0f}; }

int pt_scene_add_material(pt_scene *sc, pt_material m)
{
    sc->materials = memory_grow(sc->materials, &sc->material_capacity, sc->material_count + 1, sizeof m);
    sc->materials[sc->material_count] = m;
    return sc->material_count++;
}

void pt_scene_add_triangle(pt_scene *sc, vec3 p0, vec3 p1, vec3 p2, int material)
{
    int a = mesh_add_position(&sc->geometry, p0), b = mesh_add_position(&sc->geometry, p1);
    int c = mesh_add_position(&sc->geometry, p2);
    mesh_add_triangle(&sc->geometry, a, b, c, material);
}

void pt_scene_add_quad(pt_scene *sc, vec3 p0, vec3 p1, vec3 p2, vec3 p3, int material)
{
    pt_scene_add_triangle(sc, p0, p1, p2, material);
    pt_scene_add_triangle(sc, p0, p2, p3, material);
}

void pt_scene_add_sphere(pt_scene *sc, vec3 center, float radius, int material, bool inside_out)
{
    sc->spheres = memory_grow(sc->spheres, &sc->sphere_capacity, sc->sphere_count + 1, sizeof(pt_sphere));
    sc->spheres[sc->sphere_count++] = (pt_sphere){center, radius, material, inside_out};
}

void pt_scene_add_point_light(pt_scene *sc, vec3 position, vec3 intensity)
{
    sc->point_lights = memory_grow(sc->point_lights, &sc->point_light_capacity, sc->point_light_count + 1,
                                   sizeof(pt_point_light));
    sc->point_lights[sc->point_light_count++] = (pt_point_light){position, intensity};
}

/* At most this many triangles: no tree (build_accel). */
enum { FLAT_TRIANGLES_MAX = 64 };

/* The one place the path tracer chooses and builds its acceleration
 * structures (of all triangles, and of the occluders); pt_scene_intersect()
 * and pt_scene_occluded() are the only places that use them. */
static accel *build_accel(const triangle_set *set)
{
    /* A few dozen triangles: no tree at all, every triangle tested, eight per
     * AVX instruction (chapter 06, flat.h). On the Cornell box (32 and 22
     * triangles) a closest hit took 64 ns through the 4-wide BVH: the path
     * tracer is 14 % faster with the same image, bit for bit (README,
     * "Speed"). A flat test costs about 0.9 ns per triangle, the 4-wide
     * BVH 50-70 ns a ray on small meshes: they cross near 64. (Eight rays
     * at a time, for --wide, skip the runs of triangles whose box none of
     * them meets: one level of boxes, flat.c's "Groups".) */
    if (set->count <= FLAT_TRIANGLES_MAX)
        return flat_build(set);
    /* Chapter 06's 4-wide BVH: four boxes per node tested at once. Inside a
     * room every ray meets the boxes of the walls; a binary tree visits them
     * one level at a time, a 4-wide one in one or two nodes (README, "Speed"). */
    return bvh4_build(set, BVH_SPLIT_SAH);
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
 *     a point 2^-16 from the plane x = 0 (the smallest offset ray.h moves
 *     a ray's end off a surface by) is still judged correctly.
 *   - any other (the red wall, whose quad is not quite flat): the unit
 *     normal is rounded to float, so the plane tilts by up to 2^-24 and the
 *     error grows with the distance from the triangle; the slack is 2^-19
 *     of |p| in each coordinate plus of the corners' and offset's sizes.
 * A margin too large only sends a ray down the full test, never gives a
 * wrong answer. */
typedef struct {
    float normal[3], offset, slack[3], slack_constant;
} wall_plane;

static const float AXIS_SLACK = 0x1.0p-20f, TILTED_SLACK = 0x1.0p-19f;

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
    double offset = 0.0, size = 0.0;
    for (int k = 0; k < 3; k++) {
        out->normal[k] = (float)(n[k] / length);
        offset += (double)out->normal[k] * corners[0][k];
        size += fabs((double)corners[0][k]) + fabs((double)corners[1][k]) + fabs((double)corners[2][k]);
        out->slack[k] = TILTED_SLACK;
    }
    out->offset = (float)offset;
    out->slack_constant = (float)(TILTED_SLACK * (size + fabs(offset)));
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
static bool add_wall_plane(pt_scene *sc, const wall_plane *w)
{
    for (int k = 0; k < sc->wall_plane_count; k++) {
        const pt_wall_planes *g = &sc->wall_planes[k / 4];
        int j = k % 4;
        if (g->normal[0][j] == w->normal[0] && g->normal[1][j] == w->normal[1] && g->normal[2][j] == w->normal[2] &&
            g->offset[j] == w->offset && g->slack_constant[j] == w->slack_constant)
            return true; /* the other triangle of a flat quad: the same plane */
    }
    if (sc->wall_plane_count == WALL_PLANES_MAX)
        return false;
    int k = sc->wall_plane_count++;
    if (k % 4 == 0) {
        pt_wall_planes *g = &sc->wall_planes[sc->wall_group_count++];
        memset(g, 0, sizeof *g);
        for (int j = 0; j < 4; j++)
            g->offset[j] = -1.0f;
    }
    pt_wall_planes *g = &sc->wall_planes[k / 4];
    int j = k % 4;
    for (int a = 0; a < 3; a++) {
        g->normal[a][j] = w->normal[a];
        g->slack[a][j] = w->slack[a];
    }
    g->offset[j] = w->offset;
    g->slack_constant[j] = w->slack_constant;
    return true;
}

static void find_walls(pt_scene *sc)
{
    const mesh *m = &sc->geometry;
    int n = sc->triangles.count;
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
        if (budget <= 0 || !wall_plane_of(&sc->triangles.triangles[i], &w))
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
        for (int k = 0; k < sc->sphere_count && wall; k++) {
            const pt_sphere *s = &sc->spheres[k];
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
        const triangle *t = &sc->triangles.triangles[i];
        double a = 0.5 * (double)vec3_length(vec3_cross(vec3_sub(t->p1, t->p0), vec3_sub(t->p2, t->p0)));
        area += a;
        wall_area += keep[i] ? 0.0 : a;
    }
    if (sc->wall_count == 0 || wall_area < WALL_AREA_MIN * area) {
        sc->wall_count = sc->wall_plane_count = sc->wall_group_count = 0;
    } else {
        triangle_set_subset(&sc->occluder_triangles, &sc->triangles, keep);
        sc->occluders = build_accel(&sc->occluder_triangles);
    }
    free(keep);
}

/* Inline: it runs for every shadow ray, and a call (with the ray passed
 * through memory) cost as much as the test. */
static inline bool segment_inside_walls(const pt_scene *sc, const ray *r)
{
    if (sc->wall_group_count == 0 || sc->walls_off || !(r->t_max < INFINITY))
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
        const pt_wall_planes *w = &sc->wall_planes[g];
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
        const pt_wall_planes *w = &sc->wall_planes[g];
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

bool pt_scene_segment_inside_walls(const pt_scene *sc, const ray *r) { return segment_inside_walls(sc, r); }

#if defined(__x86_64__) && defined(__GNUC__)
/* segment_inside_walls() for eight rays, one per lane: the same float
 * operations in the same order as its SSE version, so each lane gets the
 * very answer a ray alone gets. */
__attribute__((target("avx"))) static int segments8_inside_walls_avx(const pt_scene *sc, const flat_rays8 *rays)
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
        const pt_wall_planes *w = &sc->wall_planes[k / 4];
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

int pt_scene_segments8_inside_walls(const pt_scene *sc, const flat_rays8 *rays, int active)
{
    if (sc->wall_group_count == 0 || sc->walls_off)
        return 0;
#if defined(__x86_64__) && defined(__GNUC__)
    if (__builtin_cpu_supports("avx"))
        return segments8_inside_walls_avx(sc, rays) & active;
#endif
    int inside = 0;
    for (int k = 0; k < FLAT_LANES; k++)
        if ((active >> k) & 1) {
            ray r = flat_rays8_get(rays, k);
            inside |= segment_inside_walls(sc, &r) << k;
        }
    return inside;
}

void pt_scene_use_walls(pt_scene *sc, bool on) { sc->walls_off = !on; }

/* How bright an emitter is, for choosing which light to sample: the mean of
 * L_e's channels (positive whenever any channel is). */
static double emitter_weight(vec3 le) { return ((double)le.x + (double)le.y + (double)le.z) / 3.0; }

void pt_scene_finish(pt_scene *sc)
{
    triangle_set_from_mesh(&sc->triangles, &sc->geometry);
    sc->bvh = build_accel(&sc->triangles);
    find_walls(sc);
    /* The emitter table: every triangle whose material emits, with the
     * running sum of powers, to pick one in proportion to its power. */
    int n = 0;
    for (int i = 0; i < sc->geometry.face_count; i++)
        n += vec3_max_component(sc->materials[sc->geometry.faces[i].material].emission) > 0.0f;
    sc->emitters = memory_allocate((size_t)(n > 0 ? n : 1), sizeof(int));
    sc->emitter_normals = memory_allocate((size_t)(n > 0 ? n : 1), sizeof(vec3));
    sc->emitter_cdf = memory_allocate((size_t)(n > 0 ? n : 1), sizeof(double));
    sc->emitter_count = 0;
    sc->emitter_area = 0.0;
    sc->emitter_power = 0.0;
    for (int i = 0; i < sc->geometry.face_count; i++) {
        vec3 le = sc->materials[sc->geometry.faces[i].material].emission;
        if (vec3_max_component(le) <= 0.0f)
            continue;
        const triangle *t = &sc->triangles.triangles[i];
        vec3 cross = vec3_cross(vec3_sub(t->p1, t->p0), vec3_sub(t->p2, t->p0));
        double area = 0.5 * (double)vec3_length(cross);
        sc->emitter_area += area;
        sc->emitter_power += area * emitter_weight(le);
        sc->emitters[sc->emitter_count] = i;
        sc->emitter_normals[sc->emitter_count] = vec3_normalize(cross);
        sc->emitter_cdf[sc->emitter_count] = sc->emitter_power;
        sc->emitter_count++;
    }
}

/* ---- intersection ---------------------------------------------------------- */

bool pt_scene_intersect(const pt_scene *sc, ray r, hit_record *hit, ray_counters *counters)
{
    bool found = false;
    if (sc->bvh != NULL && sc->triangles.count > 0 && accel_closest_hit(sc->bvh, r, hit, counters)) {
        found = true;
        r.t_max = hit->t;
    }
    for (int i = 0; i < sc->sphere_count; i++) {
        const pt_sphere *s = &sc->spheres[i];
        sphere shape = {s->center, s->radius};
        counters->primitive_tests++;
        if (sphere_intersect(&shape, r, hit)) {
            found = true;
            r.t_max = hit->t;
            hit->shape_id = -1 - i; /* spheres count down from -1; triangles up from 0 */
            hit->material_id = s->material;
            if (s->inside_out) /* the front is the inside */
                hit->front_face = !hit->front_face;
        }
    }
    return found;
}

/* Inline into both callers below: pt_scene_visible() builds its shadow ray
 * here and hands it on by pointer, not copied through one more call. */
static inline bool occluded(const pt_scene *sc, const ray *r, ray_counters *counters)
{
    if (segment_inside_walls(sc, r)) {
        counters->shadow_rays_inside_walls++;
        if (sc->occluder_triangles.count > 0 && accel_any_hit(sc->occluders, *r, counters))
            return true;
    } else if (sc->bvh != NULL && sc->triangles.count > 0 && accel_any_hit(sc->bvh, *r, counters)) {
        return true;
    }
    hit_record ignored;
    for (int i = 0; i < sc->sphere_count; i++) {
        sphere shape = {sc->spheres[i].center, sc->spheres[i].radius};
        counters->primitive_tests++;
        if (sphere_intersect(&shape, *r, &ignored))
            return true;
    }
    return false;
}

bool pt_scene_occluded(const pt_scene *sc, ray r, ray_counters *counters) { return occluded(sc, &r, counters); }

bool pt_scene_visible(const pt_scene *sc, const hit_record *from, const vec3 *target, const vec3 *target_normal,
                      ray_counters *counters)
{
    ray shadow = ray_spawn_to(from->point, from->normal_geometric, *target, *target_normal);
    counters->shadow_rays++;
    return !occluded(sc, &shadow, counters);
}

float pt_scene_emitter_pdf_area(const pt_scene *sc, int material)
{
    /* P(triangle) / its area = area x weight / power / area */
    return (float)(emitter_weight(sc->materials[material].emission) / sc->emitter_power);
}

camera pt_scene_camera(const pt_scene *sc, int width, int height)
{
    return camera_look_at(sc->eye, sc->target, sc->up, sc->vertical_fov_degrees, width, height);
}

/* ---- scenes ------------------------------------------------------------------ */

static vec3 v(float x, float y, float z) { return vec3_make(x, y, z); }

/* Reflectances of the box's paints as RGB (the values GAMES101's assignment 7
 * uses), and the light's emission. */
const vec3 PT_CORNELL_WHITE = {0.725f, 0.71f, 0.68f};
const vec3 PT_CORNELL_RED = {0.63f, 0.065f, 0.05f};
const vec3 PT_CORNELL_GREEN = {0.14f, 0.45f, 0.091f};
const vec3 PT_CORNELL_LIGHT = {17.0f, 12.0f, 4.0f};

void pt_scene_add_cornell_room(pt_scene *sc, int white, int red, int green, int light)
{
    /* Floor, ceiling, back wall, right (green) and left (red) walls: the
     * published coordinates, each face counter-clockwise seen from inside. */
    pt_scene_add_quad(sc, v(552.8f, 0, 0), v(0, 0, 0), v(0, 0, 559.2f), v(549.6f, 0, 559.2f), white);
    pt_scene_add_quad(sc, v(556, 548.8f, 0), v(556, 548.8f, 559.2f), v(0, 548.8f, 559.2f), v(0, 548.8f, 0), white);
    pt_scene_add_quad(sc, v(549.6f, 0, 559.2f), v(0, 0, 559.2f), v(0, 548.8f, 559.2f), v(556, 548.8f, 559.2f), white);
    pt_scene_add_quad(sc, v(0, 0, 559.2f), v(0, 0, 0), v(0, 548.8f, 0), v(0, 548.8f, 559.2f), green);
    pt_scene_add_quad(sc, v(552.8f, 0, 0), v(549.6f, 0, 559.2f), v(556, 548.8f, 559.2f), v(556, 548.8f, 0), red);
    /* The light, 0.1 mm below the ceiling so the two never coincide, facing down. */
    pt_scene_add_quad(sc, v(343, 548.7f, 227), v(343, 548.7f, 332), v(213, 548.7f, 332), v(213, 548.7f, 227), light);
    sc->eye = v(278, 273, -800);
    sc->target = v(278, 273, 0);
    /* A 35 mm lens on a 25 mm film: 2 atan(12.5 / 35) = 39.3 degrees. */
    sc->vertical_fov_degrees = 2.0f * atanf(12.5f / 35.0f) * 180.0f / (float)PI;
}

static void cornell_short_block(pt_scene *sc, int m)
{
    pt_scene_add_quad(sc, v(130, 165, 65), v(82, 165, 225), v(240, 165, 272), v(290, 165, 114), m);
    pt_scene_add_quad(sc, v(290, 0, 114), v(290, 165, 114), v(240, 165, 272), v(240, 0, 272), m);
    pt_scene_add_quad(sc, v(130, 0, 65), v(130, 165, 65), v(290, 165, 114), v(290, 0, 114), m);
    pt_scene_add_quad(sc, v(82, 0, 225), v(82, 165, 225), v(130, 165, 65), v(130, 0, 65), m);
    pt_scene_add_quad(sc, v(240, 0, 272), v(240, 165, 272), v(82, 165, 225), v(82, 0, 225), m);
}

static void cornell_tall_block(pt_scene *sc, int m)
{
    pt_scene_add_quad(sc, v(423, 330, 247), v(265, 330, 296), v(314, 330, 456), v(472, 330, 406), m);
    pt_scene_add_quad(sc, v(423, 0, 247), v(423, 330, 247), v(472, 330, 406), v(472, 0, 406), m);
    pt_scene_add_quad(sc, v(472, 0, 406), v(472, 330, 406), v(314, 330, 456), v(314, 0, 456), m);
    pt_scene_add_quad(sc, v(314, 0, 456), v(314, 330, 456), v(265, 330, 296), v(265, 0, 296), m);
    pt_scene_add_quad(sc, v(265, 0, 296), v(265, 330, 296), v(423, 330, 247), v(423, 0, 247), m);
}

void pt_scene_build_cornell_box(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_WHITE));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    cornell_short_block(sc, white);
    cornell_tall_block(sc, white);
    pt_scene_finish(sc);
}

void pt_scene_build_cornell_box_materials(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_WHITE));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    int metal = pt_scene_add_material(sc, pt_glossy(vec3_make(0.95f, 0.64f, 0.54f), 0.15f)); /* copper-like */
    int glass = pt_scene_add_material(sc, pt_glass(1.5f));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    cornell_tall_block(sc, metal);
    pt_scene_add_sphere(sc, v(185, 90, 170), 90, glass, false);
    pt_scene_finish(sc);
}

/* A rectangle centred at c with unit axes a and b (half-sizes ha, hb),
 * counter-clockwise seen from the side a x b points to. */
static void add_rectangle(pt_scene *sc, vec3 c, vec3 a, float ha, vec3 b, float hb, int material)
{
    vec3 da = vec3_scale(a, ha), db = vec3_scale(b, hb);
    pt_scene_add_quad(sc, vec3_sub(vec3_sub(c, da), db), vec3_sub(vec3_add(c, da), db),
                      vec3_add(vec3_add(c, da), db), vec3_add(vec3_sub(c, da), db), material);
}

void pt_scene_build_veach(pt_scene *sc)
{
    pt_scene_init(sc);
    sc->eye = v(0, 2.2f, 7.5f);
    sc->target = v(0, 0.7f, 0);
    sc->vertical_fov_degrees = 38.0f;
    /* Nothing else: a black world, so that all the light in the image is
     * the lights' own, reflected once (the estimators differ only there). */

    /* Four lights in a row behind the plates, each 9 times the area of the
     * last and emitting 1/9 as much per unit area: the same power. */
    const vec3 light_row = v(0, 2.6f, -1.8f);
    const float half_size[4] = {0.03f, 0.09f, 0.27f, 0.81f};
    const float light_x[4] = {-2.1f, -1.05f, 0.15f, 1.9f};
    const vec3 colour[4] = {{1.0f, 0.35f, 0.2f}, {1.0f, 0.9f, 0.3f}, {0.3f, 1.0f, 0.4f}, {0.3f, 0.5f, 1.0f}};
    for (int i = 0; i < 4; i++) {
        float le = 0.6f / (half_size[i] * half_size[i]); /* power 2.4 per colour unit */
        int m = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.0f), vec3_scale(colour[i], le)));
        vec3 c = v(light_x[i], light_row.y, light_row.z);
        /* facing the plates: its normal points at the middle of them */
        vec3 n = vec3_normalize(vec3_sub(v(light_x[i], 0.3f, 1.0f), c));
        vec3 a = v(1, 0, 0), b = vec3_normalize(vec3_cross(n, a));
        add_rectangle(sc, c, a, half_size[i], b, half_size[i], m);
    }

    /* Four plates, the sharpest at the back, each tilted so that the eye
     * sees the row of lights reflected in it: its normal halves the angle
     * between the directions to the eye and to the lights. */
    const float roughness[4] = {0.3f, 0.12f, 0.05f, 0.015f};
    const vec3 plate_centre[4] = {{0, 0.0f, 2.2f}, {0, 0.3f, 1.2f}, {0, 0.62f, 0.25f}, {0, 0.98f, -0.65f}};
    for (int i = 0; i < 4; i++) {
        int m = pt_scene_add_material(sc, pt_glossy(vec3_splat(0.8f), roughness[i]));
        vec3 c = plate_centre[i];
        vec3 to_eye = vec3_normalize(vec3_sub(sc->eye, c)), to_light = vec3_normalize(vec3_sub(light_row, c));
        vec3 n = vec3_normalize(vec3_add(to_eye, to_light));
        vec3 a = v(1, 0, 0), b = vec3_normalize(vec3_cross(n, a));
        add_rectangle(sc, c, a, 2.6f, b, 0.42f, m);
    }
    pt_scene_finish(sc);
}

void pt_scene_build_furnace(pt_scene *sc, float albedo, float emission)
{
    pt_scene_init(sc);
    int m = pt_scene_add_material(sc, pt_emitter(vec3_splat(albedo), vec3_splat(emission)));
    /* An icosphere's triangles face outwards; the furnace is seen from
     * inside, so each triangle is added with its winding reversed. */
    mesh ball;
    mesh_init(&ball);
    mesh_icosphere(&ball, v(0, 0, 0), 1.0f, 2, -1);
    for (int i = 0; i < ball.face_count; i++)
        pt_scene_add_triangle(sc, mesh_vertex(&ball, i, 0), mesh_vertex(&ball, i, 2), mesh_vertex(&ball, i, 1), m);
    mesh_free(&ball);
    sc->eye = v(0.1f, 0.2f, 0.3f);
    sc->target = v(0.5f, 0.1f, -1.0f);
    sc->vertical_fov_degrees = 90.0f;
    pt_scene_finish(sc);
}

void pt_scene_build_white_furnace(pt_scene *sc, pt_material sphere_material, vec3 environment)
{
    pt_scene_init(sc);
    int m = pt_scene_add_material(sc, sphere_material);
    pt_scene_add_sphere(sc, v(0, 0, 0), 1.0f, m, false);
    sc->environment = environment;
    sc->eye = v(0, 0, 4);
    sc->target = v(0, 0, 0);
    sc->vertical_fov_degrees = 40.0f;
    pt_scene_finish(sc);
}

void pt_scene_build_point_in_sphere(pt_scene *sc, float albedo, float intensity)
{
    pt_scene_init(sc);
    int m = pt_scene_add_material(sc, pt_diffuse(vec3_splat(albedo)));
    pt_scene_add_sphere(sc, v(0, 0, 0), 1.0f, m, true);
    pt_scene_add_point_light(sc, v(0, 0, 0), vec3_splat(intensity));
    sc->eye = v(0.2f, -0.1f, 0.3f);
    sc->target = v(0.4f, 0.3f, -1.0f);
    sc->vertical_fov_degrees = 70.0f;
    pt_scene_finish(sc);
}

/* ---- OBJ scenes ---------------------------------------------------------------- */

bool pt_scene_load_obj(pt_scene *sc, const char *path, char *err, size_t err_size)
{
    pt_scene_init(sc);
    if (!mesh_load_obj(&sc->geometry, path, err, err_size)) {
        pt_scene_free(sc);
        return false;
    }
    /* Materials from the MTL colours; faces without one get a grey diffuse. */
    for (int i = 0; i < sc->geometry.material_count; i++) {
        const mesh_material *mm = &sc->geometry.materials[i];
        pt_material m = pt_emitter(mm->diffuse, mm->emission);
        if (mm->ior > 1.0f)
            m = pt_glass(mm->ior);
        pt_scene_add_material(sc, m);
    }
    int grey = pt_scene_add_material(sc, pt_diffuse(vec3_splat(0.7f)));
    for (int i = 0; i < sc->geometry.face_count; i++)
        if (sc->geometry.faces[i].material < 0)
            sc->geometry.faces[i].material = grey;
    vec3 lo, hi;
    if (!mesh_bounds(&sc->geometry, &lo, &hi)) {
        snprintf(err, err_size, "%s: no triangles to render", path);
        pt_scene_free(sc);
        return false;
    }
    vec3 centre = vec3_scale(vec3_add(lo, hi), 0.5f);
    float radius = 0.5f * vec3_length(vec3_sub(hi, lo));
    sc->target = centre;
    sc->eye = vec3_add(centre, vec3_make(0, 0.3f * radius, 2.8f * radius));
    sc->vertical_fov_degrees = 45.0f;
    pt_scene_finish(sc);
    if (sc->emitter_count == 0 && sc->point_light_count == 0)
        sc->environment = vec3_splat(1.0f); /* nothing emits: light it with a white sky */
    return true;
}

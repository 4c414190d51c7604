/* leak_check.h -- the closed meshes and the rays of the system-level leak
 * test (tests/test_ch13.c, "Leaks"): rays from outside aimed at float
 * points of shared edges and at vertices, where every ray crosses the
 * closed surface and so must meet a triangle, and meet it no later than its
 * target. Include after <cmocka.h>.
 *
 *   leak_mesh_jittered_icosphere(&m, subdivisions, rng)    a closed mesh, unit size
 *   leak_mesh_transform(&m, scale, offset)                  every vertex p -> p scale + offset, in float
 *   leak_rays_make(&m, count, rng, rays)                    the rays (t_max = inf)
 *   leak_segment(r)                                         the ray as a segment ending just past its target
 */
#ifndef LEAK_CHECK_H
#define LEAK_CHECK_H

#include <math.h>
#include <stdlib.h>

#include "mesh.h"
#include "rng.h"

/* Each vertex moves by up to this fraction of the mesh's shortest edge, in
 * a random direction: the facets are no longer symmetric, no two edges have
 * the same length, and the icosphere's faces are no longer equilateral, yet
 * no facet folds over (a vertex would have to cross a neighbour's edge, a
 * good part of an edge away). */
static const float LEAK_JITTER = 0.15f;

/* A ray counts only if it enters the surface at its target: the faces
 * around the target all turn their fronts to it, the cosine between the
 * ray and each outward normal below -LEAK_COS_MIN. (Aimed at a silhouette
 * the exact ray only touches the surface, and may rightly miss.) */
static const double LEAK_COS_MIN = 0.1;

/* The ray is d = target - origin, so it reaches its target at t = 1; it
 * must meet a triangle there or before. A ray that leaked through the
 * target's edge meets the far side of the mesh instead, at t beyond
 * 1 + (the chord inside) / |d|: the chord through a face met at a cosine of
 * LEAK_COS_MIN or more is at least about 2 r LEAK_COS_MIN (r the
 * surface's smallest radius of curvature: the torus's tube, 0.35 of a
 * bounding radius of 1.35) and |d| at most LEAK_ORIGIN_DISTANCE + 1
 * bounding radii: t > 1 + 0.013. The slack, 2^-10, lies between that and
 * the triangle test's error in t (a few ulps, 1e-6). */
static const float LEAK_T_SLACK = 0x1.0p-10f;

/* The origins: on a sphere this many bounding radii around the mesh's
 * centre, outside everything. */
static const double LEAK_ORIGIN_DISTANCE = 2.5;

/* Targets on an edge stay this fraction of the edge away from its ends,
 * where the ray would cross the vertex's fan rather than the edge's two
 * faces (and the fan's faces are not checked for facing the ray). */
static const float LEAK_EDGE_END = 0x1.0p-6f;

static inline vec3 leak_random_unit(pcg32 *rng)
{
    float z = 2.0f * pcg32_float(rng) - 1.0f, phi = 2.0f * (float)PI * pcg32_float(rng);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return vec3_make(s * cosf(phi), s * sinf(phi), z);
}

/* Moves every vertex of m (from position `first` on) by up to LEAK_JITTER
 * of its shortest edge. */
static inline void leak_jitter(mesh *m, int first_position, pcg32 *rng)
{
    float shortest = INFINITY;
    for (int f = 0; f < m->face_count; f++)
        for (int k = 0; k < 3; k++)
            shortest = fminf(shortest, vec3_length(vec3_sub(mesh_vertex(m, f, k), mesh_vertex(m, f, (k + 1) % 3))));
    for (int i = first_position; i < m->position_count; i++)
        m->positions[i] = vec3_add(m->positions[i],
                                   vec3_scale(leak_random_unit(rng), LEAK_JITTER * shortest * pcg32_float(rng)));
}

/* A closed icosphere of radius about 1 at the origin, jittered. */
static inline void leak_mesh_jittered_icosphere(mesh *m, int subdivisions, pcg32 *rng)
{
    mesh_init(m);
    mesh_icosphere(m, vec3_make(0, 0, 0), 1.0f, subdivisions, -1);
    leak_jitter(m, 0, rng);
}

/* A closed torus around the y axis (major radius 1, tube `minor`),
 * u_segments x v_segments quads as two triangles each, jittered. */
static inline void leak_mesh_jittered_torus(mesh *m, float minor, int u_segments, int v_segments, pcg32 *rng)
{
    mesh_init(m);
    mesh_torus(m, vec3_make(0, 0, 0), vec3_make(0, 1, 0), 1.0f, minor, u_segments, v_segments, -1);
    leak_jitter(m, 0, rng);
}

/* p -> p scale + offset, in float: the mesh stays closed (its faces share
 * their vertices by index), whatever the rounding does to the shape. */
static inline void leak_mesh_transform(mesh *m, float scale, vec3 offset)
{
    for (int i = 0; i < m->position_count; i++)
        m->positions[i] = vec3_add(vec3_scale(m->positions[i], scale), offset);
}

/* The mesh's centre (of its bounds) and bounding radius about it, in double. */
static inline void leak_mesh_sphere(const mesh *m, double centre[3], double *radius)
{
    vec3 lo, hi;
    mesh_bounds(m, &lo, &hi);
    centre[0] = 0.5 * ((double)lo.x + hi.x), centre[1] = 0.5 * ((double)lo.y + hi.y),
    centre[2] = 0.5 * ((double)lo.z + hi.z);
    double r2 = 0.0;
    for (int i = 0; i < m->position_count; i++) {
        double dx = m->positions[i].x - centre[0], dy = m->positions[i].y - centre[1], dz = m->positions[i].z - centre[2];
        r2 = fmax(r2, dx * dx + dy * dy + dz * dz);
    }
    *radius = sqrt(r2);
}

/* Face f's outward unit normal, in double from its float corners. */
static inline void leak_face_normal(const mesh *m, int f, double n[3])
{
    vec3 p0 = mesh_vertex(m, f, 0), p1 = mesh_vertex(m, f, 1), p2 = mesh_vertex(m, f, 2);
    double e1[3] = {(double)p1.x - p0.x, (double)p1.y - p0.y, (double)p1.z - p0.z};
    double e2[3] = {(double)p2.x - p0.x, (double)p2.y - p0.y, (double)p2.z - p0.z};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++)
        n[k] = length > 0.0 ? n[k] / length : 0.0;
}

/* Does the ray (direction d) enter face f: cosine below -LEAK_COS_MIN? */
static inline bool leak_enters(const mesh *m, int f, vec3 d)
{
    double n[3];
    leak_face_normal(m, f, n);
    double length = sqrt((double)d.x * d.x + (double)d.y * d.y + (double)d.z * d.z);
    return (n[0] * d.x + n[1] * d.y + n[2] * d.z) / length < -LEAK_COS_MIN;
}

/* `count` rays at m: even ones aimed at a vertex, odd ones at a float point
 * of an edge, each from outside and entering the surface there (see
 * LEAK_COS_MIN). The faces around each vertex and the twin of each edge
 * are found once, here. Returns the number made (fewer only if the mesh
 * offers no such ray). */
static inline int leak_rays_make(const mesh *m, int count, pcg32 *rng, ray *rays)
{
    int n_faces = m->face_count, n_positions = m->position_count;
    if (n_faces <= 0 || n_positions <= 0)
        return 0; /* no edge to aim at (and the sizes below stay positive) */
    /* the faces around each vertex (compressed rows) and each edge's twin */
    int *fan_start = calloc((size_t)n_positions + 1, sizeof *fan_start);
    int *fan = malloc((size_t)n_faces * 3 * sizeof *fan);
    int *twin = malloc((size_t)n_faces * 3 * sizeof *twin);
    for (int f = 0; f < n_faces; f++)
        for (int k = 0; k < 3; k++)
            fan_start[m->faces[f].position[k] + 1]++;
    for (int i = 0; i < n_positions; i++)
        fan_start[i + 1] += fan_start[i];
    int *fill = calloc((size_t)n_positions, sizeof *fill);
    for (int f = 0; f < n_faces; f++)
        for (int k = 0; k < 3; k++) {
            int p = m->faces[f].position[k];
            fan[fan_start[p] + fill[p]++] = f;
        }
    for (int f = 0; f < n_faces; f++)
        for (int k = 0; k < 3; k++) {
            int a = m->faces[f].position[k], b = m->faces[f].position[(k + 1) % 3];
            twin[3 * f + k] = -1;
            for (int j = fan_start[a]; j < fan_start[a + 1]; j++) { /* the other face around a with b */
                int g = fan[j];
                const int *p = m->faces[g].position;
                if (g != f && (p[0] == b || p[1] == b || p[2] == b))
                    twin[3 * f + k] = g;
            }
        }
    double centre[3], radius;
    leak_mesh_sphere(m, centre, &radius);
    int made = 0;
    for (int i = 0, attempts = 0; made < count && attempts < 1000 * count; attempts++) {
        int f = (int)pcg32_bounded(rng, (uint32_t)n_faces), k = (int)pcg32_bounded(rng, 3);
        int a = m->faces[f].position[k], b = m->faces[f].position[(k + 1) % 3];
        bool on_edge = i % 2 == 1;
        vec3 target = m->positions[a];
        if (on_edge) { /* a float point between a and b, away from both */
            float s = LEAK_EDGE_END + (1.0f - 2.0f * LEAK_EDGE_END) * pcg32_float(rng);
            target = vec3_add(m->positions[a], vec3_scale(vec3_sub(m->positions[b], m->positions[a]), s));
        }
        vec3 u = leak_random_unit(rng);
        vec3 origin = vec3_make((float)(centre[0] + LEAK_ORIGIN_DISTANCE * radius * u.x),
                                (float)(centre[1] + LEAK_ORIGIN_DISTANCE * radius * u.y),
                                (float)(centre[2] + LEAK_ORIGIN_DISTANCE * radius * u.z));
        vec3 d = vec3_sub(target, origin);
        bool enters = true;
        if (on_edge) {
            enters = twin[3 * f + k] >= 0 && leak_enters(m, f, d) && leak_enters(m, twin[3 * f + k], d);
        } else {
            for (int j = fan_start[a]; j < fan_start[a + 1] && enters; j++)
                enters = leak_enters(m, fan[j], d);
        }
        if (!enters)
            continue;
        rays[made++] = ray_make(origin, d);
        i++;
    }
    free(fan_start);
    free(fan);
    free(twin);
    free(fill);
    return made;
}

/* The ray as a segment that ends just past its target (t = 1): an any-hit
 * query on it sees a leak, which a query over the whole ray would not (it
 * meets the far side). */
static inline ray leak_segment(ray r)
{
    r.t_max = 1.0f + LEAK_T_SLACK;
    return r;
}

/* A closest hit that did not leak: a triangle met, at the target or before. */
static inline bool leak_closest_ok(bool found, const hit_record *hit)
{
    return found && hit->t <= 1.0f + LEAK_T_SLACK;
}

#endif

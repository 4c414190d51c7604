/* scene_pt_check.c -- what a program says of a scene before it renders:
 * parts too small for where float puts them, and lights that face away
 * from what they should light (pt_scene_check_scale, pt_scene_check_lights
 * in scene_pt.h). Apart from the scene itself (scene_pt.c): they trace
 * rays and sort vertices, but render nothing. */
#include "09-path-tracing/scene_pt.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "08-monte-carlo/sampling.h"
#include "09-path-tracing/bsdf.h"
#include "memory.h"
#include "rng.h"

/* ---- what float can place ------------------------------------------------------ */

/* The warning's common part: how many steps, and what to do. */
static void warn_too_small(FILE *out, float extent, float magnitude)
{
    float step = ray_float_step(magnitude);
    fprintf(out,
            " is only %.3g float steps across at its distance from the origin (a step there is %.3g; below %.0f its "
            "shape is rounded by, and rays leave it, a visible part of its size): its shading and shadows may be "
            "wrong; move the scene near the origin (subtract its centre from every coordinate)\n",
            (double)(extent / step), (double)step, (double)RAY_MIN_STEPS_ACROSS);
}

/* At most this many parts are named one by one; the rest are counted. */
enum { SCALE_WARNINGS_SHOWN = 8 };

/* A connected part's box, size, first triangle, and whether it emits. */
typedef struct {
    vec3 lo, hi;
    int count, first;
    bool light;
} part_bounds;

typedef struct {
    vec3 p;
    int index;
} placed_position;

static int compare_placed(const void *a, const void *b)
{
    const vec3 *p = &((const placed_position *)a)->p, *q = &((const placed_position *)b)->p;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return p->z < q->z ? -1 : p->z > q->z;
}

/* Union-find: the part's representative, halving the path on the way. */
static int part_of(int *parent, int i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static void join_parts(int *parent, int a, int b)
{
    a = part_of(parent, a);
    b = part_of(parent, b);
    if (a != b)
        parent[a > b ? a : b] = a < b ? a : b;
}

/* For each position, the representative of its connected part: triangles
 * are connected through a shared corner, by index or by place (a scene
 * file's quads each have their own corners, and a box of quads meets at
 * equal points). malloc'ed. */
static int *triangle_parts(const mesh *g)
{
    int n = g->position_count;
    int *parent = memory_allocate((size_t)(n > 0 ? n : 1), sizeof *parent);
    placed_position *sorted = memory_allocate((size_t)(n > 0 ? n : 1), sizeof *sorted);
    for (int i = 0; i < n; i++) {
        parent[i] = i;
        sorted[i] = (placed_position){g->positions[i], i};
    }
    qsort(sorted, (size_t)n, sizeof *sorted, compare_placed);
    for (int i = 1; i < n; i++)
        if (compare_placed(&sorted[i - 1], &sorted[i]) == 0)
            join_parts(parent, sorted[i - 1].index, sorted[i].index);
    free(sorted);
    for (int f = 0; f < g->face_count; f++) {
        join_parts(parent, g->faces[f].position[0], g->faces[f].position[1]);
        join_parts(parent, g->faces[f].position[0], g->faces[f].position[2]);
    }
    for (int i = 0; i < n; i++)
        parent[i] = part_of(parent, i);
    return parent;
}

/* Could any connected part be too small for its place? Each part is at
 * least as large as each of its triangles and lies no farther out than the
 * whole mesh, and the float step only grows with the distance: if every
 * triangle is large enough for the mesh's farthest point, so is every part,
 * and the parts need not be found (which sorts every vertex: half a second
 * on a million triangles, before every render). */
static bool some_part_may_be_too_small(const mesh *g)
{
    float farthest = 0.0f;
    for (int i = 0; i < g->position_count; i++)
        farthest = fmaxf(farthest, vec3_max_component(vec3_abs(g->positions[i])));
    for (int f = 0; f < g->face_count; f++) {
        vec3 a = mesh_vertex(g, f, 0), b = mesh_vertex(g, f, 1), c = mesh_vertex(g, f, 2);
        vec3 extent = vec3_sub(vec3_max(a, vec3_max(b, c)), vec3_min(a, vec3_min(b, c)));
        if (ray_too_small_for_position(vec3_max_component(extent), farthest))
            return true;
    }
    return false;
}

int pt_scene_check_scale(const pt_scene *sc, const char *label, FILE *out)
{
    int warnings = 0;
    for (int i = 0; i < sc->sphere_count; i++) {
        const pt_sphere *s = &sc->spheres[i];
        float extent = 2.0f * s->radius, magnitude = vec3_max_component(vec3_abs(s->center)) + s->radius;
        if (!ray_too_small_for_position(extent, magnitude))
            continue;
        fprintf(out, "%s: warning: sphere #%d at (%.7g, %.7g, %.7g), radius %.7g,", label, i, (double)s->center.x,
                (double)s->center.y, (double)s->center.z, (double)s->radius);
        warn_too_small(out, extent, magnitude);
        warnings++;
    }
    /* The triangles by connected part: each object alone, whatever its
     * material (the Cornell box's two blocks share the walls' white; one
     * box of all three would be as large as the room). */
    const mesh *g = &sc->geometry;
    if (!some_part_may_be_too_small(g))
        return warnings;
    int reported = 0, unreported = 0;
    int *root = triangle_parts(g);
    part_bounds *b = memory_allocate((size_t)(g->position_count > 0 ? g->position_count : 1), sizeof *b);
    for (int i = 0; i < g->position_count; i++)
        b[i] = (part_bounds){vec3_splat(INFINITY), vec3_splat(-INFINITY), 0, -1, false};
    for (int f = 0; f < g->face_count; f++) {
        part_bounds *p = &b[root[g->faces[f].position[0]]];
        for (int k = 0; k < 3; k++) {
            vec3 v = mesh_vertex(g, f, k);
            p->lo = vec3_min(p->lo, v);
            p->hi = vec3_max(p->hi, v);
        }
        p->first = p->count++ == 0 ? f : p->first;
        p->light = p->light || vec3_max_component(sc->materials[g->faces[f].material].emission) > 0.0f;
    }
    for (int f = 0; f < g->face_count; f++) {
        const part_bounds *p = &b[root[g->faces[f].position[0]]];
        if (p->first != f) /* each part once, in the order of its first triangle */
            continue;
        float extent = vec3_max_component(vec3_sub(p->hi, p->lo));
        float magnitude = vec3_max_component(vec3_max(vec3_abs(p->lo), vec3_abs(p->hi)));
        if (!ray_too_small_for_position(extent, magnitude))
            continue;
        warnings++;
        if (reported == SCALE_WARNINGS_SHOWN) { /* a soup of a million loose triangles: not a million lines */
            unreported++;
            continue;
        }
        reported++;
        int m = g->faces[f].material;
        fprintf(out,
                "%s: warning: the %d connected triangle%s from triangle #%d (material #%d%s), "
                "from (%.7g, %.7g, %.7g) to (%.7g, %.7g, %.7g),",
                label, p->count, p->count == 1 ? "" : "s", f, m, p->light ? ", a light" : "", (double)p->lo.x,
                (double)p->lo.y, (double)p->lo.z, (double)p->hi.x, (double)p->hi.y, (double)p->hi.z);
        warn_too_small(out, extent, magnitude);
    }
    if (unreported > 0)
        fprintf(out, "%s: warning: and %d more connected part%s of triangles as small for their place\n", label,
                unreported, unreported == 1 ? "" : "s");
    free(b);
    free(root);
    return warnings;
}

/* ---- lights that face away -------------------------------------------------- */

/* The check's rays per side, its fixed seed, and when it warns: less than
 * a quarter of the front's light meets anything while at least half of
 * the back's would. A lamp in a room meets a wall on either side; a lamp
 * over an open scene facing the sky meets nothing in front and the
 * ground behind. */
enum { LIGHT_CHECK_RAYS = 256, LIGHT_CHECK_SEED = 0x11647 };
static const double LIGHT_CHECK_FRONT_BELOW = 0.25, LIGHT_CHECK_BACK_ABOVE = 0.5;

/* Of `rays` cosine-distributed rays leaving the emitting triangles of
 * `material` (picked by area) from their front (side 1) or back (side -1),
 * the fraction that meets a surface of another material: what a light
 * lights, its own body (the inside of a glowing closed mesh) aside. */
static double fraction_lit(const pt_scene *sc, int material, float side, int rays)
{
    /* this light's triangles, and the running sum of their areas */
    int *index = memory_allocate((size_t)sc->emitter_count, sizeof *index);
    double *cdf = memory_allocate((size_t)sc->emitter_count, sizeof *cdf), area = 0.0;
    int count = 0;
    for (int e = 0; e < sc->emitter_count; e++) {
        const triangle *t = &sc->triangles.triangles[sc->emitters[e]];
        if (sc->geometry.faces[sc->emitters[e]].material != material)
            continue;
        area += 0.5 * (double)vec3_length(vec3_cross(vec3_sub(t->p1, t->p0), vec3_sub(t->p2, t->p0)));
        index[count] = e;
        cdf[count++] = area;
    }
    pcg32 rng = pcg32_for_pixel(LIGHT_CHECK_SEED, (uint64_t)material);
    ray_counters counters = {0};
    int met = 0;
    for (int k = 0; k < rays; k++) {
        /* the first triangle whose running sum passes u x area (binary search) */
        double target = (double)pcg32_float(&rng) * area;
        int lo = 0, hi = count - 1;
        while (lo < hi) {
            int mid = (lo + hi) / 2;
            if (cdf[mid] <= target)
                lo = mid + 1;
            else
                hi = mid;
        }
        int e = index[lo];
        const triangle *t = &sc->triangles.triangles[sc->emitters[e]];
        /* a uniform point on it, as pt_scene_sample_emitter draws one */
        float s1 = sqrtf(pcg32_float(&rng)), u2 = pcg32_float(&rng);
        vec3 e1 = vec3_sub(t->p1, t->p0), e2 = vec3_sub(t->p2, t->p0);
        vec3 point = vec3_add(t->p0, vec3_add(vec3_scale(e1, (1.0f - u2) * s1), vec3_scale(e2, u2 * s1)));
        vec3 n = vec3_scale(sc->emitter_normals[e], side);
        float point_error = ray_point_error(point, n, triangle_edge_size(e1, e2));
        vec3 local = sample_cosine_hemisphere(vec2_make(pcg32_float(&rng), pcg32_float(&rng)));
        vec3 direction = frame_to_world(n, local);
        hit_record hit;
        if (pt_scene_intersect(sc, ray_spawn(point, point_error, n, direction), &hit, &counters) &&
            hit.material_id != material)
            met++;
    }
    free(index);
    free(cdf);
    return count > 0 ? (double)met / rays : 1.0;
}

int pt_scene_check_lights(const pt_scene *sc, const char *label, FILE *out)
{
    int warnings = 0;
    for (int m = 0; m < sc->material_count; m++) {
        if (vec3_max_component(sc->materials[m].emission) <= 0.0f)
            continue;
        int count = 0;
        vec3 lo = vec3_splat(INFINITY), hi = vec3_splat(-INFINITY);
        for (int e = 0; e < sc->emitter_count; e++) {
            const triangle *t = &sc->triangles.triangles[sc->emitters[e]];
            if (sc->geometry.faces[sc->emitters[e]].material != m)
                continue;
            count++;
            lo = vec3_min(lo, vec3_min(t->p0, vec3_min(t->p1, t->p2)));
            hi = vec3_max(hi, vec3_max(t->p0, vec3_max(t->p1, t->p2)));
        }
        if (count == 0)
            continue;
        double front = fraction_lit(sc, m, 1.0f, LIGHT_CHECK_RAYS), back = fraction_lit(sc, m, -1.0f, LIGHT_CHECK_RAYS);
        if (!(front < LIGHT_CHECK_FRONT_BELOW && back >= LIGHT_CHECK_BACK_ABOVE))
            continue;
        vec3 c = vec3_scale(vec3_add(lo, hi), 0.5f);
        /* an OBJ's own materials keep their MTL names (pt_scene_load_obj) */
        const char *name = m < sc->geometry.material_count ? sc->geometry.materials[m].name : "";
        fprintf(out,
                "%s: warning: the light of material #%d%s%s%s (%d triangle%s around (%.4g, %.4g, %.4g)) faces away "
                "from the scene: of the light leaving its front, %.0f %% meets a surface; from its back, %.0f %% "
                "would. Lights here emit from their front only, the side from which their corners run "
                "counter-clockwise (Blender's emit from both): if it should face the other way, flip it (in "
                "Blender: Mesh > Normals > Flip)\n",
                label, m, name[0] ? " '" : "", name, name[0] ? "'" : "", count, count == 1 ? "" : "s", (double)c.x,
                (double)c.y, (double)c.z, 100.0 * front, 100.0 * back);
        warnings++;
    }
    return warnings;
}

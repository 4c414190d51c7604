/* scene_pt.c -- the path tracer's scenes. */
#include "09-path-tracing/scene_pt.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "04-uniform-grid/grid.h"
#include "05-kd-tree/kdtree.h"
#include "06-bvh/bvh.h"
#include "08-monte-carlo/sampling.h"
#include "09-path-tracing/bsdf.h"
#include "memory.h"
#include "rng.h"

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
    triangle_set_free(&sc->triangles);
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

/* ---- the acceleration structure ---------------------------------------------
 * pt_scene_intersect() and pt_scene_occluded() are the only places that
 * trace the triangles, and they do it through chapter 03's interface, so
 * any structure of chapters 03-06 can stand here. The default is chapter
 * 06's BVH with the binned SAH: change it, and chapter 09's counters move. */
static accel *build_brute(const triangle_set *set, const void *context)
{
    (void)context;
    return brute_force_build(set);
}

static accel *build_grid(const triangle_set *set, const void *context)
{
    (void)context;
    return grid_build(set, GRID_DEFAULT_DENSITY);
}

static accel *build_kdtree(const triangle_set *set, const void *context)
{
    (void)context;
    return kdtree_build(set);
}

static accel *build_bvh(const triangle_set *set, const void *context)
{
    (void)context;
    return bvh_build(set, BVH_SPLIT_SAH);
}

const char *const PT_ACCEL_NAMES[] = {"bvh", "kdtree", "grid", "brute", NULL};
static const pt_accel_builder accel_builders[] = {build_bvh, build_kdtree, build_grid, build_brute};

pt_accel_builder pt_accel_builder_named(const char *name)
{
    for (int i = 0; PT_ACCEL_NAMES[i] != NULL; i++)
        if (strcmp(name, PT_ACCEL_NAMES[i]) == 0)
            return accel_builders[i];
    return NULL;
}

void pt_scene_use_accel(pt_scene *sc, pt_accel_builder build, const void *context)
{
    accel_destroy(sc->bvh);
    sc->bvh = build(&sc->triangles, context);
}

/* How bright an emitter is, for choosing which light to sample: the mean of
 * L_e's channels (positive whenever any channel is). */
static double emitter_weight(vec3 le) { return ((double)le.x + (double)le.y + (double)le.z) / 3.0; }

void pt_scene_finish(pt_scene *sc)
{
    triangle_set_from_mesh(&sc->triangles, &sc->geometry);
    sc->bvh = build_bvh(&sc->triangles, NULL);
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

static vec3 transformed(vec3 p, float scale, vec3 offset) { return vec3_add(vec3_scale(p, scale), offset); }

void pt_scene_transform(pt_scene *sc, float scale, vec3 offset)
{
    for (int i = 0; i < sc->geometry.position_count; i++)
        sc->geometry.positions[i] = transformed(sc->geometry.positions[i], scale, offset);
    for (int i = 0; i < sc->sphere_count; i++) {
        sc->spheres[i].center = transformed(sc->spheres[i].center, scale, offset);
        sc->spheres[i].radius *= scale;
    }
    for (int i = 0; i < sc->point_light_count; i++) {
        sc->point_lights[i].position = transformed(sc->point_lights[i].position, scale, offset);
        sc->point_lights[i].intensity = vec3_scale(sc->point_lights[i].intensity, scale * scale);
    }
    sc->eye = transformed(sc->eye, scale, offset);
    sc->target = transformed(sc->target, scale, offset);
    /* what pt_scene_finish builds, built again from the moved points */
    accel_destroy(sc->bvh);
    sc->bvh = NULL;
    triangle_set_free(&sc->triangles);
    free(sc->emitters);
    free(sc->emitter_normals);
    free(sc->emitter_cdf);
    pt_scene_finish(sc);
}

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

/* ---- intersection ---------------------------------------------------------- */

bool pt_scene_intersect_spheres(const pt_scene *sc, ray r, hit_record *hit, ray_counters *counters)
{
    bool found = false;
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

bool pt_scene_intersect(const pt_scene *sc, ray r, hit_record *hit, ray_counters *counters)
{
    bool found = false;
    if (sc->bvh != NULL && sc->triangles.count > 0 && accel_closest_hit(sc->bvh, r, hit, counters)) {
        found = true;
        r.t_max = hit->t;
    }
    return pt_scene_intersect_spheres(sc, r, hit, counters) || found;
}

/* A shadow ray asks only whether anything is in the way (any hit). */
static bool occluded(const pt_scene *sc, const ray *r, ray_counters *counters)
{
    if (sc->bvh != NULL && sc->triangles.count > 0 && accel_any_hit(sc->bvh, *r, counters))
        return true;
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

bool pt_scene_segment_clear(const pt_scene *sc, ray shadow, ray_counters *counters)
{
    counters->shadow_rays++;
    return !occluded(sc, &shadow, counters);
}

bool pt_scene_visible(const pt_scene *sc, const hit_record *from, const vec3 *target, float target_error,
                      const vec3 *target_normal, ray_counters *counters)
{
    return pt_scene_segment_clear(sc,
                                  ray_spawn_to(from->point, from->point_error, from->normal_geometric, *target,
                                               target_error, *target_normal),
                                  counters);
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

int pt_scene_add_painted_cornell_room(pt_scene *sc)
{
    int white = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_WHITE));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    return white;
}

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
    int white = pt_scene_add_painted_cornell_room(sc);
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

/* Where the loaders say what each MTL material became (NULL: nowhere). */
static FILE *material_report;
static bool material_report_set;

void pt_scene_report_materials(FILE *out)
{
    material_report = out;
    material_report_set = true;
}

/* The sharpest GGX lobe an MTL makes: at alpha 0, D(h) is 0 / 0 at its
 * peak; at 0.001 its peak 1 / (pi alpha^2), 3e5, is far inside float. */
static const float MTL_ALPHA_MIN = 0.001f;

/* The MTL's shininess Ns as GGX's alpha: a Blinn-Phong lobe of exponent p
 * is close to a microfacet lobe of alpha = sqrt(2 / (p + 2)) (Walter et al.
 * 2007), kept within what the glossy BSDF takes. */
static float alpha_from_shininess(float ns)
{
    float alpha = sqrtf(2.0f / (fmaxf(ns, 0.0f) + 2.0f));
    return fminf(1.0f, fmaxf(MTL_ALPHA_MIN, alpha));
}

/* A metal's alpha from Blender's Ns: its exporter writes a Principled
 * BSDF's roughness r as Ns = 1000 (1 - r)^2, and its GGX alpha is r^2. */
static float alpha_from_blender_shininess(float ns)
{
    float r = 1.0f - sqrtf(fminf(1.0f, fmaxf(ns, 0.0f) / 1000.0f));
    return fminf(1.0f, fmaxf(MTL_ALPHA_MIN, r * r));
}

/* A metal: GGX with F0 = Kd, the base colour a metallic workflow keeps
 * there. Said by the PBR extension (Pm at least 0.5, roughness Pr), or in
 * the way Blender's exporter writes a metal without it: illum 3
 * ("reflection on", its mark of a Principled BSDF with metallic above 0),
 * the base colour as Kd and the fixed 0.5 of its specular slider as Ks.
 * Read as the format means it, that would be a diffuse Kd, so every
 * exported metal rendered as coloured plaster. */
static bool mtl_metal(const mesh_material *mm, char *note, size_t note_size, pt_material *out)
{
    const vec3 kd = mm->diffuse;
    float alpha;
    if (mm->metallic >= 0.5f) {
        bool pr = mm->roughness >= 0.0f;
        alpha = pr ? fmaxf(MTL_ALPHA_MIN, mm->roughness * mm->roughness) : alpha_from_shininess(mm->shininess);
        snprintf(note, note_size, "glossy GGX, a metal (Pm %g), F0 = Kd %g %g %g, alpha %.3g from %s",
                 (double)mm->metallic, (double)kd.x, (double)kd.y, (double)kd.z, (double)alpha, pr ? "Pr" : "Ns");
    } else if (mm->metallic < 0.0f && mm->illum == 3) {
        alpha = alpha_from_blender_shininess(mm->shininess);
        snprintf(note, note_size,
                 "glossy GGX, a metal (illum 3, as Blender writes one), F0 = Kd %g %g %g, alpha %.3g from Ns %g "
                 "(Blender's Ns = 1000 (1 - roughness)^2); Ks dropped",
                 (double)kd.x, (double)kd.y, (double)kd.z, (double)alpha, (double)mm->shininess);
    } else {
        return false;
    }
    *out = pt_glossy(kd, alpha);
    return true;
}

pt_material pt_material_from_mtl(const mesh_material *mm, char *note, size_t note_size)
{
    float kd = vec3_max_component(mm->diffuse), ks = vec3_max_component(mm->specular);
    if (mesh_material_emits(mm)) {
        snprintf(note, note_size, "emitter, Ke %g %g %g (Kd %g %g %g as its albedo)", (double)mm->emission.x,
                 (double)mm->emission.y, (double)mm->emission.z, (double)mm->diffuse.x, (double)mm->diffuse.y,
                 (double)mm->diffuse.z);
        return pt_emitter(mm->diffuse, mm->emission);
    }
    if (mesh_material_transparent(mm)) {
        float ior = mm->ior > 1.0f ? mm->ior : 1.5f;
        snprintf(note, note_size, "glass, ior %g (%s)%s", (double)ior,
                 mm->dissolve < 1.0f ? "d < 1" : "a transparent illum", mm->ior > 1.0f ? "" : "; no Ni > 1: 1.5");
        return pt_glass(ior);
    }
    pt_material metal;
    if (mm->metallic >= 0.5f && mtl_metal(mm, note, note_size, &metal))
        return metal;
    if (ks > kd) {
        float alpha = alpha_from_shininess(mm->shininess);
        snprintf(note, note_size, "glossy GGX, F0 = Ks %g %g %g, alpha %.3g from Ns %g", (double)mm->specular.x,
                 (double)mm->specular.y, (double)mm->specular.z, (double)alpha, (double)mm->shininess);
        return pt_glossy(mm->specular, alpha);
    }
    if (mtl_metal(mm, note, note_size, &metal))
        return metal;
    snprintf(note, note_size, "diffuse, Kd %g %g %g%s%s", (double)mm->diffuse.x, (double)mm->diffuse.y,
             (double)mm->diffuse.z, ks > 0.0f ? "; Ks dropped (the diffuse part is larger: no layered material here)" : "",
             mm->ior > 1.0f ? "; Ni ignored (opaque)" : "");
    return pt_diffuse(mm->diffuse);
}

void pt_scene_add_mtl_materials(pt_scene *sc, const mesh *m, const char *source)
{
    FILE *out = material_report_set ? material_report : stdout;
    for (int i = 0; i < m->material_count; i++) {
        char note[256];
        pt_scene_add_material(sc, pt_material_from_mtl(&m->materials[i], note, sizeof note));
        if (out != NULL)
            fprintf(out, "%s: material '%s': %s\n", source, m->materials[i].name, note);
    }
}

bool pt_scene_load_obj(pt_scene *sc, const char *path, char *err, size_t err_size)
{
    pt_scene_init(sc);
    if (!mesh_load_obj(&sc->geometry, path, err, err_size)) {
        pt_scene_free(sc);
        return false;
    }
    /* Materials from the MTL; faces without one get a grey diffuse. */
    pt_scene_add_mtl_materials(sc, &sc->geometry, path);
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
    if (sc->emitter_count == 0 && sc->point_light_count == 0) {
        sc->environment = vec3_splat(1.0f); /* nothing emits: light it with a white sky */
        FILE *out = material_report_set ? material_report : stdout;
        if (out != NULL)
            fprintf(out,
                    "%s: no material emits (Ke): lit by a white sky of radiance 1 instead. Blender writes no lamp "
                    "to OBJ; to light it as you lit it, give a face an Emission material, or use a scene file "
                    "(docs/scene-format.md)\n",
                    path);
    }
    return true;
}

/* ---- the built-in scenes, by name ----------------------------------------- */

static void build_furnace(pt_scene *sc) { pt_scene_build_furnace(sc, 0.5f, 0.5f); }
static void build_white_furnace(pt_scene *sc)
{
    pt_scene_build_white_furnace(sc, pt_diffuse(vec3_splat(0.5f)), vec3_splat(1.0f));
}
static void build_glass_furnace(pt_scene *sc) { pt_scene_build_white_furnace(sc, pt_glass(1.5f), vec3_splat(1.0f)); }
static void build_point_in_sphere(pt_scene *sc) { pt_scene_build_point_in_sphere(sc, 0.5f, (float)PI); }

const char *const PT_BUILTIN_SCENE_NAMES[] = {"cornell",       "materials",     "veach", "furnace",
                                              "white-furnace", "glass-furnace", "point-in-sphere", NULL};
const char *const PT_BUILTIN_SCENE_NOTES[] = {
    "the Cornell box (the default)",
    "the box with a glossy metal block and a glass sphere",
    "glossy plates and lights of four sizes (where MIS wins)",
    "inside a closed sphere that emits and reflects 0.5: radiance 1 everywhere",
    "a diffuse sphere of albedo 0.5 under a uniform sky of radiance 1",
    "a glass sphere under a uniform sky of radiance 1",
    "a point light inside a sphere of albedo 0.5",
    NULL,
};
/* in the order of PT_BUILTIN_SCENE_NAMES (their lines are PT_BUILTIN_SCENE_NOTES) */
const pt_builtin_scene PT_BUILTIN_SCENES[] = {
    {"cornell", pt_scene_build_cornell_box, NULL},
    {"materials", pt_scene_build_cornell_box_materials, NULL},
    {"veach", pt_scene_build_veach, NULL},
    {"furnace", build_furnace, NULL},
    {"white-furnace", build_white_furnace, NULL},
    {"glass-furnace", build_glass_furnace, NULL},
    {"point-in-sphere", build_point_in_sphere, NULL},
    {NULL, NULL, NULL},
};

bool pt_scene_build_builtin(pt_scene *sc, const char *name)
{
    for (int i = 0; PT_BUILTIN_SCENES[i].name != NULL; i++)
        if (strcmp(name, PT_BUILTIN_SCENES[i].name) == 0) {
            PT_BUILTIN_SCENES[i].build(sc);
            return true;
        }
    return false;
}

/* ---- a warning before a render that cannot be right --------------------- */

bool pt_scene_has_no_light(const pt_scene *sc, char *why, size_t why_size)
{
    if (sc->emitter_count > 0 || sc->point_light_count > 0 || vec3_max_component(sc->environment) > 0.0f)
        return false;
    int emitting_spheres = 0;
    for (int i = 0; i < sc->sphere_count; i++)
        emitting_spheres += vec3_max_component(sc->materials[sc->spheres[i].material].emission) > 0.0f;
    snprintf(why, why_size, "no light: no emitting triangle, point light or background%s: the image will be black",
             emitting_spheres > 0 ? " (only emitting spheres, which light what happens to hit them)" : "");
    return emitting_spheres == 0;
}

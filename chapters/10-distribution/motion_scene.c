/* motion_scene.c -- moving spheres and meshes over the shutter interval. */
#include "10-distribution/motion_scene.h"

#include <stdlib.h>
#include <string.h>

#include "06-bvh/bvh.h"
#include "memory.h"

void motion_scene_init(motion_scene *ms)
{
    memset(ms, 0, sizeof *ms);
    pt_scene_init(&ms->base);
}

void motion_scene_free(motion_scene *ms)
{
    for (int i = 0; i < ms->mesh_count; i++) {
        accel_destroy(ms->meshes[i]->bvh);
        triangle_set_free(&ms->meshes[i]->triangles);
        mesh_free(&ms->meshes[i]->geometry);
        free(ms->meshes[i]);
    }
    free(ms->meshes);
    free(ms->spheres);
    pt_scene_free(&ms->base);
    memset(ms, 0, sizeof *ms);
}

void motion_scene_add_sphere(motion_scene *ms, vec3 center, vec3 motion, float radius, int material)
{
    ms->spheres = memory_grow(ms->spheres, &ms->sphere_capacity, ms->sphere_count + 1, sizeof(moving_sphere));
    ms->spheres[ms->sphere_count++] = (moving_sphere){center, motion, radius, material};
}

void motion_scene_add_mesh(motion_scene *ms, mesh *geometry, vec3 motion)
{
    ms->meshes = memory_grow(ms->meshes, &ms->mesh_capacity, ms->mesh_count + 1, sizeof(moving_mesh *));
    moving_mesh *m = memory_allocate(1, sizeof *m);
    ms->meshes[ms->mesh_count++] = m;
    m->geometry = *geometry;
    mesh_init(geometry);
    m->motion = motion;
    triangle_set_from_mesh(&m->triangles, &m->geometry);
    m->bvh = bvh_build(&m->triangles, BVH_SPLIT_SAH);
    /* A translation moves every point along the same segment, so the box
     * at t = 0 united with the box at t = 1 holds the mesh at every t. */
    aabb end = {vec3_add(m->triangles.bounds.lo, motion), vec3_add(m->triangles.bounds.hi, motion)};
    m->swept = aabb_union(m->triangles.bounds, end);
}

vec3 moving_sphere_center(const moving_sphere *s, float time) { return vec3_add(s->center, vec3_scale(s->motion, time)); }

vec3 moving_mesh_offset(const moving_mesh *m, float time) { return vec3_scale(m->motion, time); }

aabb moving_sphere_swept_bounds(const moving_sphere *s)
{
    vec3 r = vec3_splat(s->radius), end = vec3_add(s->center, s->motion);
    aabb start = {vec3_sub(s->center, r), vec3_add(s->center, r)};
    return aabb_union(start, (aabb){vec3_sub(end, r), vec3_add(end, r)});
}

/* The ray in the mesh's own (untranslated) frame at the ray's time. */
static ray ray_into_mesh(const moving_mesh *m, timed_ray tr)
{
    ray moved = tr.r;
    moved.origin = vec3_sub(tr.r.origin, moving_mesh_offset(m, tr.time));
    return moved;
}

/* Is the swept box in the ray's way at all? One slab test before the BVH:
 * most rays pass far from a moving object. */
static bool may_hit_swept(const aabb *swept, ray r, ray_counters *counters)
{
    counters->box_tests++;
    slab_ray sr = slab_ray_make(r);
    float t_enter, t_exit;
    return aabb_slab_test(swept, &sr, r.t_min, r.t_max, &t_enter, &t_exit);
}

/* Moving objects' shape_id: below every static sphere's (-1 - i). */
static int moving_shape_id(const motion_scene *ms, int index) { return -1 - ms->base.sphere_count - index; }

bool motion_scene_intersect(const motion_scene *ms, timed_ray tr, hit_record *hit, ray_counters *counters)
{
    ray r = tr.r;
    bool found = pt_scene_intersect(&ms->base, r, hit, counters);
    if (found)
        r.t_max = hit->t;
    for (int i = 0; i < ms->sphere_count; i++) {
        const moving_sphere *s = &ms->spheres[i];
        sphere shape = {moving_sphere_center(s, tr.time), s->radius};
        counters->primitive_tests++;
        if (sphere_intersect(&shape, r, hit)) {
            found = true;
            r.t_max = hit->t;
            hit->shape_id = moving_shape_id(ms, i);
            hit->material_id = s->material;
        }
    }
    for (int i = 0; i < ms->mesh_count; i++) {
        const moving_mesh *m = ms->meshes[i];
        if (!may_hit_swept(&m->swept, r, counters))
            continue;
        hit_record local;
        if (accel_closest_hit(m->bvh, ray_into_mesh(m, (timed_ray){r, tr.time}), &local, counters)) {
            /* Same direction, so the same t; the point moves back with the
             * mesh, rounded once more in its new coordinates. */
            *hit = local;
            hit->point = vec3_add(local.point, moving_mesh_offset(m, tr.time));
            hit->point_error = local.point_error + ray_point_error(hit->point, hit->normal_geometric, 0.0f);
            hit->shape_id = moving_shape_id(ms, ms->sphere_count + i);
            found = true;
            r.t_max = hit->t;
        }
    }
    return found;
}

bool motion_scene_occluded(const motion_scene *ms, timed_ray tr, ray_counters *counters)
{
    if (pt_scene_occluded(&ms->base, tr.r, counters))
        return true;
    hit_record ignored;
    for (int i = 0; i < ms->sphere_count; i++) {
        sphere shape = {moving_sphere_center(&ms->spheres[i], tr.time), ms->spheres[i].radius};
        counters->primitive_tests++;
        if (sphere_intersect(&shape, tr.r, &ignored))
            return true;
    }
    for (int i = 0; i < ms->mesh_count; i++) {
        const moving_mesh *m = ms->meshes[i];
        if (may_hit_swept(&m->swept, tr.r, counters) && accel_any_hit(m->bvh, ray_into_mesh(m, tr), counters))
            return true;
    }
    return false;
}

/* ---- the showcase ------------------------------------------------------------- */

static vec3 v(float x, float y, float z) { return vec3_make(x, y, z); }

/* An axis-aligned box's 12 triangles, counter-clockwise seen from outside. */
static void mesh_add_box(mesh *m, vec3 lo, vec3 hi, int material)
{
    int c[8];
    for (int i = 0; i < 8; i++)
        c[i] = mesh_add_position(m, v(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
    /* each face's corners in order around its outward normal */
    static const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (int f = 0; f < 6; f++) {
        mesh_add_triangle(m, c[faces[f][0]], c[faces[f][1]], c[faces[f][2]], material);
        mesh_add_triangle(m, c[faces[f][0]], c[faces[f][2]], c[faces[f][3]], material);
    }
}

void motion_scene_build_showcase_still(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_WHITE));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    int plate = pt_scene_add_material(sc, pt_glossy(v(0.85f, 0.85f, 0.85f), 0.12f));
    int mirror = pt_scene_add_material(sc, pt_mirror(v(0.9f, 0.9f, 0.9f)));
    int glass = pt_scene_add_material(sc, pt_glass(1.5f));
    /* the moving sphere's and the cube's, used by motion_scene_build_showcase */
    pt_scene_add_material(sc, pt_diffuse(v(0.2f, 0.3f, 0.75f)));
    pt_scene_add_material(sc, pt_diffuse(v(0.8f, 0.65f, 0.15f)));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    /* A glossy plate over the back of the floor, 1 mm above it, facing up. */
    pt_scene_add_quad(sc, v(520, 1, 230), v(40, 1, 230), v(40, 1, 540), v(520, 1, 540), plate);
    /* Behind the plane of focus a mirror sphere on the plate, in front of
     * it a glass sphere: both out of focus. */
    pt_scene_add_sphere(sc, v(400, 91, 430), 90, mirror, false);
    pt_scene_add_sphere(sc, v(120, 60, 60), 60, glass, false);
    pt_scene_finish(sc);
}

void motion_scene_build_showcase(motion_scene *ms)
{
    motion_scene_init(ms);
    motion_scene_build_showcase_still(&ms->base);
    const int blue = 7, yellow = 8; /* materials of the still part */
    /* In the plane of focus (1000 mm in front of the eye, z = 200): a
     * sphere moving 80 mm to the left (+x; the camera looks along +z) and
     * a cube rising 60 mm while the shutter is open. */
    motion_scene_add_sphere(ms, v(200, 60, 250), v(80, 0, 0), 60, blue);
    mesh cube;
    mesh_init(&cube);
    mesh_add_box(&cube, v(330, 0, 180), v(410, 80, 260), yellow);
    motion_scene_add_mesh(ms, &cube, v(0, 60, 0));
    ms->aperture_radius = 25.0f;
    ms->focus_distance = 1000.0f;
}

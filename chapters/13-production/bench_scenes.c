/* bench_scenes.c -- the benchmark's scenes (bench_scenes.h). */
#include "13-production/bench_scenes.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "atomic_file.h"
#include "rng.h"

const char *const BENCH_SCENE_NAMES[] = {"cornell", "cornell-10k", "cornell-100k", "cornell-1m", "glossy-glass",
                                        "open-100k", "many-lights", NULL};
const char *const BENCH_SCENE_NOTES[] = {
    "chapter 09's Cornell box, 32 triangles",
    "the box with a bumpy torus of 10,240 triangles",
    "the box with a bumpy torus of 102,400 triangles",
    "the box with a bumpy torus of 1,048,576 triangles",
    "a GGX copper block and a glass ball of 5,120 triangles",
    "sixteen gold tori of 102,400 triangles over a ground, under a sky: no room",
    "the box lit by 5,104 small lamps of random power on its walls and ceiling: 10,208 emitting triangles",
    NULL};

/* The torus's grid, U x V, for each mesh size: 2 U V triangles, the sizes
 * of the Embree harness's tori field (10,240, 102,400, 1,048,576). */
static const int TORUS_GRID[3][2] = {{128, 40}, {320, 160}, {1024, 512}};

void bench_bumpy_torus(mesh *m, vec3 c, float major, float r0, int u, int v, int material)
{
    int base = m->position_count;
    for (int i = 0; i < u; i++) {
        float theta = 2.0f * (float)PI * (float)i / (float)u;
        for (int j = 0; j < v; j++) {
            float phi = 2.0f * (float)PI * (float)j / (float)v;
            /* five bumps around, three across the tube, and a finer ripple */
            float r = r0 * (1.0f + 0.2f * sinf(5.0f * theta) * cosf(3.0f * phi) +
                            0.06f * sinf(17.0f * theta + 2.0f * phi));
            float ring = major + r * cosf(phi);
            mesh_add_position(m, vec3_make(c.x + ring * cosf(theta), c.y + r * sinf(phi), c.z + ring * sinf(theta)));
        }
    }
    for (int i = 0; i < u; i++)
        for (int j = 0; j < v; j++) {
            int a = base + i * v + j, b = base + ((i + 1) % u) * v + j;
            int d = base + ((i + 1) % u) * v + (j + 1) % v, e = base + i * v + (j + 1) % v;
            mesh_add_triangle(m, a, e, d, material);
            mesh_add_triangle(m, a, d, b, material);
        }
}

/* dst: src's materials, triangles and camera, without its spheres, not
 * finished (so that more can be added). */
static void copy_triangles(pt_scene *dst, const pt_scene *src)
{
    pt_scene_init(dst);
    for (int i = 0; i < src->material_count; i++)
        pt_scene_add_material(dst, src->materials[i]);
    const mesh *g = &src->geometry;
    for (int i = 0; i < g->face_count; i++)
        pt_scene_add_triangle(dst, mesh_vertex(g, i, 0), mesh_vertex(g, i, 1), mesh_vertex(g, i, 2),
                              g->faces[i].material);
    dst->eye = src->eye;
    dst->target = src->target;
    dst->up = src->up;
    dst->vertical_fov_degrees = src->vertical_fov_degrees;
    dst->environment = src->environment;
}

/* The box with the torus resting just above the short block's top
 * (y = 165, centred near x 186, z 169). Material 0 is the box's white. */
static void build_torus_box(pt_scene *sc, int size_index)
{
    pt_scene box;
    pt_scene_build_cornell_box(&box);
    copy_triangles(sc, &box);
    pt_scene_free(&box);
    const float r0 = 22.0f;
    vec3 centre = vec3_make(186.0f, 165.0f + 1.3f * r0 + 2.0f, 169.0f);
    bench_bumpy_torus(&sc->geometry, centre, 62.0f, r0, TORUS_GRID[size_index][0], TORUS_GRID[size_index][1], 0);
    pt_scene_finish(sc);
}

/* Chapter 09's materials scene with its glass sphere made of triangles:
 * an icosphere subdivided 4 times (5,120 flat triangles) of the same
 * centre, radius and material. */
static void build_glossy_glass(pt_scene *sc)
{
    pt_scene src;
    pt_scene_build_cornell_box_materials(&src);
    copy_triangles(sc, &src);
    for (int i = 0; i < src.sphere_count; i++)
        mesh_icosphere(&sc->geometry, src.spheres[i].center, src.spheres[i].radius, 4, src.spheres[i].material);
    pt_scene_free(&src);
    pt_scene_finish(sc);
}

/* A scene unlike the box: what a student exports from a modelling
 * program, objects over a ground plane under a sky, lit by the sky and one
 * small lamp. Most paths leave the scene within a few bounces, the lamp
 * is a small part of the light, and no room surrounds the camera (the
 * walls' shortcut finds only the ground and the lamp). The objects are the Embree
 * harness's tori field (16 interlocking tori, 102,400 triangles) in GGX
 * gold, so most bounces go through chapter 09's glossy BSDF. */
static void build_open(pt_scene *sc)
{
    pt_scene_init(sc);
    int ground = pt_scene_add_material(sc, pt_diffuse(vec3_make(0.5f, 0.5f, 0.45f)));
    int gold = pt_scene_add_material(sc, pt_glossy(vec3_make(1.0f, 0.78f, 0.34f), 0.25f));
    int lamp = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.0f), vec3_make(30.0f, 27.0f, 22.0f)));
    const float y = -1.6f, h = 20.0f; /* the field spans about [-1.5, 1.5] in each axis */
    pt_scene_add_quad(sc, vec3_make(-h, y, h), vec3_make(h, y, h), vec3_make(h, y, -h), vec3_make(-h, y, -h),
                      ground); /* facing up */
    pt_scene_add_quad(sc, vec3_make(0.0f, 3.5f, 0.0f), vec3_make(1.0f, 3.5f, 0.0f), vec3_make(1.0f, 3.5f, 1.0f),
                      vec3_make(0.0f, 3.5f, 1.0f), lamp); /* facing down */
    int first = sc->geometry.face_count;
    mesh_tori_field(&sc->geometry, 102400);
    for (int i = first; i < sc->geometry.face_count; i++)
        sc->geometry.faces[i].material = gold;
    sc->environment = vec3_make(0.45f, 0.55f, 0.75f);
    sc->eye = vec3_make(0.0f, 0.8f, 6.5f);
    sc->target = vec3_make(0.0f, -0.3f, 0.0f);
    sc->up = vec3_make(0.0f, 1.0f, 0.0f);
    sc->vertical_fov_degrees = 40.0f;
    pt_scene_finish(sc);
}

/* ---- many lights -------------------------------------------------------------------
 * The Cornell box (its blocks and its ceiling light) with its ceiling and
 * three walls studded with small square lamps, 6 mm across on a 36 x 36
 * grid, 1 mm in front of the surface and facing into the room; none under
 * the ceiling light. Each lamp's radiance is one of MANY_LIGHTS_LEVELS
 * colours whose brightness doubles every two levels (a range of 2^7.5,
 * about 180x), drawn at random with a fixed seed: varied power, from
 * lamps far brighter than their neighbours to lamps barely lit, so that
 * the pick by power spends its samples on bright lamps wherever they
 * are, and the light tree can do better by looking at distance and
 * facing too. The levels are materials, so that the scene's OBJ and MTL
 * stay small. */
enum { MANY_LIGHTS_GRID = 36, MANY_LIGHTS_LEVELS = 16 };
static const float MANY_LIGHTS_HALF_SIZE = 3.0f, MANY_LIGHTS_GAP = 1.0f;

/* A lamp: the square of centre c spanned by u and v (half sizes), facing
 * u x v. */
static void add_lamp(pt_scene *sc, vec3 c, vec3 u, vec3 v, int material)
{
    pt_scene_add_quad(sc, vec3_sub(vec3_sub(c, u), v), vec3_sub(vec3_add(c, u), v), vec3_add(vec3_add(c, u), v),
                      vec3_add(vec3_sub(c, u), v), material);
}

/* One surface's grid of lamps: the plane through `origin` spanned by
 * `across` and `up` (the whole wall), facing across x up (into the room:
 * ceiling, back wall, green wall, red wall), each lamp of a level drawn
 * from rng. */
static void add_lamp_grid(pt_scene *sc, vec3 origin, vec3 across, vec3 up, const int level[], pcg32 *rng)
{
    vec3 u = vec3_scale(vec3_normalize(across), MANY_LIGHTS_HALF_SIZE);
    vec3 v = vec3_scale(vec3_normalize(up), MANY_LIGHTS_HALF_SIZE);
    vec3 out = vec3_scale(vec3_normalize(vec3_cross(across, up)), MANY_LIGHTS_GAP);
    for (int i = 0; i < MANY_LIGHTS_GRID; i++)
        for (int j = 0; j < MANY_LIGHTS_GRID; j++) {
            float s = ((float)i + 0.5f) / MANY_LIGHTS_GRID, t = ((float)j + 0.5f) / MANY_LIGHTS_GRID;
            vec3 c = vec3_add(vec3_add(origin, out), vec3_add(vec3_scale(across, s), vec3_scale(up, t)));
            int material = level[pcg32_bounded(rng, MANY_LIGHTS_LEVELS)];
            /* the ceiling light's rectangle (x 213..343, z 227..332) keeps its own */
            if (out.y < 0.0f && c.x > 205.0f && c.x < 351.0f && c.z > 219.0f && c.z < 340.0f)
                continue;
            add_lamp(sc, c, u, v, material);
        }
}

static void build_many_lights(pt_scene *sc)
{
    pt_scene box;
    pt_scene_build_cornell_box(&box);
    copy_triangles(sc, &box);
    pt_scene_free(&box);
    int level[MANY_LIGHTS_LEVELS];
    for (int k = 0; k < MANY_LIGHTS_LEVELS; k++) {
        /* warm and cool in turn, doubling every two levels */
        vec3 colour = k % 2 == 0 ? vec3_make(1.0f, 0.75f, 0.45f) : vec3_make(0.55f, 0.7f, 1.0f);
        level[k] = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.0f), vec3_scale(colour, 0.4f * exp2f(0.5f * (float)k))));
    }
    pcg32 rng;
    pcg32_seed(&rng, 0x11647, 7);
    const float w = 548.0f, d = 559.2f, h = 548.8f;
    add_lamp_grid(sc, vec3_make(0.0f, h, 0.0f), vec3_make(w, 0.0f, 0.0f), vec3_make(0.0f, 0.0f, d), level, &rng);
    add_lamp_grid(sc, vec3_make(0.0f, 0.0f, d), vec3_make(0.0f, h, 0.0f), vec3_make(w, 0.0f, 0.0f), level, &rng);
    add_lamp_grid(sc, vec3_make(0.0f, 0.0f, 0.0f), vec3_make(0.0f, h, 0.0f), vec3_make(0.0f, 0.0f, d), level, &rng);
    add_lamp_grid(sc, vec3_make(w, 0.0f, 0.0f), vec3_make(0.0f, 0.0f, d), vec3_make(0.0f, h, 0.0f), level, &rng);
    pt_scene_finish(sc);
}

bool bench_scene_build(pt_scene *sc, const char *name)
{
    if (strcmp(name, "cornell") == 0)
        pt_scene_build_cornell_box(sc);
    else if (strcmp(name, "cornell-10k") == 0)
        build_torus_box(sc, 0);
    else if (strcmp(name, "cornell-100k") == 0)
        build_torus_box(sc, 1);
    else if (strcmp(name, "cornell-1m") == 0)
        build_torus_box(sc, 2);
    else if (strcmp(name, "glossy-glass") == 0)
        build_glossy_glass(sc);
    else if (strcmp(name, "open-100k") == 0)
        build_open(sc);
    else if (strcmp(name, "many-lights") == 0)
        build_many_lights(sc);
    else
        return false;
    return true;
}

bool bench_scene_write(const char *dir, const char *name, char *err, size_t err_size)
{
    pt_scene sc;
    if (!bench_scene_build(&sc, name)) {
        snprintf(err, err_size, "no benchmark scene '%s'", name);
        return false;
    }
    const char *note = "";
    for (int i = 0; BENCH_SCENE_NAMES[i] != NULL; i++)
        if (strcmp(BENCH_SCENE_NAMES[i], name) == 0)
            note = BENCH_SCENE_NOTES[i];
    char obj_path[4096];
    snprintf(obj_path, sizeof obj_path, "%s/%s.obj", dir, name);
    /* OBJ holds no environment: the scene file's background line does. */
    pt_scene surfaces = sc;
    surfaces.environment = vec3_splat(0.0f);
    bool ok = pt_scene_write_obj(&surfaces, obj_path, err, err_size);
    char scene_name[512];
    snprintf(scene_name, sizeof scene_name, "%s.scene", name);
    atomic_file f;
    if (ok && (ok = atomic_file_open_in(&f, dir, scene_name, err, err_size))) {
        fprintf(f.stream,
                "# The benchmark scene '%s' (chapters/13-production/bench_scenes.c): %s.\n"
                "# Written by make bench; its triangles and materials are %s.obj and %s.mtl.\n"
                "camera eye %.9g %.9g %.9g target %.9g %.9g %.9g up %.9g %.9g %.9g fov %.9g\n"
                "mesh path \"%s.obj\"\n",
                name, note, name, name, (double)sc.eye.x, (double)sc.eye.y, (double)sc.eye.z,
                (double)sc.target.x, (double)sc.target.y, (double)sc.target.z, (double)sc.up.x, (double)sc.up.y,
                (double)sc.up.z, (double)sc.vertical_fov_degrees, name);
        vec3 sky = sc.environment;
        if (sky.x != 0.0f || sky.y != 0.0f || sky.z != 0.0f)
            fprintf(f.stream, "background %.9g %.9g %.9g\n", (double)sky.x, (double)sky.y, (double)sky.z);
        ok = atomic_file_commit(&f, err, err_size);
    }
    pt_scene_free(&sc);
    return ok;
}

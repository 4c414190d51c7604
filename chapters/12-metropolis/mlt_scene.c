/* mlt_scene.c -- the lamp in a housing (see mlt_scene.h). */
#include "12-metropolis/mlt_scene.h"

#include <math.h>

static vec3 v(float x, float y, float z) { return vec3_make(x, y, z); }

/* An axis-aligned rectangle in the plane y = const, x0..x1 by z0..z1. */
static void add_horizontal(pt_scene *sc, float y, float x0, float x1, float z0, float z1, int m)
{
    pt_scene_add_quad(sc, v(x0, y, z0), v(x1, y, z0), v(x1, y, z1), v(x0, y, z1), m);
}

void mlt_scene_build_lamp(pt_scene *sc)
{
    pt_scene_init(sc);
    /* The Cornell box's reflectances; the light 10 times brighter than its
     * (17, 12, 4), since most of it stays in the housing. */
    int white = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_WHITE));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), vec3_make(170.0f, 120.0f, 40.0f)));
    const float width = 556.0f, height = 548.8f, depth = 559.2f;
    /* The room, each face counter-clockwise seen from inside; open at the front. */
    pt_scene_add_quad(sc, v(width, 0, 0), v(0, 0, 0), v(0, 0, depth), v(width, 0, depth), white);
    pt_scene_add_quad(sc, v(width, height, 0), v(width, height, depth), v(0, height, depth), v(0, height, 0), white);
    pt_scene_add_quad(sc, v(width, 0, depth), v(0, 0, depth), v(0, height, depth), v(width, height, depth), white);
    pt_scene_add_quad(sc, v(0, 0, depth), v(0, 0, 0), v(0, height, 0), v(0, height, depth), green);
    pt_scene_add_quad(sc, v(width, 0, 0), v(width, 0, depth), v(width, height, depth), v(width, height, 0), red);
    /* The light, 0.1 mm below the ceiling, facing down. */
    pt_scene_add_quad(sc, v(343, 548.7f, 227), v(343, 548.7f, 332), v(213, 548.7f, 332), v(213, 548.7f, 227), light);
    /* The housing: a plate 8 cm below the light, 45 mm wider on every side,
     * and walls from the ceiling down to 1 cm below the plate, standing
     * `gap` outside its edge: light leaves only down that channel. The
     * camera looks up the two side channels a little (the bright edges of
     * the housing in the picture), not up the front or back one. */
    const float gap = 20.0f, plate = 470.0f, wall_bottom = plate - 10.0f;
    const float x0 = 168.0f, x1 = 388.0f, z0 = 182.0f, z1 = 377.0f;
    const float wx0 = x0 - gap, wx1 = x1 + gap, wz0 = z0 - gap, wz1 = z1 + gap;
    add_horizontal(sc, plate, x0, x1, z0, z1, white);
    pt_scene_add_quad(sc, v(wx0, wall_bottom, wz0), v(wx1, wall_bottom, wz0), v(wx1, height, wz0), v(wx0, height, wz0),
                      white);
    pt_scene_add_quad(sc, v(wx1, wall_bottom, wz1), v(wx0, wall_bottom, wz1), v(wx0, height, wz1), v(wx1, height, wz1),
                      white);
    pt_scene_add_quad(sc, v(wx0, wall_bottom, wz1), v(wx0, wall_bottom, wz0), v(wx0, height, wz0), v(wx0, height, wz1),
                      white);
    pt_scene_add_quad(sc, v(wx1, wall_bottom, wz0), v(wx1, wall_bottom, wz1), v(wx1, height, wz1), v(wx1, height, wz0),
                      white);
    sc->eye = v(278, 273, -800);
    sc->target = v(278, 273, 0);
    sc->vertical_fov_degrees = 2.0f * atanf(12.5f / 35.0f) * 180.0f / (float)PI;
    pt_scene_finish(sc);
}


/* scene_lamp.c -- the scene where bidirectional path tracing wins. */
#include "11-bidirectional/bdpt.h"

static vec3 v(float x, float y, float z) { return vec3_make(x, y, z); }

/* The five visible faces of a box, each counter-clockwise from outside. */
static void add_box(pt_scene *sc, vec3 lo, vec3 hi, int m)
{
    float x0 = lo.x, y0 = lo.y, z0 = lo.z, x1 = hi.x, y1 = hi.y, z1 = hi.z;
    pt_scene_add_quad(sc, v(x0, y1, z0), v(x0, y1, z1), v(x1, y1, z1), v(x1, y1, z0), m); /* top */
    pt_scene_add_quad(sc, v(x0, y0, z0), v(x0, y1, z0), v(x1, y1, z0), v(x1, y0, z0), m); /* -z */
    pt_scene_add_quad(sc, v(x0, y0, z1), v(x1, y0, z1), v(x1, y1, z1), v(x0, y1, z1), m); /* +z */
    pt_scene_add_quad(sc, v(x0, y0, z0), v(x0, y0, z1), v(x0, y1, z1), v(x0, y1, z0), m); /* -x */
    pt_scene_add_quad(sc, v(x1, y0, z0), v(x1, y1, z0), v(x1, y1, z1), v(x1, y0, z1), m); /* +x */
}

/* A closed room 4 x 3 x 5 m (the camera inside, by the front wall), white
 * with a red and a green wall as in the Cornell box, a block on the floor,
 * and a lamp: a 0.3 m square 0.3 m under the ceiling, emitting upwards only.
 * Everything the eye sees is lit through the bright patch the lamp makes on
 * the ceiling. For a path tracer that is hard: light sampling from the floor
 * finds the lamp's back (no light), so a floor point is lit only when its
 * BSDF sample happens to hit the small patch and the light sample there
 * finds the lamp. A light subpath reaches the patch at once (s = 2), and
 * joining it to every camera vertex lights the room. */
void bdpt_scene_build_ceiling_lamp(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_material(sc, pt_diffuse(vec3_make(0.75f, 0.74f, 0.72f)));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    /* The lamp's underside is dark: a shade */
    int lamp = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.1f), vec3_make(100.0f, 90.0f, 75.0f)));
    pt_scene_add_quad(sc, v(0, 0, 0), v(0, 0, 5), v(4, 0, 5), v(4, 0, 0), white); /* floor */
    pt_scene_add_quad(sc, v(0, 3, 0), v(4, 3, 0), v(4, 3, 5), v(0, 3, 5), white); /* ceiling */
    pt_scene_add_quad(sc, v(0, 0, 0), v(4, 0, 0), v(4, 3, 0), v(0, 3, 0), white); /* back */
    pt_scene_add_quad(sc, v(0, 0, 5), v(0, 3, 5), v(4, 3, 5), v(4, 0, 5), white); /* front, behind the eye */
    pt_scene_add_quad(sc, v(0, 0, 0), v(0, 3, 0), v(0, 3, 5), v(0, 0, 5), red);   /* left */
    pt_scene_add_quad(sc, v(4, 0, 0), v(4, 0, 5), v(4, 3, 5), v(4, 3, 0), green); /* right */
    add_box(sc, v(0.8f, 0.0f, 1.2f), v(1.7f, 1.0f, 2.1f), white);
    /* the lamp, facing up (+y) */
    pt_scene_add_quad(sc, v(2.35f, 2.7f, 2.05f), v(2.35f, 2.7f, 2.35f), v(2.65f, 2.7f, 2.35f), v(2.65f, 2.7f, 2.05f),
                      lamp);
    sc->eye = v(2.0f, 1.5f, 4.9f);
    sc->target = v(2.0f, 1.3f, 0.0f);
    sc->up = v(0, 1, 0);
    sc->vertical_fov_degrees = 62.0f;
    pt_scene_finish(sc);
}

/* bdpt.h -- bidirectional path tracing (Veach 1997, ch. 10; Lafortune and
 * Willems 1993): a path from the eye and a path from the light, joined in
 * every possible way, each join weighted by multiple importance sampling.
 *
 * Usage:
 *   bdpt b = bdpt_defaults(&scene, &cam);      (scene from chapter 09)
 *   if (!bdpt_supports(&scene, err, sizeof err)) ... refuse the scene
 *   estimate_image e; bdpt_render(&b, spp, seed, threads, quiet, &e);
 *
 * A full path x_0 x_1 ... x_{n-1} runs from a point on a light (x_0) to the
 * eye (x_{n-1}). The light subpath y_0 .. y_{s-1} is its first s vertices,
 * the camera subpath z_0 .. z_{t-1} (z_0 the eye) its last t, read from the
 * eye: strategy (s, t) makes the path of n = s + t vertices by drawing both
 * and joining y_{s-1} to z_{t-1} with one shadow ray. s = 0 is the camera
 * path that happens to hit a light; t = 1 is light tracing (the light
 * vertex joined to the eye, added to whichever pixel it lands on); s = 1 is
 * chapter 09's light sampling. A path of n vertices can be made by n
 * strategies (t = 0 would need rays to hit the pinhole: impossible).
 *
 * What is supported: diffuse and glossy (GGX) surfaces, emitting triangles.
 * Mirrors and glass (delta BSDFs), point lights, emitting spheres and the
 * environment are refused by bdpt_supports() with a message naming them:
 * their strategies would need weight 0 and the pdf conventions for deltas,
 * which this chapter leaves as an exercise.
 */
#ifndef BDPT_H
#define BDPT_H

#include <stdbool.h>

#include "09-path-tracing/experiments.h"
#include "09-path-tracing/scene_pt.h"
#include "splat_film.h"

/* The longest subpath: a camera subpath of max_depth + 2 vertices makes a
 * path of max_depth bounces with s = 0. */
enum { BDPT_MAX_DEPTH = 64, BDPT_MAX_VERTICES = BDPT_MAX_DEPTH + 2 };

typedef enum { BDPT_VERTEX_CAMERA, BDPT_VERTEX_LIGHT, BDPT_VERTEX_SURFACE } bdpt_vertex_kind;

/* One vertex of a subpath. pdf_fwd is the density per unit area with which
 * its own subpath made it; pdf_rev the density with which the other side
 * would have made it (walking the other way through the same vertices).
 * The ratios of the two are all multiple importance sampling needs. */
typedef struct {
    bdpt_vertex_kind kind;
    vec3 point;
    vec3 normal;          /* shading normal, on the side the path arrived from (light: its front) */
    vec3 normal_geometric; /* for leaving the surface (ray_spawn) */
    float point_error;    /* the point's error bound (ray.h; 0 at the eye, which is exact) */
    int material;
    bool front_face;      /* a camera vertex on an emitter sees its emission only from the front */
    vec3 beta;            /* throughput: the product of the weights up to and including this vertex */
    float pdf_fwd, pdf_rev;
} bdpt_vertex;

typedef enum { BDPT_POWER, BDPT_BALANCE } bdpt_heuristic;

/* Deliberately wrong variants, for the tests' twins only. */
typedef enum {
    BDPT_FAULT_NONE,
    BDPT_FAULT_NO_LIGHT_COSINE,   /* the cosine at the light vertex left out of the geometry term */
    BDPT_FAULT_SOLID_ANGLE_PDF,   /* a connection's reverse pdf left per unit solid angle */
} bdpt_fault;

typedef struct {
    const pt_scene *scene;
    const camera *cam;
    int max_depth;       /* bounces counted at most: a path of n vertices has n - 2 */
    int rr_start_depth;  /* Russian roulette (on each bounce's weight) after this many vertices */
    bdpt_heuristic heuristic;
    /* --strategy s,t: only that strategy's contribution (-1: all), weighted
     * by MIS or, with unweighted, in full (then it alone is an unbiased
     * estimate of the paths it can make). */
    int only_s, only_t;
    bool unweighted;
    bdpt_fault fault;
    splat_film *film;    /* where t = 1 lands: set by bdpt_render */
} bdpt;

bdpt bdpt_defaults(const pt_scene *scene, const camera *cam);

/* True if the scene has only what this chapter handles (see above); else
 * false with err naming what it has that is not. */
bool bdpt_supports(const pt_scene *sc, char *err, size_t err_size);

/* render.h's radiance_fn (ctx points to a bdpt whose film is set): the
 * strategies with t >= 2 for this camera ray; t = 1 is splatted to the film. */
vec3 bdpt_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters);

/* The image: spp camera paths per pixel (one light path with each), the
 * camera part averaged per pixel plus the splats divided by spp. The
 * standard error is that of the camera part (the splats' is not per pixel).
 * Same image for any thread count. False if memory ran out. */
bool bdpt_render(const bdpt *b, int spp, uint64_t seed, int threads, bool quiet, estimate_image *out);

/* How long bdpt_render would take on one thread, from a pilot of a few
 * pixels (program_pilot_seconds; their splats land on a film of their own
 * and are thrown away). 0 for small images or if memory ran out. */
double bdpt_pilot_seconds(const bdpt *b, int spp, uint64_t seed);

/* ---- the pieces, exposed for the tests ---------------------------------- */

/* The density per unit area at `to` with which `from` draws the direction
 * to it, when `from` was reached from `before` (NULL at a path's end: the
 * eye draws through the image, a light on its hemisphere by cosine). */
float bdpt_pdf_area(const bdpt *b, const bdpt_vertex *from, const bdpt_vertex *before, const bdpt_vertex *to);

/* The unweighted value of the join of a light subpath's last vertex y
 * (reached from y_before; NULL when y is on the light) and a camera
 * subpath's last vertex z (reached from z_before): beta(y) f(y) G(y, z)
 * f(z) beta(z), without the visibility. Black when either BSDF or G is 0. */
vec3 bdpt_connect(const bdpt *b, const bdpt_vertex *y, const bdpt_vertex *y_before, const bdpt_vertex *z,
                  const bdpt_vertex *z_before);

/* The MIS weight of strategy (s, t) for the path light[0..s-1] + camera
 * [t-1..0], from the subpaths' pdfs and those the join changes. */
float bdpt_mis_weight(const bdpt *b, const bdpt_vertex *light, int s, const bdpt_vertex *camera, int t);

/* A subpath's pdf_fwd and pdf_rev from its vertices alone (what the random
 * walk stores as it goes): for the tests, which build paths by hand. */
void bdpt_subpath_fill_pdfs(const bdpt *b, bdpt_vertex *v, int count);

/* Where the eye sees `point`: raster coordinates, and the importance factor
 * W_e cos(theta) / |eye - point|^2 ... false if outside the image. */
bool bdpt_camera_project(const camera *cam, vec3 point, float *px, float *py);

/* The density per unit solid angle of the pinhole camera's ray direction
 * (uniform over the image plane at distance 1): 1 / (A cos^3 theta). */
float bdpt_camera_pdf_direction(const camera *cam, vec3 direction);

/* The scene where bidirectional path tracing wins: a room lit by a small
 * lamp just under the ceiling that shines up at it, so that every lit point
 * is lit only by the bright patch on the ceiling. */
void bdpt_scene_build_ceiling_lamp(pt_scene *sc);

#endif

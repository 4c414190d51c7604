/* 03-aabb-slabs: bounding boxes over a mesh, and what testing them first saves.
 *
 * The scene is the "tori field" (16 tori, 10240 triangles). Each torus gets
 * one bounding box. A ray first takes the slab test against a torus's box and
 * tests that torus's triangles only if the box is hit: the lecture's "if a
 * ray misses the bounding volume, it misses the object inside". The picture
 * shows the tori with their boxes drawn over them; the report compares the
 * triangle tests per ray with and without the boxes. */
#include <stdio.h>
#include <stdlib.h>

#include "03-aabb-slabs/accel_program.h"
#include "cli.h"
#include "explain.h"
#include "memory.h"
#include "program.h"

enum { TORI = 16 };

typedef struct {
    triangle_set set;
    int object_count;  /* the 16 tori, or the shapes of a scene file */
    aabb *boxes;       /* one per object */
    int *first;        /* object k owns triangles first[k] .. first[k+1]-1 */
    bool use_boxes;
    bool draw_boxes;
} boxed_scene;

/* Width of a drawn box edge, as a fraction of the box's size. */
static const float EDGE_WIDTH = 0.006f;

/* Is the point p on the box's surface near one of its 12 edges? It is when
 * two of its three coordinates lie on the box's faces. */
static bool near_box_edge(const aabb *b, vec3 p)
{
    vec3 e = aabb_extent(*b);
    float tolerance = EDGE_WIDTH * vec3_max_component(e);
    int on_faces = 0;
    for (int axis = 0; axis < 3; axis++) {
        float v = vec3_axis(p, axis);
        on_faces += fabsf(v - vec3_axis(b->lo, axis)) < tolerance || fabsf(v - vec3_axis(b->hi, axis)) < tolerance;
    }
    return on_faces >= 2;
}

static vec3 torus_colour(int k)
{
    /* Distinct, calm colours from a golden-ratio walk around the hue circle. */
    float h = fmodf(0.13f + 0.618034f * (float)k, 1.0f) * 6.0f;
    float x = 1.0f - fabsf(fmodf(h, 2.0f) - 1.0f);
    vec3 c = h < 1 ? vec3_make(1, x, 0) : h < 2 ? vec3_make(x, 1, 0) : h < 3 ? vec3_make(0, 1, x)
           : h < 4 ? vec3_make(0, x, 1) : h < 5 ? vec3_make(x, 0, 1) : vec3_make(1, 0, x);
    return vec3_add(vec3_scale(c, 0.55f), vec3_splat(0.2f));
}

static vec3 boxed_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)rng;
    const boxed_scene *sc = ctx;
    slab_ray sr = slab_ray_make(r);
    /* The triangle test is the watertight one (chapter 01's shapes.h): its
     * ray part once, here, for every triangle below. */
    watertight_ray wr = watertight_ray_make(&r);
    uint64_t tests_before = counters->primitive_tests;
    int best = -1;
    float best_t = INFINITY, best_b1 = 0, best_b2 = 0;
    vec3 overlay = vec3_splat(0.0f);
    for (int k = 0; k < sc->object_count; k++) {
        float t_enter, t_exit;
        if (sc->use_boxes) {
            counters->box_tests++;
            bool hit_box = aabb_slab_test(&sc->boxes[k], &sr, 0.0f, INFINITY, &t_enter, &t_exit);
            if (hit_box && sc->draw_boxes) {
                /* Boxes tint what is behind them; their edges are drawn. */
                overlay = vec3_add(overlay, vec3_scale(torus_colour(k), 0.05f));
                if (near_box_edge(&sc->boxes[k], ray_at(r, t_enter)) || near_box_edge(&sc->boxes[k], ray_at(r, t_exit)))
                    overlay = vec3_add(overlay, vec3_scale(torus_colour(k), 0.6f));
            }
            /* Missed the box, or the box starts beyond the closest hit so
             * far: nothing inside can be closer. */
            if (!hit_box || t_enter > best_t)
                continue;
        }
        counters->primitive_tests += (uint64_t)(sc->first[k + 1] - sc->first[k]);
        for (int i = sc->first[k]; i < sc->first[k + 1]; i++) {
            float t, b1, b2;
            if (watertight_intersect_triangle(&wr, &sc->set.triangles[i], r.t_max, &t, &b1, &b2)) {
                best = i;
                r.t_max = best_t = t; /* only closer hits from now on */
                best_b1 = b1;
                best_b2 = b2;
            }
        }
    }
    if (explain_on()) {
        explain_line(1, "%d object boxes tested, %llu triangles tested (only inside boxes the ray entered, nearer "
                     "than the best hit)", sc->use_boxes ? sc->object_count : 0,
                     (unsigned long long)(counters->primitive_tests - tests_before));
        if (best >= 0)
            explain_line(1, "closest hit: triangle #%d at t = %.6g", best, (double)best_t);
        else
            explain_line(1, "no triangle hit: the background");
    }
    vec3 colour = vec3_make(0.02f, 0.02f, 0.03f);
    if (best >= 0) {
        hit_record hit;
        triangle_set_fill_hit(&sc->set, best, r, best_t, best_b1, best_b2, &hit);
        int k = 0;
        while (best >= sc->first[k + 1])
            k++;
        /* Headlight shading: brightest where the surface faces the eye. */
        float facing = fabsf(vec3_dot(hit.normal_geometric, vec3_normalize(r.direction)));
        colour = vec3_scale(torus_colour(k), 0.15f + 0.85f * facing);
    }
    return vec3_add(colour, overlay);
}

/* The tori field: mesh_tori_field builds the tori one after another, each
 * with the same number of triangles. */
static void load_tori(mesh *m, boxed_scene *sc)
{
    mesh_tori_field(m, 10240);
    sc->object_count = TORI;
    sc->first = memory_allocate(TORI + 1, sizeof(int));
    int per_torus = m->face_count / TORI;
    for (int k = 0; k <= TORI; k++)
        sc->first[k] = k * per_torus;
}

/* One box around each object's triangles. */
static void build_boxes(boxed_scene *sc)
{
    sc->boxes = memory_allocate((size_t)sc->object_count, sizeof(aabb));
    for (int k = 0; k < sc->object_count; k++) {
        sc->boxes[k] = aabb_empty();
        for (int i = sc->first[k]; i < sc->first[k + 1]; i++)
            sc->boxes[k] = aabb_union(sc->boxes[k], sc->set.boxes[i]);
    }
}

/* The scene file's objects (--scene) or the tori field, their boxes, and
 * the camera: the file's, or the same view as the Embree harness's
 * coherent ray set. On a bad scene file prints why and returns false. */
static bool boxed_scene_load(boxed_scene *sc, mesh *m, cli_options *opts, const char *program, camera *cam)
{
    scene_desc desc;
    mesh_init(m);
    if (program_load_scene(opts, program, &desc)) {
        char err[SCENE_ERROR_SIZE];
        if (!accel_mesh_from_desc(m, &desc, program, &sc->first, &sc->object_count, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", program, err);
            scene_desc_free(&desc);
            return false;
        }
    } else {
        load_tori(m, sc);
    }
    triangle_set_from_mesh(&sc->set, m);
    build_boxes(sc);
    *cam = accel_scene_camera(&desc, sc->set.bounds, opts->width, opts->height);
    scene_desc_free(&desc);
    return true;
}

static void boxed_scene_report(const boxed_scene *sc, const render_stats *stats)
{
    double rays = (double)stats->counters.camera_rays;
    if (sc->use_boxes)
        printf("with boxes: %.1f box tests and %.1f triangle tests per ray (without: %d triangle tests per ray)\n",
               (double)stats->counters.box_tests / rays, (double)stats->counters.primitive_tests / rays, sc->set.count);
    else
        printf("without boxes: %.1f triangle tests per ray\n", (double)stats->counters.primitive_tests / rays);
}

static void boxed_scene_free(boxed_scene *sc, mesh *m)
{
    triangle_set_free(&sc->set);
    free(sc->boxes);
    free(sc->first);
    mesh_free(m);
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch03.exr", 640, 480, 1);
    bool no_boxes = false, hide_boxes = false;
    const cli_flag extras[] = {
        {"--no-boxes", CLI_BOOL, &no_boxes, NULL, "test every triangle (no bounding boxes): compare the counts", 0, 0},
        {"--hide-boxes", CLI_BOOL, &hide_boxes, NULL, "use the boxes but do not draw them", 0, 0},
    };
    cli_spec spec = {"03-aabb-slabs",
                     "Bounding volumes and the slab test (GAMES101 lecture 13): 16 tori, 10240 triangles, one\n"
                     "axis-aligned box per torus. Rays take the slab test against a box before testing the\n"
                     "triangles inside. Prints the box and triangle tests per ray. The built-in scene is\n"
                     "chapters/03-aabb-slabs/scenes/default.scene; with --scene, each triangle, quad or mesh\n"
                     "statement gets one box (the tori field one per torus).",
                     extras, 2, "its camera ray (the boxes and triangles it is tested against)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    mesh m;
    boxed_scene sc = {.use_boxes = !no_boxes, .draw_boxes = !no_boxes && !hide_boxes};
    camera cam;
    if (!boxed_scene_load(&sc, &m, &opts, spec.program, &cam))
        return 1;
    render_stats stats;
    int status = program_render(&opts, spec.program, boxed_radiance, &sc, &cam, &stats);
    if (status == 0 && !opts.quiet)
        boxed_scene_report(&sc, &stats);
    boxed_scene_free(&sc, &m);
    return status;
}

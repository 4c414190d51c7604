/* speed.c -- the production steps measured side by side (speed.h). */
#include "13-production/speed.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "06-bvh/bvh.h"
#include "09-path-tracing/experiments.h"
#include "13-production/bench_scenes.h"
#include "13-production/path_tracer_wide.h"
#include "13-production/walls.h"

/* ---- speed ------------------------------------------------------------------------
 * Seconds per million camera samples, for each case, on 1 and 2 threads.
 * CPU time (all threads together) is printed beside the wall time: on a
 * shared machine the wall time of 2 threads depends on what else runs. */

typedef enum {
    ON_LECTURE_BVH,  /* chapter 06's binary BVH: the lecture track */
    ON_PRODUCTION,   /* production_accel_build(), walls off */
    ON_WALLS,        /* ... with the walls (the caller's builder) */
    EIGHT_PATHS,     /* ... and eight paths at a time (path_tracer_wide.c) */
} speed_structure;

typedef struct {
    pt_integrator integrator;
    pt_russian_roulette rr;
    int rr_start_depth;
    const char *label;
    speed_structure structure;
} speed_case;

/* The first four are the steps, in order, on the lecture rung with the
 * lecture's roulette. The rest compare at the references' depths: Russian
 * roulette on the throughput from bounce 5 on (pbrt-v3's rule), on the
 * surface's albedo from bounce 6 on (smallpt's: `if (++depth > 5)`
 * continue with probability max(f)), and none at all, the full 50
 * bounces (RTROWL), each by MIS one path at a time and by the lecture rung
 * eight paths at a time. */
static const speed_case speed_cases[] = {
    {PT_LECTURE, RR_FIXED, 0, "lecture, P_RR 0.8, chapter 06 BVH", ON_LECTURE_BVH},
    {PT_LECTURE, RR_FIXED, 0, "lecture, P_RR 0.8, flat / wide BVH", ON_PRODUCTION},
    {PT_LECTURE, RR_FIXED, 0, "lecture, P_RR 0.8, + walls", ON_WALLS},
    {PT_LECTURE, RR_FIXED, 0, "lecture, P_RR 0.8, 8 paths at a time", EIGHT_PATHS},
    {PT_COSINE, RR_FIXED, 0, "cosine, P_RR 0.8", ON_WALLS},
    {PT_MIS, RR_FIXED, 0, "mis, P_RR 0.8", ON_WALLS},
    {PT_MIS, RR_THROUGHPUT, RR_START_PBRT, "mis, RR on throughput from 5 (pbrt)", ON_WALLS},
    {PT_LECTURE, RR_THROUGHPUT, RR_START_PBRT, "lecture, pbrt's RR, 8 paths at a time", EIGHT_PATHS},
    {PT_MIS, RR_ALBEDO, RR_START_SMALLPT, "mis, RR on albedo from 6 (smallpt)", ON_WALLS},
    {PT_LECTURE, RR_ALBEDO, RR_START_SMALLPT, "lecture, smallpt's RR, 8 paths at a time", EIGHT_PATHS},
    {PT_MIS, RR_OFF, 0, "mis, no RR, depth 50 (RTROWL)", ON_WALLS},
    {PT_LECTURE, RR_OFF, 0, "lecture, RTROWL's depth, 8 paths at a time", EIGHT_PATHS},
};
_Static_assert(sizeof speed_cases / sizeof speed_cases[0] == PRODUCTION_SPEED_CASES,
               "speed.h: PRODUCTION_SPEED_CASES is the number of speed cases");

static accel *lecture_bvh(const triangle_set *set, const void *context)
{
    (void)context;
    return bvh_build(set, BVH_SPLIT_SAH);
}

static accel *production_alone(const triangle_set *set, const void *context)
{
    (void)context;
    return production_accel_build(set);
}

int production_speed_scene(pt_scene *sc, const char *label, int size, int spp, int repeats,
                           pt_accel_builder production, const void *context, production_speed_row *rows)
{
    camera cam = pt_scene_camera(sc, size, size);
    double million_samples = (double)size * (double)size * (double)spp * 1e-6;
    printf("%s %dx%d, %d spp (%.2f M camera samples), max depth %d, best of %d runs\n", label, size, size, spp,
           million_samples, SPEED_MAX_DEPTH, repeats);
    printf("%-44s %7s %12s %12s %10s %8s\n", "case", "threads", "s/M (wall)", "s/M (CPU)", "rays/spl", "scaling");
    const int n_cases = (int)(sizeof speed_cases / sizeof speed_cases[0]);
    for (int k = 0; k < n_cases; k++) {
        speed_structure s = speed_cases[k].structure;
        if (s == ON_LECTURE_BVH)
            pt_scene_use_accel(sc, lecture_bvh, NULL);
        else if (s == ON_PRODUCTION)
            pt_scene_use_accel(sc, production_alone, NULL);
        else
            pt_scene_use_accel(sc, production, context);
        path_tracer pt = path_tracer_defaults(sc);
        pt.integrator = speed_cases[k].integrator;
        pt.russian_roulette = speed_cases[k].rr;
        pt.max_depth = SPEED_MAX_DEPTH;
        if (speed_cases[k].rr_start_depth > 0)
            pt.rr_start_depth = speed_cases[k].rr_start_depth;
        char why[128];
        bool wide = s == EIGHT_PATHS && path_tracer_wide_supported(&pt, why, sizeof why);
        if (s == EIGHT_PATHS && !wide)
            printf("%s: not here (%s), one path at a time instead\n", speed_cases[k].label, why);
        /* 1 and 2 threads take turns, repeat after repeat, so that both see
         * the same machine: on a shared or virtual machine the speed drifts
         * by 10 % over seconds, and the best of runs taken back to back
         * would put that drift into the scaling. */
        double best_wall[2] = {INFINITY, INFINITY}, best_cpu[2] = {INFINITY, INFINITY}, rays = 0.0;
        for (int r = 0; r < repeats; r++) {
            for (int threads = 1; threads <= 2; threads++) {
                double cpu_start = experiment_cpu_seconds();
                estimate_image e;
                if (!wide || !render_estimate_wide(&pt, &cam, spp, 1, threads, &e))
                    e = render_estimate(&pt, &cam, spp, 1, threads);
                double cpu = experiment_cpu_seconds() - cpu_start;
                best_wall[threads - 1] = fmin(best_wall[threads - 1], e.seconds);
                best_cpu[threads - 1] = fmin(best_cpu[threads - 1], cpu);
                rays = (double)counters_total_rays(&e.counters) / (million_samples * 1e6);
                estimate_image_free(&e);
            }
        }
        production_speed_row row = {.label = speed_cases[k].label, .rays_per_sample = rays, .wide = wide};
        for (int threads = 1; threads <= 2; threads++) {
            row.wall[threads - 1] = best_wall[threads - 1] / million_samples;
            row.cpu[threads - 1] = best_cpu[threads - 1] / million_samples;
            row.scaling[threads - 1] = best_wall[0] / best_wall[threads - 1];
            printf("%-44s %7d %12.3f %12.3f %10.2f %7.2fx\n", row.label, threads, row.wall[threads - 1],
                   row.cpu[threads - 1], rays, row.scaling[threads - 1]);
            fflush(stdout);
        }
        if (rows != NULL)
            rows[k] = row;
    }
    return n_cases;
}

/* ---- the triangle test ----------------------------------------------------------------
 * What the watertight triangle test costs the renderers, against the
 * lecture's Moller-Trumbore on the same structure (accel_use_triangle_test):
 * the lecture rung with the walls one path at a time, and eight paths at a
 * time, on 1 thread, the two tests taking turns repeat after repeat (each
 * first in every other repeat), the best of `repeats` of each. */
typedef struct {
    const char *label;
    bool wide;
    double wall[2], cpu[2]; /* seconds per million camera samples: watertight, Moller-Trumbore */
} triangle_test_row;

static void production_speed_triangle_tests(pt_scene *sc, int size, int spp, int repeats, triangle_test_row rows[2])
{
    camera cam = pt_scene_camera(sc, size, size);
    double million_samples = (double)size * (double)size * (double)spp * 1e-6;
    pt_scene_use_accel(sc, production_scene_accel, sc);
    path_tracer pt = path_tracer_defaults(sc);
    pt.max_depth = SPEED_MAX_DEPTH;
    printf("\nthe watertight triangle test against Moller-Trumbore, the same structure, 1 thread, taking turns, "
           "best of %d\n", repeats);
    printf("%-44s %12s %12s %12s %12s %8s\n", "case", "wt s/M wall", "wt s/M CPU", "mt s/M wall", "mt s/M CPU",
           "cost");
    for (int k = 0; k < 2; k++) {
        triangle_test_row *row = &rows[k];
        row->wide = k == 1 && path_tracer_wide_supported(&pt, NULL, 0);
        row->label = k == 0 ? "lecture, P_RR 0.8, + walls" : row->wide ? "lecture, P_RR 0.8, 8 paths at a time"
                                                                      : "lecture, P_RR 0.8, 8 paths: not here";
        for (int test = 0; test < 2; test++)
            row->wall[test] = row->cpu[test] = INFINITY;
        for (int r = 0; r < repeats; r++)
            for (int turn = 0; turn < 2; turn++) {
                int test = r % 2 ? 1 - turn : turn;
                accel_use_triangle_test(sc->bvh, (triangle_test)test);
                double cpu_start = experiment_cpu_seconds();
                estimate_image e;
                if (!row->wide || !render_estimate_wide(&pt, &cam, spp, 1, 1, &e))
                    e = render_estimate(&pt, &cam, spp, 1, 1);
                row->cpu[test] = fmin(row->cpu[test], (experiment_cpu_seconds() - cpu_start) / million_samples);
                row->wall[test] = fmin(row->wall[test], e.seconds / million_samples);
                estimate_image_free(&e);
            }
        printf("%-44s %12.3f %12.3f %12.3f %12.3f %+7.1f%%\n", row->label, row->wall[0], row->cpu[0], row->wall[1],
               row->cpu[1], 100.0 * (row->cpu[0] / row->cpu[1] - 1.0));
        fflush(stdout);
    }
    accel_use_triangle_test(sc->bvh, TRIANGLE_TEST_WATERTIGHT);
}

bool production_speed(int size, int spp, int repeats, const char *csv_path, char *err, size_t err_size)
{
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    FILE *csv = NULL;
    char csv_temp[4200];
    if (csv_path != NULL)
        snprintf(csv_temp, sizeof csv_temp, "%s.tmp", csv_path); /* as experiment_csv_open names it */
    /* Opened before the minutes of rendering, so that a bad path fails at once. */
    if (csv_path != NULL && (csv = fopen(csv_temp, "w")) == NULL) {
        snprintf(err, err_size, "%s: %s", csv_path, strerror(errno));
        pt_scene_free(&sc);
        return false;
    }
    production_speed_row rows[PRODUCTION_SPEED_CASES];
    int n = production_speed_scene(&sc, "Cornell box", size, spp, repeats, production_scene_accel, &sc, rows);
    triangle_test_row tests[2];
    production_speed_triangle_tests(&sc, size, spp, repeats, tests);
    if (csv != NULL) {
        fprintf(csv, "case,threads,wall_s_per_msample,cpu_s_per_msample,rays_per_sample,scaling\n");
        for (int k = 0; k < n; k++)
            for (int t = 0; t < 2; t++)
                fprintf(csv, "\"%s\",%d,%.4f,%.4f,%.3f,%.3f\n", rows[k].label, t + 1, rows[k].wall[t], rows[k].cpu[t],
                        rows[k].rays_per_sample, rows[k].scaling[t]);
        /* the triangle tests' rows: 1 thread, no ray count or scaling */
        for (int k = 0; k < 2; k++)
            for (int test = 0; test < 2; test++)
                fprintf(csv, "\"%s, %s\",1,%.4f,%.4f,,\n", tests[k].label, triangle_test_name((triangle_test)test),
                        tests[k].wall[test], tests[k].cpu[test]);
    }
    pt_scene_free(&sc);
    return csv == NULL || experiment_csv_close(csv, csv_path, err, err_size);
}

/* ---- scenes larger than the flat set ------------------------------------------------ */

void production_scene_box_with_torus(pt_scene *sc, int triangles)
{
    pt_scene_init(sc);
    int white = pt_scene_add_painted_cornell_room(sc);
    /* 2 u v = triangles with u = 2 v: v = sqrt(triangles / 4) */
    int v = (int)lround(sqrt((double)(triangles > 8 ? triangles : 8) / 4.0)), u = 2 * v;
    mesh torus;
    mesh_init(&torus);
    mesh_torus(&torus, vec3_make(278.0f, 200.0f, 300.0f), vec3_normalize(vec3_make(0.3f, 1.0f, -0.4f)), 150.0f, 60.0f,
               u, v, -1);
    for (int f = 0; f < torus.face_count; f++)
        pt_scene_add_triangle(sc, mesh_vertex(&torus, f, 0), mesh_vertex(&torus, f, 1), mesh_vertex(&torus, f, 2),
                              white);
    mesh_free(&torus);
    pt_scene_finish(sc);
}

/* One case's best of `repeats`, 1 thread: seconds per million samples. */
static void time_case(const path_tracer *pt, const camera *cam, int spp, int repeats, bool wide, double *wall,
                      double *cpu)
{
    double million_samples = (double)cam->width * (double)cam->height * (double)spp * 1e-6;
    *wall = *cpu = INFINITY;
    for (int r = 0; r < repeats; r++) {
        double cpu_start = experiment_cpu_seconds();
        estimate_image e;
        if (!wide || !render_estimate_wide(pt, cam, spp, 1, 1, &e))
            e = render_estimate(pt, cam, spp, 1, 1);
        *cpu = fmin(*cpu, (experiment_cpu_seconds() - cpu_start) / million_samples);
        *wall = fmin(*wall, e.seconds / million_samples);
        estimate_image_free(&e);
    }
}

void production_speed_scenes(int size, int spp, int repeats)
{
    /* The benchmark set's (bench_scenes.h), which `make bench` also times. */
    static const char *const scenes[] = {"cornell", "cornell-10k", "cornell-100k", "glossy-glass"};
    printf("seconds per million camera samples, %dx%d, %d spp, 1 thread, max depth %d, best of %d (wall, CPU)\n",
           size, size, spp, SPEED_MAX_DEPTH, repeats);
    printf("%-18s %9s %18s %18s %18s\n", "scene", "triangles", "8 paths", "--one-path", "ch09 mis, ch06 bvh");
    for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++) {
        pt_scene sc;
        bench_scene_build(&sc, scenes[i]);
        camera cam = pt_scene_camera(&sc, size, size);
        double wall[3], cpu[3];
        path_tracer pt = path_tracer_defaults(&sc);
        pt.max_depth = SPEED_MAX_DEPTH;
        pt.integrator = PT_MIS; /* chapter 09's best rung, on its own BVH */
        time_case(&pt, &cam, spp, repeats, false, &wall[2], &cpu[2]);
        pt_scene_use_accel(&sc, production_scene_accel, &sc);
        pt.integrator = PT_LECTURE;
        time_case(&pt, &cam, spp, repeats, true, &wall[0], &cpu[0]);
        time_case(&pt, &cam, spp, repeats, false, &wall[1], &cpu[1]);
        printf("%-18s %9d %8.3f %8.3f  %8.3f %8.3f  %8.3f %8.3f\n", scenes[i], sc.triangles.count, wall[0],
               cpu[0], wall[1], cpu[1], wall[2], cpu[2]);
        fflush(stdout);
        pt_scene_free(&sc);
    }
}

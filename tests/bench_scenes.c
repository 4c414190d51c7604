/* bench_scenes.c -- chapter 13's renderer on the benchmark scenes
 * (chapters/13-production/bench_scenes.h), beside the same renderer on
 * Embree's kernels and chapter 09's MIS rung. Modes:
 *
 *   --write DIR     the scene set as DIR/NAME.scene + NAME.obj + NAME.mtl
 *                   (what every renderer of the benchmark loads, Cycles too)
 *   --speed         for each scene: seconds per million camera samples (wall
 *                   and this process's CPU time), million rays per second
 *                   (wall) and per CPU-second, and rays per sample, on 1
 *                   and 2 threads, of
 *                     13 as run       chapter 13's renderer as its program runs
 *                                     it: eight paths at a time where
 *                                     path_tracer_wide_supported() says so,
 *                                     else one path at a time
 *                     13 one path     the same renderer one path at a time on
 *                                     chapter 13's structures (with the walls)
 *                     13 on Embree    the same, its rays traced by Embree 3
 *                                     (rtcIntersect1, rtcOccluded1) inside the
 *                                     same walls
 *                     13 on Embree8   eight paths at a time on Embree's
 *                                     rtcIntersect8 and rtcOccluded8, through
 *                                     the renderer's eight-ray trace
 *                                     interface (wide_trace.h)
 *                     09 mis          chapter 09's MIS rung on chapter 06's BVH
 *                   every case taking turns with the others, repeat after
 *                   repeat (A B C D A B C D ...), the best of --reps; then the
 *                   ratios the targets are stated in.
 *   --render        one image of one renderer (--renderer) at --spp, its EXR
 *                   and one line appended to --manifest: renderer, scene, spp,
 *                   threads, seed, CPU and wall seconds of the render alone
 *                   (the scene loaded and its structure built before), file
 *   --reference     the common reference: chapter 09's MIS rung at --spp,
 *                   its mean and standard error (experiment_reference_save)
 *
 * The renderers are driven through their libraries, as chapter 13's and
 * chapter 09's programs drive them (render_estimate_wide where supported,
 * render_estimate), so that a render's time is the render's alone.
 * Built only by make bench; Embree's rows only where its header is
 * (BENCH_EMBREE, make bench-deps). A benchmark: it prints figures and
 * asserts nothing about time. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "09-path-tracing/experiments.h"
#include "09-path-tracing/path_tracer.h"
#include "09-path-tracing/scene_pt.h"
#include "13-production/bench_scenes.h"
#include "13-production/path_tracer_wide.h"
#include "13-production/walls.h"
#include "atomic_file.h"
#include "image_file.h"
#include "scene_file.h"
#include "timer.h"
#ifdef BENCH_EMBREE
#include "embree_accel.h"
/* Eight paths on Embree's eight-ray kernels: chapter 13's renderer takes
 * another tracer (wide_trace.h: render_estimate_wide_traced). */
#define BENCH_EMBREE8 1
#include "13-production/wide_trace.h"
#endif

/* ---- the renderers ------------------------------------------------------------ */

typedef enum { R_CH13, R_CH13_ONE_PATH, R_EMBREE, R_EMBREE8, R_MIS, R_COUNT } renderer_kind;
static const char *const RENDERER_NAMES[] = {"ch13", "ch13-one-path", "ch13-embree", "ch13-embree8", "ch09-mis", NULL};
static const char *const RENDERER_LABELS[] = {"13 as run", "13 one path", "13 on Embree", "13 on Embree8",
                                              "09 mis"};

/* A scene with the three structures the renderers trace through: chapter
 * 06's BVH (chapter 09's default), chapter 13's (production_scene_accel:
 * the walls over the flat set or the 4-wide BVH) and Embree's inside the
 * same walls. sc.bvh is switched between them and is chapter 06's when
 * the scene is freed. */
typedef struct {
    pt_scene sc;
    accel *structures[3]; /* chapter 06, chapter 13, Embree (NULL without it) */
    char name[256];
} bench_scene;

enum { ON_CH06, ON_CH13, ON_EMBREE };

#ifdef BENCH_EMBREE
static accel *embree_inner(const triangle_set *set) { return embree_build(set, TWIN_NONE); }
static accel *embree_scene_accel(const triangle_set *set, const void *scene)
{
    return walls_accel_build_over(set, scene, true, embree_inner);
}
#endif

static bool bench_scene_load(bench_scene *b, const char *path, char *err, size_t err_size)
{
    scene_desc desc;
    scene_desc_init(&desc);
    pt_scene_report_materials(NULL);
    bool ok = scene_desc_load(&desc, path, err, err_size) &&
              pt_scene_from_desc(&b->sc, &desc, "bench_scenes", err, err_size);
    scene_desc_free(&desc);
    if (!ok)
        return false;
    const char *slash = strrchr(path, '/');
    snprintf(b->name, sizeof b->name, "%s", slash != NULL ? slash + 1 : path);
    char *dot = strrchr(b->name, '.');
    if (dot != NULL)
        *dot = '\0';
    b->structures[ON_CH06] = b->sc.bvh;
    b->structures[ON_CH13] = production_scene_accel(&b->sc.triangles, &b->sc);
    b->structures[ON_EMBREE] = NULL;
#ifdef BENCH_EMBREE
    b->structures[ON_EMBREE] = embree_scene_accel(&b->sc.triangles, &b->sc);
    if (b->structures[ON_EMBREE] == NULL)
        fprintf(stderr, "bench_scenes: %s: Embree failed to build the scene; its rows are left out\n", path);
#endif
    return true;
}

static void bench_scene_free(bench_scene *b)
{
    accel_destroy(b->structures[ON_CH13]);
    accel_destroy(b->structures[ON_EMBREE]);
    b->sc.bvh = b->structures[ON_CH06];
    pt_scene_free(&b->sc);
}

#ifdef BENCH_EMBREE8
/* ---- Embree's eight-ray kernels as a wide_tracer --------------------------------
 * rtcIntersect8 and rtcOccluded8 on the lanes of `active`, over the
 * Embree scene of an embree_accel (context): the triangle's index, t and
 * barycentrics as hits8 wants them. */

static void embree_rays8(const rays8 *rays, int active, int valid[8], struct RTCRay8 *e)
{
    for (int k = 0; k < 8; k++) {
        valid[k] = (active >> k & 1) ? -1 : 0;
        e->org_x[k] = rays->origin[0][k];
        e->org_y[k] = rays->origin[1][k];
        e->org_z[k] = rays->origin[2][k];
        e->dir_x[k] = rays->direction[0][k];
        e->dir_y[k] = rays->direction[1][k];
        e->dir_z[k] = rays->direction[2][k];
        e->tnear[k] = rays->t_min[k];
        e->tfar[k] = rays->t_max[k];
        e->time[k] = 0.0f;
        e->mask[k] = 0xFFFFFFFFu;
        e->id[k] = (unsigned)k;
        e->flags[k] = 0;
    }
}

static int embree8_closest_hit(const void *context, const rays8 *rays, int active, hits8 *hits,
                               ray_counters *counters)
{
    (void)counters;
    const embree_accel *ea = context;
    _Alignas(32) int valid[8];
    struct RTCRayHit8 rh;
    embree_rays8(rays, active, valid, &rh.ray);
    for (int k = 0; k < 8; k++) {
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect8(valid, ea->scene, &ctx, &rh);
    int hit = 0;
    for (int k = 0; k < 8; k++)
        if ((active >> k & 1) && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {
            hits->index[k] = (int32_t)rh.hit.primID[k];
            hits->t[k] = rh.ray.tfar[k];
            hits->b1[k] = rh.hit.u[k];
            hits->b2[k] = rh.hit.v[k];
            hit |= 1 << k;
        }
    return hit;
}

static int embree8_any_hit(const void *context, const rays8 *rays, int active, ray_counters *counters)
{
    (void)counters;
    const embree_accel *ea = context;
    _Alignas(32) int valid[8];
    struct RTCRay8 e;
    embree_rays8(rays, active, valid, &e);
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcOccluded8(valid, ea->scene, &ctx, &e);
    int blocked = 0;
    for (int k = 0; k < 8; k++)
        blocked |= ((active >> k & 1) && e.tfar[k] < 0.0f) << k; /* occluded: tfar set to -inf */
    return blocked;
}

/* The tracers of the scene's Embree structure (walls over Embree, as
 * wide_scene_tracers_for() makes them of ours). */
static wide_scene_tracers embree8_tracers(const accel *walls)
{
    wide_scene_tracers t;
    t.all = (wide_tracer){embree8_closest_hit, embree8_any_hit, walls_all(walls), "Embree rtcIntersect8"};
    t.walls = walls_found(walls) ? walls : NULL;
    t.occluders = t.walls != NULL ? (wide_tracer){embree8_closest_hit, embree8_any_hit, walls_occluders(walls),
                                                  "Embree rtcIntersect8"}
                                  : wide_tracer_for(NULL);
    t.lights = walls_light_tree(walls);
    return t;
}
#endif

static bool renderer_available(const bench_scene *b, renderer_kind r)
{
#ifndef BENCH_EMBREE8
    if (r == R_EMBREE8)
        return false;
#endif
    return (r != R_EMBREE && r != R_EMBREE8) || b->structures[ON_EMBREE] != NULL;
}

/* --sampler and --integrator: chapter 13's renderers' numbers and rung */
static pt_sampler bench_sampler = PRODUCTION_SAMPLER;
static pt_integrator bench_integrator = PRODUCTION_INTEGRATOR;

/* The path tracer renderer r runs: chapter 13's program's (the MIS rung
 * with Sobol samples and roulette on throughput from bounce 3, at most 64
 * bounces: production_path_tracer_defaults; --sampler and --integrator
 * change its numbers and rung), or chapter 09's MIS rung as chapter 09
 * runs it (random numbers, P_RR 0.8 from bounce 3). The scene's structure
 * is switched to the renderer's. */

static path_tracer renderer_setup(bench_scene *b, renderer_kind r)
{
    b->sc.bvh = b->structures[r == R_MIS ? ON_CH06 : r == R_EMBREE || r == R_EMBREE8 ? ON_EMBREE : ON_CH13];
    path_tracer pt = r == R_MIS ? path_tracer_defaults(&b->sc) : production_path_tracer_defaults(&b->sc);
    if (r == R_MIS) {
        pt.integrator = PT_MIS;
    } else {
        pt.sampler = bench_sampler;
        pt.integrator = bench_integrator;
    }
    return pt;
}

typedef struct {
    double wall, cpu; /* seconds of the render alone */
    double rays;      /* rays traced */
    bool wide;        /* eight paths at a time */
} render_run;

/* One render; e receives the image (the caller frees it). */
static render_run render_once(bench_scene *b, renderer_kind r, const camera *cam, int spp, uint64_t seed, int threads,
                              estimate_image *e)
{
    path_tracer pt = renderer_setup(b, r);
    render_run run = {0};
    double cpu_start = experiment_cpu_seconds();
    run.wide = r == R_CH13 && path_tracer_wide_supported(&pt, NULL, 0) &&
               render_estimate_wide(&pt, cam, spp, seed, threads, e);
#ifdef BENCH_EMBREE8
    if (r == R_EMBREE8) {
        wide_scene_tracers t = embree8_tracers(b->structures[ON_EMBREE]);
        run.wide = path_tracer_wide_supported(&pt, NULL, 0) &&
                   render_estimate_wide_traced(&pt, &t, cam, spp, seed, threads, e);
    }
#endif
    if (!run.wide)
        *e = render_estimate(&pt, cam, spp, seed, threads);
    run.cpu = experiment_cpu_seconds() - cpu_start;
    run.wall = e->seconds;
    run.rays = (double)counters_total_rays(&e->counters);
    b->sc.bvh = b->structures[ON_CH06];
    return run;
}

/* ---- --speed -------------------------------------------------------------------- */

/* An embarrassingly parallel loop, the yardstick of the scaling target:
 * `threads` threads each hash their own share of `work` numbers, no memory
 * shared, nothing to wait for. Wall seconds; the hashes go to loop_sink,
 * so that the loop cannot be optimized away. */
static volatile uint64_t loop_sink;
static double parallel_loop(long work, int threads)
{
    double start = timer_seconds();
    uint64_t total = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : total)
    for (int chunk = 0; chunk < 64; chunk++) {
        uint64_t x = (uint64_t)chunk * 0x9E3779B97F4A7C15ULL;
        for (long i = 0; i < work / 64; i++) {
            x ^= x >> 31;
            x *= 0xBF58476D1CE4E5B9ULL;
            x ^= x >> 29;
        }
        total += x;
    }
    loop_sink += total;
    return timer_seconds() - start;
}

typedef struct {
    double wall[2], cpu[2]; /* best seconds per million camera samples, 1 and 2 threads */
    double rays_per_sample;
    bool wide, measured;
} speed_row;

static void speed_scene(bench_scene *b, int size, int spp, int reps, FILE *csv)
{
    camera cam = pt_scene_camera(&b->sc, size, size);
    double msamples = (double)size * size * spp * 1e-6;
    speed_row rows[R_COUNT];
    for (int r = 0; r < R_COUNT; r++)
        rows[r] = (speed_row){{INFINITY, INFINITY}, {INFINITY, INFINITY}, 0.0, false, false};
    /* Where chapter 13 renders one path at a time anyway, its one-path row
     * would time the same thing again. */
    path_tracer probe = renderer_setup(b, R_CH13);
    bool wide_here = path_tracer_wide_supported(&probe, NULL, 0);
    b->sc.bvh = b->structures[ON_CH06];
    /* Every case in turn, repeat after repeat: a drift in the machine's
     * speed (other work, the clock) then weighs on all of them alike. The
     * parallel loop takes its turn too, 1 and 2 threads, about as long as
     * one render on 1 thread. */
    double loop_best[2] = {INFINITY, INFINITY};
    long loop_work = 0;
    for (int rep = 0; rep < reps; rep++) {
        if (loop_work == 0) { /* sized once, to about 0.1 s */
            loop_work = 1 << 20;
            while (parallel_loop(loop_work, 1) < 0.1 && loop_work < (1L << 40))
                loop_work *= 2;
        }
        for (int t = 0; t < 2; t++)
            loop_best[t] = fmin(loop_best[t], parallel_loop(loop_work, t + 1));
        for (int r = 0; r < R_COUNT; r++)
            for (int t = 0; t < 2; t++) {
                if (!renderer_available(b, (renderer_kind)r) || ((r == R_CH13_ONE_PATH || r == R_EMBREE8) && !wide_here))
                    continue;
                estimate_image e;
                render_run run = render_once(b, (renderer_kind)r, &cam, spp, 1, t + 1, &e);
                estimate_image_free(&e);
                speed_row *row = &rows[r];
                row->wall[t] = fmin(row->wall[t], run.wall / msamples);
                row->cpu[t] = fmin(row->cpu[t], run.cpu / msamples);
                row->rays_per_sample = run.rays / (msamples * 1e6);
                row->wide = run.wide;
                row->measured = true;
            }
    }
    printf("\n%s: %d triangles, %dx%d, %d spp (%.3f M camera samples), best of %d, cases taking turns\n", b->name,
           b->sc.triangles.count, size, size, spp, msamples, reps);
    printf("%-14s %-9s %7s %10s %10s %9s %11s %9s %8s\n", "renderer", "paths", "threads", "s/M wall", "s/M CPU",
           "Mrays/s", "Mrays/CPUs", "rays/spl", "scaling");
    for (int r = 0; r < R_COUNT; r++) {
        const speed_row *row = &rows[r];
        if (!row->measured) {
            printf("%-14s %s\n", RENDERER_LABELS[r],
                   r == R_CH13_ONE_PATH ? "(13 as run is one path at a time here)"
                   : r == R_EMBREE8 && !renderer_available(b, R_EMBREE8)
                       ? "(no Embree: make bench-deps)"
                   : r == R_EMBREE8 ? "(13 as run is one path at a time here)"
                                    : "(no Embree: make bench-deps)");
            continue;
        }
        for (int t = 0; t < 2; t++) {
            printf("%-14s %-9s %7d %10.3f %10.3f %9.2f %11.2f %9.2f %7.2fx\n", RENDERER_LABELS[r],
                   row->wide ? "8 at once" : "one", t + 1, row->wall[t], row->cpu[t],
                   row->rays_per_sample / row->wall[t], row->rays_per_sample / row->cpu[t], row->rays_per_sample,
                   row->wall[0] / row->wall[t]);
            if (csv != NULL)
                fprintf(csv, "%s,%d,%s,%d,%d,%.5f,%.5f,%.4f,%.3f,%d\n", b->name, b->sc.triangles.count,
                        RENDERER_NAMES[r], t + 1, row->wide, row->wall[t], row->cpu[t],
                        row->rays_per_sample / row->wall[t], row->rays_per_sample, size);
        }
    }
    /* The targets, as ratios of CPU time per sample on 1 thread
     * (samples per CPU-second of one over the other). */
    const speed_row *ours = &rows[R_CH13], *one = &rows[wide_here ? R_CH13_ONE_PATH : R_CH13], *embree = &rows[R_EMBREE],
                    *mis = &rows[R_MIS];
    printf("ratios, 1 thread, CPU: 13 as run / 09 mis speed %.2fx (target >= 4x)", mis->cpu[0] / ours->cpu[0]);
    if (embree->measured)
        printf("; 13 one path / 13 on Embree speed %.2fx (target >= 0.9x)", embree->cpu[0] / one->cpu[0]);
    if (rows[R_EMBREE8].measured) {
        printf("; 13 as run / 13 on Embree8 speed %.2fx", rows[R_EMBREE8].cpu[0] / ours->cpu[0]);
        /* Chapter 13's paths on Embree's kernels against chapter 09: how
         * far the state of the art in tracing takes the same estimator. */
        printf("\n13 on Embree8 / 09 mis speed %.2fx", mis->cpu[0] / rows[R_EMBREE8].cpu[0]);
    }
    printf("\n2-thread scaling (wall): 13 as run %.2fx, 09 mis %.2fx; an embarrassingly parallel loop, taking "
           "turns with them, %.2fx (target: within 5 %%)\n", ours->wall[0] / ours->wall[1],
           mis->wall[0] / mis->wall[1], loop_best[0] / loop_best[1]);
    fflush(stdout);
}

/* ---- options -------------------------------------------------------------------- */

typedef enum { MODE_NONE, MODE_WRITE, MODE_SPEED, MODE_RENDER, MODE_REFERENCE } bench_mode;

typedef struct {
    bench_mode mode;
    const char *dir, *scenes, *scene, *out, *manifest, *csv;
    int size, spp, reps, threads;
    uint64_t seed;
    renderer_kind renderer;
    pt_sampler sampler;
    pt_integrator integrator;
    wide_lights lights;
} bench_options;

static void usage(void)
{
    printf("usage: bench_scenes --write DIR [--scenes A,B,...]\n"
           "       bench_scenes --speed DIR [--scenes A,B,...] [--width N] [--spp N] [--reps N] [--csv FILE]\n"
           "       bench_scenes --render FILE.scene --renderer NAME --spp N [--threads N] [--seed N] [--width N]\n"
           "                    --out FILE.exr [--manifest FILE.csv]\n"
           "       bench_scenes --reference FILE.scene --spp N [--threads N] [--width N] --out FILE.exr\n"
           "The benchmark's scenes (chapters/13-production/bench_scenes.h) and chapter 13's renderer on\n"
           "them beside the same renderer on Embree's kernels and chapter 09's MIS rung.\n"
           "  --write DIR      write DIR/NAME.scene, NAME.obj, NAME.mtl for each scene\n"
           "  --speed DIR      time every renderer on DIR/NAME.scene, 1 and 2 threads, taking turns\n"
           "  --render FILE    one image by --renderer (ch13, ch13-one-path, ch13-embree, ch13-embree8, ch09-mis);\n"
           "                   appends 'renderer,scene,spp,threads,seed,cpu_s,wall_s,file' to --manifest\n"
           "  --reference FILE chapter 09's MIS rung at --spp: FILE.exr and its -stderr.exr\n"
           "  --scenes LIST    which scenes (default all: cornell,cornell-10k,cornell-100k,cornell-1m,glossy-glass,\n"
           "                   open-100k)\n"
           "  --width N        image N x N (default 64)    --spp N   samples per pixel (default 16)\n"
           "  --reps N         best of N (default 3)       --threads N (default 2)   --seed N (default 1)\n"
           "  --csv FILE       with --speed: the table as CSV too\n"
           "  --sampler random|sobol  chapter 13's numbers (default sobol, its program's); random names its\n"
           "                   manifest rows NAME-random\n"
           "  --integrator lecture|cosine|mis  chapter 13's rung (default mis, its program's); another names\n"
           "                   its manifest rows NAME-RUNG (ch13-lecture, ch13-lecture-random, ...)\n"
           "  --lights auto|power|tree  how chapter 13 picks a light (default auto, its program's: the light\n"
           "                   tree from 16 emitting triangles on); power or tree names its manifest rows\n"
           "                   NAME-power, NAME-tree\n");
}

static bool parse_renderer(const char *name, renderer_kind *out)
{
    for (int r = 0; RENDERER_NAMES[r] != NULL; r++)
        if (strcmp(name, RENDERER_NAMES[r]) == 0) {
            *out = (renderer_kind)r;
            return true;
        }
    return false;
}

/* 0 to go on, else the exit status (help: 0 after printing it, -1). */
static int parse_options(int argc, char **argv, bench_options *o)
{
    *o = (bench_options){MODE_NONE, NULL, NULL, NULL, NULL, NULL, NULL, 64, 16, 3, 2, 1, R_CH13,
                         PRODUCTION_SAMPLER, production_path_tracer_defaults(NULL).integrator, WIDE_LIGHTS_AUTO};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *value = i + 1 < argc ? argv[i + 1] : NULL;
        bool takes = true;
        if (strcmp(a, "--help") == 0) {
            usage();
            return -1;
        } else if (value == NULL) {
            takes = false;
        } else if (strcmp(a, "--write") == 0 || strcmp(a, "--speed") == 0) {
            o->mode = a[2] == 'w' ? MODE_WRITE : MODE_SPEED;
            o->dir = value;
        } else if (strcmp(a, "--render") == 0 || strcmp(a, "--reference") == 0) {
            o->mode = strcmp(a, "--render") == 0 ? MODE_RENDER : MODE_REFERENCE;
            o->scene = value;
        } else if (strcmp(a, "--scenes") == 0) {
            o->scenes = value;
        } else if (strcmp(a, "--out") == 0) {
            o->out = value;
        } else if (strcmp(a, "--manifest") == 0) {
            o->manifest = value;
        } else if (strcmp(a, "--csv") == 0) {
            o->csv = value;
        } else if (strcmp(a, "--renderer") == 0) {
            if (!parse_renderer(value, &o->renderer)) {
                fprintf(stderr, "bench_scenes: --renderer %s: unknown (ch13, ch13-one-path, ch13-embree, ch13-embree8, ch09-mis)\n",
                        value);
                return 2;
            }
        } else if (strcmp(a, "--sampler") == 0 && (strcmp(value, "random") == 0 || strcmp(value, "sobol") == 0)) {
            o->sampler = value[0] == 's' ? PT_SAMPLER_SOBOL : PT_SAMPLER_RANDOM;
        } else if (strcmp(a, "--integrator") == 0) {
            if (!pt_integrator_parse(value, &o->integrator)) {
                fprintf(stderr, "bench_scenes: --integrator %s: unknown (lecture, cosine, mis)\n", value);
                return 2;
            }
        } else if (strcmp(a, "--lights") == 0 && (strcmp(value, "auto") == 0 || strcmp(value, "power") == 0 ||
                                                   strcmp(value, "tree") == 0)) {
            o->lights = value[0] == 'a' ? WIDE_LIGHTS_AUTO : value[0] == 'p' ? WIDE_LIGHTS_POWER : WIDE_LIGHTS_TREE;
        } else if (strcmp(a, "--width") == 0 && atoi(value) > 0) {
            o->size = atoi(value);
        } else if (strcmp(a, "--spp") == 0 && atoi(value) > 0) {
            o->spp = atoi(value);
        } else if (strcmp(a, "--reps") == 0 && atoi(value) > 0) {
            o->reps = atoi(value);
        } else if (strcmp(a, "--threads") == 0 && atoi(value) > 0) {
            o->threads = atoi(value);
        } else if (strcmp(a, "--seed") == 0) {
            o->seed = strtoull(value, NULL, 10);
        } else {
            takes = false;
        }
        if (!takes) {
            fprintf(stderr, "bench_scenes: unknown or incomplete argument '%s' (try --help)\n", a);
            return 2;
        }
        i++;
    }
    if (o->mode == MODE_NONE || ((o->mode == MODE_RENDER || o->mode == MODE_REFERENCE) && o->out == NULL)) {
        fprintf(stderr, "bench_scenes: say --write, --speed, --render or --reference (with --out) (try --help)\n");
        return 2;
    }
#ifndef BENCH_EMBREE
    if (o->mode == MODE_RENDER && o->renderer == R_EMBREE) {
        fprintf(stderr, "bench_scenes: --renderer ch13-embree: built without Embree (make bench-deps)\n");
        return 2;
    }
#endif
#ifndef BENCH_EMBREE8
    if (o->mode == MODE_RENDER && o->renderer == R_EMBREE8) {
        fprintf(stderr, "bench_scenes: --renderer ch13-embree8: built without Embree (make bench-deps)\n");
        return 2;
    }
#endif
    return 0;
}

/* The scenes --scenes names (default all), one at a time: fn(name) for
 * each; false at the first that fails. */
static bool for_each_scene(const char *list, bool (*fn)(const char *name, const bench_options *o, char *err,
                                                        size_t err_size),
                           const bench_options *o, char *err, size_t err_size)
{
    if (list == NULL) {
        for (int i = 0; BENCH_SCENE_NAMES[i] != NULL; i++)
            if (!fn(BENCH_SCENE_NAMES[i], o, err, err_size))
                return false;
        return true;
    }
    char copy[1024];
    snprintf(copy, sizeof copy, "%s", list);
    for (char *save = NULL, *name = strtok_r(copy, ",", &save); name != NULL; name = strtok_r(NULL, ",", &save))
        if (!fn(name, o, err, err_size))
            return false;
    return true;
}

static bool write_one(const char *name, const bench_options *o, char *err, size_t err_size)
{
    if (!bench_scene_write(o->dir, name, err, err_size))
        return false;
    printf("bench_scenes: %s/%s.scene\n", o->dir, name);
    return true;
}

static FILE *speed_csv;

static bool speed_one(const char *name, const bench_options *o, char *err, size_t err_size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.scene", o->dir, name);
    bench_scene b;
    if (!bench_scene_load(&b, path, err, err_size))
        return false;
    speed_scene(&b, o->size, o->spp, o->reps, speed_csv);
    bench_scene_free(&b);
    return true;
}

/* The renderer's name in the manifest: chapter 13's with the rung and the
 * numbers where they are not its program's (ch13-lecture, ch13-random,
 * ch13-cosine-random). */
static void row_name(const bench_options *o, char *out, size_t size)
{
    bool ch13 = o->renderer != R_MIS;
    bool other_rung = ch13 && o->integrator != production_path_tracer_defaults(NULL).integrator;
    bool other_sampler = ch13 && o->sampler != PRODUCTION_SAMPLER;
    const char *lights = !ch13 ? "" : o->lights == WIDE_LIGHTS_POWER ? "-power" : o->lights == WIDE_LIGHTS_TREE ? "-tree" : "";
    snprintf(out, size, "%s%s%s%s%s", RENDERER_NAMES[o->renderer], other_rung ? "-" : "",
             other_rung ? pt_integrator_name(o->integrator) : "", other_sampler ? "-random" : "", lights);
}

/* One line appended to the manifest (a log the runs add to one by one;
 * bench_equal_time reads it). */
static bool manifest_append(const bench_options *o, const char *scene, const render_run *run, char *err,
                            size_t err_size)
{
    if (o->manifest == NULL)
        return true;
    FILE *f = fopen(o->manifest, "a");
    if (f == NULL) {
        snprintf(err, err_size, "%s: cannot append to it", o->manifest);
        return false;
    }
    char name[64];
    row_name(o, name, sizeof name);
    fprintf(f, "%s,%s,%d,%d,%llu,%.6f,%.6f,%s\n", name, scene, o->spp, o->threads, (unsigned long long)o->seed,
            run->cpu, run->wall, o->out);
    if (fclose(f) != 0) {
        snprintf(err, err_size, "%s: cannot append to it", o->manifest);
        return false;
    }
    return true;
}

static bool render_mode(const bench_options *o, char *err, size_t err_size)
{
    bench_scene b;
    if (!bench_scene_load(&b, o->scene, err, err_size))
        return false;
    camera cam = pt_scene_camera(&b.sc, o->size, o->size);
    estimate_image e;
    bool ok;
    if (o->mode == MODE_REFERENCE) {
        b.sc.bvh = b.structures[ON_CH06];
        path_tracer pt = renderer_setup(&b, R_MIS);
        e = render_estimate(&pt, &cam, o->spp, 0x5eedULL, o->threads);
        ok = experiment_reference_save(&e, o->out, err, err_size);
        if (ok)
            printf("bench_scenes: reference %s, %dx%d, %d spp, %.1f s, estimated relative error %.4f -> %s\n", b.name,
                   o->size, o->size, o->spp, e.seconds, estimate_relative_error(&e), o->out);
    } else {
        render_run run = render_once(&b, o->renderer, &cam, o->spp, o->seed, o->threads, &e);
        ok = image_write(&e.mean, o->out, 0.0f, err, err_size) && manifest_append(o, b.name, &run, err, err_size);
        char name[64];
        row_name(o, name, sizeof name);
        if (ok)
            printf("bench_scenes: %s %s %d spp %d threads seed %llu: %.3f s CPU, %.3f s wall%s -> %s\n", name, b.name, o->spp, o->threads, (unsigned long long)o->seed, run.cpu,
                   run.wall, run.wide ? ", 8 paths at a time" : "", o->out);
    }
    estimate_image_free(&e);
    bench_scene_free(&b);
    return ok;
}

int main(int argc, char **argv)
{
    bench_options o;
    int status = parse_options(argc, argv, &o);
    if (status != 0)
        return status < 0 ? 0 : status;
    bench_sampler = o.sampler;
    bench_integrator = o.integrator;
    path_tracer_wide_lights(o.lights);
    char err[8192] = "";
    bool ok = true;
    atomic_file csv;
    if (o.mode == MODE_WRITE) {
        ok = for_each_scene(o.scenes, write_one, &o, err, sizeof err);
    } else if (o.mode == MODE_SPEED) {
        if (o.csv != NULL && !atomic_file_open(&csv, o.csv, err, sizeof err)) {
            fprintf(stderr, "bench_scenes: %s\n", err);
            return 1;
        }
        speed_csv = o.csv != NULL ? csv.stream : NULL;
        if (speed_csv != NULL)
            fprintf(speed_csv, "scene,triangles,renderer,threads,wide,wall_s_per_msample,cpu_s_per_msample,"
                               "mrays_per_s,rays_per_sample,size\n");
#ifndef BENCH_EMBREE
        printf("bench_scenes: built without Embree (no embree3/rtcore.h: make bench-deps); its rows are left out\n");
#endif
        const char *policy = getenv("OMP_WAIT_POLICY");
        if (policy == NULL || strcasecmp(policy, "passive") != 0)
            printf("bench_scenes: warning: OMP_WAIT_POLICY is not passive, so after a 2-thread run the idle thread\n"
                   "  spins while 1 thread renders, and its spin counts as CPU time (make bench sets it)\n");
        ok = for_each_scene(o.scenes, speed_one, &o, err, sizeof err);
        if (speed_csv != NULL)
            ok = ok ? atomic_file_commit(&csv, err, sizeof err) : (atomic_file_abandon(&csv), false);
    } else {
        ok = render_mode(&o, err, sizeof err);
    }
    if (!ok)
        fprintf(stderr, "bench_scenes: %s\n", err);
    return ok ? 0 : 1;
}

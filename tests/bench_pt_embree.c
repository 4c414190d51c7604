/* bench_pt_embree.c -- where the path tracer's time goes: the same path
 * tracer, its rays traced once by chapter 13's structures and once by
 * Embree 3, the industry's fast CPU kernel. The difference bounds what any
 * work on traversal can buy; what is left is shading and sampling.
 *
 * The path tracer reaches its triangles only through one accel (chapter
 * 03's interface), sc->bvh. Chapter 13 makes it a walls_accel (walls.h):
 * the structure of every triangle (on the Cornell box the flat set, which
 * tests every triangle), and that of the triangles that are not walls, for
 * shadow rays inside the walls. Here both inner structures are Embree's,
 * which fill the hit record with the same triangle_set_fill_hit() from
 * Embree's triangle index, t and barycentrics. Nothing else changes.
 *
 * Prints, on the Cornell box:
 *   1. a check on 10^4 random rays in the box: Embree and ours find the same
 *      triangle at the same t (within 1e-4 relative) and the same hit point,
 *      and give the same any-hit answer, except where two candidates tie;
 *   2. chapter 13's speed table (production_speed_scene) for ours, then for
 *      Embree, and per case the ratio of wall times, ours / Embree;
 *   3. for the lecture rung on one thread: every ray of one render recorded,
 *      then traced alone by ours and by Embree: nanoseconds per closest-hit
 *      and per shadow ray, and the render's time less its tracing time;
 *      and once more by chapter 06's 4-wide BVH over the same triangles, one
 *      ray at a time and in streams (wide_bvh_closest_hit_stream), which hide
 *      waits for memory that this small scene never has;
 *   4. the image means of the lecture rung rendered by both, with their
 *      standard errors: they must agree within 5 standard errors.
 * Exits 1 if check 1 or 4 fails. With --twin uv (Embree's barycentrics
 * swapped) or --twin no-shadows (Embree's any hit never finds one), a
 * deliberately wrong Embree accel shows that the checks can fail.
 *
 * A benchmark, built only by `make bench` (Embree is a bench dependency:
 * `make bench-deps`). Embree visits no nodes or triangles we can count: its
 * accel leaves counters->box_tests and primitive_tests untouched (0). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "03-aabb-slabs/accel.h"
#include "09-path-tracing/experiments.h"
#include "09-path-tracing/path_tracer.h"
#include "09-path-tracing/scene_pt.h"
#include "13-production/wide_bvh.h"
#include "13-production/speed.h"
#include "13-production/walls.h"
#include "atomic_file.h"
#include "embree_accel.h"
#include "memory.h"
#include "timer.h"

/* ---- an accel that records every ray it is asked to trace ---------------------
 * Wrapped around ours for a one-thread render, it keeps the rays in the
 * order the path tracer traced them, camera, bounce and shadow rays alike,
 * so that they can be traced again alone. One thread only: it is not safe
 * to call from two at once. */

typedef struct {
    ray *rays;
    int count, capacity;
} ray_list;

typedef struct {
    accel base;
    const accel *inner;                   /* a walls_accel */
    ray_list *closest, *shadow, *inside; /* inside: shadow rays inside the walls */
} recording_accel;

static void ray_list_push(ray_list *list, ray r)
{
    list->rays = memory_grow(list->rays, &list->capacity, list->count + 1, sizeof(ray));
    list->rays[list->count++] = r;
}

static bool recording_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    const recording_accel *rec = (const recording_accel *)a;
    ray_list_push(rec->closest, r);
    return accel_closest_hit(rec->inner, r, hit, counters);
}

static bool recording_any_hit(const accel *a, ray r, ray_counters *counters)
{
    const recording_accel *rec = (const recording_accel *)a;
    ray_list_push(walls_segment_inside(rec->inner, &r) ? rec->inside : rec->shadow, r);
    return accel_any_hit(rec->inner, r, counters);
}

static void recording_destroy(accel *a) { (void)a; /* lives on the caller's stack */ }

static const accel_ops recording_ops = {recording_closest_hit, recording_any_hit, recording_destroy, NULL};

/* ---- 1. the same hits on random rays ------------------------------------------ */

static float uniform(pcg32 *rng, float lo, float hi) { return lo + (hi - lo) * pcg32_float(rng); }

static vec3 uniform_direction(pcg32 *rng)
{
    float z = uniform(rng, -1.0f, 1.0f), phi = uniform(rng, 0.0f, 6.2831853f);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return vec3_make(s * cosf(phi), s * sinf(phi), z);
}

static bool close_relative(float a, float b, float tolerance)
{
    return fabsf(a - b) <= tolerance * fmaxf(fabsf(a), fabsf(b));
}

/* Rays from points uniform in the box's bounds in directions uniform on the
 * sphere: closest hits compared over the whole line, any hits over a
 * segment of random length (so that some end before the first surface).
 * A tie -- two triangles within the tolerance of each other along the ray
 * (the ray through a shared edge), or the first surface within it of the
 * segment's end -- may go either way, and is counted but not failed. */
/* A thousandth of the box's diagonal: the least distance a hit point's
 * tolerance is taken of (check_random_rays). */
static const float HIT_POINT_FLOOR = 1e-3f;

static int check_random_rays(const accel *ours, const accel *embree, int count, uint64_t seed)
{
    const float tolerance = 1e-4f;
    const aabb box = ours->set->bounds;
    vec3 extent = vec3_sub(box.hi, box.lo);
    float diagonal = vec3_length(extent);
    pcg32 rng;
    pcg32_seed(&rng, seed, 54);
    int mismatches = 0, ties = 0, hits = 0, occluded = 0;
    for (int k = 0; k < count; k++) {
        vec3 origin = vec3_make(uniform(&rng, box.lo.x, box.hi.x), uniform(&rng, box.lo.y, box.hi.y),
                                uniform(&rng, box.lo.z, box.hi.z));
        ray r = {origin, uniform_direction(&rng), 0.0f, INFINITY};
        ray_counters counters = {0};
        hit_record a, b;
        bool hit_a = accel_closest_hit(ours, r, &a, &counters), hit_b = accel_closest_hit(embree, r, &b, &counters);
        bool same;
        if (hit_a != hit_b)
            same = false;
        else if (!hit_a)
            same = true;
        else {
            /* the hit points are compared relative to their distance from
             * the origin, with a floor of HIT_POINT_FLOOR of the box's size
             * so that a hit at t near 0 is not held to a tolerance of 0 */
            float scale = a.t * vec3_length(r.direction) + diagonal * HIT_POINT_FLOOR;
            same = a.shape_id == b.shape_id && close_relative(a.t, b.t, tolerance) &&
                   vec3_length(vec3_sub(a.point, b.point)) <= tolerance * scale;
            if (!same && a.shape_id != b.shape_id && close_relative(a.t, b.t, tolerance)) {
                ties++;
                same = true;
            }
        }
        hits += hit_a;
        if (!same) {
            if (mismatches < 5)
                printf("  closest hit differs: ray %d, ours %s triangle %d t %.7g, Embree %s triangle %d t %.7g, "
                       "points %.3g apart\n",
                       k, hit_a ? "hit" : "missed", hit_a ? a.shape_id : -1, hit_a ? a.t : 0.0, hit_b ? "hit" : "missed",
                       hit_b ? b.shape_id : -1, hit_b ? b.t : 0.0,
                       hit_a && hit_b ? vec3_length(vec3_sub(a.point, b.point)) : 0.0);
            mismatches++;
        }
        ray segment = r;
        segment.t_max = uniform(&rng, 0.0f, diagonal);
        bool occluded_a = accel_any_hit(ours, segment, &counters), occluded_b = accel_any_hit(embree, segment, &counters);
        occluded += occluded_a;
        if (occluded_a != occluded_b) {
            if (hit_a && close_relative(a.t, segment.t_max, tolerance)) {
                ties++;
            } else {
                if (mismatches < 5)
                    printf("  any hit differs: ray %d over t < %.7g, ours %d, Embree %d\n", k, segment.t_max,
                           occluded_a, occluded_b);
                mismatches++;
            }
        }
    }
    printf("random rays: %d in the box's bounds, %d closest hits, %d segments occluded; %d ties, %d mismatches\n",
           count, hits, occluded, ties, mismatches);
    return mismatches;
}

/* ---- 3. tracing alone --------------------------------------------------------- */

/* Seconds to trace the rays alone, one run; the hits counted so that the
 * loop cannot be optimized away and both kernels can be seen to agree.
 * Rays that do not depend on each other let the processor overlap one
 * ray's traversal with the next (throughput); in the render each ray waits
 * for the hit before it. With `chained`, each ray's origin is made to wait
 * for the previous answer (it adds that answer times 0, which leaves the
 * origin as it was, bit for bit), as in the render (latency). */
static double trace_alone(const accel *a, const ray_list *list, bool closest, bool chained, long *hits)
{
    ray_counters counters = {0};
    long found = 0;
    float wait = 0.0f;
    double start = timer_seconds();
    for (int k = 0; k < list->count; k++) {
        ray r = list->rays[k];
        if (chained)
            r.origin.x += wait;
        if (closest) {
            hit_record hit;
            bool h = accel_closest_hit(a, r, &hit, &counters);
            found += h;
            wait = h ? hit.t * 0.0f : 0.0f;
        } else {
            bool h = accel_any_hit(a, r, &counters);
            found += h;
            wait = (float)h * 0.0f;
        }
    }
    *hits = found;
    return timer_seconds() - start;
}

/* The same rays through chapter 06's streams (wide_bvh_closest_hit_stream):
 * WIDE_BVH_STREAM_LANES rays taking turns, in chunks of STREAM_CHUNK. Seconds,
 * one run, and the hits counted. */
enum { STREAM_CHUNK = 1024 };
static double trace_streams(const accel *a, const ray_list *list, bool closest, long *hits)
{
    ray_counters counters = {0};
    hit_record *chunk_hits = memory_allocate(STREAM_CHUNK, sizeof *chunk_hits);
    bool found[STREAM_CHUNK];
    long total = 0;
    double start = timer_seconds();
    for (int first = 0; first < list->count; first += STREAM_CHUNK) {
        int n = list->count - first < STREAM_CHUNK ? list->count - first : STREAM_CHUNK;
        if (closest)
            wide_bvh_closest_hit_stream(a, list->rays + first, n, chunk_hits, found, &counters);
        else
            wide_bvh_any_hit_stream(a, list->rays + first, n, found, &counters);
        for (int k = 0; k < n; k++)
            total += found[k];
    }
    double seconds = timer_seconds() - start;
    free(chunk_hits);
    *hits = total;
    return seconds;
}

/* ---- 4. the image means ------------------------------------------------------- */

/* The mean over pixels of one channel, and its standard error from the
 * pixels' own: sqrt(sum se_i^2) / n (the pixels are independent). */
static void image_mean(const estimate_image *e, int channel, double *mean, double *standard_error)
{
    long n = (long)e->mean.width * e->mean.height;
    double sum = 0.0, variance = 0.0;
    for (long i = 0; i < n; i++) {
        sum += e->mean.rgb[3 * i + channel];
        double s = e->standard_error.rgb[3 * i + channel];
        variance += s * s;
    }
    *mean = sum / (double)n;
    *standard_error = sqrt(variance) / (double)n;
}

/* Which structure traces the scene's rays (a walls_accel: the whole
 * tree, and the occluders' for shadow rays inside the walls). The caller
 * keeps them and restores the scene's own before freeing it. */
static void use_kernel(pt_scene *sc, accel *structure) { sc->bvh = structure; }

/* Embree's scene as a walls_inner_builder (walls.h), with the twin the
 * command line asked for. */
static twin_kind embree_twin = TWIN_NONE;
static accel *embree_inner(const triangle_set *set) { return embree_build(set, embree_twin); }

static accel *embree_scene_accel(const triangle_set *set, const void *scene)
{
    return walls_accel_build_over(set, scene, true, embree_inner);
}

static path_tracer lecture_rung(const pt_scene *sc)
{
    /* the speed table's first case: the lecture's estimator, P_RR 0.8,
     * at most 50 bounces. */
    path_tracer pt = path_tracer_defaults(sc);
    pt.integrator = PT_LECTURE;
    pt.russian_roulette = RR_FIXED;
    pt.max_depth = 50;
    return pt;
}

/* ---- main ----------------------------------------------------------------------- */

static void usage(void)
{
    printf("usage: bench_pt_embree [--width N] [--spp N] [--reps N] [--data DIR] [--twin uv|no-shadows]\n"
           "Chapter 09's path tracer on the Cornell box with its rays traced by chapter 13's\n"
           "structures and by Embree 3: the speed table of each, their ratio, the time of tracing\n"
           "alone, and checks that both give the same hits and the same image.\n"
           "  --width N    image N x N (default 256)\n"
           "  --spp N      samples per pixel, at least 2: the image check needs each pixel's\n"
           "               standard error (default 16)\n"
           "  --reps N     best of N runs (default 5)\n"
           "  --data DIR   also write DIR/ch09_embree.csv\n"
           "  --twin KIND  a wrong Embree accel, to see the checks fail: uv (barycentrics\n"
           "               swapped) or no-shadows (any hit never finds one)\n");
}

int main(int argc, char **argv)
{
    int size = 256, spp = 16, reps = 5;
    const char *data_dir = NULL;
    twin_kind twin = TWIN_NONE;
    for (int i = 1; i < argc; i++) {
        const char *value = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(argv[i], "--help") == 0) {
            usage();
            return 0;
        } else if (strcmp(argv[i], "--width") == 0 && value && atoi(value) > 0) {
            size = atoi(value);
            i++;
        } else if (strcmp(argv[i], "--spp") == 0 && value && atoi(value) > 1) {
            spp = atoi(value);
            i++;
        } else if (strcmp(argv[i], "--reps") == 0 && value && atoi(value) > 0) {
            reps = atoi(value);
            i++;
        } else if (strcmp(argv[i], "--data") == 0 && value) {
            data_dir = value;
            i++;
        } else if (strcmp(argv[i], "--twin") == 0 && value &&
                   (strcmp(value, "uv") == 0 || strcmp(value, "no-shadows") == 0)) {
            twin = strcmp(value, "uv") == 0 ? TWIN_UV : TWIN_NO_SHADOWS;
            i++;
        } else if (strcmp(argv[i], "--spp") == 0 && value) {
            fprintf(stderr, "bench_pt_embree: --spp %s: at least 2 (the image check needs each pixel's standard "
                            "error)\n", value);
            return 2;
        } else {
            fprintf(stderr, "bench_pt_embree: unknown or incomplete argument '%s' (try --help)\n", argv[i]);
            return 2;
        }
    }
    char err[4400] = "";
    atomic_file out;
    FILE *csv = NULL;
    if (data_dir != NULL) {
        if (!atomic_file_open_in(&out, data_dir, "ch09_embree.csv", err, sizeof err)) {
            fprintf(stderr, "bench_pt_embree: %s\n", err);
            return 1;
        }
        csv = out.stream;
    }

    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    /* Shadow rays inside the room's walls go to the occluders' own
     * structure (walls.h): Embree gets one there too. */
    embree_twin = twin;
    pt_scene_use_accel(&sc, production_scene_accel, &sc);
    accel *ours = sc.bvh, *embree = embree_scene_accel(&sc.triangles, &sc);
    const accel *ours_occluders = walls_occluders(ours);
    const accel *embree_occluders = embree != NULL ? walls_occluders(embree) : NULL;
    if (embree == NULL || (ours_occluders != NULL && embree_occluders == NULL)) {
        fprintf(stderr, "bench_pt_embree: Embree failed to build the scene\n");
        accel_destroy(embree);
        pt_scene_free(&sc);
        if (csv != NULL)
            atomic_file_abandon(&out);
        return 1;
    }
    printf("Cornell box: %d triangles; %s, %s\n", sc.triangles.count, ours->stats.name, embree->stats.name);
    int failures = check_random_rays(walls_all(ours), walls_all(embree), 10000, 9) != 0;
    if (ours_occluders != NULL)
        failures += check_random_rays(ours_occluders, embree_occluders, 10000, 10) != 0;

    /* 2. The speed tables, ours then Embree's, in one run. */
    production_speed_row rows[2][PRODUCTION_SPEED_CASES];
    /* ours: chapter 13's structure (production_accel_build): the flat set
     * on the Cornell box, the 4-wide BVH on larger scenes */
    char ours_name[64];
    snprintf(ours_name, sizeof ours_name, "ours (%s)", ours->stats.name);
    const char *tracers[2] = {ours_name, "Embree 3"};
    int n = 0;
    for (int k = 0; k < 2; k++) {
        char label[128];
        snprintf(label, sizeof label, "Cornell box, traced by %s,", tracers[k]);
        printf("\n");
        n = production_speed_scene(&sc, label, size, spp, reps, k == 0 ? production_scene_accel : embree_scene_accel,
                                   &sc, rows[k]);
    }
    /* the speed table rebuilt the scene's structure for each case */
    pt_scene_use_accel(&sc, production_scene_accel, &sc);
    ours = sc.bvh;
    ours_occluders = walls_occluders(ours);
    printf("\nours / Embree (wall s/M)                         1 thread  2 threads\n");
    for (int c = 0; c < n; c++)
        printf("%-44s %9.2fx %9.2fx%s\n", rows[0][c].label, rows[0][c].wall[0] / rows[1][c].wall[0],
               rows[0][c].wall[1] / rows[1][c].wall[1],
               rows[0][c].wide != rows[1][c].wide ? "   (ours 8 paths at a time, Embree's one: not the kernels alone)" : "");
    if (csv != NULL) {
        fprintf(csv, "tracer,case,threads,wall_s_per_msample,cpu_s_per_msample,rays_per_sample,scaling\n");
        for (int k = 0; k < 2; k++)
            for (int c = 0; c < n; c++)
                for (int t = 0; t < 2; t++)
                    fprintf(csv, "\"%s\",\"%s\",%d,%.4f,%.4f,%.3f,%.3f\n", tracers[k], rows[k][c].label, t + 1,
                            rows[k][c].wall[t], rows[k][c].cpu[t], rows[k][c].rays_per_sample, rows[k][c].scaling[t]);
    }

    /* 3. One one-thread render of the lecture rung with every ray recorded,
     * then those rays traced alone by each kernel. */
    /* lists[0] closest hits, [1] shadow rays through the whole tree, [2]
     * shadow rays inside the walls, through the occluders' tree */
    ray_list lists[3] = {{0}};
    recording_accel recorder = {{&recording_ops, &sc.triangles, ours->stats, TRIANGLE_TEST_WATERTIGHT}, ours, &lists[0], &lists[1], &lists[2]};
    camera cam = pt_scene_camera(&sc, size, size);
    double million_samples = (double)size * size * spp * 1e-6;
    use_kernel(&sc, &recorder.base);
    path_tracer pt = lecture_rung(&sc);
    estimate_image recorded = render_estimate(&pt, &cam, spp, 1, 1);
    use_kernel(&sc, ours);
    int shadow_count = lists[1].count + lists[2].count;
    printf("\nlecture rung, 1 thread, %.2f M camera samples: %d closest-hit and %d shadow rays recorded, %d of "
           "them inside the walls (the render counted %llu)\n",
           million_samples, lists[0].count, shadow_count, lists[2].count,
           (unsigned long long)counters_total_rays(&recorded.counters));
    estimate_image_free(&recorded);
    /* The best of reps runs, the two kernels taking turns (as the speed
     * table's 1 and 2 threads do) so that both see the same machine:
     * seconds[kernel][chained][list]. */
    double seconds[2][2][3];
    long hits[2][3] = {{0}};
    for (int k = 0; k < 12; k++)
        seconds[k / 6][k / 3 % 2][k % 3] = INFINITY;
    for (int rep = 0; rep < reps; rep++)
        for (int k = 0; k < 12; k++) {
            int kernel = k / 6, chained = k / 3 % 2, kind = k % 3;
            const accel *a = kind == 2 ? (kernel == 0 ? ours_occluders : embree_occluders)
                                       : walls_all(kernel == 0 ? ours : embree);
            double s = lists[kind].count > 0 ? trace_alone(a, &lists[kind], kind == 0, chained, &hits[kernel][kind]) : 0.0;
            seconds[kernel][chained][kind] = fmin(seconds[kernel][chained][kind], s);
        }
    printf("%-20s %-12s %12s %12s %12s %12s %12s\n", "tracer", "rays", "ns/closest", "ns/shadow", "trace s/M",
           "render s/M", "rest s/M");
    double trace[2][2];
    for (int k = 0; k < 2; k++)
        for (int chained = 0; chained < 2; chained++) {
            double shadow_seconds = seconds[k][chained][1] + seconds[k][chained][2];
            trace[k][chained] = (seconds[k][chained][0] + shadow_seconds) / million_samples;
            printf("%-20s %-12s %12.1f %12.1f %12.3f %12.3f %12.3f\n", tracers[k],
                   chained ? "each waits" : "independent", seconds[k][chained][0] / lists[0].count * 1e9,
                   shadow_seconds / shadow_count * 1e9, trace[k][chained], rows[k][0].wall[0],
                   rows[k][0].wall[0] - trace[k][chained]);
        }
    /* Chapter 06's 4-wide BVH over the same triangles (what the scene used
     * before it went flat), one ray at a time and in streams. Would the
     * streams help? They hide waits for memory, and this scene's trees
     * (1.5 KB) never wait: expect them slower. */
    accel *tree = wide_bvh_build(&sc.triangles, BVH_SPLIT_SAH);
    accel *tree_occluders = ours_occluders != NULL ? wide_bvh_build(ours_occluders->set, BVH_SPLIT_SAH) : NULL;
    double tree_seconds[2][3];
    long tree_hits[2][3] = {{0}};
    for (int k = 0; k < 6; k++)
        tree_seconds[k / 3][k % 3] = lists[k % 3].count > 0 ? INFINITY : 0.0;
    for (int rep = 0; rep < reps; rep++)
        for (int k = 0; k < 6; k++) {
            int streams = k / 3, kind = k % 3;
            const accel *a = kind == 2 ? tree_occluders : tree;
            if (lists[kind].count == 0)
                continue;
            double s = streams ? trace_streams(a, &lists[kind], kind == 0, &tree_hits[1][kind])
                               : trace_alone(a, &lists[kind], kind == 0, false, &tree_hits[0][kind]);
            tree_seconds[streams][kind] = fmin(tree_seconds[streams][kind], s);
        }
    for (int streams = 0; streams < 2; streams++) {
        double shadow_seconds = tree_seconds[streams][1] + tree_seconds[streams][2];
        printf("%-20s %-12s %12.1f %12.1f %12.3f\n", "wide BVH (chapter 13)", streams ? "streams" : "independent",
               tree_seconds[streams][0] / lists[0].count * 1e9, shadow_seconds / shadow_count * 1e9,
               (tree_seconds[streams][0] + shadow_seconds) / million_samples);
    }
    accel_destroy(tree);
    accel_destroy(tree_occluders);
    printf("hits: closest %ld (ours) %ld (Embree) %ld (wide BVH) %ld (wide BVH streams), occluded %ld (ours) %ld (Embree) "
           "%ld (wide BVH) %ld (wide BVH streams)\n",
           hits[0][0], hits[1][0], tree_hits[0][0], tree_hits[1][0], hits[0][1] + hits[0][2],
           hits[1][1] + hits[1][2], tree_hits[0][1] + tree_hits[0][2],
           tree_hits[1][1] + tree_hits[1][2]);
    printf("traversal saved by Embree, s/M: %.3f in the render, %.3f tracing alone (each waits), "
           "%.3f (independent)\n",
           rows[0][0].wall[0] - rows[1][0].wall[0], trace[0][1] - trace[1][1], trace[0][0] - trace[1][0]);
    for (int k = 0; k < 3; k++)
        free(lists[k].rays);

    /* 4. The same image: the lecture rung rendered by both, on 2 threads. */
    estimate_image images[2];
    for (int k = 0; k < 2; k++) {
        use_kernel(&sc, k == 0 ? ours : embree);
        images[k] = render_estimate(&pt, &cam, spp, 1, 2);
    }
    use_kernel(&sc, ours);
    printf("\nimage mean, lecture rung, %dx%d, %d spp:\n", size, size, spp);
    double worst = 0.0;
    for (int channel = 0; channel < 3; channel++) {
        double mean[2], se[2];
        for (int k = 0; k < 2; k++)
            image_mean(&images[k], channel, &mean[k], &se[k]);
        double z = (mean[0] - mean[1]) / sqrt(se[0] * se[0] + se[1] * se[1]);
        worst = fmax(worst, fabs(z));
        printf("  %c: ours %.6f +- %.6f, Embree %.6f +- %.6f, z %.2f\n", "RGB"[channel], mean[0], se[0], mean[1], se[1],
               z);
    }
    if (!(worst <= 5.0)) {
        printf("the image means differ by %.1f standard errors (more than 5)\n", worst);
        failures++;
    }
    for (int k = 0; k < 2; k++)
        estimate_image_free(&images[k]);

    accel_destroy(embree);
    pt_scene_free(&sc);
    if (csv != NULL && !atomic_file_commit(&out, err, sizeof err)) {
        fprintf(stderr, "bench_pt_embree: %s\n", err);
        return 1;
    }
    printf(failures ? "FAILED: Embree and ours disagree\n" : "Embree and ours agree\n");
    return failures ? 1 : 0;
}

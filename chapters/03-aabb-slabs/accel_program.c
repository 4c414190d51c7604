/* accel_program.c -- what the programs of chapters 03-06 share (see
 * accel_program.h): the mesh their flags ask for, the camera that looks at
 * it, the Embree harness's ray sets and their one-thread timing, and rays
 * aimed at the mesh. One copy here, so the chapters' main.c files hold only
 * what is their own: the structure's flags and figures. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "03-aabb-slabs/accel_program.h"
#include "03-aabb-slabs/accel_view.h"
#include "memory.h"
#include "obj.h"
#include "program.h"
#include "timer.h"

const char *const accel_mesh_names[] = {"tori", "stadium", "icosphere", NULL};

int accel_input_load(accel_input *in, cli_options *opts, const char *program, const char *mesh_name,
                     const char *obj_path, int tori_triangles, int icosphere_subdivisions)
{
    memset(in, 0, sizeof *in);
    mesh_init(&in->m);
    in->name = mesh_name;
    /* --scene: the scene file's triangles (and camera) replace the mesh. */
    if (program_load_scene(opts, program, &in->desc)) {
        char err[SCENE_ERROR_SIZE];
        if (obj_path != NULL) {
            fprintf(stderr, "%s: --scene and --obj: choose one\n", program);
            accel_input_free(in);
            return 2;
        }
        if (!accel_mesh_from_desc(&in->m, &in->desc, program, NULL, NULL, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", program, err);
            accel_input_free(in);
            return 1;
        }
        in->name = in->desc.source;
        return 0;
    }
    if (obj_path != NULL) {
        char err[MESH_ERROR_SIZE];
        if (!mesh_load_obj(&in->m, obj_path, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", program, err);
            accel_input_free(in); /* the load left m as it was, but its arrays may have grown */
            return 1;
        }
        in->name = obj_path;
    } else if (strcmp(mesh_name, "tori") == 0) {
        mesh_tori_field(&in->m, tori_triangles);
    } else if (strcmp(mesh_name, "stadium") == 0) {
        /* 81920 triangles of teapot (a sphere of radius 1), 10 of stadium
         * 200 x 50 x 200 */
        mesh_teapot_in_stadium(&in->m, 6, 200.0f);
        in->stadium = true;
    } else if (strcmp(mesh_name, "icosphere") == 0) {
        mesh_icosphere(&in->m, vec3_make(0, 0, 0), 1.0f, icosphere_subdivisions, -1);
    } else {
        fprintf(stderr, "%s: --mesh must be tori, stadium or icosphere, not '%s'\ntry --help\n", program, mesh_name);
        accel_input_free(in);
        return 2;
    }
    if (in->m.face_count == 0) {
        fprintf(stderr, "%s: %s: no triangles\n", program, in->name);
        accel_input_free(in);
        return 1;
    }
    return 0;
}

camera accel_input_camera(const accel_input *in, aabb bounds, int width, int height)
{
    /* The harness's view of the whole bounds makes the stadium's teapot two
     * pixels wide, so there a spectator looks at it from 12 units away, with
     * the ground and the far walls behind. */
    if (in->stadium)
        return camera_look_at(vec3_make(7, 5, 10), vec3_make(0, 1, 0), vec3_make(0, 1, 0), 30.0f, width, height);
    return accel_scene_camera(&in->desc, bounds, width, height);
}

void accel_input_free(accel_input *in)
{
    mesh_free(&in->m);
    scene_desc_free(&in->desc);
}

int accel_input_render(const cli_options *opts, const char *program, const accel_input *in, const accel *a,
                       bool heatmap, float heatmap_max, const camera_override *view, render_stats *stats)
{
    accel_view seen = {a, heatmap, heatmap_max};
    camera cam = accel_input_camera(in, a->set->bounds, opts->width, opts->height);
    cam = camera_overridden(&cam, view);
    return program_render(opts, program, accel_view_radiance, &seen, &cam, stats);
}

/* ---- the Embree harness's ray sets, timed on one thread ------------------- */

enum { BENCH_REPEATS = 3 };

/* CPU time of this thread: on a machine shared with other work it counts
 * only the time this thread ran, which the wall clock does not. */
static double thread_cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void accel_bench_harness(const accel *a, bool coherent)
{
    int count;
    ray *rays = accel_harness_rays(a->set->bounds, coherent, &count);
    double closest[BENCH_REPEATS], any[BENCH_REPEATS], closest_cpu[BENCH_REPEATS], any_cpu[BENCH_REPEATS];
    long hits = 0;
    double t_sum = 0.0;
    ray_counters counters = {0};
    for (int rep = 0; rep < BENCH_REPEATS; rep++) {
        hits = 0;
        t_sum = 0.0;
        double start = timer_seconds(), start_cpu = thread_cpu_seconds();
        for (int i = 0; i < count; i++) {
            hit_record hit;
            if (accel_closest_hit(a, rays[i], &hit, &counters)) {
                hits++;
                t_sum += hit.t;
            }
        }
        closest[rep] = timer_seconds() - start;
        closest_cpu[rep] = thread_cpu_seconds() - start_cpu;
        start = timer_seconds();
        start_cpu = thread_cpu_seconds();
        for (int i = 0; i < count; i++)
            accel_any_hit(a, rays[i], &counters);
        any[rep] = timer_seconds() - start;
        any_cpu[rep] = thread_cpu_seconds() - start_cpu;
    }
    qsort(closest, BENCH_REPEATS, sizeof *closest, compare_doubles);
    qsort(any, BENCH_REPEATS, sizeof *any, compare_doubles);
    qsort(closest_cpu, BENCH_REPEATS, sizeof *closest_cpu, compare_doubles);
    qsort(any_cpu, BENCH_REPEATS, sizeof *any_cpu, compare_doubles);
    int m = BENCH_REPEATS / 2;
    printf("bench %-10s %7d rays, 1 thread: closest hit %.2f Mrays/s, any hit %.2f Mrays/s (by CPU time: %.2f and "
           "%.2f)\n",
           coherent ? "coherent" : "incoherent", count, count / closest[m] * 1e-6, count / any[m] * 1e-6,
           count / closest_cpu[m] * 1e-6, count / any_cpu[m] * 1e-6);
    printf("      hit fraction %.4f, sum of t %.6e\n", (double)hits / count, t_sum);
    double tests = (double)count * BENCH_REPEATS * 2;
    printf("      %.2f nodes visited and %.2f triangles tested per ray (closest and any hit together)\n",
           (double)counters.box_tests / tests, (double)counters.primitive_tests / tests);
    free(rays);
}

/* ---- the Embree harness's ray sets ------------------------------------------ */

static double harness_uniform(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static vec3 harness_unit(vec3 a) { return vec3_scale(a, 1.0f / sqrtf(vec3_dot(a, a))); }

ray *accel_harness_rays(aabb bounds, bool coherent, int *count)
{
    enum { SIDE = 1024, INCOHERENT = 1 << 20 };
    if (coherent) {
        *count = SIDE * SIDE;
        ray *rays = memory_allocate((size_t)*count, sizeof *rays);
        vec3 c = vec3_scale(vec3_add(bounds.lo, bounds.hi), 0.5f);
        vec3 diagonal = vec3_sub(bounds.hi, bounds.lo);
        float rb = 0.5f * sqrtf(vec3_dot(diagonal, diagonal));
        vec3 eye = vec3_add(c, vec3_scale(harness_unit(vec3_make(0.3f, 0.4f, 1.0f)), 2.5f * rb));
        vec3 forward = harness_unit(vec3_sub(c, eye));
        vec3 right = harness_unit(vec3_cross(forward, vec3_make(0, 1, 0)));
        vec3 up = vec3_cross(right, forward);
        float th = 0.3f, tw = th * (float)SIDE / (float)SIDE;
        for (int y = 0; y < SIDE; y++)
            for (int x = 0; x < SIDE; x++) {
                float u = (2 * (x + 0.5f) / (float)SIDE - 1) * tw, v = (1 - 2 * (y + 0.5f) / (float)SIDE) * th;
                vec3 d = harness_unit(vec3_add(forward, vec3_add(vec3_scale(right, u), vec3_scale(up, v))));
                rays[(size_t)y * SIDE + (size_t)x] = ray_make(eye, d);
            }
        return rays;
    }
    *count = INCOHERENT;
    ray *rays = memory_allocate((size_t)*count, sizeof *rays);
    uint64_t state = 0xBADC0DE;
    for (int k = 0; k < *count; k++) {
        vec3 o;
        o.x = (float)(bounds.lo.x + (bounds.hi.x - bounds.lo.x) * harness_uniform(&state));
        o.y = (float)(bounds.lo.y + (bounds.hi.y - bounds.lo.y) * harness_uniform(&state));
        o.z = (float)(bounds.lo.z + (bounds.hi.z - bounds.lo.z) * harness_uniform(&state));
        float z = (float)(2 * harness_uniform(&state) - 1);
        float phi = (float)(2 * PI * harness_uniform(&state));
        float s = sqrtf(1 - z * z);
        rays[k] = ray_make(o, vec3_make(s * cosf(phi), s * sinf(phi), z));
    }
    return rays;
}

ray *accel_aimed_rays(const triangle_set *set, int count, uint64_t seed)
{
    ray *rays = memory_allocate((size_t)count, sizeof *rays);
    pcg32 rng = pcg32_for_pixel(seed, 0x9120);
    vec3 lo = set->bounds.lo, e = aabb_extent(set->bounds);
    for (int i = 0; i < count; i++) {
        /* in a written order (C leaves a call's argument order open): GCC's */
        float u_z = pcg32_float(&rng), u_y = pcg32_float(&rng), u_x = pcg32_float(&rng);
        vec3 o = vec3_make(lo.x + e.x * u_x, lo.y + e.y * u_y, lo.z + e.z * u_z);
        const triangle *t = &set->triangles[pcg32_bounded(&rng, (uint32_t)set->count)];
        vec3 target = vec3_scale(vec3_add(vec3_add(t->p0, t->p1), t->p2), 1.0f / 3.0f);
        rays[i] = ray_make(o, vec3_normalize(vec3_sub(target, o)));
    }
    return rays;
}

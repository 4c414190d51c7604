/* experiments.c -- measuring error against time (see experiments.h). */
#include "09-path-tracing/experiments.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "atomic_file.h"
#include "checkpoint.h"
#include "image_file.h"
#include "mpi_split.h"
#include "record_file.h"
#include "run_record.h"
#include "timer.h"

/* relMSE's guard against dividing by near-black pixels (as image_relmse). */
static const double RELATIVE_ERROR_EPSILON = 1e-2;

/* CPU time of the whole process (all threads): on a machine shared with
 * other jobs, it measures the work done; wall time also measures the
 * neighbours. */
double experiment_cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* progressive.h's, for the path tracer. */
estimate_image render_estimate(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int threads)
{
    return estimate_render_sampled(path_trace_radiance, path_tracer_sample_fn(pt), pt, cam, spp, seed, threads);
}

estimate_image render_progressive(const path_tracer *pt, const camera *cam, uint64_t seed, int threads,
                                  double seconds, double target_error, FILE *log)
{
    return progressive_render_sampled(path_trace_radiance, path_tracer_sample_fn(pt), pt, cam, seed, threads, seconds,
                                      target_error, log);
}

/* ---- the reference ------------------------------------------------------------ */

static void standard_error_path(const char *path, char *out, size_t size)
{
    size_t n = strlen(path);
    snprintf(out, size, "%.*s-stderr.exr", (int)(n > 4 ? n - 4 : n), path);
}

bool experiment_reference_load(const char *path, int width, int height, estimate_image *out, char *err,
                               size_t err_size)
{
    char se_path[4096];
    standard_error_path(path, se_path, sizeof se_path);
    image mean = {0}, se = {0};
    if (access(path, R_OK) == 0 && access(se_path, R_OK) == 0 && image_read_exr(&mean, path, err, err_size) &&
        image_read_exr(&se, se_path, err, err_size) && mean.width == width && mean.height == height &&
        se.width == width && se.height == height) {
        out->mean = mean;
        out->standard_error = se;
        out->spp = 0;
        out->seconds = 0.0;
        memset(&out->counters, 0, sizeof out->counters);
        printf("reference: %s (cached; delete it to render it again)\n", path);
        return true;
    }
    image_free(&mean);
    image_free(&se);
    return false;
}

bool experiment_reference_save(const estimate_image *e, const char *path, char *err, size_t err_size)
{
    char se_path[4096];
    standard_error_path(path, se_path, sizeof se_path);
    if (!image_write_exr(&e->mean, path, err, err_size))
        return false;
    /* The cache is the pair: a new mean beside an old standard error (or
     * none) must not be taken for one next time. */
    if (!image_write_exr(&e->standard_error, se_path, err, err_size)) {
        unlink(path);
        return false;
    }
    return true;
}

/* ---- how a reference was made ------------------------------------------------------
 * Beside the pair, NAME-record.txt says how it was made: its size, samples,
 * seed, method, a hash of the scene it shows and the project's version. A
 * cached reference whose record is not this run's (another --reference-spp,
 * a changed scene, another build) is stale and made again. The record is
 * written last, so a pair whose writing was cut short has none, and is
 * made again too. */

/* FNV-1a over bytes, added to h. */
static uint64_t hash_bytes(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static uint64_t hash_floats(uint64_t h, const float *f, size_t n) { return hash_bytes(h, f, n * sizeof *f); }
static uint64_t hash_vec3(uint64_t h, vec3 v) { return hash_floats(h, (const float[3]){v.x, v.y, v.z}, 3); }

/* What the path tracer sees of the scene, field by field (the structs'
 * padding bytes are not the scene's): triangles, materials, spheres,
 * point lights, environment and camera. */
static uint64_t scene_fingerprint(const pt_scene *sc)
{
    uint64_t h = 14695981039346656037ULL;
    const mesh *m = &sc->geometry;
    for (int i = 0; i < m->position_count; i++)
        h = hash_vec3(h, m->positions[i]);
    for (int i = 0; i < m->face_count; i++) {
        const int corners[4] = {m->faces[i].position[0], m->faces[i].position[1], m->faces[i].position[2],
                                m->faces[i].material};
        h = hash_bytes(h, corners, sizeof corners);
    }
    for (int i = 0; i < sc->material_count; i++) {
        const pt_material *mat = &sc->materials[i];
        const int kind = (int)mat->kind;
        h = hash_bytes(h, &kind, sizeof kind);
        h = hash_floats(hash_vec3(hash_vec3(h, mat->albedo), mat->emission), (const float[2]){mat->roughness, mat->ior}, 2);
    }
    for (int i = 0; i < sc->sphere_count; i++) {
        const pt_sphere *sp = &sc->spheres[i];
        const int rest[2] = {sp->material, sp->inside_out};
        h = hash_bytes(hash_floats(hash_vec3(h, sp->center), &sp->radius, 1), rest, sizeof rest);
    }
    for (int i = 0; i < sc->point_light_count; i++)
        h = hash_vec3(hash_vec3(h, sc->point_lights[i].position), sc->point_lights[i].intensity);
    h = hash_vec3(hash_vec3(hash_vec3(hash_vec3(h, sc->environment), sc->eye), sc->target), sc->up);
    return hash_floats(h, &sc->vertical_fov_degrees, 1);
}

static void record_path(const char *path, char *out, size_t size)
{
    size_t n = strlen(path);
    snprintf(out, size, "%.*s-record.txt", (int)(n > 4 ? n - 4 : n), path);
}

/* This run's record of the reference at `path`, one "key value" a line. */
static void reference_record(const path_tracer *reference, const camera *cam, int spp, uint64_t seed, char *out,
                             size_t size)
{
    snprintf(out, size,
             "width %d\nheight %d\nspp %d\nseed %llu\nmethod path tracing, %s, Russian roulette %s, max depth %d, "
             "%s samples\nscene-hash %016llx\nversion %s\n",
             cam->width, cam->height, spp, (unsigned long long)seed, pt_integrator_name(reference->integrator),
             pt_russian_roulette_name(reference->russian_roulette), reference->max_depth,
             PT_SAMPLER_NAMES[reference->sampler], (unsigned long long)scene_fingerprint(reference->scene),
             PROJECT_VERSION);
}

/* Whether the record beside `path` is `expected`; if not, why, in why
 * ("its spp 1024, now 4096; ..."; "no record"): record_file.h. */
static bool record_matches(const char *path, const char *expected, char *why, size_t why_size)
{
    char stored_path[4200];
    record_path(path, stored_path, sizeof stored_path);
    return record_file_matches(stored_path, expected, why, why_size);
}

static bool record_write(const char *path, const char *record, char *err, size_t err_size)
{
    char p[4200];
    record_path(path, p, sizeof p);
    return record_file_write(p, record, err, err_size);
}

/* A reference the ranks made together goes on rank 0; the others, which
 * stop after the references (mpi_split_leave), get a blank one. */
static void reference_blank(const camera *cam, estimate_image *out)
{
    memset(out, 0, sizeof *out);
    out->mean = image_make(cam->width, cam->height);
    out->standard_error = image_make(cam->width, cam->height);
}

/* Where a reference keeps its checkpoint while it renders: the image's
 * name with ".checkpoint". One left by an interrupted run of the same
 * reference is resumed; one of another (the identity differs) is not. */
static void reference_checkpointing(const char *path, const char *record, const camera *cam, int spp, uint64_t seed,
                                    checkpointing *cp, checkpoint *resumed, char *cp_path, size_t cp_size)
{
    memset(cp, 0, sizeof *cp);
    memset(resumed, 0, sizeof *resumed);
    checkpoint_path_for_image(path, cp_path, cp_size);
    cp->path = cp_path;
    cp->every_seconds = 60.0;
    snprintf(cp->id.kind, sizeof cp->id.kind, "reference");
    snprintf(cp->id.program, sizeof cp->id.program, "09-path-tracing");
    snprintf(cp->id.version, sizeof cp->id.version, "%s", PROJECT_VERSION);
    snprintf(cp->id.scene, sizeof cp->id.scene, "%s", path);
    cp->id.width = cam->width;
    cp->id.height = cam->height;
    cp->id.spp = spp;
    cp->id.seed = seed;
    for (size_t i = 0, n = 0; record[i] != '\0' && n + 1 < sizeof cp->id.flags; i++) /* one line */
        cp->id.flags[n++] = record[i] == '\n' ? ';' : record[i];
    size_t bytes = (size_t)cam->width * (size_t)cam->height * sizeof(render_pixel_state);
    char err[8192];
    int found = mpi_split_is_root() && access(cp_path, R_OK) == 0;
    if (found && !checkpoint_read(cp_path, &cp->id, bytes, resumed, err, sizeof err)) {
        printf("reference: not resuming: %s\n", err);
        found = 0;
    } else if (found && render_resume_problem(resumed) != NULL) {
        printf("reference: not resuming: %s: %s\n", cp_path, render_resume_problem(resumed));
        checkpoint_free(resumed);
        found = 0;
    }
    cp->resuming = mpi_split_broadcast_int(found);
    if (found) {
        cp->resume = resumed;
        printf("reference: resuming %s: %ld of %d samples per pixel done\n", cp_path, resumed->done, spp);
    }
}

bool experiment_reference(const path_tracer *pt, const camera *cam, int spp, int threads, const char *path,
                          estimate_image *out, char *err, size_t err_size)
{
    path_tracer reference = *pt;
    reference.integrator = PT_MIS;
    reference.russian_roulette = RR_THROUGHPUT;
    const uint64_t seed = 0x5eedULL;
    char record[2048], why[4096];
    reference_record(&reference, cam, spp, seed, record, sizeof record);
    /* Rank 0 decides whether the cache serves; under mpirun the others
     * then render with it, or stop. */
    int cached = 0;
    if (mpi_split_is_root() && access(path, F_OK) == 0) {
        cached = record_matches(path, record, why, sizeof why) &&
                 experiment_reference_load(path, cam->width, cam->height, out, err, err_size);
        if (!cached)
            printf("reference: %s is stale (%s): rendering it again\n", path, why);
    }
    if (mpi_split_broadcast_int(cached)) {
        if (!mpi_split_is_root())
            reference_blank(cam, out);
        out->spp = spp;
        return true;
    }
    checkpointing cp;
    checkpoint resumed;
    char cp_path[4200];
    reference_checkpointing(path, record, cam, spp, seed, &cp, &resumed, cp_path, sizeof cp_path);
    if (mpi_split_is_root()) {
        printf("reference: rendering %dx%d at %d spp with MIS%s ...\n", cam->width, cam->height, spp,
               mpi_split_ranks() > 1 ? " on every MPI rank" : "");
        fflush(stdout);
    }
    *out = estimate_render_checkpointed(path_trace_radiance, path_tracer_sample_fn(&reference), &reference, cam, spp,
                                        seed, threads, &cp);
    checkpoint_free(&resumed);
    if (!mpi_split_is_root())
        return true;
    printf("reference: %.1f s, estimated relative error %.4f -> %s\n", out->seconds, estimate_relative_error(out), path);
    if (!experiment_reference_save(out, path, err, err_size) || !record_write(path, record, err, err_size))
        return false;
    unlink(cp_path); /* the reference holds all it did */
    return true;
}

/* ---- error against the reference ---------------------------------------------------
 * The reference has noise of its own, which adds its variance to every
 * measured MSE; subtracting the mean of its squared standard error leaves the
 * error of the image under test (an unbiased correction). */
void experiment_error(const image *img, const estimate_image *ref, double *rmse, double *relmse)
{
    size_t n = (size_t)img->width * (size_t)img->height * 3;
    double sum = 0.0, sum_relative = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)img->rgb[i] - (double)ref->mean.rgb[i];
        double s = ref->standard_error.rgb[i], r = ref->mean.rgb[i];
        double squared = d * d - s * s;
        sum += squared;
        sum_relative += squared / (r * r + RELATIVE_ERROR_EPSILON);
    }
    /* A NaN pixel makes the error NaN, never 0 (fmax would pick 0 over it),
     * so that a broken image cannot score as a perfect one. */
    *rmse = isnan(sum) ? (double)NAN : sqrt(fmax(0.0, sum / (double)n));
    *relmse = isnan(sum_relative) ? (double)NAN : fmax(0.0, sum_relative / (double)n);
}

/* A CSV is written as "<path>.tmp" and renamed into place only when every
 * write succeeded: a full disk or a killed run leaves the old table (or
 * none), never half of one that a plot would draw without complaint. */
static void csv_temp_path(const char *path, char *temp, size_t size) { snprintf(temp, size, "%s.tmp", path); }

FILE *experiment_csv_open(const char *dir, const char *name, char *path, size_t path_size, char *err, size_t err_size)
{
    char temp[4200];
    snprintf(path, path_size, "%s/%s", dir, name);
    csv_temp_path(path, temp, sizeof temp);
    FILE *f = fopen(temp, "w");
    if (f == NULL)
        snprintf(err, err_size, "%s: %s", path, strerror(errno));
    return f;
}

/* Closes without keeping anything: for a run that failed elsewhere. */
void experiment_csv_discard(FILE *f, const char *path)
{
    char temp[4200];
    csv_temp_path(path, temp, sizeof temp);
    fclose(f);
    unlink(temp);
}

bool experiment_csv_close(FILE *f, const char *path, char *err, size_t err_size)
{
    char temp[4200];
    csv_temp_path(path, temp, sizeof temp);
    /* An earlier fprintf may have failed (ferror); the final flush and close
     * may fail too (a full disk shows up there). */
    bool written = !ferror(f) && fflush(f) == 0;
    int reason = errno;
    if (fclose(f) != 0 && written) {
        written = false;
        reason = errno;
    }
    if (!written) {
        snprintf(err, err_size, "%s: write failed (%s)", path, reason != 0 ? strerror(reason) : "stream error");
        unlink(temp);
        return false;
    }
    if (rename(temp, path) != 0) {
        snprintf(err, err_size, "%s: %s", path, strerror(errno));
        unlink(temp);
        return false;
    }
    return true;
}

typedef struct {
    pt_integrator integrator;
    pt_russian_roulette rr;
    const char *label;
    pt_sampler sampler; /* PT_SAMPLER_RANDOM unless given */
} rung;

/* The ladder, then better samples on its first and last rung (after them,
 * so that the rows' numbers in the CSV stay what the plots expect). */
static const rung rungs[] = {
    {PT_LECTURE, RR_FIXED, "lecture (uniform hemisphere, P_RR 0.8)", PT_SAMPLER_RANDOM},
    {PT_COSINE, RR_FIXED, "cosine-weighted (P_RR 0.8)", PT_SAMPLER_RANDOM},
    {PT_MIS, RR_FIXED, "BSDF sampling + MIS (P_RR 0.8)", PT_SAMPLER_RANDOM},
    {PT_MIS, RR_THROUGHPUT, "BSDF sampling + MIS, RR on throughput", PT_SAMPLER_RANDOM},
    {PT_LECTURE, RR_FIXED, "lecture, Sobol samples", PT_SAMPLER_SOBOL},
    {PT_MIS, RR_THROUGHPUT, "MIS, RR on throughput, Sobol samples", PT_SAMPLER_SOBOL},
};
enum { RUNG_COUNT = sizeof rungs / sizeof rungs[0] };

/* The errors the time-to-error table is read at. */
static const double TARGET_RELMSE[] = {0.1, 0.03, 0.01};
enum { TARGET_COUNT = sizeof TARGET_RELMSE / sizeof TARGET_RELMSE[0], MAX_POINTS = 32 };

/* The time at which relMSE falls to `target`, from renders at doubling spp:
 * log(relMSE) interpolated linearly in log(seconds) between the two renders
 * either side of it. -1 if no render reached it; *spp_out = the first spp
 * that did. */
double experiment_time_to_reach(const double *seconds, const double *relmse, const int *spp, int n, double target,
                            int *spp_out)
{
    *spp_out = 0;
    for (int i = 0; i < n; i++) {
        if (!(relmse[i] <= target && relmse[i] > 0.0))
            continue;
        *spp_out = spp[i];
        if (i == 0 || !(relmse[i - 1] > target) || !(seconds[i - 1] > 0.0))
            return seconds[i];
        double f = log(relmse[i - 1] / target) / log(relmse[i - 1] / relmse[i]);
        return exp(log(seconds[i - 1]) + f * log(seconds[i] / seconds[i - 1]));
    }
    return -1.0;
}

bool experiment_convergence(const pt_scene *sc, const char *name, const camera *cam, const estimate_image *reference,
                            int max_spp, int threads, const char *dir, char *err, size_t err_size)
{
    char path[4096], time_path[4096], file[256];
    snprintf(file, sizeof file, "ch09_convergence_%s.csv", name);
    FILE *csv = experiment_csv_open(dir, file, path, sizeof path, err, err_size);
    if (csv == NULL)
        return false;
    snprintf(file, sizeof file, "ch09_time_to_error_%s.csv", name);
    FILE *time_csv = experiment_csv_open(dir, file, time_path, sizeof time_path, err, err_size);
    if (time_csv == NULL) {
        experiment_csv_discard(csv, path);
        return false;
    }
    fprintf(csv, "rung,integrator,russian_roulette,spp,seconds,rmse,relmse,rays_per_sample,cpu_seconds,sampler\n");
    fprintf(time_csv, "rung,label,target_relmse,cpu_seconds,spp\n");
    printf("\n%-42s %6s %9s %9s %10s %10s\n", "rung", "spp", "seconds", "CPU s", "RMSE", "relMSE");
    double reached[RUNG_COUNT][TARGET_COUNT];
    int reached_spp[RUNG_COUNT][TARGET_COUNT], last_spp = 0;
    for (int k = 0; k < RUNG_COUNT; k++) {
        path_tracer pt = path_tracer_defaults(sc);
        pt.integrator = rungs[k].integrator;
        pt.russian_roulette = rungs[k].rr;
        pt.sampler = rungs[k].sampler;
        double seconds[MAX_POINTS], relmses[MAX_POINTS];
        int spps[MAX_POINTS], n = 0;
        for (int spp = 1; spp <= max_spp && n < MAX_POINTS; spp *= 2, n++) {
            double cpu_start = experiment_cpu_seconds();
            estimate_image e = render_estimate(&pt, cam, spp, 1000 + (uint64_t)spp, threads);
            double cpu = experiment_cpu_seconds() - cpu_start;
            double rmse, relmse;
            experiment_error(&e.mean, reference, &rmse, &relmse);
            double rays = (double)counters_total_rays(&e.counters) / ((double)spp * cam->width * cam->height);
            fprintf(csv, "%d,%s,%s,%d,%.6f,%.6e,%.6e,%.3f,%.6f,%s\n", k, pt_integrator_name(pt.integrator),
                    pt_russian_roulette_name(pt.russian_roulette), spp, e.seconds, rmse, relmse, rays, cpu,
                    PT_SAMPLER_NAMES[pt.sampler]);
            printf("%-42s %6d %9.3f %9.3f %10.4f %10.5f\n", rungs[k].label, spp, e.seconds, cpu, rmse, relmse);
            seconds[n] = cpu;
            relmses[n] = relmse;
            spps[n] = last_spp = spp;
            estimate_image_free(&e);
        }
        for (int t = 0; t < TARGET_COUNT; t++) {
            reached[k][t] = experiment_time_to_reach(seconds, relmses, spps, n, TARGET_RELMSE[t], &reached_spp[k][t]);
            fprintf(time_csv, "%d,\"%s\",%g,%.6f,%d\n", k, rungs[k].label, TARGET_RELMSE[t], reached[k][t],
                    reached_spp[k][t]);
        }
    }
    printf("\nCPU seconds (all threads) and spp to reach relMSE (%s, %dx%d; \"-\": not within %d spp):\n%-42s", name,
           cam->width, cam->height, last_spp, "rung");
    for (int t = 0; t < TARGET_COUNT; t++)
        printf(" %14g", TARGET_RELMSE[t]);
    printf("\n");
    for (int k = 0; k < RUNG_COUNT; k++) {
        printf("%-42s", rungs[k].label);
        for (int t = 0; t < TARGET_COUNT; t++) {
            if (reached[k][t] < 0.0)
                printf(" %14s", "-");
            else
                printf(" %7.3f s %4d", reached[k][t], reached_spp[k][t]);
        }
        printf("\n");
    }
    /* Both files or neither: a failed first one discards the second. */
    if (!experiment_csv_close(csv, path, err, err_size)) {
        experiment_csv_discard(time_csv, time_path);
        return false;
    }
    return experiment_csv_close(time_csv, time_path, err, err_size);
}

bool experiment_russian_roulette(const pt_scene *sc, const camera *cam, const estimate_image *reference, int spp,
                                 int threads, const char *dir, char *err, size_t err_size)
{
    char path[4096];
    FILE *csv = experiment_csv_open(dir, "ch09_russian_roulette.csv", path, sizeof path, err, err_size);
    if (csv == NULL)
        return false;
    const float probabilities[] = {0.2f, 0.4f, 0.6f, 0.8f, 0.9f, 0.95f};
    fprintf(csv, "p_rr,cpu_seconds,mse,efficiency,rays_per_sample\n");
    printf("\nRussian roulette (cosine rung, %d spp): P_RR, CPU seconds, MSE, efficiency 1/(MSE x time)\n", spp);
    for (int i = 0; i < 6; i++) {
        path_tracer pt = path_tracer_defaults(sc);
        pt.integrator = PT_COSINE;
        pt.russian_roulette = RR_FIXED;
        pt.rr_probability = probabilities[i];
        double cpu_start = experiment_cpu_seconds();
        estimate_image e = render_estimate(&pt, cam, spp, 77, threads);
        double cpu = experiment_cpu_seconds() - cpu_start;
        double rmse, relmse;
        experiment_error(&e.mean, reference, &rmse, &relmse);
        double mse = rmse * rmse;
        double rays = (double)counters_total_rays(&e.counters) / ((double)spp * cam->width * cam->height);
        fprintf(csv, "%.2f,%.6f,%.6e,%.6e,%.3f\n", (double)probabilities[i], cpu, mse, 1.0 / (mse * cpu), rays);
        printf("  %.2f %8.3f s  %.4e  %.4e  %.2f rays/sample\n", (double)probabilities[i], cpu, mse, 1.0 / (mse * cpu),
               rays);
        estimate_image_free(&e);
    }
    if (!experiment_csv_close(csv, path, err, err_size))
        return false;
    return experiment_roulettes(sc, cam, reference, spp, threads, dir, err, err_size);
}

/* The references' roulettes against the lecture's, on the lecture rung eight
 * paths at a time (the renderer of the speed target), each counting at most
 * SPEED_MAX_DEPTH bounces: what a deeper roulette buys in noise for what it
 * costs in rays. */
enum { SPEED_MAX_DEPTH = 50 };
static const struct {
    pt_russian_roulette rr;
    int rr_start_depth;
    const char *label;
} roulettes[] = {
    {RR_FIXED, 0, "P_RR 0.8 (the lecture)"},
    {RR_THROUGHPUT, RR_START_PBRT, "throughput from 5 (pbrt)"},
    {RR_ALBEDO, RR_START_SMALLPT, "albedo from 6 (smallpt)"},
    {RR_OFF, 0, "none, 50 bounces (RTROWL)"},
};

bool experiment_roulettes(const pt_scene *sc, const camera *cam, const estimate_image *reference, int spp, int threads,
                          const char *dir, char *err, size_t err_size)
{
    char path[4096];
    FILE *csv = experiment_csv_open(dir, "ch09_roulettes.csv", path, sizeof path, err, err_size);
    if (csv == NULL)
        return false;
    /* A render's MSE is itself noisy (a few bright paths decide it), so
     * each roulette renders ROULETTE_RENDERS times with other seeds: the
     * mean MSE, and the lowest and highest to show how far one render's can
     * be trusted. The time is the least of the renders' CPU times, as the
     * speed table takes the best of its runs: a neighbour on the machine
     * only ever adds time. */
    enum { ROULETTE_RENDERS = 8 };
    fprintf(csv, "roulette,label,cpu_seconds,mse,mse_low,mse_high,efficiency,rays_per_sample\n");
    printf("\nThe references' roulettes (lecture rung, %d spp, at most %d bounces,\n"
           "MSE the mean of %d renders, CPU s the least):\n  %-28s %8s %11s %23s %11s %9s\n",
           spp, SPEED_MAX_DEPTH, ROULETTE_RENDERS, "roulette", "CPU s", "MSE", "(lowest, highest)", "efficiency",
           "rays/spl");
    for (size_t i = 0; i < sizeof roulettes / sizeof roulettes[0]; i++) {
        path_tracer pt = path_tracer_defaults(sc);
        pt.russian_roulette = roulettes[i].rr;
        pt.max_depth = SPEED_MAX_DEPTH;
        if (roulettes[i].rr_start_depth > 0)
            pt.rr_start_depth = roulettes[i].rr_start_depth;
        double cpu = INFINITY, mse = 0.0, low = INFINITY, high = 0.0, rays = 0.0;
        for (int r = 0; r < ROULETTE_RENDERS; r++) {
            double cpu_start = experiment_cpu_seconds();
            estimate_image e = render_estimate(&pt, cam, spp, 78 + (uint64_t)r, threads);
            cpu = fmin(cpu, experiment_cpu_seconds() - cpu_start);
            double rmse, relmse;
            experiment_error(&e.mean, reference, &rmse, &relmse);
            mse += rmse * rmse / ROULETTE_RENDERS;
            low = fmin(low, rmse * rmse);
            high = fmax(high, rmse * rmse);
            rays += (double)counters_total_rays(&e.counters) / ((double)spp * cam->width * cam->height) /
                    ROULETTE_RENDERS;
            estimate_image_free(&e);
        }
        fprintf(csv, "%s,\"%s\",%.6f,%.6e,%.6e,%.6e,%.6e,%.3f\n", pt_russian_roulette_name(roulettes[i].rr),
                roulettes[i].label, cpu, mse, low, high, 1.0 / (mse * cpu), rays);
        printf("  %-28s %8.3f %11.4e (%10.4e, %10.4e) %11.4e %9.2f\n", roulettes[i].label, cpu, mse, low, high,
               1.0 / (mse * cpu), rays);
    }
    return experiment_csv_close(csv, path, err, err_size);
}

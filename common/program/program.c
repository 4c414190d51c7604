#include "program.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "counters_file.h"
#include "explain.h"
#include "image_file.h"
#include "input_file.h"
#include "mpi_split.h"
#include "progressive.h"
#include "run_record.h"
#include "timer.h"

#ifdef _OPENMP
#include <omp.h>
#endif

void program_note_effects(const effects_report *e)
{
    char list[256];
    size_t used = (size_t)snprintf(list, sizeof list, "[");
    bool first = true;
    for (int k = 0; k < EFFECT_COUNT; k++)
        if (e->simulated & (1u << k)) {
            used += (size_t)snprintf(list + used, sizeof list - used, "%s\"%s\"", first ? "" : ", ",
                                     effect_name(1u << k));
            first = false;
        }
    snprintf(list + used, sizeof list - used, "]");
    run_record_note("effects_simulated", list);
}

/* The structure the rays were traced through, for the report ("" until noted). */
static char noted_accel[64];

void program_note_accel(const char *name)
{
    snprintf(noted_accel, sizeof noted_accel, "%s", name);
    run_record_note("accel", name);
}

bool program_write_record(const cli_options *opts, const char *label, const ray_counters *c, double seconds,
                          char *err, size_t err_size)
{
    char path[4096], extra[128];
    counters_path_for_image(opts->out, path, sizeof path);
    snprintf(extra, sizeof extra, "\"program\": \"%s\"", label);
    return counters_write_json(path, c, seconds, extra, err, err_size);
}

void program_warn(const char *label, const scene_desc *d, int line, int column, const char *format, ...)
{
    char where[SCENE_PATH_SIZE + 32];
    if (line > 0)
        scene_desc_where(d, line, column, where, sizeof where);
    else
        snprintf(where, sizeof where, "%s", d->source);
    fprintf(stderr, "%s: %s: warning: ", label, where);
    va_list args;
    va_start(args, format);
    vfprintf(stderr, format, args);
    va_end(args);
    fputc('\n', stderr);
}

bool program_load_scene(cli_options *opts, const char *label, scene_desc *d)
{
    scene_desc_init(d);
    if (opts->scene == NULL)
        return false;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_load(d, opts->scene, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", label, err);
        exit(1);
    }
    /* The meshes it names are inputs too, whether or not this chapter
     * reads them: none may be a file the run writes (exits 2 if one is). */
    for (int i = 0; i < d->shape_count; i++)
        if (d->shapes[i].kind == SCENE_SHAPE_MESH_OBJ)
            input_file_check_not_output(d->shapes[i].path);
    if (d->has_width && !opts->width_given)
        opts->width = d->width;
    if (d->has_height && !opts->height_given)
        opts->height = d->height;
    if (d->has_spp && !opts->spp_given)
        opts->spp = d->spp;
    return true;
}

/* Under mpirun: how many ranks, and what handing their rows over cost,
 * for the record and the report. */
static void note_ranks(const render_stats *stats)
{
    if (mpi_split_ranks() == 1)
        return;
    char text[64];
    snprintf(text, sizeof text, "%d", mpi_split_ranks());
    run_record_note("mpi_ranks", text);
    snprintf(text, sizeof text, "%.6f", stats->gather_seconds);
    run_record_note("mpi_gather_seconds", text);
    snprintf(text, sizeof text, "%.6f", stats->wait_seconds);
    run_record_note("mpi_wait_seconds", text);
}

void program_print_ranks(const render_stats *stats)
{
    if (mpi_split_ranks() > 1)
        printf("split over %d MPI ranks: rank 0 waited %.3f s for the slowest; handing rows between them took "
               "%.3f s, %.2f%% of the render\n", mpi_split_ranks(), stats->wait_seconds, stats->gather_seconds,
               stats->seconds > 0.0 ? 100.0 * stats->gather_seconds / stats->seconds : 0.0);
}

/* --explain X,Y: one pixel, one thread, every step printed. */
static int program_explain(const cli_options *opts, const char *label, const render_job *job, render_stats *stats_out)
{
    if (opts->explain_x >= job->cam->width || opts->explain_y >= job->cam->height) {
        fprintf(stderr, "%s: --explain %d,%d: outside the %dx%d image\n", label, opts->explain_x, opts->explain_y,
                job->cam->width, job->cam->height);
        return 2;
    }
    printf("%s: how pixel (%d, %d) of %dx%d is computed, %d sample%s (seed %llu)\n", label, opts->explain_x,
           opts->explain_y, job->cam->width, job->cam->height, job->spp, job->spp > 1 ? "s" : "",
           (unsigned long long)job->seed);
    /* The camera, so that a reader (docs/figures/explain_paths.py) can put
     * the points below back on the image: a point p is at
     * x = W/2 (1 + s_x / half_width), y = H/2 (1 - s_y / half_height), with
     * s = ((p - eye).right, (p - eye).up) / (p - eye).forward. */
    const camera *cam = job->cam;
    printf("camera: eye (%.9g, %.9g, %.9g), forward (%.9g, %.9g, %.9g), right (%.9g, %.9g, %.9g), "
           "up (%.9g, %.9g, %.9g), half width %.9g, half height %.9g\n",
           (double)cam->eye.x, (double)cam->eye.y, (double)cam->eye.z, (double)cam->forward.x,
           (double)cam->forward.y, (double)cam->forward.z, (double)cam->right.x, (double)cam->right.y,
           (double)cam->right.z, (double)cam->up.x, (double)cam->up.y, (double)cam->up.z,
           (double)cam->half_width, (double)cam->half_height);
    ray_counters counters;
    memset(&counters, 0, sizeof counters);
    explain_begin(stdout);
    vec3 c = render_pixel(job, opts->explain_x, opts->explain_y, &counters, NULL);
    explain_end();
    char value[64];
    printf("pixel (%d, %d) = %s: the mean of the samples above\n", opts->explain_x, opts->explain_y,
           explain_vec3(value, c));
    counters_print(stdout, &counters, 0.0);
    /* What callers print after a render then describes this one pixel. */
    if (stats_out != NULL) {
        stats_out->seconds = 0.0;
        stats_out->counters = counters;
    }
    return 0;
}

/* ---- a warning before a long render ---------------------------------------------
 * A learner who asks for 4096 samples of a million-triangle mesh through a
 * brute-force chapter should hear so before the minutes pass, not after.
 * A pilot renders PILOT_PIXELS pixels spread over the image at the full
 * spp, on one thread, and scales its time to the image and the threads.
 * It costs PILOT_PIXELS / (width x height) of the render, and draws its
 * numbers from its own counters and the pixels' own streams, so the image
 * is untouched. Only renders of more than LONG_RENDER_PIXELS pixels are
 * piloted: smaller ones end before a warning would help. */
enum { PILOT_GRID = 8, PILOT_PIXELS = PILOT_GRID * PILOT_GRID, LONG_RENDER_PIXELS = 16384, PROGRESSIVE_PILOT_SPP = 16 };
static const double LONG_RENDER_SECONDS = 60.0;

/* The pilot: one-thread seconds for the whole image, and through
 * relative_error (if not NULL) the error its pixels show, measured as
 * estimate_relative_error measures an image. */
static double pilot(const render_job *job, double *relative_error)
{
    long pixels = (long)job->cam->width * job->cam->height;
    ray_counters ignored;
    memset(&ignored, 0, sizeof ignored);
    double start = timer_seconds(), sum = 0.0;
    /* An 8 x 8 grid of pixels, each at the centre of its cell: every part
     * of the picture has its say, the sky and the model alike. */
    for (int k = 0; k < PILOT_PIXELS; k++) {
        int x = (int)(((double)(k % PILOT_GRID) + 0.5) * job->cam->width / (double)PILOT_GRID);
        int y = (int)(((double)(k / PILOT_GRID) + 0.5) * job->cam->height / (double)PILOT_GRID);
        vec3 se;
        vec3 m = render_pixel(job, x, y, &ignored, &se);
        const float mean[3] = {m.x, m.y, m.z}, error[3] = {se.x, se.y, se.z};
        for (int c = 0; c < 3; c++) /* progressive.c's RELATIVE_ERROR_EPSILON */
            sum += (double)error[c] * error[c] / ((double)mean[c] * mean[c] + 1e-2);
    }
    if (relative_error != NULL)
        *relative_error = sqrt(sum / (3.0 * PILOT_PIXELS));
    return (timer_seconds() - start) / PILOT_PIXELS * (double)pixels;
}

double program_pilot_seconds(const render_job *job)
{
    long pixels = (long)job->cam->width * job->cam->height;
    return pixels < LONG_RENDER_PIXELS ? 0.0 : pilot(job, NULL);
}

/* Every thread of every rank (mpi_split.h) shares the work. */
static int all_threads(const cli_options *opts)
{
#ifdef _OPENMP
    int threads = opts->threads > 0 ? opts->threads : omp_get_max_threads();
#else
    int threads = 1; /* built without OpenMP (the fuzz targets): one thread */
#endif
    return threads * mpi_split_ranks();
}

static void warn_long(const cli_options *opts, const char *label, double one_thread_seconds, const char *advice)
{
    int threads = all_threads(opts);
    double estimate = one_thread_seconds / threads;
    if (opts->quiet || estimate <= LONG_RENDER_SECONDS)
        return;
    bool minutes = estimate >= 120.0;
    fprintf(stderr, "%s: warning: this render will take about %.0f %s on %d threads%s (from a pilot of %d "
            "pixels): %s\n", label, minutes ? estimate / 60.0 : estimate, minutes ? "minutes" : "seconds", threads,
            mpi_split_ranks() > 1 ? " of all ranks" : "", PILOT_PIXELS, advice);
}

void program_warn_if_black(const cli_options *opts, const char *label, const image *img)
{
    size_t values = (size_t)img->width * (size_t)img->height * 3;
    for (size_t i = 0; i < values; i++)
        if (img->rgb[i] != 0.0f)
            return;
    if (!opts->quiet)
        fprintf(stderr, "%s: warning: every pixel of the image is black: the camera sees nothing lit. Is it inside "
                        "an object, under the floor or facing away? --eye and --target are in the scene's own "
                        "coordinates; an OBJ exported from Blender is Y-up, so Blender's (x, y, z) is (x, z, -y) "
                        "here\n",
                label);
}

void program_warn_if_long(const cli_options *opts, const char *label, double one_thread_seconds)
{
    warn_long(opts, label, one_thread_seconds,
              "a smaller --width, --height or --spp first, or a chapter with an acceleration structure (06, 09, 13) "
              "for a large mesh");
}

void program_warn_if_long_progressive(const cli_options *opts, const char *label, const render_job *job,
                                      double seconds, double target_error, long spp_done)
{
    long pixels = (long)job->cam->width * job->cam->height;
    if (opts->quiet || pixels < LONG_RENDER_PIXELS || (seconds > 0.0 && seconds <= LONG_RENDER_SECONDS))
        return;
    double one_thread = seconds * all_threads(opts); /* the budget, if that is all */
    if (target_error > 0.0) {
        /* The error falls as 1/sqrt(spp): from the pilot's error at its
         * spp, the passes (doubling from 2) stop at the first power of two
         * past PILOT_SPP (e / target)^2, and at 16 at least. */
        render_job at_16 = *job;
        at_16.spp = PROGRESSIVE_PILOT_SPP;
        double error = 0.0;
        double per_spp = pilot(&at_16, &error) / PROGRESSIVE_PILOT_SPP;
        double needed = PROGRESSIVE_PILOT_SPP * (error / target_error) * (error / target_error);
        long spp = 16;
        while ((double)spp < needed && spp < (1L << 40))
            spp *= 2;
        double until_target = per_spp * (double)(spp > spp_done ? spp - spp_done : 0);
        one_thread = seconds > 0.0 && one_thread < until_target ? one_thread : until_target;
    }
    warn_long(opts, label, one_thread,
              target_error > 0.0 ? "a larger --target-error, or a --time-budget, first" : "a smaller --time-budget first");
}

bool program_checkpointing(const cli_options *opts, const char *label, const char *kind, size_t payload_bytes,
                           checkpointing *cp, checkpoint *resumed)
{
    memset(cp, 0, sizeof *cp);
    memset(resumed, 0, sizeof *resumed);
    if (!opts->checkpoint_offered)
        return true;
    cp->path = opts->checkpoint;
    cp->every_seconds = opts->checkpoint_every;
    cp->id = checkpoint_identity_of(kind, label, opts);
    cp->quiet = opts->quiet;
    cp->resuming = opts->resume != NULL;
    if (!cp->resuming)
        return true;
    char err[8192] = "";
    int ok = !mpi_split_is_root() || checkpoint_read(opts->resume, &cp->id, payload_bytes, resumed, err, sizeof err);
    if (ok && mpi_split_is_root()) {
        /* whole and of this render: then what it holds must be a render's */
        const char *problem =
            strcmp(kind, "progressive") == 0 ? progressive_resume_problem(resumed) : render_resume_problem(resumed);
        if (problem != NULL) {
            snprintf(err, sizeof err, "%s: %s, not resumed", opts->resume, problem);
            checkpoint_free(resumed);
            ok = 0;
        }
    }
    if (!mpi_split_broadcast_int(ok)) {
        if (mpi_split_is_root())
            fprintf(stderr, "%s: --resume %s\n", label, err);
        return false;
    }
    cp->resume = resumed;
    if (!opts->quiet)
        printf("%s: resuming %s: %ld samples per pixel done in %.1f s\n", label, opts->resume, resumed->spp_done,
               resumed->seconds);
    return true;
}

void program_checkpoint_done(const cli_options *opts, const checkpointing *cp)
{
    /* The image holds all the checkpoint did: it has served. */
    if (cp->path != NULL && mpi_split_is_root() && opts->checkpoint_offered)
        unlink(cp->path);
}

int program_render(const cli_options *opts, const char *label, radiance_fn radiance, const void *scene,
                   const camera *cam, render_stats *stats_out)
{
    return program_render_sampled(opts, label, radiance, NULL, scene, cam, stats_out);
}

int program_render_sampled(const cli_options *opts, const char *label, radiance_fn radiance, render_sample_fn sample,
                           const void *scene, const camera *cam, render_stats *stats_out)
{
    render_job job = {.cam = cam,
                      .spp = opts->spp,
                      .seed = opts->seed,
                      .threads = opts->threads,
                      .quiet = opts->quiet,
                      .label = label,
                      .radiance = radiance,
                      .scene = scene,
                      .jitter = opts->jitter,
                      .stratify = opts->stratify,
                      .sample = sample};
    if (opts->explain) /* one rank explains */
        return mpi_split_is_root() ? program_explain(opts, label, &job, stats_out) : 0;
    checkpointing cp;
    checkpoint resumed;
    if (!program_checkpointing(opts, label, "render", (size_t)cam->width * cam->height * sizeof(render_pixel_state),
                               &cp, &resumed))
        return 1;
    /* The pilot warns of a long render, and decides whether it keeps
     * checkpoints: one that ends before the first would be due runs in one
     * pass, without every pixel's state (88 bytes a pixel). A resumed
     * render has only the rest to do. */
    double one_thread = 0.0;
    if (mpi_split_is_root() && (!opts->quiet || cp.path != NULL) && !cp.resuming) {
        one_thread = program_pilot_seconds(&job);
        program_warn_if_long(opts, label, one_thread);
    } else if (mpi_split_is_root() && cp.resuming && !opts->quiet) {
        program_warn_if_long(opts, label,
                             program_pilot_seconds(&job) * (double)(job.spp - cp.resume->done) / job.spp);
    }
    mpi_split_broadcast(&one_thread, sizeof one_thread);
    if (cp.resuming || (cp.path != NULL && one_thread / all_threads(opts) >= cp.every_seconds))
        job.checkpoints = &cp;
    image img = image_make(cam->width, cam->height);
    if (img.rgb == NULL) {
        fprintf(stderr, "%s: out of memory for a %dx%d image\n", label, cam->width, cam->height);
        return 1;
    }
    render_stats stats;
    render_image(&job, &img, &stats);
    checkpoint_free(&resumed);
    note_ranks(&stats);
    if (!mpi_split_is_root()) { /* rank 0 writes and reports */
        image_free(&img);
        return 0;
    }

    char err[IMAGE_ERROR_SIZE];
    program_warn_if_black(opts, label, &img);
    bool ok = image_write(&img, opts->out, opts->exposure, err, sizeof err);
    image_free(&img);
    if (!ok) {
        fprintf(stderr, "%s: %s\n", label, err);
        return 1;
    }
    char counters_path[4096], extra[128];
    counters_path_for_image(opts->out, counters_path, sizeof counters_path);
    snprintf(extra, sizeof extra, "\"program\": \"%s\"", label);
    if (!counters_write_json(counters_path, &stats.counters, stats.seconds, extra, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", label, err);
        return 1;
    }
    program_checkpoint_done(opts, &cp);
    if (!opts->quiet) {
        printf("%s: %dx%d, %d spp, %d threads, %.3f s -> %s\n", label, cam->width, cam->height, opts->spp,
               opts->threads, stats.seconds, opts->out);
        program_print_ranks(&stats);
        counters_print(stdout, &stats.counters, stats.seconds);
        if (noted_accel[0] != '\0')
            printf("rays traced through: %s\n", noted_accel);
        printf("counters -> %s\n", counters_path);
    }
    if (stats_out != NULL)
        *stats_out = stats;
    return 0;
}

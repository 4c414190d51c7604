#include "program.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "explain.h"
#include "input_file.h"
#include "run_record.h"
#include "timer.h"

#include <omp.h>

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
enum { PILOT_PIXELS = 8 * 8, LONG_RENDER_PIXELS = 16384 };
static const double LONG_RENDER_SECONDS = 60.0;

double program_pilot_seconds(const render_job *job)
{
    long pixels = (long)job->cam->width * job->cam->height;
    if (pixels < LONG_RENDER_PIXELS)
        return 0.0;
    ray_counters ignored;
    memset(&ignored, 0, sizeof ignored);
    double start = timer_seconds();
    /* An 8 x 8 grid of pixels, each at the centre of its cell: every part
     * of the picture has its say, the sky and the model alike. */
    for (int k = 0; k < PILOT_PIXELS; k++) {
        int x = (int)(((double)(k % 8) + 0.5) * job->cam->width / 8.0);
        int y = (int)(((double)(k / 8) + 0.5) * job->cam->height / 8.0);
        render_pixel(job, x, y, &ignored, NULL);
    }
    return (timer_seconds() - start) / PILOT_PIXELS * (double)pixels;
}

void program_warn_if_long(const cli_options *opts, const char *label, double one_thread_seconds)
{
    int threads = opts->threads > 0 ? opts->threads : omp_get_max_threads();
    double estimate = one_thread_seconds / threads;
    if (opts->quiet || estimate <= LONG_RENDER_SECONDS)
        return;
    bool minutes = estimate >= 120.0;
    fprintf(stderr, "%s: warning: this render will take about %.0f %s on %d threads (from a pilot of %d "
            "pixels): a smaller --width, --height or --spp first, or a chapter with an acceleration structure "
            "(06, 09, 13) for a large mesh\n", label, minutes ? estimate / 60.0 : estimate,
            minutes ? "minutes" : "seconds", threads, PILOT_PIXELS);
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
    if (opts->explain)
        return program_explain(opts, label, &job, stats_out);
    if (!opts->quiet)
        program_warn_if_long(opts, label, program_pilot_seconds(&job));
    image img = image_make(cam->width, cam->height);
    if (img.rgb == NULL) {
        fprintf(stderr, "%s: out of memory for a %dx%d image\n", label, cam->width, cam->height);
        return 1;
    }
    render_stats stats;
    render_image(&job, &img, &stats);

    char err[IMAGE_ERROR_SIZE];
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
    if (!opts->quiet) {
        printf("%s: %dx%d, %d spp, %d threads, %.3f s -> %s\n", label, cam->width, cam->height, opts->spp,
               opts->threads, stats.seconds, opts->out);
        counters_print(stdout, &stats.counters, stats.seconds);
        if (noted_accel[0] != '\0')
            printf("rays traced through: %s\n", noted_accel);
        printf("counters -> %s\n", counters_path);
    }
    if (stats_out != NULL)
        *stats_out = stats;
    return 0;
}

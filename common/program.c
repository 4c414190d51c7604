#include "program.h"

#include <stdio.h>

int program_render(const cli_options *opts, const char *label, radiance_fn radiance, const void *scene,
                   const camera *cam, render_stats *stats_out)
{
    image img = image_make(cam->width, cam->height);
    if (img.rgb == NULL) {
        fprintf(stderr, "%s: out of memory for a %dx%d image\n", label, cam->width, cam->height);
        return 1;
    }
    render_job job = {.cam = cam,
                      .spp = opts->spp,
                      .seed = opts->seed,
                      .threads = opts->threads,
                      .quiet = opts->quiet,
                      .label = label,
                      .radiance = radiance,
                      .scene = scene,
                      .jitter = opts->jitter};
    render_stats stats;
    render_image(&job, &img, &stats);

    char err[IMAGE_ERROR_SIZE];
    bool ok = image_write(&img, opts->out, opts->exposure, err, sizeof err);
    image_free(&img);
    if (!ok) {
        fprintf(stderr, "%s: %s\n", label, err);
        return 1;
    }
    if (!opts->quiet) {
        printf("%s: %dx%d, %d spp, %d threads, %.3f s -> %s\n", label, cam->width, cam->height, opts->spp,
               opts->threads, stats.seconds, opts->out);
        counters_print(stdout, &stats.counters, stats.seconds);
    }
    if (stats_out != NULL)
        *stats_out = stats;
    return 0;
}

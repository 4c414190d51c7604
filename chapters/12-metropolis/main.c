/* 12-metropolis: Metropolis light transport in primary sample space
 * (Kelemen et al. 2002) on chapter 09's path tracer, and its equal-time
 * comparison with path tracing. */
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/path_tracer.h"
#include "12-metropolis/mlt.h"
#include "12-metropolis/mlt_experiments.h"
#include "12-metropolis/mlt_scene.h"
#include "cli.h"
#include "program.h"

static bool build_scene(pt_scene *sc, const char *name)
{
    if (strcmp(name, "cornell") == 0)
        pt_scene_build_cornell_box(sc);
    else if (strcmp(name, "materials") == 0)
        pt_scene_build_cornell_box_materials(sc);
    else if (strcmp(name, "lamp") == 0)
        mlt_scene_build_lamp(sc);
    else
        return false;
    return true;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch12.exr", 256, 256, 64);
    const char *scene_name = "lamp", *start = "bootstrap", *data = NULL;
    float p_large = 0.3f;
    int bootstrap = 100000, chains = 256, max_depth = 64;
    bool path_trace = false;
    const cli_flag extras[] = {
        {"--p-large", CLI_FLOAT, &p_large, "P", "probability of a large step (all new numbers; default 0.3)", 0.0, 1.0},
        {"--bootstrap", CLI_INT, &bootstrap, "N", "paths that estimate the normalization b (default 100000)", 1,
         1 << 30},
        {"--chains", CLI_INT, &chains, "N", "Markov chains, run in parallel (default 256)", 1, 1 << 20},
        {"--start", CLI_STRING, &start, "HOW",
         "bootstrap (default: chains start at bootstrap paths picked in proportion to f) or fixed (all at the "
         "first path with f > 0: start-up bias)", 0, 0},
        {"--builtin", CLI_STRING, &scene_name, "NAME",
         "lamp (default: the ceiling light shut in a housing; light leaves only down a 2 cm channel), cornell, materials", 0, 0},
        {"--path-trace", CLI_BOOL, &path_trace, NULL,
         "render the same scene with chapter 09's path tracer instead (--spp samples per pixel), to compare", 0, 0},
        {"--max-depth", CLI_INT, &max_depth, "N", "bounces counted at most (default 64)", 0, 1000},
        {"--data", CLI_DIR, &data, "DIR",
         "run the experiments (equal-time error of MLT and path tracing; start-up bias; which method for which "
         "scene: path tracing, BDPT and MLT on three scenes) and write CSV into DIR", 0,
         0},
    };
    cli_spec spec = {"12-metropolis",
                     "Metropolis light transport (Kelemen et al. 2002; GAMES101 lecture 16's closing slides):\n"
                     "a Markov chain over the path tracer's uniform numbers whose stationary density is the\n"
                     "path's luminance f over b = E[f]. --spp is mutations per pixel; b is estimated from\n"
                     "--bootstrap paths. Uses chapter 09's path tracer (MIS, Russian roulette on throughput).\n"
                     "--data DIR measures error against time against chapter 09's path tracer and chapter 11's BDPT.",
                     extras, sizeof extras / sizeof extras[0]};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    mlt_start start_mode;
    if (strcmp(start, "bootstrap") == 0)
        start_mode = MLT_START_BOOTSTRAP;
    else if (strcmp(start, "fixed") == 0)
        start_mode = MLT_START_FIXED;
    else {
        fprintf(stderr, "12-metropolis: --start: unknown '%s' (bootstrap, fixed)\ntry --help\n", start);
        return 2;
    }
    if (opts.explain) {
        fprintf(stderr, "12-metropolis: --explain is not supported (a chain has no per-pixel paths; try "
                        "09-path-tracing --explain)\ntry --help\n");
        return 2;
    }
    pt_scene sc;
    scene_desc desc;
    char err[1024];
    if (program_load_scene(&opts, "12-metropolis", &desc)) {
        if (data != NULL) {
            fprintf(stderr, "12-metropolis: --scene does not combine with --data\n");
            scene_desc_free(&desc);
            return 2;
        }
        bool ok = pt_scene_from_desc(&sc, &desc, "12-metropolis", err, sizeof err);
        scene_desc_free(&desc);
        if (!ok) {
            fprintf(stderr, "12-metropolis: %s\n", err);
            return 1;
        }
    } else if (!build_scene(&sc, scene_name)) {
        fprintf(stderr, "12-metropolis: --builtin: unknown scene '%s' (lamp, cornell, materials)\ntry --help\n",
                scene_name);
        return 2;
    }
    pt_scene_check_scale(&sc, "12-metropolis", stderr);
    path_tracer pt = path_tracer_defaults(&sc);
    pt.integrator = PT_MIS;
    pt.russian_roulette = RR_THROUGHPUT;
    pt.max_depth = max_depth;

    int status = 0;
    if (data != NULL) {
        pt_scene_free(&sc);
        if (!mlt_experiments_run(data, opts.threads, err, sizeof err)) {
            fprintf(stderr, "12-metropolis: %s\n", err);
            return 1;
        }
        return 0;
    }
    camera cam = pt_scene_camera(&sc, opts.width, opts.height);
    if (path_trace) {
        opts.jitter = true; /* Monte Carlo over the pixel area, even at 1 spp */
        status = program_render(&opts, spec.program, path_trace_radiance, &pt, &cam, NULL);
        pt_scene_free(&sc);
        return status;
    }
    mlt_options o = mlt_defaults(&pt, &cam);
    o.mutations_per_pixel = opts.spp;
    o.p_large = p_large;
    o.bootstrap = bootstrap;
    o.chains = chains;
    o.seed = opts.seed;
    o.threads = opts.threads;
    o.start = start_mode;
    o.quiet = opts.quiet;
    image img = image_make(cam.width, cam.height);
    mlt_result r;
    if (!mlt_render(&o, &img, &r)) {
        fprintf(stderr, "12-metropolis: out of memory\n");
        status = 1;
    } else if (!image_write(&img, opts.out, opts.exposure, err, sizeof err)) {
        fprintf(stderr, "12-metropolis: %s\n", err);
        status = 1;
    } else {
        double acceptance = r.proposed > 0 ? (double)r.accepted / (double)r.proposed : 0.0;
        if (!opts.quiet) {
            printf("12-metropolis: %s, %d mutations per pixel, %d chains, p_large %.2f: %.2f s (bootstrap %.2f s) "
                   "-> %s\n", opts.scene != NULL ? opts.scene : scene_name, opts.spp, chains, (double)p_large, r.seconds, r.bootstrap_seconds, opts.out);
            printf("b = %.5g +- %.2g (%d bootstrap paths), acceptance %.3f\n", r.b, r.b_standard_error, bootstrap,
                   acceptance);
            counters_print(stdout, &r.counters, r.seconds);
        }
        char counters_path[4096], extra[256];
        counters_path_for_image(opts.out, counters_path, sizeof counters_path);
        snprintf(extra, sizeof extra, "\"b\": %.9g, \"b_standard_error\": %.9g, \"acceptance\": %.6f", r.b,
                 r.b_standard_error, acceptance);
        if (!counters_write_json(counters_path, &r.counters, r.seconds, extra, err, sizeof err)) {
            fprintf(stderr, "12-metropolis: %s\n", err);
            status = 1;
        }
    }
    image_free(&img);
    pt_scene_free(&sc);
    return status;
}

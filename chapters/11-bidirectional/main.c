/* 11-bidirectional: bidirectional path tracing with multiple importance
 * sampling over every strategy (Veach 1997, ch. 10), the picture of one
 * strategy at a time, and the equal-time comparison with chapter 09. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "11-bidirectional/bdpt_experiments.h"
#include "cli.h"
#include "program.h"

static bool build_scene(pt_scene *sc, const char *name, char *err, size_t err_size)
{
    if (strcmp(name, "cornell") == 0)
        pt_scene_build_cornell_box(sc);
    else if (strcmp(name, "ceiling-lamp") == 0)
        bdpt_scene_build_ceiling_lamp(sc);
    else if (strcmp(name, "veach") == 0)
        pt_scene_build_veach(sc);
    else {
        snprintf(err, err_size, "--builtin: unknown scene '%s' (cornell, ceiling-lamp, veach)", name);
        return false;
    }
    return true;
}

/* "S,T" with each a number or '*' (any). */
static bool parse_strategy(const char *text, int *s, int *t)
{
    const char *comma = strchr(text, ',');
    if (comma == NULL)
        return false;
    int values[2];
    const char *parts[2] = {text, comma + 1};
    for (int k = 0; k < 2; k++) {
        if (parts[k][0] == '*' && (parts[k][1] == '\0' || parts[k][1] == ',')) {
            values[k] = -1;
            continue;
        }
        char *end;
        long value = strtol(parts[k], &end, 10);
        if (end == parts[k] || (k == 0 ? *end != ',' : *end != '\0') || value < 0 || value > BDPT_MAX_VERTICES)
            return false;
        values[k] = (int)value;
    }
    *s = values[0];
    *t = values[1];
    return true;
}

static int run_experiments(const char *data, int size, int reference_spp, double seconds, int threads)
{
    const char *names[2] = {"cornell", "ceiling-lamp"};
    char err[1024];
    for (int k = 0; k < 2; k++) {
        pt_scene sc;
        build_scene(&sc, names[k], err, sizeof err);
        camera cam = pt_scene_camera(&sc, size, size);
        char reference_path[4096];
        snprintf(reference_path, sizeof reference_path, "%s/ch11_reference_%s_%d.exr", data, names[k], size);
        path_tracer pt = path_tracer_defaults(&sc);
        estimate_image reference;
        memset(&reference, 0, sizeof reference);
        bdpt_experiment_result result;
        printf("\n== scene %s\n", names[k]);
        bool ok = experiment_reference(&pt, &cam, reference_spp, threads, reference_path, &reference, err, sizeof err);
        if (ok)
            ok = bdpt_experiment_equal_time(&sc, names[k], &cam, &reference, seconds, threads, data, &result, err,
                                            sizeof err);
        /* filled even when writing it failed */
        estimate_image_free(&reference);
        pt_scene_free(&sc);
        if (!ok) {
            fprintf(stderr, "11-bidirectional: %s\n", err);
            return 1;
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch11.exr", 256, 256, 16);
    const char *scene_name = "cornell", *strategy = NULL, *heuristic = "power", *data = NULL, *integrator = "bdpt";
    bool unweighted = false;
    int max_depth = -1, experiment_size = 32, reference_spp = 32768;
    float experiment_seconds = 8.0f;
    const cli_flag extras[] = {
        {"--max-depth", CLI_INT, &max_depth, "N", "bounces counted at most (default 64)", 0, BDPT_MAX_DEPTH},
        {"--builtin", CLI_STRING, &scene_name, "NAME",
         "cornell (default), ceiling-lamp (a lamp shining at the ceiling: where BDPT wins), veach", 0, 0},
        {"--strategy", CLI_STRING, &strategy, "S,T",
         "only strategy (s, t): s light vertices, t camera vertices ('*' for any), MIS-weighted unless "
         "--unweighted", 0, 0},
        {"--unweighted", CLI_BOOL, &unweighted, NULL, "with --strategy: each strategy's full estimate, no MIS weight",
         0, 0},
        {"--integrator", CLI_STRING, &integrator, "NAME",
         "bdpt (default), or pt: chapter 09's path tracer (MIS, RR on throughput) on the same scene, for "
         "equal-time pictures", 0, 0},
        {"--heuristic", CLI_STRING, &heuristic, "NAME", "MIS weights: power (default) or balance", 0, 0},
        {"--data", CLI_DIR, &data, "DIR",
         "equal-time error against chapter 09's path tracer (Cornell box and ceiling-lamp), CSV into DIR", 0, 0},
        {"--experiment-size", CLI_INT, &experiment_size, "N", "image side of the experiments (default 32)", 8, 1024},
        {"--reference-spp", CLI_INT, &reference_spp, "N", "samples of the cached references (default 32768)", 16,
         1 << 20},
        {"--experiment-seconds", CLI_FLOAT, &experiment_seconds, "S",
         "CPU seconds each method gets per scene (default 8)", 0.1, 1e5},
    };
    cli_spec spec = {"11-bidirectional",
                     "Bidirectional path tracing (Veach 1997, ch. 10): a path from the eye and one from the light,\n"
                     "joined in every way (s light vertices, t camera vertices), each join weighted by multiple\n"
                     "importance sampling. --strategy S,T renders one strategy; --data DIR measures error against\n"
                     "CPU time beside chapter 09's path tracer. Diffuse and glossy surfaces, emitting triangles.",
                     extras, sizeof extras / sizeof extras[0]};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if (data != NULL)
        return run_experiments(data, experiment_size, reference_spp, experiment_seconds, opts.threads);
    if (opts.explain) {
        fprintf(stderr, "11-bidirectional: --explain is not supported (a pixel's light arrives from other pixels' "
                        "light paths too)\n");
        return 2;
    }

    bdpt_heuristic chosen_heuristic;
    if (strcmp(heuristic, "power") == 0)
        chosen_heuristic = BDPT_POWER;
    else if (strcmp(heuristic, "balance") == 0)
        chosen_heuristic = BDPT_BALANCE;
    else {
        fprintf(stderr, "11-bidirectional: --heuristic: unknown '%s' (power, balance)\n", heuristic);
        return 2;
    }
    bool path_trace = strcmp(integrator, "pt") == 0;
    if (!path_trace && strcmp(integrator, "bdpt") != 0) {
        fprintf(stderr, "11-bidirectional: --integrator: unknown '%s' (bdpt, pt)\n", integrator);
        return 2;
    }
    if (path_trace && strategy != NULL) {
        fprintf(stderr, "11-bidirectional: --strategy: only with --integrator bdpt\n");
        return 2;
    }
    int only_s = -1, only_t = -1;
    if (strategy != NULL && !parse_strategy(strategy, &only_s, &only_t)) {
        fprintf(stderr, "11-bidirectional: --strategy: '%s' is not S,T (numbers or '*')\n", strategy);
        return 2;
    }
    if (unweighted && strategy == NULL) {
        fprintf(stderr, "11-bidirectional: --unweighted: only with --strategy\n");
        return 2;
    }

    char err[1024];
    pt_scene sc;
    scene_desc desc;
    int max_depth_file = -1;
    if (program_load_scene(&opts, spec.program, &desc)) {
        max_depth_file = desc.max_depth;
        bool ok = pt_scene_from_desc(&sc, &desc, spec.program, err, sizeof err);
        scene_desc_free(&desc);
        if (!ok) {
            fprintf(stderr, "11-bidirectional: %s\n", err);
            return 1;
        }
    } else if (!build_scene(&sc, scene_name, err, sizeof err)) {
        fprintf(stderr, "11-bidirectional: %s\n", err);
        return 2;
    }
    if (!bdpt_supports(&sc, err, sizeof err)) {
        fprintf(stderr, "11-bidirectional: %s\n", err);
        pt_scene_free(&sc);
        return 1;
    }
    pt_scene_check_scale(&sc, spec.program, stderr);
    if (max_depth < 0)
        max_depth = max_depth_file >= 0 && max_depth_file <= BDPT_MAX_DEPTH ? max_depth_file : BDPT_MAX_DEPTH;

    camera cam = pt_scene_camera(&sc, opts.width, opts.height);
    bdpt b = bdpt_defaults(&sc, &cam);
    b.max_depth = max_depth;
    b.heuristic = chosen_heuristic;
    b.only_s = only_s;
    b.only_t = only_t;
    b.unweighted = unweighted;
    estimate_image e;
    int status = 0;
    if (path_trace) {
        path_tracer pt = path_tracer_defaults(&sc);
        pt.integrator = PT_MIS;
        pt.russian_roulette = RR_THROUGHPUT;
        pt.max_depth = max_depth;
        e = render_estimate(&pt, &cam, opts.spp, opts.seed, opts.threads);
    } else if (!bdpt_render(&b, opts.spp, opts.seed, opts.threads, opts.quiet, &e)) {
        fprintf(stderr, "11-bidirectional: out of memory\n");
        pt_scene_free(&sc);
        return 1;
    }
    if (!image_write(&e.mean, opts.out, opts.exposure, err, sizeof err)) {
        fprintf(stderr, "11-bidirectional: %s\n", err);
        status = 1;
    }
    char counters_path[4096];
    counters_path_for_image(opts.out, counters_path, sizeof counters_path);
    if (status == 0 && !counters_write_json(counters_path, &e.counters, e.seconds, NULL, err, sizeof err)) {
        fprintf(stderr, "11-bidirectional: %s\n", err);
        status = 1;
    }
    if (status == 0 && !opts.quiet) {
        printf("11-bidirectional: %s, %dx%d, %d spp, %.2f s -> %s\n", path_trace ? "path tracing" : "bidirectional",
               opts.width, opts.height, opts.spp, e.seconds, opts.out);
        counters_print(stdout, &e.counters, e.seconds);
    }
    estimate_image_free(&e);
    pt_scene_free(&sc);
    return status;
}

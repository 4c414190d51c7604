/* 11-bidirectional: bidirectional path tracing with multiple importance
 * sampling over every strategy (Veach 1997, ch. 10), the picture of one
 * strategy at a time, and the equal-time comparison with chapter 09. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "11-bidirectional/bdpt_experiments.h"
#include "cli.h"
#include "counters_file.h"
#include "image_file.h"
#include "program.h"
#include "mpi_split.h"

/* The built-in scenes (--builtin), each with the line --help shows. */
static const pt_builtin_scene BUILTINS[] = {
    {"cornell", pt_scene_build_cornell_box, "the Cornell box (default)"},
    {"ceiling-lamp", bdpt_scene_build_ceiling_lamp, "a lamp shining at the ceiling: where BDPT wins"},
    {"veach", pt_scene_build_veach, "four glossy plates under four lights of growing size (chapter 09's)"},
};
enum { BUILTIN_COUNT = sizeof BUILTINS / sizeof BUILTINS[0] };

/* The --builtin choice, its names and notes taken from the table. */
static const char *builtin_names[BUILTIN_COUNT + 1], *builtin_notes[BUILTIN_COUNT];

static const char *const INTEGRATOR_NAMES[] = {"bdpt", "pt", NULL};
enum { INTEGRATOR_BDPT, INTEGRATOR_PT };
/* In bdpt_heuristic's order. */
static const char *const HEURISTIC_NAMES[] = {"power", "balance", NULL};

/* The program's own flags. */
typedef struct {
    cli_choice builtin, integrator, heuristic;
    const char *strategy, *data;
    bool unweighted;
    int max_depth; /* -1: the scene file's, else BDPT_MAX_DEPTH */
    int experiment_size, reference_spp;
    float experiment_seconds;
} bdpt_flags;

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

/* --data: equal-time error against chapter 09's path tracer, on the Cornell
 * box and the ceiling lamp. */
static int run_experiments(const bdpt_flags *f, int threads, const char *program)
{
    const pt_builtin_scene *measured[2] = {&BUILTINS[0], &BUILTINS[1]};
    char err[1024];
    for (int k = 0; k < 2; k++) {
        pt_scene sc;
        measured[k]->build(&sc);
        camera cam = pt_scene_camera(&sc, f->experiment_size, f->experiment_size);
        char reference_path[4096];
        snprintf(reference_path, sizeof reference_path, "%s/ch11_reference_%s_%d.exr", f->data, measured[k]->name,
                 f->experiment_size);
        path_tracer pt = path_tracer_defaults(&sc);
        estimate_image reference;
        memset(&reference, 0, sizeof reference);
        bdpt_experiment_result result;
        printf("\n== scene %s\n", measured[k]->name);
        bool ok = experiment_reference(&pt, &cam, f->reference_spp, threads, reference_path, &reference, err,
                                       sizeof err) &&
                  bdpt_experiment_equal_time(&sc, measured[k]->name, &cam, &reference, f->experiment_seconds, threads,
                                             f->data, &result, err, sizeof err);
        /* filled even when writing it failed */
        estimate_image_free(&reference);
        pt_scene_free(&sc);
        if (!ok) {
            fprintf(stderr, "%s: %s\n", program, err);
            return 1;
        }
    }
    return 0;
}

/* What the flags cannot combine into; the strategy as (s, t). Returns 0,
 * or 2 after printing why. */
static int check_flags(const cli_options *opts, const bdpt_flags *f, int *only_s, int *only_t, const char *program)
{
    const char *why = NULL;
    if (opts->explain)
        why = "--explain is not supported (a pixel's light arrives from other pixels' light paths too)";
    else if (f->integrator.index == INTEGRATOR_PT && f->strategy != NULL)
        why = "--strategy: only with --integrator bdpt";
    else if (f->unweighted && f->strategy == NULL)
        why = "--unweighted: only with --strategy";
    if (why != NULL) {
        fprintf(stderr, "%s: %s\n", program, why);
        return 2;
    }
    *only_s = *only_t = -1;
    if (f->strategy != NULL && !parse_strategy(f->strategy, only_s, only_t)) {
        fprintf(stderr, "%s: --strategy: '%s' is not S,T (numbers or '*')\n", program, f->strategy);
        return 2;
    }
    return 0;
}

/* --scene FILE or the built-in scene; *max_depth becomes the file's (if
 * --max-depth was not given and the file's is in range) or the default.
 * Returns 0, or 1 after printing why. */
static int load_scene(pt_scene *sc, cli_options *opts, const char *program, const bdpt_flags *f, int *max_depth)
{
    char err[1024];
    scene_desc desc;
    int max_depth_file = -1;
    if (program_load_scene(opts, program, &desc)) {
        max_depth_file = desc.max_depth;
        bool ok = pt_scene_from_desc(sc, &desc, program, err, sizeof err);
        scene_desc_free(&desc);
        if (!ok) {
            fprintf(stderr, "%s: %s\n", program, err);
            return 1;
        }
    } else {
        BUILTINS[f->builtin.index].build(sc);
    }
    if (!bdpt_supports(sc, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        pt_scene_free(sc);
        return 1;
    }
    *max_depth = f->max_depth;
    if (*max_depth < 0)
        *max_depth = max_depth_file >= 0 && max_depth_file <= BDPT_MAX_DEPTH ? max_depth_file : BDPT_MAX_DEPTH;
    return 0;
}

/* The image and its counters file; the report. Returns the exit status. */
static int write_render(const cli_options *opts, const char *program, const estimate_image *e, bool path_trace)
{
    char err[1024], counters_path[4096];
    if (!image_write(&e->mean, opts->out, opts->exposure, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        return 1;
    }
    counters_path_for_image(opts->out, counters_path, sizeof counters_path);
    if (!counters_write_json(counters_path, &e->counters, e->seconds, NULL, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        return 1;
    }
    if (!opts->quiet) {
        printf("%s: %s, %dx%d, %d spp, %.2f s -> %s\n", program, path_trace ? "path tracing" : "bidirectional",
               opts->width, opts->height, opts->spp, e->seconds, opts->out);
        counters_print(stdout, &e->counters, e->seconds);
    }
    return 0;
}

/* The picture: bidirectional (all strategies, or the one of --strategy),
 * or chapter 09's path tracer on the same scene. */
static int render(const cli_options *opts, const char *program, const pt_scene *sc, const bdpt_flags *f,
                  int max_depth, int only_s, int only_t)
{
    camera cam = pt_scene_camera(sc, opts->width, opts->height);
    bool path_trace = f->integrator.index == INTEGRATOR_PT;
    estimate_image e;
    if (path_trace) {
        path_tracer pt = path_tracer_defaults(sc);
        pt.integrator = PT_MIS;
        pt.russian_roulette = RR_THROUGHPUT;
        pt.max_depth = max_depth;
        render_job pilot = {.cam = &cam, .spp = opts->spp, .seed = opts->seed, .radiance = path_trace_radiance,
                            .scene = &pt, .sample = path_tracer_sample_fn(&pt), .jitter = true};
        if (!opts->quiet)
            program_warn_if_long(opts, program, program_pilot_seconds(&pilot));
        e = render_estimate(&pt, &cam, opts->spp, opts->seed, opts->threads);
    } else {
        bdpt b = bdpt_defaults(sc, &cam);
        b.max_depth = max_depth;
        b.heuristic = (bdpt_heuristic)f->heuristic.index;
        b.only_s = only_s;
        b.only_t = only_t;
        b.unweighted = f->unweighted;
        if (!opts->quiet)
            program_warn_if_long(opts, program, bdpt_pilot_seconds(&b, opts->spp, opts->seed));
        if (!bdpt_render(&b, opts->spp, opts->seed, opts->threads, opts->quiet, &e)) {
            fprintf(stderr, "%s: out of memory\n", program);
            return 1;
        }
    }
    int status = write_render(opts, program, &e, path_trace);
    estimate_image_free(&e);
    return status;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch11.exr", 256, 256, 16);
    bdpt_flags f = {pt_builtin_scene_choice(BUILTINS, BUILTIN_COUNT, builtin_names, builtin_notes), {INTEGRATOR_NAMES, NULL, INTEGRATOR_BDPT}, {HEURISTIC_NAMES, NULL, BDPT_POWER},
                    NULL, NULL, false, -1, 32, 32768, 8.0f};
    const cli_flag extras[] = {
        {"--max-depth", CLI_INT, &f.max_depth, "N", "bounces counted at most (default 64)", 0, BDPT_MAX_DEPTH},
        {"--builtin", CLI_CHOICE, &f.builtin, "NAME", "the built-in scene, when there is no --scene:", 0, 0},
        {"--strategy", CLI_STRING, &f.strategy, "S,T",
         "only strategy (s, t): s light vertices, t camera vertices ('*' for any), MIS-weighted unless "
         "--unweighted", 0, 0},
        {"--unweighted", CLI_BOOL, &f.unweighted, NULL,
         "with --strategy: each strategy's full estimate, no MIS weight", 0, 0},
        {"--integrator", CLI_CHOICE, &f.integrator, NULL,
         "bdpt (default), or pt: chapter 09's path tracer (MIS, RR on throughput) on the same scene, for "
         "equal-time pictures", 0, 0},
        {"--heuristic", CLI_CHOICE, &f.heuristic, NULL, "MIS weights: power (default) or balance", 0, 0},
        {"--data", CLI_DIR, &f.data, "DIR",
         "equal-time error against chapter 09's path tracer (Cornell box and ceiling-lamp), CSV into DIR", 0, 0},
        {"--experiment-size", CLI_INT, &f.experiment_size, "N", "image side of the experiments (default 32)", 8,
         1024},
        {"--reference-spp", CLI_INT, &f.reference_spp, "N", "samples of the cached references (default 32768)", 16,
         1 << 20},
        {"--experiment-seconds", CLI_FLOAT, &f.experiment_seconds, "S",
         "CPU seconds each method gets per scene (default 8)", 0.1, 1e5},
    };
    cli_spec spec = {"11-bidirectional",
                     "Bidirectional path tracing (Veach 1997, ch. 10): a path from the eye and one from the light,\n"
                     "joined in every way (s light vertices, t camera vertices), each join weighted by multiple\n"
                     "importance sampling. --strategy S,T renders one strategy; --data DIR measures error against\n"
                     "CPU time beside chapter 09's path tracer. Diffuse and glossy surfaces, emitting triangles.",
                     extras, sizeof extras / sizeof extras[0], NULL};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if (mpi_split_refuse(spec.program, "bidirectional path tracing (its light paths land on any pixel)"))
        return 2;
    if (f.data != NULL)
        return run_experiments(&f, opts.threads, spec.program);
    int only_s, only_t, max_depth;
    int status = check_flags(&opts, &f, &only_s, &only_t, spec.program);
    pt_scene sc;
    if (status == 0)
        status = load_scene(&sc, &opts, spec.program, &f, &max_depth);
    if (status != 0)
        return status;
    pt_scene_check_scale(&sc, spec.program, stderr);
    pt_scene_check_lights(&sc, spec.program, stderr);
    status = render(&opts, spec.program, &sc, &f, max_depth, only_s, only_t);
    pt_scene_free(&sc);
    return status;
}

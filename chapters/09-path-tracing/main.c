/* 09-path-tracing: the Cornell box by path tracing (lecture 16), each rung of
 * the integrator ladder selectable, traced through any structure of chapters
 * 03-06, and the measurements of what accuracy costs in time. */
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/experiments.h"
#include "09-path-tracing/path_tracer.h"
#include "cli.h"
#include "counters_file.h"
#include "effects.h"
#include "image_file.h"
#include "mpi_split.h"
#include "program.h"
#include "run_record.h"

#define PROGRAM "09-path-tracing"

/* The chapter's own flags. */
typedef struct {
    cli_choice integrator, rr, builtin, accel, sampler;
    const char *obj, *data;
    float rr_probability, time_budget, target_error;
    int max_depth, rr_start, experiment_size, reference_spp, experiment_spp;
    camera_override view; /* --eye, --target, --fov */
} chapter_flags;

/* The scene the flags name (a scene file, an OBJ file or a built-in one),
 * its effects decided and noted, on the structure --accel asks for, and
 * the path tracer the flags and the scene file describe. 0, or the exit
 * status after a message. */
static int load(cli_options *opts, const chapter_flags *f, pt_scene *sc, path_tracer *pt)
{
    char err[SCENE_PATH_SIZE + 1024];
    scene_desc desc;
    bool from_file = program_load_scene(opts, PROGRAM, &desc);
    if (opts->quiet)
        pt_scene_report_materials(NULL);
    pt_integrator integrator = f->integrator.index < 0 ? PT_LECTURE : (pt_integrator)f->integrator.index;
    int status = 0;
    if (from_file && (f->obj != NULL || f->data != NULL)) {
        snprintf(err, sizeof err, "--scene does not combine with --obj or --data");
        status = 2;
    } else if (f->data != NULL && opts->resume != NULL) {
        snprintf(err, sizeof err, "--resume continues a render, not --data (whose references resume by themselves)");
        status = 2;
    } else if (f->integrator.index < 0 && from_file && desc.integrator[0] != '\0' &&
               !pt_integrator_parse(desc.integrator, &integrator)) {
        snprintf(err, sizeof err, "%s:%d:%d: unknown integrator '%s' (lecture, cosine, mis)", desc.source,
                 desc.integrator_line, desc.integrator_column, desc.integrator);
        status = 1;
    } else if (from_file ? !pt_scene_from_desc(sc, &desc, PROGRAM, err, sizeof err)
                         : f->obj != NULL && !pt_scene_load_obj(sc, f->obj, err, sizeof err)) {
        status = 1;
    }
    if (status != 0) {
        fprintf(stderr, PROGRAM ": %s\n", err);
        scene_desc_free(&desc);
        return status;
    }
    if (!from_file && f->obj == NULL)
        pt_scene_build_builtin(sc, cli_choice_name(&f->builtin));
    camera_override_apply(&f->view, &sc->eye, &sc->target, &sc->vertical_fov_degrees);
    if (pt_scene_has_no_light(sc, err, sizeof err))
        fprintf(stderr, PROGRAM ": warning: %s\n", err);
    if (!from_file)
        pt_scene_describe(sc, &desc);
    /* The path tracer can simulate every effect; it simulates those the
     * scene (file or built-in) calls for and allows. The experiments (--data)
     * measure the integrators themselves, so they keep every effect on. */
    effects_report e = effects_analyse(&desc);
    if (!opts->quiet && f->data == NULL)
        effects_print(stdout, &e, PROGRAM);
    program_note_effects(&e);
    if (f->accel.index != 0) /* the default, chapter 06's BVH, is built already */
        pt_scene_use_accel(sc, pt_accel_builder_named(cli_choice_name(&f->accel)), NULL);
    program_note_accel(sc->bvh->stats.name);
    pt_scene_check_scale(sc, PROGRAM, stderr);
    pt_scene_check_lights(sc, PROGRAM, stderr);
    *pt = path_tracer_defaults(sc);
    pt->effects = f->data != NULL ? EFFECT_ALL : effects_decide(&e, EFFECT_ALL);
    pt->integrator = integrator;
    pt->russian_roulette = (pt_russian_roulette)f->rr.index;
    pt->sampler = (pt_sampler)f->sampler.index;
    pt->rr_probability = f->rr_probability;
    pt->rr_start_depth = f->rr_start;
    pt->max_depth = f->max_depth >= 0 ? f->max_depth : from_file && desc.max_depth >= 0 ? desc.max_depth : 64;
    char depth[32];
    snprintf(depth, sizeof depth, "%d", pt->max_depth);
    run_record_note("integrator", pt_integrator_name(pt->integrator));
    run_record_note("russian_roulette", pt_russian_roulette_name(pt->russian_roulette));
    run_record_note("max_depth", depth);
    scene_desc_free(&desc);
    return 0;
}

/* --data: on the chosen scene a cached reference, then every rung at
 * doubling sample counts, then (on the first scene) the Russian roulette
 * sweep. The Cornell box, all diffuse, is where MIS gains least; by
 * default the Veach scene, where it gains most, is measured after it.
 * Under mpirun every rank renders the references with the others; then
 * rank 0 alone measures (the other ranks stop: a measurement of time
 * wants the machine to itself). */
static int run_experiments(const cli_options *opts, const chapter_flags *f, const path_tracer *pt)
{
    const char *first = f->obj != NULL ? "obj" : cli_choice_name(&f->builtin);
    const char *names[2] = {first, "veach"};
    int scene_count = strcmp(first, "cornell") == 0 ? 2 : 1;
    char err[1024] = "";
    bool ok = true;
    pt_scene other;
    path_tracer experiment_pt[2] = {*pt, *pt};
    if (scene_count > 1) {
        pt_scene_build_builtin(&other, names[1]);
        experiment_pt[1].scene = &other;
    }
    camera cams[2];
    estimate_image references[2];
    memset(references, 0, sizeof references);
    int made = 0;
    for (int k = 0; k < scene_count && ok; k++, made++) {
        cams[k] = pt_scene_camera(experiment_pt[k].scene, f->experiment_size, f->experiment_size);
        char reference_path[4096];
        snprintf(reference_path, sizeof reference_path, "%s/ch09_reference_%s_%d.exr", f->data, names[k],
                 f->experiment_size);
        if (mpi_split_is_root())
            printf("\n== reference of scene %s\n", names[k]);
        ok = experiment_reference(&experiment_pt[k], &cams[k], f->reference_spp, opts->threads, reference_path,
                                  &references[k], err, sizeof err);
        ok = mpi_split_broadcast_int(ok); /* rank 0's saving may fail: all stop */
    }
    if (mpi_split_leave()) { /* rank 0 measures */
        for (int k = 0; k < scene_count && ok; k++) {
            const pt_scene *scene = experiment_pt[k].scene;
            printf("\n== scene %s\n", names[k]);
            ok = experiment_convergence(scene, names[k], &cams[k], &references[k], f->experiment_spp, opts->threads,
                                        f->data, err, sizeof err) &&
                 (k > 0 || experiment_russian_roulette(scene, &cams[k], &references[k], 64, opts->threads, f->data,
                                                       err, sizeof err));
        }
        if (!ok)
            fprintf(stderr, PROGRAM ": %s\n", err);
    }
    for (int k = 0; k < made; k++)
        estimate_image_free(&references[k]);
    if (scene_count > 1)
        pt_scene_free(&other);
    return ok ? 0 : 1;
}

/* --time-budget, --target-error: passes until either is reached, with
 * checkpoints of the passes so far (--resume continues them). */
static int render_progressively(const cli_options *opts, const chapter_flags *f, const path_tracer *pt)
{
    if (opts->explain) {
        fprintf(stderr, PROGRAM ": --explain explains one pixel of a plain render, not a progressive one\n");
        return 2;
    }
    char err[1024], counters_path[4096];
    camera cam = pt_scene_camera(pt->scene, opts->width, opts->height);
    checkpointing cp;
    checkpoint resumed;
    size_t state_bytes = 2 * (size_t)cam.width * (size_t)cam.height * 3 * sizeof(float);
    if (!program_checkpointing(opts, PROGRAM, "progressive", state_bytes, &cp, &resumed))
        return 1;
    render_job pilot = {.cam = &cam, .seed = opts->seed, .radiance = path_trace_radiance,
                        .sample = path_tracer_sample_fn(pt), .scene = pt, .jitter = true, .threads = opts->threads};
    if (mpi_split_is_root())
        program_warn_if_long_progressive(opts, PROGRAM, &pilot, f->time_budget, f->target_error,
                                         cp.resume != NULL ? cp.resume->spp_done : 0);
    estimate_image e = progressive_render_resumable(path_trace_radiance, path_tracer_sample_fn(pt), pt, &cam,
                                                    opts->seed, opts->threads, f->time_budget, f->target_error,
                                                    opts->quiet ? NULL : stdout, &cp);
    checkpoint_free(&resumed);
    bool ok = true;
    if (mpi_split_is_root()) { /* rank 0 writes */
        program_warn_if_black(opts, PROGRAM, &e.mean);
        counters_path_for_image(opts->out, counters_path, sizeof counters_path);
        ok = image_write(&e.mean, opts->out, opts->exposure, err, sizeof err) &&
             counters_write_json(counters_path, &e.counters, e.seconds, NULL, err, sizeof err);
    }
    if (ok)
        program_checkpoint_done(opts, &cp);
    if (!ok) {
        fprintf(stderr, PROGRAM ": %s\n", err);
    } else if (!opts->quiet) {
        printf(PROGRAM ": %s, %ld spp in %.2f s, estimated relative error %.4f -> %s\n",
               pt_integrator_name(pt->integrator), e.spp, e.seconds, estimate_relative_error(&e), opts->out);
        counters_print(stdout, &e.counters, e.seconds);
    }
    estimate_image_free(&e);
    return ok ? 0 : 1;
}

/* One image, --spp samples per pixel (or the path tree of one pixel). */
static int render(const cli_options *opts, const path_tracer *pt)
{
    camera cam = pt_scene_camera(pt->scene, opts->width, opts->height);
    render_stats stats;
    int status =
        program_render_sampled(opts, PROGRAM, path_trace_radiance, path_tracer_sample_fn(pt), pt, &cam, &stats);
    if (status == 0 && !opts->quiet && !opts->explain)
        printf("%s: %.3f s per million camera samples (%d threads, %s Russian roulette, %s samples)\n",
               pt_integrator_name(pt->integrator),
               stats.seconds / ((double)opts->width * opts->height * opts->spp) * 1e6, opts->threads,
               pt_russian_roulette_name(pt->russian_roulette), PT_SAMPLER_NAMES[pt->sampler]);
    return status;
}

static const char *const SAMPLER_NOTES[] = {"independent numbers from each pixel's stream (default)",
                                            "sample i of a pixel is point i of an Owen-scrambled Sobol sequence",
                                            NULL};

static const char *const ACCEL_NOTES[] = {"chapter 06's BVH, binned SAH (default)", "chapter 05's kd-tree",
                                          "chapter 04's uniform grid", "chapter 03: every triangle", NULL};

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch09.exr", 512, 512, 16);
    /* --integrator and --max-depth not given (-1): the scene file's, else lecture and 64 */
    chapter_flags f = {{PT_INTEGRATOR_NAMES, NULL, -1}, {PT_ROULETTE_NAMES, NULL, RR_FIXED},
                       {PT_BUILTIN_SCENE_NAMES, PT_BUILTIN_SCENE_NOTES, 0}, {PT_ACCEL_NAMES, ACCEL_NOTES, 0},
                       {PT_SAMPLER_NAMES, SAMPLER_NOTES, PT_SAMPLER_RANDOM}, NULL, NULL, 0.8f, 0.0f, 0.0f, -1, 3, 96, 4096,
                       256, CAMERA_NOT_OVERRIDDEN};
    const cli_flag extras[] = {
        {"--integrator", CLI_CHOICE, &f.integrator, NULL, "the rung of the ladder (default lecture)", 0, 0},
        {"--rr", CLI_CHOICE, &f.rr, NULL, "Russian roulette: fixed P_RR (default), pbrt's on the throughput, "
                                          "smallpt's on the albedo, or none", 0, 0},
        {"--rr-probability", CLI_FLOAT, &f.rr_probability, "P", "P_RR for --rr fixed (default 0.8)", 0.01, 1.0},
        {"--rr-start", CLI_INT, &f.rr_start, "N", "--rr throughput or albedo: the first bounce the roulette may "
                                                  "end (default 3; pbrt-v3's is 5, smallpt's 6)", 0, 1000},
        {"--sampler", CLI_CHOICE, &f.sampler, NULL, "where a path's numbers come from (default random)", 0, 0},
        {"--max-depth", CLI_INT, &f.max_depth, "N", "bounces counted at most (default 64)", 0, 1000},
        {"--builtin", CLI_CHOICE, &f.builtin, NULL, "the built-in scene (default cornell)", 0, 0},
        {"--obj", CLI_STRING, &f.obj, "FILE", "render an OBJ file with its MTL materials instead", 0, 0},
        CLI_CAMERA_FLAGS(f.view),
        {"--accel", CLI_CHOICE, &f.accel, NULL, "the structure the rays are traced through", 0, 0},
        {"--time-budget", CLI_FLOAT, &f.time_budget, "SECONDS", "progressive: passes until this much time is spent",
         0.0, 1e6},
        {"--target-error", CLI_FLOAT, &f.target_error, "E",
         "progressive: passes until the estimated relative error is below E", 0.0, 10.0},
        {"--data", CLI_DIR, &f.data, "DIR", "run the experiments (error against time) and write CSV into DIR", 0, 0},
        {"--experiment-size", CLI_INT, &f.experiment_size, "N", "image side of the experiments (default 96)", 8, 1024},
        {"--reference-spp", CLI_INT, &f.reference_spp, "N", "samples of the cached reference (default 4096)", 16,
         1 << 20},
        {"--experiment-spp", CLI_INT, &f.experiment_spp, "N", "largest spp of the experiments (default 256)", 1,
         1 << 16},
        CLI_CHECKPOINT_FLAGS(opts),
    };
    cli_spec spec = {PROGRAM,
                     "Path tracing (GAMES101 lecture 16): the rendering equation by Monte Carlo, one sample per\n"
                     "bounce, direct light by sampling the light's area, Russian roulette. Renders the Cornell\n"
                     "box; --integrator climbs the ladder (lecture -> cosine -> mis), --sampler sobol draws\n"
                     "better samples; --accel picks the structure of chapters 03-06. --time-budget or\n"
                     "--target-error render progressively; --data DIR measures error against time. The built-in\n"
                     "Cornell box is chapters/09-path-tracing/scenes/cornell.scene. The same path tracer made\n"
                     "fast: chapter 13 (13-production).",
                     extras, sizeof extras / sizeof extras[0], "the path tree (every ray, hit, light sample and Russian roulette decision)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    opts.jitter = true; /* Monte Carlo over the pixel area, even at 1 spp */
    pt_scene sc;
    path_tracer pt;
    int status = load(&opts, &f, &sc, &pt);
    if (status != 0)
        return status;
    if (f.data != NULL)
        status = run_experiments(&opts, &f, &pt);
    else if (f.time_budget > 0.0f || f.target_error > 0.0f)
        status = render_progressively(&opts, &f, &pt);
    else
        status = render(&opts, &pt);
    pt_scene_free(&sc);
    return status;
}

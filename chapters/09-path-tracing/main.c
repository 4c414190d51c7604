/* 09-path-tracing: the Cornell box by path tracing (lecture 16), each rung of
 * the integrator ladder selectable, and the measurements of what accuracy
 * costs in time. */
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/experiments.h"
#include "effects.h"
#include "09-path-tracing/path_tracer.h"
#include "cli.h"
#include "program.h"

static bool build_scene(pt_scene *sc, const char *name, const char *obj, char *err, size_t err_size)
{
    if (obj != NULL)
        return pt_scene_load_obj(sc, obj, err, err_size);
    if (strcmp(name, "cornell") == 0)
        pt_scene_build_cornell_box(sc);
    else if (strcmp(name, "materials") == 0)
        pt_scene_build_cornell_box_materials(sc);
    else if (strcmp(name, "veach") == 0)
        pt_scene_build_veach(sc);
    else if (strcmp(name, "furnace") == 0)
        pt_scene_build_furnace(sc, 0.5f, 0.5f);
    else if (strcmp(name, "white-furnace") == 0)
        pt_scene_build_white_furnace(sc, pt_diffuse(vec3_splat(0.5f)), vec3_splat(1.0f));
    else if (strcmp(name, "glass-furnace") == 0)
        pt_scene_build_white_furnace(sc, pt_glass(1.5f), vec3_splat(1.0f));
    else if (strcmp(name, "point-in-sphere") == 0)
        pt_scene_build_point_in_sphere(sc, 0.5f, (float)PI);
    else {
        snprintf(err, err_size, "--builtin: unknown scene '%s' (cornell, materials, veach, furnace, "
                                "white-furnace, glass-furnace, point-in-sphere)", name);
        return false;
    }
    return true;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch09.exr", 512, 512, 16);
    /* integrator NULL and max_depth -1: not given, so the scene file's (or the default) */
    const char *integrator = NULL, *rr = "fixed", *scene_name = "cornell", *obj = NULL, *data = NULL;
    const char *accel_name = "bvh";
    float rr_probability = 0.8f, time_budget = 0.0f, target_error = 0.0f;
    int max_depth = -1, rr_start = 3, experiment_size = 96, reference_spp = 4096, experiment_spp = 256;
    const cli_flag extras[] = {
        {"--integrator", CLI_STRING, &integrator, "NAME", "lecture (default), cosine or mis: the rung of the ladder", 0, 0},
        {"--rr", CLI_STRING, &rr, "MODE",
         "Russian roulette: fixed (default, P_RR), throughput (pbrt's), albedo (smallpt's), or off", 0, 0},
        {"--rr-probability", CLI_FLOAT, &rr_probability, "P", "P_RR for --rr fixed (default 0.8)", 0.01, 1.0},
        {"--rr-start", CLI_INT, &rr_start, "N",
         "--rr throughput or albedo: the first bounce the roulette may end (default 3; pbrt-v3's is 5, smallpt's 6)",
         0, 1000},
        {"--max-depth", CLI_INT, &max_depth, "N", "bounces counted at most (default 64)", 0, 1000},
        {"--builtin", CLI_STRING, &scene_name, "NAME",
         "cornell (default), materials (glossy metal, glass), veach (glossy plates, lights of 4 sizes), furnace, "
         "white-furnace, glass-furnace, point-in-sphere",
         0, 0},
        {"--obj", CLI_STRING, &obj, "FILE", "render an OBJ file (MTL Kd, Ke, Ni) instead", 0, 0},
        {"--accel", CLI_STRING, &accel_name, "NAME",
         "the structure the rays are traced through: bvh (default, chapter 06), kdtree (05), grid (04) or "
         "brute (03)", 0, 0},
        {"--time-budget", CLI_FLOAT, &time_budget, "SECONDS", "progressive: passes until this much time is spent", 0.0, 1e6},
        {"--target-error", CLI_FLOAT, &target_error, "E",
         "progressive: passes until the estimated relative error is below E", 0.0, 10.0},
        {"--data", CLI_DIR, &data, "DIR", "run the experiments (error against time) and write CSV into DIR", 0, 0},
        {"--experiment-size", CLI_INT, &experiment_size, "N", "image side of the experiments (default 96)", 8, 1024},
        {"--reference-spp", CLI_INT, &reference_spp, "N", "samples of the cached reference (default 4096)", 16, 1 << 20},
        {"--experiment-spp", CLI_INT, &experiment_spp, "N", "largest spp of the experiments (default 256)", 1, 1 << 16},
    };
    cli_spec spec = {"09-path-tracing",
                     "Path tracing (GAMES101 lecture 16): the rendering equation by Monte Carlo, one sample per\n"
                     "bounce, direct light by sampling the light's area, Russian roulette. Renders the Cornell\n"
                     "box; --integrator climbs the ladder (lecture -> cosine -> mis). --time-budget or\n"
                     "--target-error render progressively; --data DIR measures error against time.\n"
                     "The built-in Cornell box is chapters/09-path-tracing/scenes/cornell.scene.",
                     extras, sizeof extras / sizeof extras[0]};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    opts.jitter = true; /* Monte Carlo over the pixel area, even at 1 spp */
    path_tracer pt;
    pt_scene sc;
    char err[1024];
    scene_desc desc;
    bool from_file = program_load_scene(&opts, spec.program, &desc);
    if (from_file && (obj != NULL || data != NULL)) {
        fprintf(stderr, "09-path-tracing: --scene does not combine with --obj or --data\n");
        scene_desc_free(&desc);
        return 2;
    }
    pt_integrator chosen = PT_LECTURE;
    if (integrator != NULL && !pt_integrator_parse(integrator, &chosen)) {
        fprintf(stderr, "09-path-tracing: --integrator: unknown '%s' (lecture, cosine, mis)\n", integrator);
        scene_desc_free(&desc);
        return 2;
    }
    if (integrator == NULL && from_file && desc.integrator[0] != '\0' && !pt_integrator_parse(desc.integrator, &chosen)) {
        fprintf(stderr, "09-path-tracing: %s:%d:%d: unknown integrator '%s' (lecture, cosine, mis)\n", desc.source,
                desc.integrator_line, desc.integrator_column, desc.integrator);
        scene_desc_free(&desc);
        return 1;
    }
    if (max_depth < 0)
        max_depth = from_file && desc.max_depth >= 0 ? desc.max_depth : 64;
    pt_accel_builder accel_builder = pt_accel_builder_named(accel_name);
    if (accel_builder == NULL) {
        fprintf(stderr, "09-path-tracing: --accel: unknown '%s' (bvh, kdtree, grid, brute)\ntry --help\n", accel_name);
        scene_desc_free(&desc);
        return 2;
    }
    pt_russian_roulette rr_mode;
    if (!pt_russian_roulette_parse(rr, &rr_mode)) {
        fprintf(stderr, "09-path-tracing: --rr: unknown '%s' (fixed, throughput, albedo, off)\n", rr);
        scene_desc_free(&desc);
        return 2;
    }
    if (from_file) {
        bool ok = pt_scene_from_desc(&sc, &desc, spec.program, err, sizeof err);
        if (!ok) {
            scene_desc_free(&desc);
            fprintf(stderr, "09-path-tracing: %s\n", err);
            return 1;
        }
    } else if (!build_scene(&sc, scene_name, obj, err, sizeof err)) {
        fprintf(stderr, "09-path-tracing: %s\n", err);
        return obj != NULL ? 1 : 2;
    } else {
        pt_scene_describe(&sc, &desc);
    }
    /* The path tracer can simulate every effect; it simulates those the
     * scene (file or built-in) calls for and allows. The experiments (--data)
     * measure the integrators themselves, so they keep every effect on. */
    effects_report e = effects_analyse(&desc);
    unsigned effects = data != NULL ? EFFECT_ALL : effects_decide(&e, EFFECT_ALL);
    if (!opts.quiet && data == NULL)
        effects_print(stdout, &e, spec.program);
    program_note_effects(&e);
    scene_desc_free(&desc);
    if (accel_builder != pt_accel_builder_named("bvh"))
        pt_scene_use_accel(&sc, accel_builder, NULL);
    program_note_accel(sc.bvh->stats.name);
    pt_scene_check_scale(&sc, spec.program, stderr);
    pt = path_tracer_defaults(&sc);
    pt.effects = effects;
    pt.integrator = chosen;
    pt.russian_roulette = rr_mode;
    pt.rr_probability = rr_probability;
    pt.rr_start_depth = rr_start;
    pt.max_depth = max_depth;

    int status = 0;
    if (data != NULL) {
        /* The experiments, on the chosen scene: a cached reference, then
         * every rung at doubling sample counts, then (on the first scene)
         * the Russian roulette sweep. The Cornell box, all diffuse, is
         * where MIS gains least; by default the Veach scene, where it gains
         * most, is measured after it. */
        const char *names[2] = {obj ? "obj" : scene_name, "veach"};
        int scene_count = obj == NULL && strcmp(scene_name, "cornell") == 0 ? 2 : 1;
        for (int k = 0; k < scene_count && status == 0; k++) {
            pt_scene other;
            const pt_scene *scene = &sc;
            if (k > 0) {
                build_scene(&other, names[k], NULL, err, sizeof err);
                scene = &other;
            }
            path_tracer experiment_pt = pt;
            experiment_pt.scene = scene;
            camera cam = pt_scene_camera(scene, experiment_size, experiment_size);
            char reference_path[4096];
            snprintf(reference_path, sizeof reference_path, "%s/ch09_reference_%s_%d.exr", data, names[k],
                     experiment_size);
            estimate_image reference;
            printf("\n== scene %s\n", names[k]);
            if (!experiment_reference(&experiment_pt, &cam, reference_spp, opts.threads, reference_path, &reference,
                                      err, sizeof err) ||
                !experiment_convergence(scene, names[k], &cam, &reference, experiment_spp, opts.threads, data, err,
                                        sizeof err) ||
                (k == 0 && !experiment_russian_roulette(scene, &cam, &reference, 64, opts.threads, data, err,
                                                        sizeof err))) {
                fprintf(stderr, "09-path-tracing: %s\n", err);
                status = 1;
            }
            estimate_image_free(&reference);
            if (k > 0)
                pt_scene_free(&other);
        }
    } else if (time_budget > 0.0f || target_error > 0.0f) {
        if (opts.explain) {
            fprintf(stderr, "09-path-tracing: --explain explains one pixel of a plain render, not a progressive one\n");
            pt_scene_free(&sc);
            return 2;
        }
        camera cam = pt_scene_camera(&sc, opts.width, opts.height);
        estimate_image e = render_progressive(&pt, &cam, opts.seed, opts.threads, time_budget, target_error,
                                              opts.quiet ? NULL : stdout);
        if (!image_write(&e.mean, opts.out, opts.exposure, err, sizeof err)) {
            fprintf(stderr, "09-path-tracing: %s\n", err);
            status = 1;
        } else if (!opts.quiet) {
            printf("09-path-tracing: %s, %ld spp in %.2f s, estimated relative error %.4f -> %s\n",
                   pt_integrator_name(pt.integrator), e.spp, e.seconds, estimate_relative_error(&e), opts.out);
            counters_print(stdout, &e.counters, e.seconds);
        }
        char counters_path[4096];
        counters_path_for_image(opts.out, counters_path, sizeof counters_path);
        if (status == 0 && !counters_write_json(counters_path, &e.counters, e.seconds, NULL, err, sizeof err)) {
            fprintf(stderr, "09-path-tracing: %s\n", err);
            status = 1;
        }
        estimate_image_free(&e);
    } else {
        camera cam = pt_scene_camera(&sc, opts.width, opts.height);
        render_stats stats;
        status = program_render(&opts, spec.program, path_trace_radiance, &pt, &cam, &stats);
        if (status == 0 && !opts.quiet && !opts.explain) {
            double samples = (double)opts.width * opts.height * opts.spp;
            printf("%s: %.3f s per million camera samples (%d threads, %s, %s Russian roulette)\n",
                   pt_integrator_name(pt.integrator), stats.seconds / samples * 1e6, opts.threads,
                   pt_integrator_name(pt.integrator), rr);
        }
    }
    pt_scene_free(&sc);
    return status;
}

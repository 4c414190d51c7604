/* 13-production: chapter 09's path tracer on the production structures --
 * the flat set or the 8-wide BVH, the walls, eight paths at a time -- and
 * the table of what each step buys (--bench). */
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/experiments.h"
#include "09-path-tracing/path_tracer.h"
#include "13-production/wide_bvh.h"
#include "13-production/flat.h"
#include "13-production/path_tracer_wide.h"
#include "13-production/speed.h"
#include "13-production/walls.h"
#include "cli.h"
#include "counters_file.h"
#include "effects.h"
#include "image_file.h"
#include "program.h"
#include "run_record.h"
#include "timer.h"
#include "mpi_split.h"

typedef struct {
    cli_choice builtin, walls, rr, sampler, integrator;
    const char *obj, *bench_csv;
    bool bench, bench_scenes, one_path;
    int rr_start, torus;
    camera_override view; /* --eye, --target, --fov */
} production_flags;

static const char *const ON_OFF[] = {"on", "off", NULL};

/* Eight paths at a time: chapter 09's image of the same rung, by another route. */
static int render_eight_paths(const cli_options *opts, const path_tracer *pt, const camera *cam)
{
    char err[1024], counters_path[4096];
    estimate_image e;
    /* the warning program_render() gives before a long render, from a
     * pilot of 64 pixels, for images as large as it pilots */
    if (!opts->quiet && (long)cam->width * cam->height >= 16384)
        program_warn_if_long(opts, "13-production", render_estimate_wide_pilot(pt, cam, opts->spp, opts->seed, 64));
    render_estimate_wide(pt, cam, opts->spp, opts->seed, opts->threads, &e);
    program_warn_if_black(opts, "13-production", &e.mean);
    counters_path_for_image(opts->out, counters_path, sizeof counters_path);
    int status = 0;
    if (!image_write(&e.mean, opts->out, opts->exposure, err, sizeof err) ||
        !counters_write_json(counters_path, &e.counters, e.seconds, NULL, err, sizeof err)) {
        fprintf(stderr, "13-production: %s\n", err);
        status = 1;
    } else if (!opts->quiet) {
        printf("13-production: %dx%d, %d spp, the %s rung, 8 paths at a time, %d threads, %.3f s -> %s\n",
               opts->width, opts->height, opts->spp, pt_integrator_name(pt->integrator), opts->threads, e.seconds,
               opts->out);
        counters_print(stdout, &e.counters, e.seconds);
        printf("%.3f s per million camera samples\n", e.seconds / ((double)opts->width * opts->height * opts->spp) * 1e6);
    }
    estimate_image_free(&e);
    return status;
}

/* Which structures the scene's rays go through, and why (not --quiet). */
static void report_structures(const pt_scene *sc, bool walls_asked)
{
    const accel *all = walls_all(sc->bvh);
    if (sc->triangles.count == 0)
        printf("13-production: no triangles (spheres only)\n");
    else if (flat_is(all))
        printf("13-production: %d triangles: the flat set (at most 64: every triangle tested, eight rays per AVX "
               "instruction)\n", sc->triangles.count);
    else if (wide_bvh_is(all))
        printf("13-production: %d triangles: the " WIDE_BVH_NAME " (more than the 64 the flat set holds), each lane's ray "
               "walking it alone\n", sc->triangles.count);
    if (!walls_asked)
        printf("13-production: walls off (--walls off)\n");
    else if (walls_found(sc->bvh))
        printf("13-production: walls: %d triangles with the whole scene in front of them; shadow rays between "
               "them skip them\n", walls_triangle_count(sc->bvh));
    else
        printf("13-production: walls off: no triangle has the whole scene in front of it\n");
}

/* The scene the flags name: a scene file, an OBJ file, the box with a
 * torus, or a built-in. */
static bool load_scene(cli_options *opts, const production_flags *f, pt_scene *sc, scene_desc *desc, bool *from_file,
                       char *err, size_t err_size)
{
    /* the production structures are built below, in place of chapter 06's */
    pt_scene_finish_builds(NULL);
    *from_file = program_load_scene(opts, "13-production", desc);
    if (opts->quiet)
        pt_scene_report_materials(NULL);
    if (*from_file)
        return pt_scene_from_desc(sc, desc, "13-production", err, err_size);
    if (f->obj != NULL)
        return pt_scene_load_obj(sc, f->obj, err, err_size);
    if (f->torus > 0) {
        production_scene_box_with_torus(sc, f->torus);
        return true;
    }
    return pt_scene_build_builtin(sc, cli_choice_name(&f->builtin));
}

/* One image of the scene the flags name, on the production structures. */
static int render(cli_options *opts, const production_flags *f)
{
    pt_scene sc;
    char err[1024];
    scene_desc desc;
    bool from_file;
    /* the work before the first sample, by the wall clock: what more
     * threads do not speed up unless it is parallel too */
    double start = timer_seconds();
    if (!load_scene(opts, f, &sc, &desc, &from_file, err, sizeof err)) {
        fprintf(stderr, "13-production: %s\n", err);
        scene_desc_free(&desc);
        return 1;
    }
    pt_scene_check_scale(&sc, "13-production", stderr);
    pt_scene_check_lights(&sc, "13-production", stderr);
    double loaded = timer_seconds();
    if (!from_file)
        pt_scene_describe(&sc, &desc);
    double described = timer_seconds();
    camera_override_apply(&f->view, &sc.eye, &sc.target, &sc.vertical_fov_degrees);
    if (pt_scene_has_no_light(&sc, err, sizeof err))
        fprintf(stderr, "13-production: warning: %s\n", err);
    effects_report e = effects_analyse(&desc);
    /* the rung: --integrator, else the scene file's, else the program's default */
    pt_integrator integrator = production_path_tracer_defaults(&sc).integrator;
    if (f->integrator.index >= 0) {
        integrator = (pt_integrator)f->integrator.index;
    } else if (from_file && desc.integrator[0] != '\0' && !pt_integrator_parse(desc.integrator, &integrator)) {
        fprintf(stderr, "13-production: %s:%d:%d: unknown integrator '%s' (lecture, cosine, mis)\n", desc.source,
                desc.integrator_line, desc.integrator_column, desc.integrator);
        scene_desc_free(&desc);
        pt_scene_free(&sc);
        return 1;
    }
    scene_desc_free(&desc);
    bool walls = f->walls.index == 0;
    double built = timer_seconds();
    pt_scene_use_accel(&sc, walls ? production_scene_accel : production_scene_accel_no_walls, &sc);
    double ready = timer_seconds();
    program_note_accel(sc.bvh->stats.name);
    path_tracer pt = production_path_tracer_defaults(&sc);
    pt.effects = effects_decide(&e, EFFECT_ALL);
    pt.russian_roulette = (pt_russian_roulette)f->rr.index;
    pt.rr_start_depth = f->rr_start;
    pt.sampler = (pt_sampler)f->sampler.index;
    pt.integrator = integrator;
    camera cam = pt_scene_camera(&sc, opts->width, opts->height);
    char why[160];
    int status;
    run_record_note("russian_roulette", pt_russian_roulette_name(pt.russian_roulette));
    run_record_note("sampler", PT_SAMPLER_NAMES[pt.sampler]);
    if (!opts->quiet && !opts->explain) {
        report_structures(&sc, walls);
        printf("13-production: before the first sample %.3f s on %d threads: the scene %.3f s, its description "
               "%.3f s, the structures %.3f s\n", ready - start, opts->threads, loaded - start, described - loaded,
               ready - built);
    }
    bool wide = !f->one_path && !opts->explain && path_tracer_wide_supported(&pt, why, sizeof why);
    if (wide && opts->resume != NULL)
        fprintf(stderr, "13-production: --resume %s: eight paths at a time keep no checkpoints (--one-path does)\n",
                opts->resume);
    if (wide && (opts->resume != NULL || mpi_split_refuse("13-production", "eight paths at a time (--one-path is)"))) {
        pt_scene_free(&sc);
        return 2;
    }
    char note[64];
    snprintf(note, sizeof note, "%s, %s at a time", pt_integrator_name(pt.integrator), wide ? "eight paths" : "one path");
    run_record_note("integrator", note);
    if (wide) {
        status = render_eight_paths(opts, &pt, &cam);
    } else {
        if (!f->one_path && !opts->quiet && !opts->explain)
            printf("13-production: one path at a time (eight at a time: %s)\n", why);
        status = program_render_sampled(opts, "13-production", path_trace_radiance, path_tracer_sample_fn(&pt), &pt,
                                        &cam, NULL);
    }
    pt_scene_free(&sc);
    return status;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch13.exr", 512, 512, 16);
    production_flags f = {{PT_BUILTIN_SCENE_NAMES, PT_BUILTIN_SCENE_NOTES, 0}, {ON_OFF, NULL, 0},
                          {PT_ROULETTE_NAMES, NULL, PRODUCTION_ROULETTE}, {PT_SAMPLER_NAMES, NULL, PRODUCTION_SAMPLER},
                          {PT_INTEGRATOR_NAMES, NULL, -1}, NULL, NULL,
                          false, false, false, 3, 0, CAMERA_NOT_OVERRIDDEN};
    const cli_flag extras[] = {
        {"--builtin", CLI_CHOICE, &f.builtin, NULL, "a scene of chapter 09 (default cornell)", 0, 0},
        {"--obj", CLI_STRING, &f.obj, "FILE", "render an OBJ file with its MTL materials instead", 0, 0},
        {"--torus", CLI_INT, &f.torus, "N", "the Cornell box's room with a diffuse torus of about N triangles in it",
         8, 100000000},
        CLI_CAMERA_FLAGS(f.view),
        {"--walls", CLI_CHOICE, &f.walls, NULL, "on (default): shadow rays inside a room skip its walls", 0, 0},
        {"--integrator", CLI_CHOICE, &f.integrator, NULL, "chapter 09's rung (default mis, or the scene file's): "
                                                          "each eight paths at a time", 0, 0},
        {"--rr", CLI_CHOICE, &f.rr, NULL, "Russian roulette: throughput (default, from --rr-start), fixed (P_RR 0.8), albedo or off", 0,
         0},
        {"--rr-start", CLI_INT, &f.rr_start, "N", "--rr throughput or albedo: the first bounce it may end", 0, 1000},
        {"--sampler", CLI_CHOICE, &f.sampler, NULL, "sobol (default): each pixel's samples the points of a "
                                                  "scrambled Sobol sequence (chapter 09); random: independent numbers", 0, 0},
        {"--one-path", CLI_BOOL, &f.one_path, NULL, "one path at a time even where eight at a time could run", 0, 0},
        {"--bench", CLI_BOOL, &f.bench, NULL, "the table of what each step buys, on the Cornell box (a square of "
                                              "--width pixels, --spp samples; best of 5)", 0, 0},
        {"--bench-csv", CLI_STRING, &f.bench_csv, "FILE", "with --bench: also write the table as CSV", 0, 0},
        {"--bench-scenes", CLI_BOOL, &f.bench_scenes, NULL, "s per million samples on 1 thread, 8 paths, one path "
                                                            "and chapter 09's MIS, on the box and with 10k and "
                                                            "100k-triangle tori (--width, --spp; best of 3)", 0, 0},
        CLI_CHECKPOINT_FLAGS(opts),
    };
    cli_spec spec = {"13-production",
                     "What production renderers do: chapter 09's path tracer, eight paths at a time, on\n"
                     "any scene chapter 09 renders (meshes, spheres, every material, area and point lights,\n"
                     "the environment): the flat set for at most 64 triangles, the " WIDE_BVH_NAME " above, shadow\n"
                     "rays that skip a room's walls where it has them; it says which. --bench measures each step.",
                     extras, sizeof extras / sizeof extras[0], "the path tree (every ray, hit, light sample and Russian roulette decision, one path at a time)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if ((f.bench || f.bench_scenes) && mpi_split_refuse("13-production", "--bench"))
        return 2;
    opts.jitter = true;
    if (f.bench_csv != NULL && !f.bench) {
        fprintf(stderr, "13-production: --bench-csv %s: only with --bench\ntry --help\n", f.bench_csv);
        return 2;
    }
    if (f.bench_scenes) {
        production_speed_scenes(opts.width, opts.spp, 3);
        return 0;
    }
    if (!f.bench)
        return render(&opts, &f);
    char err[1024];
    if (production_speed(opts.width, opts.spp, 5, f.bench_csv, err, sizeof err))
        return 0;
    fprintf(stderr, "13-production: %s\n", err);
    return 1;
}

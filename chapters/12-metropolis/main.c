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
#include "counters_file.h"
#include "image_file.h"
#include "program.h"
#include "mpi_split.h"

/* The built-in scenes (--builtin), each with the line --help shows. */
static const pt_builtin_scene BUILTINS[] = {
    {"lamp", mlt_scene_build_lamp,
     "the ceiling light shut in a housing; light leaves only down a 2 cm channel (default)"},
    {"cornell", pt_scene_build_cornell_box, "the Cornell box"},
    {"materials", pt_scene_build_cornell_box_materials, "the Cornell box with a metal block and a glass sphere"},
};
enum { BUILTIN_COUNT = sizeof BUILTINS / sizeof BUILTINS[0] };

/* The --builtin choice, its names and notes taken from the table. */
static const char *builtin_names[BUILTIN_COUNT + 1], *builtin_notes[BUILTIN_COUNT];

/* In mlt_start's order. */
static const char *const START_NAMES[] = {"bootstrap", "fixed", NULL};

/* The program's own flags. */
typedef struct {
    cli_choice builtin, start;
    const char *data;
    float p_large;
    int bootstrap, chains, max_depth;
    bool path_trace, quick;
} mlt_flags;

/* --scene FILE or the built-in scene. Returns 0, or the exit status after
 * printing why. */
static int load_scene(pt_scene *sc, cli_options *opts, const char *program, const mlt_flags *f)
{
    scene_desc desc;
    char err[1024];
    if (!program_load_scene(opts, program, &desc)) {
        BUILTINS[f->builtin.index].build(sc);
        return 0;
    }
    if (f->data != NULL) {
        fprintf(stderr, "%s: --scene does not combine with --data\n", program);
        scene_desc_free(&desc);
        return 2;
    }
    bool ok = pt_scene_from_desc(sc, &desc, program, err, sizeof err);
    scene_desc_free(&desc);
    if (!ok) {
        fprintf(stderr, "%s: %s\n", program, err);
        return 1;
    }
    return 0;
}

/* --data: equal time against path tracing, start-up bias, which method. */
static int run_experiments(const char *dir, int threads, bool quick, const char *program)
{
    char err[1024];
    if (!mlt_experiments_run(dir, threads, quick, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        return 1;
    }
    return 0;
}

static void print_mlt(const cli_options *opts, const mlt_flags *f, const mlt_result *r, double acceptance)
{
    printf("12-metropolis: %s, %d mutations per pixel, %d chains, p_large %.2f: %.2f s (bootstrap %.2f s) -> %s\n",
           opts->scene != NULL ? opts->scene : cli_choice_name(&f->builtin), opts->spp, f->chains,
           (double)f->p_large, r->seconds, r->bootstrap_seconds, opts->out);
    printf("b = %.5g +- %.2g (%d bootstrap paths), acceptance %.3f\n", r->b, r->b_standard_error, f->bootstrap,
           acceptance);
    counters_print(stdout, &r->counters, r->seconds);
}

/* The image, the report, and the counters with b and the acceptance. */
static int write_mlt(const cli_options *opts, const char *program, const mlt_flags *f, const image *img,
                     const mlt_result *r)
{
    char err[1024], counters_path[4096], extra[256];
    if (!image_write(img, opts->out, opts->exposure, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        return 1;
    }
    double acceptance = r->proposed > 0 ? (double)r->accepted / (double)r->proposed : 0.0;
    if (!opts->quiet)
        print_mlt(opts, f, r, acceptance);
    counters_path_for_image(opts->out, counters_path, sizeof counters_path);
    snprintf(extra, sizeof extra, "\"b\": %.9g, \"b_standard_error\": %.9g, \"acceptance\": %.6f", r->b,
             r->b_standard_error, acceptance);
    if (!counters_write_json(counters_path, &r->counters, r->seconds, extra, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        return 1;
    }
    return 0;
}

/* The picture by Metropolis: --spp mutations per pixel. */
static int render_mlt(const cli_options *opts, const char *program, const mlt_flags *f, const path_tracer *pt,
                      const camera *cam)
{
    mlt_options o = mlt_defaults(pt, cam);
    o.mutations_per_pixel = opts->spp;
    o.p_large = f->p_large;
    o.bootstrap = f->bootstrap;
    o.chains = f->chains;
    o.seed = opts->seed;
    o.threads = opts->threads;
    o.start = (mlt_start)f->start.index;
    o.quiet = opts->quiet;
    /* Each mutation is one path through the path tracer, so a pilot of
     * the path tracer at as many samples per pixel as there are mutations
     * per pixel says roughly how long the chains will run (the bootstrap
     * and the splats come on top). */
    render_job pilot = {.cam = cam, .spp = opts->spp, .seed = opts->seed, .radiance = path_trace_radiance,
                        .scene = pt, .sample = path_tracer_sample_fn(pt), .jitter = true};
    if (!opts->quiet)
        program_warn_if_long(opts, program, program_pilot_seconds(&pilot));
    image img = image_make(cam->width, cam->height);
    mlt_result r;
    int status = 0;
    if (!mlt_render(&o, &img, &r)) {
        fprintf(stderr, "%s: out of memory\n", program);
        status = 1;
    } else {
        status = write_mlt(opts, program, f, &img, &r);
    }
    image_free(&img);
    return status;
}

/* The picture by Metropolis, or by chapter 09's path tracer with
 * --path-trace (MIS, Russian roulette on throughput, as MLT uses it). */
static int render(cli_options *opts, const char *program, const mlt_flags *f, const pt_scene *sc)
{
    path_tracer pt = path_tracer_defaults(sc);
    pt.integrator = PT_MIS;
    pt.russian_roulette = RR_THROUGHPUT;
    pt.max_depth = f->max_depth;
    camera cam = pt_scene_camera(sc, opts->width, opts->height);
    if (!f->path_trace)
        return render_mlt(opts, program, f, &pt, &cam);
    opts->jitter = true; /* Monte Carlo over the pixel area, even at 1 spp */
    return program_render(opts, program, path_trace_radiance, &pt, &cam, NULL);
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch12.exr", 256, 256, 64);
    mlt_flags f = {pt_builtin_scene_choice(BUILTINS, BUILTIN_COUNT, builtin_names, builtin_notes), {START_NAMES, NULL, MLT_START_BOOTSTRAP}, NULL, 0.3f, 100000, 256, 64, false, false};
    const cli_flag extras[] = {
        {"--p-large", CLI_FLOAT, &f.p_large, "P", "probability of a large step (all new numbers; default 0.3)", 0.0,
         1.0},
        {"--bootstrap", CLI_INT, &f.bootstrap, "N", "paths that estimate the normalization b (default 100000)", 1,
         1 << 30},
        {"--chains", CLI_INT, &f.chains, "N", "Markov chains, run in parallel (default 256)", 1, 1 << 20},
        {"--start", CLI_CHOICE, &f.start, NULL,
         "bootstrap (default: chains start at bootstrap paths picked in proportion to f) or fixed (all at the "
         "first path with f > 0: start-up bias)", 0, 0},
        {"--builtin", CLI_CHOICE, &f.builtin, "NAME", "the built-in scene, when there is no --scene:", 0, 0},
        {"--path-trace", CLI_BOOL, &f.path_trace, NULL,
         "render the same scene with chapter 09's path tracer instead (--spp samples per pixel), to compare", 0, 0},
        {"--max-depth", CLI_INT, &f.max_depth, "N", "bounces counted at most (default 64)", 0, 1000},
        {"--data", CLI_DIR, &f.data, "DIR",
         "run the experiments (equal-time error of MLT and path tracing; start-up bias; which method for which "
         "scene: path tracing, BDPT and MLT on three scenes) and write CSV into DIR", 0,
         0},
        {"--quick", CLI_BOOL, &f.quick, NULL,
         "with --data: every table in seconds, rough (32 x 32, short runs, small references)", 0, 0},
    };
    cli_spec spec = {"12-metropolis",
                     "Metropolis light transport (Kelemen et al. 2002; GAMES101 lecture 16's closing slides):\n"
                     "a Markov chain over the path tracer's uniform numbers whose stationary density is the\n"
                     "path's luminance f over b = E[f]. --spp is mutations per pixel; b is estimated from\n"
                     "--bootstrap paths. Uses chapter 09's path tracer (MIS, Russian roulette on throughput).\n"
                     "--data DIR measures error against time against chapter 09's path tracer and chapter 11's BDPT.",
                     extras, sizeof extras / sizeof extras[0], NULL};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    /* --path-trace renders through program_render, split like chapter 09 */
    if ((f.data != NULL || !f.path_trace) && mpi_split_refuse(spec.program, "Metropolis light transport (and --data)"))
        return 2;
    if (opts.explain) {
        fprintf(stderr, "%s: --explain is not supported (a chain has no per-pixel paths; try "
                        "09-path-tracing --explain)\ntry --help\n", spec.program);
        return 2;
    }
    pt_scene sc;
    int status = load_scene(&sc, &opts, spec.program, &f);
    if (status == 0) {
        pt_scene_check_scale(&sc, spec.program, stderr);
        pt_scene_check_lights(&sc, spec.program, stderr);
    }
    if (status != 0)
        return status;
    if (f.data != NULL) {
        pt_scene_free(&sc);
        return run_experiments(f.data, opts.threads, f.quick, spec.program);
    }
    status = render(&opts, spec.program, &f, &sc);
    pt_scene_free(&sc);
    return status;
}

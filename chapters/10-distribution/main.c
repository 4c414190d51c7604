/* 10-distribution: Cook's distribution ray tracing (1984) of a scene with
 * every effect it introduced: jittered pixels, soft shadows, glossy
 * reflection, depth of field and motion blur; and, with --data, what its
 * rays per bounce cost against more samples per pixel. */
#include <stdio.h>
#include <string.h>

#include "10-distribution/distribution.h"
#include "10-distribution/experiments_dist.h"
#include "cli.h"
#include "effects.h"
#include "program.h"
#include "mpi_split.h"

static const char *const MOTION_NAMES[] = {"on", "off", NULL};
enum { MOTION_ON, MOTION_OFF };

/* The program's own flags. */
typedef struct {
    int light_samples, glossy_samples;
    int max_depth;              /* -1: the scene file's, else 5 */
    float aperture, focus_distance; /* -1: not given, so the scene's own lens */
    cli_choice motion;
    const char *data;
    bool quick;
} dist_flags;

/* --scene FILE (a chapter 09 scene file; nothing moves) or the built-in
 * showcase. From a file, *effects becomes what the file calls for, and
 * its max_depth applies unless --max-depth was given. Returns 0, or the
 * exit status after printing why. */
static int load_scene(motion_scene *ms, cli_options *opts, const char *program, dist_flags *f, unsigned *effects)
{
    scene_desc desc;
    char err[1024];
    *effects = EFFECT_ALL;
    if (!program_load_scene(opts, program, &desc)) {
        motion_scene_build_showcase(ms);
        return 0;
    }
    if (f->data != NULL) {
        fprintf(stderr, "%s: --scene does not combine with --data\n", program);
        scene_desc_free(&desc);
        return 2;
    }
    motion_scene_init(ms);
    pt_scene_free(&ms->base);
    if (!pt_scene_from_desc(&ms->base, &desc, program, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        scene_desc_free(&desc);
        return 1;
    }
    /* Only the effects the file calls for; indirect diffuse light is beyond
     * distribution ray tracing, whatever the file says. */
    effects_report e = effects_analyse(&desc);
    *effects = effects_decide(&e, EFFECT_ALL & ~(unsigned)EFFECT_INDIRECT);
    if (!opts->quiet)
        effects_print(stdout, &e, program);
    program_note_effects(&e);
    if (f->max_depth < 0 && desc.max_depth >= 0)
        f->max_depth = desc.max_depth;
    scene_desc_free(&desc);
    /* No lens in the file: a pinhole unless --aperture, focused on the
     * camera's target unless --focus-distance. */
    ms->focus_distance = vec3_length(vec3_sub(ms->base.target, ms->base.eye));
    return 0;
}

/* --data: rays per bounce against samples per pixel. */
static int run_experiments(const motion_scene *ms, int threads, bool quick, const char *dir, const char *program)
{
    char err[1024];
    if (!experiment_rays_per_bounce(ms, threads, quick, dir, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", program, err);
        return 1;
    }
    return 0;
}

static void print_rays(const render_stats *stats, const distribution_tracer *dt, const dist_flags *f)
{
    double camera_rays = (double)stats->counters.camera_rays;
    printf("per camera ray: %.2f shadow, %.2f glossy, %.2f reflection, %.2f refraction rays "
           "(N_light %d, N_glossy %d, max depth %d, aperture %g, focus %g, motion %s)\n",
           (double)stats->counters.shadow_rays / camera_rays, (double)stats->counters.indirect_rays / camera_rays,
           (double)stats->counters.reflection_rays / camera_rays,
           (double)stats->counters.refraction_rays / camera_rays, dt->light_samples, dt->glossy_samples,
           dt->max_depth, (double)dt->lens.aperture_radius, (double)dt->lens.focus_distance,
           cli_choice_name(&f->motion));
}

/* The picture, with the flags' samples, lens and motion. */
static int render(cli_options *opts, const char *program, const motion_scene *ms, const dist_flags *f,
                  unsigned effects)
{
    camera cam = pt_scene_camera(&ms->base, opts->width, opts->height);
    distribution_tracer dt = distribution_tracer_defaults(ms, &cam);
    if (f->aperture >= 0.0f)
        dt.lens.aperture_radius = f->aperture;
    if (f->focus_distance > 0.0f)
        dt.lens.focus_distance = f->focus_distance;
    dt.light_samples = f->light_samples;
    dt.glossy_samples = f->glossy_samples;
    dt.max_depth = f->max_depth >= 0 ? f->max_depth : 5;
    dt.motion = f->motion.index == MOTION_ON;
    dt.effects = effects;
    render_stats stats;
    int status = program_render(opts, program, distribution_radiance, &dt, &cam, &stats);
    if (status == 0 && !opts->quiet && !opts->explain)
        print_rays(&stats, &dt, f);
    return status;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch10.exr", 512, 512, 16);
    dist_flags f = {4, 4, -1, -1.0f, -1.0f, {MOTION_NAMES, NULL, MOTION_ON}, NULL, false};
    const cli_flag extras[] = {
        {"--light-samples", CLI_INT, &f.light_samples, "N", "shadow rays to the area lights per hit (default 4)", 1,
         4096},
        {"--glossy-samples", CLI_INT, &f.glossy_samples, "N",
         "rays from the GGX lobe per glossy hit, each recursing (default 4; 0: highlights only)", 0, 4096},
        {"--max-depth", CLI_INT, &f.max_depth, "N", "bounces counted at most (default 5, or the scene file's max_depth)",
         0, 64},
        {"--aperture", CLI_FLOAT, &f.aperture, "R",
         "radius of the thin lens in scene units (0: pinhole; default the scene's, 25 mm for the built-in)", 0.0, 1e6},
        {"--focus-distance", CLI_FLOAT, &f.focus_distance, "D",
         "distance of the plane of focus along the view direction (default the scene's, 1000 mm)", 1e-3, 1e9},
        {"--motion", CLI_CHOICE, &f.motion, NULL, "on (default): a shutter instant per sample; off: all at 0", 0, 0},
        {"--data", CLI_DIR, &f.data, "DIR", "measure noise against time, rays per bounce against spp; CSV into DIR", 0,
         0},
        {"--quick", CLI_BOOL, &f.quick, NULL,
         "with --data: a rough run in seconds (32 x 32, a 1024-spp reference) instead of minutes", 0, 0},
        CLI_CHECKPOINT_FLAGS(opts),
    };
    cli_spec spec = {"10-distribution",
                     "Distribution ray tracing (Cook, Porter and Carpenter 1984): chapter 02's recursion with\n"
                     "several rays spread over each dimension of the integral -- stratified pixel samples,\n"
                     "a thin lens (depth of field), a shutter instant per sample (motion blur), N_light shadow\n"
                     "rays to the area light (soft shadows), N_glossy rays from the GGX lobe (glossy\n"
                     "reflection). Diffuse surfaces get direct light only. The built-in scene is the Cornell\n"
                     "room with a glossy plate, mirror and glass spheres, a moving sphere and a rising cube;\n"
                     "--scene FILE renders a chapter 09 scene file (nothing moves). --data DIR measures noise\n"
                     "against time for N rays per bounce against N samples per pixel.",
                     extras, sizeof extras / sizeof extras[0], "the ray tree (every ray, hit and light sample, with its time and lens point)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if (f.data != NULL && mpi_split_refuse(spec.program, "--data"))
        return 2;
    opts.stratify = true; /* Cook's jittered pixel samples */

    motion_scene ms;
    unsigned effects;
    int status = load_scene(&ms, &opts, spec.program, &f, &effects);
    if (status != 0)
        return status;
    pt_scene_check_scale(&ms.base, spec.program, stderr); /* the still part; moving objects are not checked */
    pt_scene_check_lights(&ms.base, spec.program, stderr);
    status = f.data != NULL ? run_experiments(&ms, opts.threads, f.quick, f.data, spec.program)
                            : render(&opts, spec.program, &ms, &f, effects);
    motion_scene_free(&ms);
    return status;
}

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

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch10.exr", 512, 512, 16);
    const char *motion = "on", *data = NULL;
    int light_samples = 4, glossy_samples = 4, max_depth = -1; /* -1: the scene file's, else 5 */
    /* -1: not given, so the scene's own lens */
    float aperture = -1.0f, focus_distance = -1.0f;
    const cli_flag extras[] = {
        {"--light-samples", CLI_INT, &light_samples, "N", "shadow rays to the area lights per hit (default 4)", 1, 4096},
        {"--glossy-samples", CLI_INT, &glossy_samples, "N",
         "rays from the GGX lobe per glossy hit, each recursing (default 4; 0: highlights only)", 0, 4096},
        {"--max-depth", CLI_INT, &max_depth, "N", "bounces counted at most (default 5, or the scene file's max_depth)", 0, 64},
        {"--aperture", CLI_FLOAT, &aperture, "R",
         "radius of the thin lens in scene units (0: pinhole; default the scene's, 25 mm for the built-in)", 0.0, 1e6},
        {"--focus-distance", CLI_FLOAT, &focus_distance, "D",
         "distance of the plane of focus along the view direction (default the scene's, 1000 mm)", 1e-3, 1e9},
        {"--motion", CLI_STRING, &motion, "on|off", "on (default): a shutter instant per sample; off: all at 0", 0, 0},
        {"--data", CLI_DIR, &data, "DIR", "measure noise against time, rays per bounce against spp; CSV into DIR", 0,
         0},
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
                     extras, sizeof extras / sizeof extras[0]};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    opts.stratify = true; /* Cook's jittered pixel samples */
    if (strcmp(motion, "on") != 0 && strcmp(motion, "off") != 0) {
        fprintf(stderr, "10-distribution: --motion: '%s' is neither on nor off\ntry --help\n", motion);
        return 2;
    }

    motion_scene ms;
    scene_desc desc;
    char err[1024];
    bool from_file = program_load_scene(&opts, spec.program, &desc);
    if (from_file && data != NULL) {
        fprintf(stderr, "10-distribution: --scene does not combine with --data\n");
        scene_desc_free(&desc);
        return 2;
    }
    unsigned effects = EFFECT_ALL;
    if (from_file) {
        motion_scene_init(&ms);
        pt_scene_free(&ms.base);
        if (!pt_scene_from_desc(&ms.base, &desc, spec.program, err, sizeof err)) {
            fprintf(stderr, "10-distribution: %s\n", err);
            scene_desc_free(&desc);
            return 1;
        }
        /* Only the effects the file calls for; indirect diffuse light is
         * beyond distribution ray tracing, whatever the file says. */
        effects_report e = effects_analyse(&desc);
        effects = effects_decide(&e, EFFECT_ALL & ~(unsigned)EFFECT_INDIRECT);
        if (!opts.quiet && data == NULL)
            effects_print(stdout, &e, spec.program);
        program_note_effects(&e);
        if (max_depth < 0 && desc.max_depth >= 0)
            max_depth = desc.max_depth;
        scene_desc_free(&desc);
        /* No lens in the file: a pinhole unless --aperture, focused on the
         * camera's target unless --focus-distance. */
        ms.focus_distance = vec3_length(vec3_sub(ms.base.target, ms.base.eye));
    } else {
        motion_scene_build_showcase(&ms);
    }
    /* (the still part; the moving objects are not checked) */
    pt_scene_check_scale(&ms.base, spec.program, stderr);

    int status = 0;
    if (data != NULL) {
        if (!experiment_rays_per_bounce(&ms, opts.threads, data, err, sizeof err)) {
            fprintf(stderr, "10-distribution: %s\n", err);
            status = 1;
        }
    } else {
        camera cam = pt_scene_camera(&ms.base, opts.width, opts.height);
        distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
        if (aperture >= 0.0f)
            dt.lens.aperture_radius = aperture;
        if (focus_distance > 0.0f)
            dt.lens.focus_distance = focus_distance;
        dt.light_samples = light_samples;
        dt.glossy_samples = glossy_samples;
        dt.max_depth = max_depth >= 0 ? max_depth : 5;
        dt.motion = strcmp(motion, "on") == 0;
        dt.effects = effects;
        render_stats stats;
        status = program_render(&opts, spec.program, distribution_radiance, &dt, &cam, &stats);
        if (status == 0 && !opts.quiet && !opts.explain) {
            double camera_rays = (double)stats.counters.camera_rays;
            printf("per camera ray: %.2f shadow, %.2f glossy, %.2f reflection, %.2f refraction rays "
                   "(N_light %d, N_glossy %d, max depth %d, aperture %g, focus %g, motion %s)\n",
                   (double)stats.counters.shadow_rays / camera_rays, (double)stats.counters.indirect_rays / camera_rays,
                   (double)stats.counters.reflection_rays / camera_rays,
                   (double)stats.counters.refraction_rays / camera_rays, dt.light_samples, dt.glossy_samples,
                   dt.max_depth, (double)dt.lens.aperture_radius, (double)dt.lens.focus_distance, motion);
        }
    }
    motion_scene_free(&ms);
    return status;
}

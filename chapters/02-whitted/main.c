/* 02-whitted: render chapter 02's scene by Whitted-style ray tracing (lecture 13). */
#include <stdio.h>

#include "cli.h"
#include "effects.h"
#include "program.h"
#include "whitted.h"

static const int DEFAULT_MAX_DEPTH = 5;

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch02.exr", 1280, 720, 1);
    int max_depth = -1; /* not given: the scene file's max_depth, or DEFAULT_MAX_DEPTH */
    cli_flag extras[] = {
        {"--max-depth", CLI_INT, &max_depth, "N",
         "most reflected/refracted rays in a row; deeper ones return black (0..64, default 5)", 0, 64},
    };
    cli_spec spec = {"02-whitted",
                     "Whitted-style ray tracing (GAMES101 lecture 13): ray casting plus recursion. Mirrors\n"
                     "reflect the ray and trace it again; glass splits it into a reflected and a refracted\n"
                     "ray (Snell's law), weighted by the exact Fresnel reflectance; diffuse surfaces stop\n"
                     "with a shadow ray to each point light and Blinn-Phong shading. The built-in scene is\n"
                     "chapters/02-whitted/scenes/default.scene.",
                     extras, 1};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    scene sc;
    scene_desc desc;
    if (program_load_scene(&opts, spec.program, &desc)) {
        char err[SCENE_ERROR_SIZE];
        if (!scene_from_desc(&sc, &desc, spec.program, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", spec.program, err);
            scene_desc_free(&desc);
            return 1;
        }
    } else {
        scene_build_whitted_demo(&sc);
        scene_describe(&sc, &desc);
    }
    /* The effects analysis, on the file or on the built-in scene alike. */
    effects_report e = effects_analyse(&desc);
    sc.effects = effects_decide(&e, EFFECT_SHADOWS | EFFECT_REFLECTION | EFFECT_REFRACTION);
    if (!opts.quiet)
        effects_print(stdout, &e, spec.program);
    program_note_effects(&e);
    if (max_depth < 0 && desc.max_depth >= 0)
        max_depth = desc.max_depth > 64 ? 64 : desc.max_depth;
    scene_desc_free(&desc);
    if (max_depth < 0)
        max_depth = DEFAULT_MAX_DEPTH;
    camera cam = scene_make_camera(&sc, opts.width, opts.height);
    whitted_context ctx = {&sc, max_depth};
    int status = program_render(&opts, spec.program, whitted_radiance, &ctx, &cam, NULL);
    scene_free(&sc);
    return status;
}

/* 02-whitted: render chapter 02's scene by Whitted-style ray tracing (lecture 13). */
#include <stdio.h>

#include "02-whitted/whitted.h"
#include "cli.h"
#include "effects.h"
#include "program.h"

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
                     extras, 1, "its ray tree (each hit, light, reflected and refracted ray)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    scene sc;
    scene_desc desc;
    int load_status = scene_load_for_program(&sc, &desc, &opts, spec.program, scene_build_whitted_demo,
                                             EFFECT_SHADOWS | EFFECT_REFLECTION | EFFECT_REFRACTION);
    if (load_status != 0)
        return load_status;
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

/* 01-ray-casting: render chapter 01's scene by ray casting (lecture 13). */
#include <stdio.h>

#include "01-ray-casting/ray_casting.h"
#include "cli.h"
#include "effects.h"
#include "program.h"

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch01.exr", 1280, 720, 1);
    cli_spec spec = {"01-ray-casting",
                     "Ray casting (GAMES101 lecture 13): one ray from the eye through each pixel, the closest\n"
                     "hit among a sphere, a plane, a triangle (Moller-Trumbore) and an implicit torus (sphere\n"
                     "tracing), a shadow ray to each point light, and Blinn-Phong shading. The built-in scene\n"
                     "is chapters/01-ray-casting/scenes/default.scene.",
                     NULL, 0, "its rays (camera and shadow rays, each hit and light)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    scene sc;
    scene_desc desc;
    /* Ray casting shows shadows and nothing that needs a second bounce. */
    int load_status = scene_load_for_program(&sc, &desc, &opts, spec.program, scene_build_ray_casting_demo,
                                             EFFECT_SHADOWS);
    if (load_status != 0)
        return load_status;
    scene_desc_free(&desc);
    camera cam = scene_make_camera(&sc, opts.width, opts.height);
    int status = program_render(&opts, spec.program, ray_cast_radiance, &sc, &cam, NULL);
    scene_free(&sc);
    return status;
}

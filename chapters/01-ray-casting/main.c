/* 01-ray-casting: render chapter 01's scene by ray casting (lecture 13). */
#include "cli.h"
#include "program.h"
#include "ray_casting.h"

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch01.exr", 1280, 720, 1);
    cli_spec spec = {"01-ray-casting",
                     "Ray casting (GAMES101 lecture 13): one ray from the eye through each pixel, the closest\n"
                     "hit among a sphere, a plane, a triangle (Moller-Trumbore) and an implicit torus (sphere\n"
                     "tracing), a shadow ray to each point light, and Blinn-Phong shading.",
                     NULL, 0};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    scene sc;
    scene_build_ray_casting_demo(&sc);
    camera cam = scene_make_camera(&sc, opts.width, opts.height);
    int status = program_render(&opts, spec.program, ray_cast_radiance, &sc, &cam, NULL);
    scene_free(&sc);
    return status;
}

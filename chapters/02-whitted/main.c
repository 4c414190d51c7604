/* 02-whitted: render chapter 02's scene by Whitted-style ray tracing (lecture 13). */
#include "cli.h"
#include "program.h"
#include "whitted.h"

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch02.exr", 1280, 720, 1);
    int max_depth = 5;
    cli_flag extras[] = {
        {"--max-depth", CLI_INT, &max_depth, "N",
         "most reflected/refracted rays in a row; deeper ones return black (0..64, default 5)", 0, 64},
    };
    cli_spec spec = {"02-whitted",
                     "Whitted-style ray tracing (GAMES101 lecture 13): ray casting plus recursion. Mirrors\n"
                     "reflect the ray and trace it again; glass splits it into a reflected and a refracted\n"
                     "ray (Snell's law), weighted by the exact Fresnel reflectance; diffuse surfaces stop\n"
                     "with a shadow ray to each point light and Blinn-Phong shading.",
                     extras, 1};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    scene sc;
    scene_build_whitted_demo(&sc);
    camera cam = scene_make_camera(&sc, opts.width, opts.height);
    whitted_context ctx = {&sc, max_depth};
    int status = program_render(&opts, spec.program, whitted_radiance, &ctx, &cam, NULL);
    scene_free(&sc);
    return status;
}

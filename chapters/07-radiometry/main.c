/* 07-radiometry: lectures 14-15 as numbers. Every radiometric quantity of
 * the lectures (solid angle, intensity and flux, irradiance, the BRDF, the
 * reflection equation, the rendering equation as L = E + K L) is computed
 * twice: by deterministic quadrature of its defining integral, and by its
 * closed form. The program prints both, their relative difference and the
 * quadrature's own error estimate (the tables: experiments_radiometry.c).
 *
 * Its picture is a false-colour map of the irradiance on a floor under a
 * square area light (Lambert's polygon formula), with contour lines every
 * 10% of the maximum. With --data DIR it writes the CSV files that the
 * gnuplot scripts plots/ch07_*.gp draw. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

#include "07-radiometry/experiments_radiometry.h"
#include "07-radiometry/radiometry.h"
#include "cli.h"
#include "image.h"
#include "image_file.h"
#include "memory.h"
#include "program.h"
#include "scene_file.h"
#include "timer.h"
#include "vec3.h"
#include "mpi_split.h"

static const char *PROGRAM = "07-radiometry";

/* Gauss-Legendre points per side of each triangle piece, for the check of
 * the picture's closed form against the area integral (as in the tables). */
enum { TRIANGLE_N = 8 };

/* ---- The picture: irradiance on a floor under a square light ---------------- */

/* Viridis (matplotlib's perceptually uniform map), nine sRGB anchors. */
static vec3 false_colour(double t)
{
    static const unsigned char anchors[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                                {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                                {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
    t = fmin(fmax(t, 0.0), 1.0) * 8.0;
    int i = t >= 8.0 ? 7 : (int)t;
    double f = t - i;
    float rgb[3];
    for (int c = 0; c < 3; c++) {
        double srgb = ((1.0 - f) * anchors[i][c] + f * anchors[i + 1][c]) / 255.0;
        /* The image holds linear values; the PNG preview encodes them to sRGB again. */
        rgb[c] = (float)(srgb <= 0.04045 ? srgb / 12.92 : pow((srgb + 0.055) / 1.055, 2.4));
    }
    return vec3_make(rgb[0], rgb[1], rgb[2]);
}

/* Which tenth of the maximum: 0 to 9 (the maximum itself counts as 9, so
 * that it draws no contour of its own). */
static int contour_band(double t) { return t >= 0.9 ? 9 : (int)(10.0 * t); }

/* The light: a unit square at height 0.75, tilted 30 degrees about the x axis. */
static const double LIGHT_TILT = 30.0 * PI / 180.0, LIGHT_HEIGHT = 0.75;

static void floor_light(dvec3 light[4])
{
    const double corners[4][2] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
    for (int i = 0; i < 4; i++)
        light[i] = dvec3_make(corners[i][0], corners[i][1] * cos(LIGHT_TILT),
                              LIGHT_HEIGHT + corners[i][1] * sin(LIGHT_TILT));
}

/* Lambert's closed form at every pixel of the floor z = 0 seen from straight
 * above, `scale` units per pixel; *E_max gets the largest value. */
static double *floor_irradiance(int w, int h, double scale, const dvec3 light[4], double *E_max)
{
    double *E = memory_allocate((size_t)w * (size_t)h, sizeof *E);
    dvec3 up = dvec3_make(0, 0, 1);
    *E_max = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            dvec3 p = dvec3_make((x + 0.5 - 0.5 * w) * scale, (0.5 * h - y - 0.5) * scale, 0.0);
            E[(size_t)y * (size_t)w + (size_t)x] = irradiance_polygon(1.0, light, 4, p, up);
            *E_max = fmax(*E_max, E[(size_t)y * (size_t)w + (size_t)x]);
        }
    return E;
}

/* Contour lines every 10% of the maximum: where the band index changes
 * between a pixel and its right or lower neighbour. The light's outline,
 * seen from straight above, in white. */
static void floor_draw(image *img, const double *E, double E_max, double scale)
{
    int w = img->width, h = img->height;
    double half_x = 0.5, half_y = 0.5 * cos(LIGHT_TILT), half_pixel = 0.5 * scale;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double t = E[(size_t)y * (size_t)w + (size_t)x] / E_max;
            int band = contour_band(t);
            bool edge = (x + 1 < w && contour_band(E[(size_t)y * (size_t)w + (size_t)x + 1] / E_max) != band) ||
                        (y + 1 < h && contour_band(E[(size_t)(y + 1) * (size_t)w + (size_t)x] / E_max) != band);
            double px = fabs((x + 0.5 - 0.5 * w) * scale), py = fabs((0.5 * h - y - 0.5) * scale);
            bool outline = px <= half_x + half_pixel && py <= half_y + half_pixel &&
                           (fabs(px - half_x) <= half_pixel || fabs(py - half_y) <= half_pixel);
            image_set(img, x, y, outline ? vec3_splat(1.0f) : edge ? vec3_splat(0.02f) : false_colour(t));
        }
}

/* What the picture shows, and its closed form checked below the light's
 * centre against the area integral. */
static void floor_report(const cli_options *opts, const dvec3 light[4], double E_max, double seconds)
{
    dvec3 centre = dvec3_make(0, 0, 0), up = dvec3_make(0, 0, 1);
    printf("\nPicture: irradiance on the floor under a unit square light (L = 1) at height %.2f, tilted 30 deg;\n"
           "  viridis from 0 to E_max = %.4f, contour lines every 10%%, the light's outline in white. %dx%d, %.3f s -> %s\n"
           "  E below the light's centre: %.12f (Lambert's polygon formula)\n",
           LIGHT_HEIGHT, E_max, opts->width, opts->height, seconds, opts->out,
           irradiance_polygon(1.0, light, 4, centre, up));
    quadrature_result q1 = irradiance_from_triangle_area(1.0, light[0], light[1], light[2], centre, up, 3, TRIANGLE_N);
    quadrature_result q2 = irradiance_from_triangle_area(1.0, light[0], light[2], light[3], centre, up, 3, TRIANGLE_N);
    printf("                             %.12f (area integral, estimate %.1e)\n", q1.value + q2.value,
           q1.error_estimate + q2.error_estimate);
}

/* The floor z = 0 seen from straight above, 4 units across the wider side,
 * under the tilted square light. */
static bool render_floor(const cli_options *opts)
{
    dvec3 light[4];
    floor_light(light);
    int w = opts->width, h = opts->height;
    double scale = 4.0 / (w > h ? w : h), E_max;
    double start = timer_seconds();
    double *E = floor_irradiance(w, h, scale, light, &E_max);
    image img = image_make(w, h);
    if (img.rgb == NULL) {
        fprintf(stderr, "%s: out of memory for a %dx%d image\n", PROGRAM, w, h);
        free(E);
        return false;
    }
    floor_draw(&img, E, E_max, scale);
    double seconds = timer_seconds() - start;
    char err[IMAGE_ERROR_SIZE];
    ray_counters none = {0}; /* quadrature, not rays: the record is the run's */
    bool ok = image_write(&img, opts->out, opts->exposure, err, sizeof err) &&
              program_write_record(opts, PROGRAM, &none, seconds, err, sizeof err);
    if (!ok)
        fprintf(stderr, "%s: %s\n", PROGRAM, err);
    else if (!opts->quiet)
        floor_report(opts, light, E_max, seconds);
    image_free(&img);
    free(E);
    return ok;
}

/* ---- the program ------------------------------------------------------------ */

/* --rho is read as a double (a float flag would make 0.8 into 0.800000012). */
static bool parse_rho(const char *text, double *rho)
{
    char *end;
    errno = 0;
    *rho = strtod(text, &end);
    if (errno != 0 || end == text || *end != '\0' || !(*rho >= 0.0 && *rho < 1.0)) {
        fprintf(stderr, "%s: --rho: expected an albedo 0 <= X < 1, got '%s'\n(try '%s --help')\n", PROGRAM, text,
                PROGRAM);
        return false;
    }
    return true;
}

/* The tables, the CSV (with --data) and the picture. */
static int run_tables(const cli_options *opts, double rho, int bounces, const char *data_dir)
{
    double start = timer_seconds();
    if (!opts->quiet)
        printf("%s: every quantity by quadrature and in closed form. 'estimate' is the quadrature's own\n"
               "relative error estimate; 'agrees' says |numeric - closed form| <= estimate.\n",
               PROGRAM);
    bool ok = radiometry_experiments_print(rho, bounces, !opts->quiet);
    char err[1024];
    if (data_dir != NULL && !radiometry_experiments_write_csv(data_dir, rho, err, sizeof err)) {
        fprintf(stderr, "%s: %s\n", PROGRAM, err);
        return 1;
    }
    if (!render_floor(opts))
        return 1;
    if (!opts->quiet)
        printf("\n%s: %s, %.2f s%s%s\n", PROGRAM,
               ok ? "every numeric value agrees with its closed form" : "SOME VALUES DISAGREE (see 'NO' above)",
               timer_seconds() - start, data_dir ? "; data in " : "", data_dir ? data_dir : "");
    return ok ? 0 : 1;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch07.exr", 512, 512, 1);
    const char *data_dir = NULL;
    const char *rho_text = "0.8";
    int bounces = 30;
    const cli_flag extras[] = {
        {"--data", CLI_DIR, &data_dir, "DIR", "write ch07_furnace.csv, ch07_disk_irradiance.csv, ch07_albedo.csv there",
         0, 0},
        {"--rho", CLI_STRING, &rho_text, "X", "albedo of the closed furnace, 0 <= X < 1 (default 0.8)", 0, 0},
        {"--bounces", CLI_INT, &bounces, "N", "bounces of the furnace table, 1 to 1000 (default 30)", 1, 1000},
    };
    cli_spec spec = {"07-radiometry",
                     "Radiometry (GAMES101 lectures 14-15): solid angle, intensity, irradiance, radiance, the BRDF,\n"
                     "the reflection equation and the rendering equation L = E + K L. Each quantity is computed by\n"
                     "deterministic quadrature and by its closed form; the table shows both and their difference.\n"
                     "The picture is the irradiance on a floor under a square area light, in false colour.\n"
                     "--scene FILE instead prints the irradiance at the camera's target from the scene's lights,\n"
                     "closed form against quadrature, and writes no image.",
                     extras, 3, NULL};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if (mpi_split_refuse(spec.program, "this program (its tables are quadrature, not a render)"))
        return 2;
    if (opts.explain) {
        fprintf(stderr, "%s: --explain: this chapter traces no rays, so there is no path to explain\n", PROGRAM);
        return 2;
    }
    scene_desc desc;
    if (program_load_scene(&opts, PROGRAM, &desc)) {
        bool scene_ok = radiometry_scene_irradiance(&desc, PROGRAM);
        scene_desc_free(&desc);
        return scene_ok ? 0 : 1;
    }
    double rho;
    if (!parse_rho(rho_text, &rho))
        return 2;
    return run_tables(&opts, rho, bounces, data_dir);
}

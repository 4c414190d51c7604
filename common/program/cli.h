/* cli.h -- the command line every chapter program shares.
 *
 *   --width N --height N --spp N --seed N --threads N --out FILE
 *   --exposure STOPS --scene FILE --explain X,Y --max-input-mb N --quiet --help
 *
 * plus flags of a chapter's own, described in a small table so that --help
 * lists them and parsing checks them the same way.
 *
 * Usage:
 *   cli_options opts = cli_defaults("build/out/ch01.exr", 640, 360, 1);
 *   cli_flag extras[] = { {"--max-depth", CLI_INT, &max_depth, "N", "recursion limit"} };
 *   cli_spec spec = {"01-ray-casting", "Ray casting (lecture 13) ...", extras, 1};
 *   cli_parse_or_exit(argc, argv, &spec, &opts);
 *
 * A flag whose value is one of a few names is a CLI_CHOICE:
 *   static const char *const modes[] = {"fixed", "throughput", NULL};
 *   cli_choice rr = {modes, NULL, 0};        (default: "fixed")
 *   {"--rr", CLI_CHOICE, &rr, NULL, "Russian roulette", 0, 0}
 *   ... rr.index is 0 or 1 after parsing; cli_choice_name(&rr) is the name.
 *
 * A bad flag or value prints one line naming it and exits with status 2.
 */
#ifndef CLI_H
#define CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "camera.h"

typedef struct {
    int width, height;
    int spp;            /* samples per pixel */
    uint64_t seed;
    int threads;        /* 0: as many as OpenMP offers */
    const char *out;    /* .exr (plus a .png preview beside it) or .png */
    float exposure;     /* preview brightness in stops */
    bool quiet;
    const char *scene;  /* --scene FILE (docs/scene-format.md), or NULL: the built-in scene */
    bool explain;       /* --explain X,Y: print the path tree of that pixel */
    int explain_x, explain_y;
    int max_input_mb;   /* --max-input-mb N: the largest OBJ or MTL file read (input_file.h) */
    /* Whether --width, --height, --spp were given: a scene file's image
     * statement applies to those that were not. */
    bool width_given, height_given, spp_given;
    /* Not a flag: set by programs that integrate over the pixel (the path
     * tracer) so that even one sample per pixel lands at a random point
     * inside it, rather than at its centre (see render.h). */
    bool jitter;
    /* Not a flag either: stratified pixel positions (render.h), chapter 10. */
    bool stratify;
    /* --checkpoint FILE, --checkpoint-every SECONDS, --resume FILE
     * (CLI_CHECKPOINT_FLAGS; checkpoint.h). In a program that offers them
     * a long render keeps its state in `checkpoint` (by default the image's
     * name with .checkpoint) every checkpoint_every seconds (default 60),
     * removed when the image is written. */
    const char *checkpoint, *resume;
    float checkpoint_every;
    bool checkpoint_offered; /* not a flag: the program lists them */
} cli_options;

/* CLI_DIR: a directory that must exist and be writable when the flags are
 * read (an output directory for data files), so a typo fails at once rather
 * than after the experiment it was to hold.
 * CLI_CHOICE: one of a list of names (a cli_choice). Anything else is
 * refused with "--flag: unknown 'x' (a, b, c)", here, for every program. */
/* CLI_VEC3: three numbers "X,Y,Z" into a vec3, each within [min, max]. */
typedef enum { CLI_INT, CLI_FLOAT, CLI_STRING, CLI_BOOL, CLI_DIR, CLI_CHOICE, CLI_VEC3 } cli_kind;

/* What a CLI_CHOICE flag points to. The names are the only accepted
 * values; index is the default before parsing (-1: none, for "not given")
 * and the position of the name given after. notes, if not NULL, has one
 * line per name, which --help prints under the flag. */
typedef struct {
    const char *const *names; /* NULL-terminated */
    const char *const *notes; /* NULL, or as many as names */
    int index;
} cli_choice;

/* names[index], or NULL when index is -1. */
const char *cli_choice_name(const cli_choice *c);

typedef struct {
    const char *name;   /* "--max-depth" */
    cli_kind kind;
    void *value;        /* int *, float *, const char ** (STRING, DIR), bool *, cli_choice * */
    const char *metavar;/* "N" in the help text; NULL for CLI_BOOL, and for
                         * CLI_CHOICE to show the names as "a|b|c" */
    const char *help;
    double min, max;    /* accepted range for numbers (inclusive); both 0: any */
} cli_flag;

typedef struct {
    const char *program;
    const char *summary; /* what the program shows, for --help */
    const cli_flag *extras;
    int extra_count;
    /* What --explain X,Y prints in this program, for --help (NULL: it has
     * nothing to explain per pixel, --help does not offer the flag, and
     * the program says why if it is given). */
    const char *explain;
} cli_spec;

typedef enum { CLI_OK, CLI_HELP, CLI_ERROR } cli_status;

cli_options cli_defaults(const char *out, int width, int height, int spp);

/* Parse argv into opts and the extras' values. On CLI_ERROR, err holds one
 * line naming the flag and what was wrong. Also checks that the output file
 * can be created (its directory exists and is writable). */
cli_status cli_parse(int argc, char **argv, const cli_spec *spec, cli_options *opts, char *err, size_t err_size);
/* cli_parse, then: --help prints usage and exits 0; an error prints
 * "program: message" and "try --help", and exits 2. Then applies
 * --max-input-mb, and declares --out, its .png preview and its counters
 * file as outputs no input may be (input_file_protect: reading one of them
 * as input stops the program with status 2). */
void cli_parse_or_exit(int argc, char **argv, const cli_spec *spec, cli_options *opts);
void cli_print_help(const cli_spec *spec, const cli_options *defaults);

/* The camera flags of every program that renders a mesh it was given
 * (--obj, a scene file): three entries for a cli_flag table, filling a
 * camera_override (camera.h) that starts as CAMERA_NOT_OVERRIDDEN. */
#define CLI_CAMERA_FLAGS(o)                                                                                           \
    {"--eye", CLI_VEC3, &(o).eye, "X,Y,Z", "where the camera stands (default: the scene's camera, or one that "    \
                                           "frames the mesh)", -1e7, 1e7},                                          \
        {"--target", CLI_VEC3, &(o).target, "X,Y,Z", "the point it looks at (default: along the scene camera's view)", \
         -1e7, 1e7},                                                                                                 \
        {"--fov", CLI_FLOAT, &(o).vertical_fov_degrees, "DEGREES", "its vertical field of view", 1.0, 179.0}

/* The flags of a program whose long renders keep checkpoints and resume
 * (cli_options' checkpoint, checkpoint_every, resume): three entries for
 * its cli_flag table. */
#define CLI_CHECKPOINT_FLAGS(opts)                                                                                    \
    {"--checkpoint", CLI_STRING, &(opts).checkpoint, "FILE", "keep a long render's state here (default: --out's "   \
                                                             "name with .checkpoint)", 0, 0},                      \
        {"--checkpoint-every", CLI_FLOAT, &(opts).checkpoint_every, "SECONDS",                                        \
         "at least this long between two checkpoints (default 60; 0: after every pass)", 0.0, 1e7},                   \
        {"--resume", CLI_STRING, &(opts).resume, "FILE", "continue the render a checkpoint holds: the same "         \
                                                         "image, bit for bit, as if never stopped", 0, 0}

#endif

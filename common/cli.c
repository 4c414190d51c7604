/* cli.c -- one parser for every chapter program's flags (see cli.h). */
#include "cli.h"

#include "counters.h"
#include "input_file.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifdef _OPENMP
#include <omp.h>
#endif

/* Limits that catch typos (an extra zero) before they become a frozen machine. */
static const int CLI_MAX_IMAGE_SIDE = 16384;
static const int CLI_MAX_SPP = 1 << 20;
static const int CLI_MAX_THREADS = 1024;

cli_options cli_defaults(const char *out, int width, int height, int spp)
{
    cli_options o = {0};
    o.width = width;
    o.height = height;
    o.spp = spp;
    o.seed = 1;
    o.threads = 0;
    o.out = out;
    o.exposure = 0.0f;
    o.quiet = false;
    o.max_input_mb = INPUT_DEFAULT_MESH_MB;
    return o;
}

static bool parse_int(const char *text, long min, long max, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (errno != 0 || end == text || *end != '\0' || v < min || v > max)
        return false;
    *out = (int)v;
    return true;
}

static bool parse_float(const char *text, double min, double max, float *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    /* isfinite: an unranged flag's bounds are +-HUGE_VAL, which "inf" would meet. */
    if (errno != 0 || end == text || *end != '\0' || !isfinite(v) || !(v >= min && v <= max))
        return false;
    *out = (float)v;
    return true;
}

static bool parse_u64(const char *text, uint64_t *out)
{
    char *end;
    errno = 0;
    if (text[0] == '-' || text[0] == '\0')
        return false;
    unsigned long long v = strtoull(text, &end, 0);
    if (errno != 0 || *end != '\0')
        return false;
    *out = (uint64_t)v;
    return true;
}

/* "X,Y": two non-negative whole numbers (checked against the image size
 * once the size is known: a scene file may still change it). */
static bool parse_pixel(const char *text, int *x, int *y)
{
    const char *comma = strchr(text, ',');
    if (comma == NULL || comma - text >= 32)
        return false;
    char first[32];
    snprintf(first, sizeof first, "%.*s", (int)(comma - text), text);
    return parse_int(first, 0, CLI_MAX_IMAGE_SIDE - 1, x) && parse_int(comma + 1, 0, CLI_MAX_IMAGE_SIDE - 1, y);
}

static bool has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

/* Can files be created in `dir`? It must exist, be a directory and be
 * writable. `flag` and `value` name what the user typed, for the message. */
static bool check_directory(const char *flag, const char *value, const char *dir, char *err, size_t err_size)
{
    if (access(dir, F_OK) != 0) {
        snprintf(err, err_size, "%s '%s': directory '%s' does not exist", flag, value, dir);
        return false;
    }
    struct stat info;
    if (stat(dir, &info) != 0 || !S_ISDIR(info.st_mode)) {
        snprintf(err, err_size, "%s '%s': '%s' is not a directory", flag, value, dir);
        return false;
    }
    if (access(dir, W_OK | X_OK) != 0) {
        snprintf(err, err_size, "%s '%s': directory '%s' is not writable", flag, value, dir);
        return false;
    }
    return true;
}

/* Can `path` be created? Its directory must exist and be writable. Checked
 * before rendering, so nobody waits a minute to learn of a typo. */
static bool check_output_path(const char *path, char *err, size_t err_size)
{
    if (!has_suffix(path, ".exr") && !has_suffix(path, ".png")) {
        snprintf(err, err_size, "--out '%s': the output must end in .exr or .png", path);
        return false;
    }
    char dir[PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (slash == NULL)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    return check_directory("--out", path, dir, err, err_size);
}

static bool set_extra(const cli_flag *f, const char *value, char *err, size_t err_size)
{
    bool ranged = !(f->min == 0 && f->max == 0);
    switch (f->kind) {
    case CLI_INT:
        if (!parse_int(value, ranged ? (long)f->min : INT_MIN, ranged ? (long)f->max : INT_MAX, f->value)) {
            if (ranged)
                snprintf(err, err_size, "%s: expected a whole number from %.0f to %.0f, got '%s'", f->name, f->min, f->max,
                         value);
            else
                snprintf(err, err_size, "%s: expected a whole number, got '%s'", f->name, value);
            return false;
        }
        return true;
    case CLI_FLOAT:
        if (!parse_float(value, ranged ? f->min : -HUGE_VAL, ranged ? f->max : HUGE_VAL, f->value)) {
            if (ranged)
                snprintf(err, err_size, "%s: expected a number from %g to %g, got '%s'", f->name, f->min, f->max, value);
            else
                snprintf(err, err_size, "%s: expected a finite number, got '%s'", f->name, value);
            return false;
        }
        return true;
    case CLI_STRING:
        *(const char **)f->value = value;
        return true;
    case CLI_DIR:
        if (value[0] == '\0') {
            snprintf(err, err_size, "%s: expected a directory, got ''", f->name);
            return false;
        }
        if (!check_directory(f->name, value, value, err, err_size))
            return false;
        *(const char **)f->value = value;
        return true;
    case CLI_BOOL:
        break;
    }
    return false;
}

cli_status cli_parse(int argc, char **argv, const cli_spec *spec, cli_options *opts, char *err, size_t err_size)
{
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0)
            return CLI_HELP;
        if (strcmp(arg, "--quiet") == 0 || strcmp(arg, "-q") == 0) {
            opts->quiet = true;
            continue;
        }
        bool handled = false;
        for (int k = 0; k < spec->extra_count; k++) {
            const cli_flag *f = &spec->extras[k];
            if (f->kind == CLI_BOOL && strcmp(arg, f->name) == 0) {
                *(bool *)f->value = true;
                handled = true;
            }
        }
        if (handled)
            continue;

        /* Every other flag takes a value: "--name value" or "--name=value". */
        char name[64];
        const char *value = NULL;
        const char *equals = strchr(arg, '=');
        if (strncmp(arg, "--", 2) != 0) {
            snprintf(err, err_size, "unexpected argument '%s' (flags start with --)", arg);
            return CLI_ERROR;
        }
        if (equals != NULL) {
            snprintf(name, sizeof name, "%.*s", (int)(equals - arg), arg);
            value = equals + 1;
        } else {
            snprintf(name, sizeof name, "%s", arg);
        }

        const cli_flag *extra = NULL;
        for (int k = 0; k < spec->extra_count; k++)
            if (spec->extras[k].kind != CLI_BOOL && strcmp(name, spec->extras[k].name) == 0)
                extra = &spec->extras[k];
        bool core = strcmp(name, "--width") == 0 || strcmp(name, "--height") == 0 || strcmp(name, "--spp") == 0 ||
                    strcmp(name, "--seed") == 0 || strcmp(name, "--threads") == 0 || strcmp(name, "--out") == 0 ||
                    strcmp(name, "--exposure") == 0 || strcmp(name, "--scene") == 0 ||
                    strcmp(name, "--explain") == 0 || strcmp(name, INPUT_LIMIT_FLAG) == 0;
        if (!core && extra == NULL) {
            snprintf(err, err_size, "unknown flag '%s'", name);
            return CLI_ERROR;
        }
        if (value == NULL) {
            if (i + 1 >= argc) {
                snprintf(err, err_size, "%s needs a value", name);
                return CLI_ERROR;
            }
            value = argv[++i];
        }

        if (extra != NULL) {
            if (!set_extra(extra, value, err, err_size))
                return CLI_ERROR;
        } else if (strcmp(name, "--width") == 0 || strcmp(name, "--height") == 0) {
            int *dst = name[2] == 'w' ? &opts->width : &opts->height;
            *(name[2] == 'w' ? &opts->width_given : &opts->height_given) = true;
            if (!parse_int(value, 1, CLI_MAX_IMAGE_SIDE, dst)) {
                snprintf(err, err_size, "%s: expected a whole number of pixels from 1 to %d, got '%s'", name,
                         CLI_MAX_IMAGE_SIDE, value);
                return CLI_ERROR;
            }
        } else if (strcmp(name, "--spp") == 0) {
            if (!parse_int(value, 1, CLI_MAX_SPP, &opts->spp)) {
                snprintf(err, err_size, "--spp: expected samples per pixel from 1 to %d, got '%s'", CLI_MAX_SPP, value);
                return CLI_ERROR;
            }
            opts->spp_given = true;
        } else if (strcmp(name, "--scene") == 0) {
            if (value[0] == '\0') {
                snprintf(err, err_size, "--scene: expected a file name");
                return CLI_ERROR;
            }
            opts->scene = value;
        } else if (strcmp(name, "--explain") == 0) {
            if (!parse_pixel(value, &opts->explain_x, &opts->explain_y)) {
                snprintf(err, err_size, "--explain: expected a pixel as X,Y (two whole numbers >= 0), got '%s'", value);
                return CLI_ERROR;
            }
            opts->explain = true;
        } else if (strcmp(name, INPUT_LIMIT_FLAG) == 0) {
            if (!parse_int(value, 1, INPUT_MAX_MESH_MB, &opts->max_input_mb)) {
                snprintf(err, err_size, "%s: expected megabytes from 1 to %d, got '%s'", name, INPUT_MAX_MESH_MB, value);
                return CLI_ERROR;
            }
        } else if (strcmp(name, "--threads") == 0) {
            if (!parse_int(value, 1, CLI_MAX_THREADS, &opts->threads)) {
                snprintf(err, err_size, "--threads: expected a thread count from 1 to %d, got '%s'", CLI_MAX_THREADS, value);
                return CLI_ERROR;
            }
        } else if (strcmp(name, "--seed") == 0) {
            if (!parse_u64(value, &opts->seed)) {
                snprintf(err, err_size, "--seed: expected a non-negative whole number, got '%s'", value);
                return CLI_ERROR;
            }
        } else if (strcmp(name, "--exposure") == 0) {
            if (!parse_float(value, -64.0, 64.0, &opts->exposure)) {
                snprintf(err, err_size, "--exposure: expected stops from -64 to 64, got '%s'", value);
                return CLI_ERROR;
            }
        } else { /* --out */
            opts->out = value;
        }
    }
    if (!check_output_path(opts->out, err, err_size))
        return CLI_ERROR;
    return CLI_OK;
}

static const char *kind_metavar(const cli_flag *f)
{
    if (f->metavar != NULL)
        return f->metavar;
    return f->kind == CLI_INT      ? "N"
           : f->kind == CLI_FLOAT  ? "X"
           : f->kind == CLI_STRING ? "TEXT"
           : f->kind == CLI_DIR    ? "DIR"
                                   : "";
}

void cli_print_help(const cli_spec *spec, const cli_options *d)
{
    printf("usage: %s [flags]\n\n%s\n\n", spec->program, spec->summary);
    printf("flags shared by every chapter program:\n");
    printf("  --width N        image width in pixels (default %d)\n", d->width);
    printf("  --height N       image height in pixels (default %d)\n", d->height);
    printf("  --spp N          samples per pixel (default %d; 1 = one ray through each pixel centre)\n", d->spp);
    printf("  --seed N         random seed: the same seed gives the same image (default %llu)\n",
           (unsigned long long)d->seed);
    printf("  --threads N      OpenMP threads (default: all cores); the image does not depend on it\n");
    printf("  --out FILE       .exr writes the EXR and a .png preview beside it; .png the preview only\n");
    printf("                   (default %s)\n", d->out);
    printf("  --exposure X     preview brightness in stops, 2^X (default %g)\n", (double)d->exposure);
    printf("  --scene FILE     render a scene file instead of the built-in scene (docs/scene-format.md)\n");
    printf("  --explain X,Y    print the path tree of pixel (X, Y) -- every ray, hit, light sample and\n");
    printf("                   Russian roulette decision -- instead of rendering the image\n");
    printf("  --max-input-mb N the largest OBJ or MTL file read, in MB of 2^20 bytes (default %d)\n", d->max_input_mb);
    printf("  --quiet          no progress line and no report\n");
    printf("  --help           this text\n");
    if (spec->extra_count > 0) {
        printf("\nflags of %s:\n", spec->program);
        for (int k = 0; k < spec->extra_count; k++) {
            const cli_flag *f = &spec->extras[k];
            char left[64];
            snprintf(left, sizeof left, "%s %s", f->name, kind_metavar(f));
            printf("  %-16s %s\n", left, f->help);
        }
    }
}

void cli_parse_or_exit(int argc, char **argv, const cli_spec *spec, cli_options *opts)
{
    cli_options defaults = *opts;
    char err[512];
    switch (cli_parse(argc, argv, spec, opts, err, sizeof err)) {
    case CLI_OK:
        break;
    case CLI_HELP:
        cli_print_help(spec, &defaults);
        exit(0);
    case CLI_ERROR:
        fprintf(stderr, "%s: %s\n(try '%s --help')\n", spec->program, err, spec->program);
        exit(2);
    }
    /* Inputs are bounded, and none may be a file this run writes. */
    input_file_set_mesh_limit((uint64_t)opts->max_input_mb << 20);
    char sidecar[PATH_MAX];
    input_file_protect(spec->program, "--out", opts->out, opts->out, "");
    if (has_suffix(opts->out, ".exr")) {
        snprintf(sidecar, sizeof sidecar, "%.*s.png", (int)strlen(opts->out) - 4, opts->out);
        input_file_protect(spec->program, "--out", opts->out, sidecar, "its .png preview");
    }
    counters_path_for_image(opts->out, sidecar, sizeof sidecar);
    input_file_protect(spec->program, "--out", opts->out, sidecar, "its counters file");
#ifdef _OPENMP
    if (opts->threads == 0)
        opts->threads = omp_get_max_threads();
#else
    opts->threads = 1;
#endif
}

/* cli.c -- one parser for every chapter program's flags (see cli.h). */
#include "cli.h"

#include "checkpoint.h"
#include "counters.h"
#include "counters_file.h"
#include "input_file.h"
#include "mpi_split.h"
#include "run_record.h"

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
    o.checkpoint_every = 60.0f;
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

const char *cli_choice_name(const cli_choice *c)
{
    return c->index >= 0 ? c->names[c->index] : NULL;
}

/* "--flag: unknown 'x' (a, b, c)": the one message every choice flag gives. */
static bool set_choice(const cli_flag *f, const char *value, char *err, size_t err_size)
{
    cli_choice *c = f->value;
    for (int k = 0; c->names[k] != NULL; k++)
        if (strcmp(value, c->names[k]) == 0) {
            c->index = k;
            return true;
        }
    int n = snprintf(err, err_size, "%s: unknown '%s' (", f->name, value);
    for (int k = 0; c->names[k] != NULL && n >= 0 && (size_t)n < err_size; k++)
        n += snprintf(err + n, err_size - (size_t)n, "%s%s", k > 0 ? ", " : "", c->names[k]);
    if (n >= 0 && (size_t)n < err_size)
        snprintf(err + n, err_size - (size_t)n, ")");
    return false;
}

static bool set_int(const cli_flag *f, const char *value, char *err, size_t err_size)
{
    bool ranged = !(f->min == 0 && f->max == 0);
    if (parse_int(value, ranged ? (long)f->min : INT_MIN, ranged ? (long)f->max : INT_MAX, f->value))
        return true;
    if (ranged)
        snprintf(err, err_size, "%s: expected a whole number from %.0f to %.0f, got '%s'", f->name, f->min, f->max,
                 value);
    else
        snprintf(err, err_size, "%s: expected a whole number, got '%s'", f->name, value);
    return false;
}

static bool set_float(const cli_flag *f, const char *value, char *err, size_t err_size)
{
    bool ranged = !(f->min == 0 && f->max == 0);
    if (parse_float(value, ranged ? f->min : -HUGE_VAL, ranged ? f->max : HUGE_VAL, f->value))
        return true;
    if (ranged)
        snprintf(err, err_size, "%s: expected a number from %g to %g, got '%s'", f->name, f->min, f->max, value);
    else
        snprintf(err, err_size, "%s: expected a finite number, got '%s'", f->name, value);
    return false;
}

/* "X,Y,Z": three numbers within [min, max], nothing else. */
static bool set_vec3(const cli_flag *f, const char *value, char *err, size_t err_size)
{
    float c[3];
    char part[64];
    const char *p = value;
    for (int k = 0; k < 3; k++) {
        const char *end = k < 2 ? strchr(p, ',') : p + strlen(p);
        if (end == NULL || end - p >= (long)sizeof part)
            break;
        snprintf(part, sizeof part, "%.*s", (int)(end - p), p);
        if (!parse_float(part, f->min, f->max, &c[k]))
            break;
        if (k == 2) {
            *(vec3 *)f->value = vec3_make(c[0], c[1], c[2]);
            return true;
        }
        p = end + 1;
    }
    snprintf(err, err_size, "%s: expected three numbers X,Y,Z from %g to %g, got '%s'", f->name, f->min, f->max,
             value);
    return false;
}

static bool set_extra(const cli_flag *f, const char *value, char *err, size_t err_size)
{
    switch (f->kind) {
    case CLI_VEC3:
        return set_vec3(f, value, err, err_size);
    case CLI_INT:
        return set_int(f, value, err, err_size);
    case CLI_FLOAT:
        return set_float(f, value, err, err_size);
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
    case CLI_CHOICE:
        return set_choice(f, value, err, err_size);
    case CLI_BOOL:
        break;
    }
    return false;
}

/* One of the flags every program has, given its value. */
static bool set_core(cli_options *opts, const char *name, const char *value, char *err, size_t err_size)
{
    if (strcmp(name, "--width") == 0 || strcmp(name, "--height") == 0) {
        bool width = name[2] == 'w';
        *(width ? &opts->width_given : &opts->height_given) = true;
        if (parse_int(value, 1, CLI_MAX_IMAGE_SIDE, width ? &opts->width : &opts->height))
            return true;
        snprintf(err, err_size, "%s: expected a whole number of pixels from 1 to %d, got '%s'", name,
                 CLI_MAX_IMAGE_SIDE, value);
    } else if (strcmp(name, "--spp") == 0) {
        if (parse_int(value, 1, CLI_MAX_SPP, &opts->spp))
            return opts->spp_given = true;
        snprintf(err, err_size, "--spp: expected samples per pixel from 1 to %d, got '%s'", CLI_MAX_SPP, value);
    } else if (strcmp(name, "--scene") == 0) {
        if (value[0] != '\0') {
            opts->scene = value;
            return true;
        }
        snprintf(err, err_size, "--scene: expected a file name");
    } else if (strcmp(name, "--explain") == 0) {
        if (parse_pixel(value, &opts->explain_x, &opts->explain_y))
            return opts->explain = true;
        snprintf(err, err_size, "--explain: expected a pixel as X,Y (two whole numbers >= 0), got '%s'", value);
    } else if (strcmp(name, INPUT_LIMIT_FLAG) == 0) {
        if (parse_int(value, 1, INPUT_MAX_MESH_MB, &opts->max_input_mb))
            return true;
        snprintf(err, err_size, "%s: expected megabytes from 1 to %d, got '%s'", name, INPUT_MAX_MESH_MB, value);
    } else if (strcmp(name, "--threads") == 0) {
        if (parse_int(value, 1, CLI_MAX_THREADS, &opts->threads))
            return true;
        snprintf(err, err_size, "--threads: expected a thread count from 1 to %d, got '%s'", CLI_MAX_THREADS, value);
    } else if (strcmp(name, "--seed") == 0) {
        if (parse_u64(value, &opts->seed))
            return true;
        snprintf(err, err_size, "--seed: expected a non-negative whole number, got '%s'", value);
    } else if (strcmp(name, "--exposure") == 0) {
        if (parse_float(value, -64.0, 64.0, &opts->exposure))
            return true;
        snprintf(err, err_size, "--exposure: expected stops from -64 to 64, got '%s'", value);
    } else { /* --out */
        opts->out = value;
        return true;
    }
    return false;
}

static bool is_core_flag(const char *name)
{
    static const char *const core[] = {"--width", "--height",   "--spp",   "--seed",    "--threads",
                                       "--out",   "--exposure", "--scene", "--explain", INPUT_LIMIT_FLAG, NULL};
    for (int k = 0; core[k] != NULL; k++)
        if (strcmp(name, core[k]) == 0)
            return true;
    return false;
}

/* The chapter's flag called `name`: a switch (CLI_BOOL) or one that takes a value. */
static const cli_flag *find_extra(const cli_spec *spec, const char *name, bool is_switch)
{
    for (int k = 0; k < spec->extra_count; k++)
        if ((spec->extras[k].kind == CLI_BOOL) == is_switch && strcmp(name, spec->extras[k].name) == 0)
            return &spec->extras[k];
    return NULL;
}

/* One flag that takes a value, "--name value" or "--name=value", starting
 * at argv[*i]; *i moves past its value. */
static bool parse_valued(int argc, char **argv, int *i, const cli_spec *spec, cli_options *opts, char *err,
                         size_t err_size)
{
    const char *arg = argv[*i];
    if (strncmp(arg, "--", 2) != 0) {
        snprintf(err, err_size, "unexpected argument '%s' (flags start with --)", arg);
        return false;
    }
    char name[64];
    const char *value = NULL;
    const char *equals = strchr(arg, '=');
    if (equals != NULL) {
        snprintf(name, sizeof name, "%.*s", (int)(equals - arg), arg);
        value = equals + 1;
    } else {
        snprintf(name, sizeof name, "%s", arg);
    }
    const cli_flag *extra = find_extra(spec, name, false);
    if (extra == NULL && !is_core_flag(name)) {
        snprintf(err, err_size, "unknown flag '%s'", name);
        return false;
    }
    if (value == NULL) {
        if (*i + 1 >= argc) {
            snprintf(err, err_size, "%s needs a value", name);
            return false;
        }
        value = argv[++*i];
    }
    return extra != NULL ? set_extra(extra, value, err, err_size) : set_core(opts, name, value, err, err_size);
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
        const cli_flag *on_off = find_extra(spec, arg, true);
        if (on_off != NULL)
            *(bool *)on_off->value = true;
        else if (!parse_valued(argc, argv, &i, spec, opts, err, err_size))
            return CLI_ERROR;
    }
    if (!check_output_path(opts->out, err, err_size))
        return CLI_ERROR;
    return CLI_OK;
}

/* The left column of a chapter flag's help line: its name and what its value
 * looks like; a choice without a metavar shows its names, "a|b|c". */
static void flag_usage(const cli_flag *f, char *out, size_t size)
{
    int n = snprintf(out, size, "%s ", f->name);
    if (f->kind == CLI_CHOICE && f->metavar == NULL) {
        const cli_choice *c = f->value;
        for (int k = 0; c->names[k] != NULL && n >= 0 && (size_t)n < size; k++)
            n += snprintf(out + n, size - (size_t)n, "%s%s", k > 0 ? "|" : "", c->names[k]);
        return;
    }
    const char *metavar = f->metavar != NULL ? f->metavar
                          : f->kind == CLI_INT    ? "N"
                          : f->kind == CLI_FLOAT  ? "X"
                          : f->kind == CLI_STRING ? "TEXT"
                          : f->kind == CLI_DIR    ? "DIR"
                          : f->kind == CLI_CHOICE ? "NAME"
                          : f->kind == CLI_VEC3   ? "X,Y,Z"
                                                  : "";
    snprintf(out + n, size - (size_t)n, "%s", metavar);
}

/* Under a choice flag's help line: each name with its note, or, when the
 * usage column did not already show them, the names. */
static void print_choices(const cli_flag *f)
{
    const cli_choice *c = f->value;
    if (c->notes != NULL) {
        int width = 0;
        for (int k = 0; c->names[k] != NULL; k++)
            width = (int)strlen(c->names[k]) > width ? (int)strlen(c->names[k]) : width;
        for (int k = 0; c->names[k] != NULL; k++)
            printf("                     %-*s  %s\n", width, c->names[k], c->notes[k]);
    } else if (f->metavar != NULL) {
        printf("                   one of:");
        for (int k = 0; c->names[k] != NULL; k++)
            printf("%s %s", k > 0 ? "," : "", c->names[k]);
        printf("\n");
    }
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
    if (spec->explain != NULL)
        printf("  --explain X,Y    instead of rendering, print for pixel (X, Y) %s\n", spec->explain);
    printf("  --max-input-mb N the largest OBJ or MTL file read, in MB of 2^20 bytes (default %d)\n", d->max_input_mb);
    printf("  --quiet          no progress line and no report\n");
    printf("  --help           this text\n");
    if (spec->extra_count > 0)
        printf("\nflags of %s:\n", spec->program);
    for (int k = 0; k < spec->extra_count; k++) {
        const cli_flag *f = &spec->extras[k];
        char left[256];
        flag_usage(f, left, sizeof left);
        printf("  %-16s %s\n", left, f->help);
        if (f->kind == CLI_CHOICE)
            print_choices(f);
    }
}

/* A program that offers --resume: where its checkpoints go (by default
 * beside the image; with --resume, over the file resumed), which no input
 * may be; and the file resumed must not be one the run writes either. */
static void protect_checkpoint(const cli_spec *spec, cli_options *opts)
{
    static char default_path[PATH_MAX];
    char err[512];
    const size_t err_size = sizeof err;
    opts->checkpoint_offered = find_extra(spec, "--resume", false) != NULL;
    if (!opts->checkpoint_offered)
        return;
    if (opts->resume != NULL)
        input_file_check_not_output(opts->resume);
    if (opts->checkpoint != NULL) { /* its directory must be there and writable, as --out's */
        char dir[PATH_MAX];
        const char *slash = strrchr(opts->checkpoint, '/');
        snprintf(dir, sizeof dir, "%.*s", slash == NULL ? 1 : slash == opts->checkpoint ? 1 : (int)(slash - opts->checkpoint),
                 slash == NULL ? "." : opts->checkpoint);
        if (!check_directory("--checkpoint", opts->checkpoint, dir, err, err_size)) {
            fprintf(stderr, "%s: %s\n(try '%s --help')\n", spec->program, err, spec->program);
            exit(2);
        }
    }
    if (opts->checkpoint == NULL && opts->resume != NULL) {
        opts->checkpoint = opts->resume;
    } else if (opts->checkpoint == NULL) {
        checkpoint_path_for_image(opts->out, default_path, sizeof default_path);
        opts->checkpoint = default_path;
    }
    input_file_protect(spec->program, "--checkpoint", opts->checkpoint, opts->checkpoint, "");
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
    run_record_command(argc, argv, opts);
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
    protect_checkpoint(spec, opts);
#ifdef _OPENMP
    if (opts->threads == 0)
        opts->threads = omp_get_max_threads();
    /* Everything else the program runs in parallel (building its trees)
     * takes --threads too, not only the render. */
    omp_set_num_threads(opts->threads);
#else
    opts->threads = 1;
#endif
    /* Under mpirun: every rank but 0 renders its rows and says nothing. */
    mpi_split_begin();
    if (!mpi_split_is_root())
        opts->quiet = true;
}

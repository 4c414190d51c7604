/* scene_file.c -- the scene file parser (see scene_file.h and
 * docs/scene-format.md for the grammar).
 *
 * Hand-written rather than generated or borrowed: the grammar is one
 * statement per line, "keyword [kind] key value ...", which a 30-line
 * tokenizer and one table of keys per statement cover. No Debian library
 * parses a custom grammar this small (a JSON/YAML/TOML library would impose
 * its own syntax on learners and still leave every check below to us), and a
 * parser generator would add a build step for less code than it replaces.
 *
 * Every statement is parsed in two steps: its key-value pairs are read into
 * a table (unknown keys, repeated keys, missing values and bad numbers are
 * errors here, with the token's column), then the statement's own function
 * checks what the keys mean together and appends to the description. Any
 * error frees everything, so a caller never sees half a scene. The
 * description itself, once read (made empty, freed, its meshes loaded, its
 * kinds named), is scene_desc.c.
 */
#include "scene_file.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"
#include "memory.h"

/* Coordinates and colours beyond these are typos, not scenes (and float
 * arithmetic on them would overflow to Inf in a ray-sphere test). */
static const double SCENE_MAX_COORDINATE = 1e7;
static const double SCENE_MAX_RADIANCE = 1e9;
/* The smallest length a shape or a checker square may have: below it a
 * length is a typo (or 0), and at 1e7 from the origin it is already below
 * one float step. */
static const double SCENE_MIN_LENGTH = 1e-6;
/* The smallest GGX alpha a glossy material may have (docs/scene-format.md):
 * below it the lobe (about α radians wide) is narrower than a pixel at any
 * usual field of view, so it renders as a mirror, while its peak density
 * 1 / (π α²) grows without bound and the MIS weights with it: a mirror is
 * the kind for that. */
static const double SCENE_MIN_ROUGHNESS = 1e-3;
/* A camera's vertical field of view in degrees: open, and short of 180 where
 * tan(fov / 2), the image plane's half height, goes to infinity. */
static const double SCENE_MIN_FOV = 0.01, SCENE_MAX_FOV = 179.0;

enum { MAX_TOKENS = 64, MAX_KEYS = 16 };

/* ---- tokens ------------------------------------------------------------------ */

typedef struct {
    const char *text; /* not NUL-terminated */
    int length;
    int column;       /* 1-based */
    bool quoted;      /* "a string", text without the quotes */
} token;

typedef struct {
    const char *name;
    int line;
    char *err;
    size_t err_size;
    bool recognised; /* a statement was read: the file is a scene file */
} parse_context;

static bool fail(const parse_context *pc, int column, const char *format, ...)
{
    char message[SCENE_ERROR_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    snprintf(pc->err, pc->err_size, "%s:%d:%d: %s", pc->name, pc->line, column, message);
    return false;
}

static bool token_is(const token *t, const char *word)
{
    return !t->quoted && (int)strlen(word) == t->length && strncmp(t->text, word, (size_t)t->length) == 0;
}

/* Splits one line into tokens: words separated by blanks, "quoted strings"
 * (no escapes; for paths with spaces), and a '#' comment to the end. */
static bool tokenize(const parse_context *pc, const char *line, int length, token *tokens, int *count)
{
    *count = 0;
    int i = 0;
    while (i < length) {
        char c = line[i];
        if (c == ' ' || c == '\t' || c == '\r') {
            i++;
            continue;
        }
        if (c == '#')
            break;
        if (*count >= MAX_TOKENS)
            return fail(pc, i + 1, "too many words on one line (at most %d)", MAX_TOKENS);
        token *t = &tokens[(*count)++];
        t->column = i + 1;
        if (c == '"') {
            int start = ++i;
            while (i < length && line[i] != '"')
                i++;
            if (i >= length)
                return fail(pc, t->column, "unterminated string (a '\"' is missing)");
            t->text = line + start;
            t->length = i - start;
            t->quoted = true;
            i++;
            continue;
        }
        if ((unsigned char)c < 32 || (unsigned char)c >= 127)
            return fail(pc, i + 1, "unexpected character (byte 0x%02x): scene files are plain ASCII",
                        (unsigned)(unsigned char)c);
        int start = i;
        while (i < length && line[i] != ' ' && line[i] != '\t' && line[i] != '\r' && line[i] != '#' &&
               line[i] != '"' && (unsigned char)line[i] >= 32 && (unsigned char)line[i] < 127)
            i++;
        t->text = line + start;
        t->length = i - start;
        t->quoted = false;
    }
    return true;
}

/* A number: decimal only (no hex, no "inf" or "nan"), finite, in [min, max]. */
static bool parse_number(const parse_context *pc, const token *t, double min, double max, double *out)
{
    char buffer[64];
    if (t->quoted || t->length == 0 || t->length >= (int)sizeof buffer)
        return fail(pc, t->column, "expected a number, got '%.*s'", t->length > 40 ? 40 : t->length, t->text);
    for (int k = 0; k < t->length; k++) {
        char c = t->text[k];
        if (!((c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'))
            return fail(pc, t->column, "expected a number, got '%.*s'", t->length, t->text);
    }
    memcpy(buffer, t->text, (size_t)t->length);
    buffer[t->length] = '\0';
    char *end;
    errno = 0;
    double v = strtod(buffer, &end);
    if (end != buffer + t->length)
        return fail(pc, t->column, "expected a number, got '%s'", buffer);
    if (errno == ERANGE || !isfinite(v))
        return fail(pc, t->column, "number '%s' is out of range", buffer);
    if (!(v >= min && v <= max))
        return fail(pc, t->column, "%s must be from %g to %g", buffer, min, max);
    *out = v;
    return true;
}

/* ---- keys --------------------------------------------------------------------- */

typedef enum { ARG_VEC3, ARG_NUMBER, ARG_INT, ARG_WORD, ARG_STRING, ARG_FLAG } arg_kind;

typedef struct {
    const char *key;
    arg_kind kind;
    double min, max; /* for numbers (each component of a vec3) */
} key_spec;

typedef struct {
    bool present;
    int column;       /* of the key */
    int value_column; /* of its (first) value */
    double v[3];
    char text[SCENE_PATH_SIZE];
} key_value;

/* Reads "key value key value ..." from tokens[first..count) against spec. */
static bool parse_keys(const parse_context *pc, const token *tokens, int first, int count, const key_spec *spec,
                       int spec_count, key_value *values, const char *statement)
{
    memset(values, 0, sizeof(key_value) * (size_t)spec_count);
    int i = first;
    while (i < count) {
        const token *t = &tokens[i];
        int k = 0;
        while (k < spec_count && !token_is(t, spec[k].key))
            k++;
        if (k == spec_count) {
            char known[512] = "";
            for (int j = 0; j < spec_count; j++) {
                size_t used = strlen(known);
                snprintf(known + used, sizeof known - used, "%s%s", j ? ", " : "", spec[j].key);
            }
            return fail(pc, t->column, "unknown key '%.*s' for %s (known: %s)", t->length > 40 ? 40 : t->length,
                        t->text, statement, known);
        }
        if (values[k].present)
            return fail(pc, t->column, "'%s' given twice", spec[k].key);
        values[k].present = true;
        values[k].column = t->column;
        i++;
        values[k].value_column = i < count ? tokens[i].column : t->column;
        int needed = spec[k].kind == ARG_VEC3 ? 3 : spec[k].kind == ARG_FLAG ? 0 : 1;
        if (count - i < needed)
            return fail(pc, t->column, "'%s' needs %d value%s", spec[k].key, needed, needed > 1 ? "s" : "");
        switch (spec[k].kind) {
        case ARG_VEC3:
            for (int c = 0; c < 3; c++)
                if (!parse_number(pc, &tokens[i + c], spec[k].min, spec[k].max, &values[k].v[c]))
                    return false;
            break;
        case ARG_NUMBER:
            if (!parse_number(pc, &tokens[i], spec[k].min, spec[k].max, &values[k].v[0]))
                return false;
            break;
        case ARG_INT:
            if (!parse_number(pc, &tokens[i], spec[k].min, spec[k].max, &values[k].v[0]))
                return false;
            if (values[k].v[0] != floor(values[k].v[0]))
                return fail(pc, tokens[i].column, "'%s' must be a whole number", spec[k].key);
            break;
        case ARG_WORD:
        case ARG_STRING:
            if (spec[k].kind == ARG_WORD && tokens[i].quoted)
                return fail(pc, tokens[i].column, "'%s' takes a name, not a quoted string", spec[k].key);
            if (tokens[i].length >= (spec[k].kind == ARG_WORD ? SCENE_NAME_SIZE : SCENE_PATH_SIZE))
                return fail(pc, tokens[i].column, "'%s': value too long", spec[k].key);
            if (tokens[i].length == 0)
                return fail(pc, tokens[i].column, "'%s': empty value", spec[k].key);
            memcpy(values[k].text, tokens[i].text, (size_t)tokens[i].length);
            values[k].text[tokens[i].length] = '\0';
            break;
        case ARG_FLAG:
            break;
        }
        i += needed;
    }
    return true;
}

static vec3 value_vec3(const key_value *v) { return vec3_make((float)v->v[0], (float)v->v[1], (float)v->v[2]); }

static bool require(const parse_context *pc, const key_value *values, const key_spec *spec, int k, int column,
                    const char *statement)
{
    if (!values[k].present)
        return fail(pc, column, "%s needs '%s'", statement, spec[k].key);
    return true;
}

#define COORD -SCENE_MAX_COORDINATE, SCENE_MAX_COORDINATE
#define RADIANCE 0.0, SCENE_MAX_RADIANCE
#define REFLECTANCE 0.0, 1.0

/* ---- the description ---------------------------------------------------------- */

static int find_material(const scene_desc *d, const char *name)
{
    for (int i = 0; i < d->material_count; i++)
        if (strcmp(d->materials[i].name, name) == 0)
            return i;
    return -1;
}

static bool resolve_material(const parse_context *pc, const scene_desc *d, const key_value *v, int *out)
{
    *out = find_material(d, v->text);
    if (*out < 0)
        return fail(pc, v->value_column, "unknown material '%s' (define it with 'material %s KIND ...' before using it)",
                    v->text, v->text);
    return true;
}

static bool add_shape(const parse_context *pc, scene_desc *d, scene_shape *s, int column)
{
    if (d->shape_count >= SCENE_MAX_SHAPES) {
        free(s->path);
        return fail(pc, column, "too many shapes (at most %d)", SCENE_MAX_SHAPES);
    }
    s->line = pc->line;
    s->column = column;
    d->shapes = memory_grow(d->shapes, &d->shape_capacity, d->shape_count + 1, sizeof *s);
    d->shapes[d->shape_count++] = *s;
    return true;
}

/* ---- statements ---------------------------------------------------------------- */

static bool statement_camera(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    static const key_spec spec[] = {
        {"eye", ARG_VEC3, COORD}, {"target", ARG_VEC3, COORD}, {"up", ARG_VEC3, COORD}, {"fov", ARG_NUMBER, SCENE_MIN_FOV, SCENE_MAX_FOV}};
    key_value v[4];
    if (d->has_camera)
        return fail(pc, t[0].column, "a second camera (a scene has one)");
    if (!parse_keys(pc, t, 1, n, spec, 4, v, "camera") || !require(pc, v, spec, 0, t[0].column, "camera") ||
        !require(pc, v, spec, 1, t[0].column, "camera"))
        return false;
    d->eye = value_vec3(&v[0]);
    d->target = value_vec3(&v[1]);
    if (v[2].present)
        d->up = value_vec3(&v[2]);
    if (v[3].present)
        d->fov_degrees = (float)v[3].v[0];
    vec3 forward = vec3_sub(d->target, d->eye);
    if (vec3_length_squared(forward) == 0.0f)
        return fail(pc, v[1].column, "the camera's target is its eye: no direction to look in");
    if (vec3_length_squared(vec3_cross(forward, d->up)) == 0.0f)
        return fail(pc, v[2].present ? v[2].column : t[0].column,
                    "'up' is zero or parallel to the viewing direction: the image's rotation is undefined");
    d->has_camera = true;
    return true;
}

static bool statement_image(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    static const key_spec spec[] = {
        {"width", ARG_INT, 1, 16384}, {"height", ARG_INT, 1, 16384}, {"spp", ARG_INT, 1, 1 << 20}};
    key_value v[3];
    if (!parse_keys(pc, t, 1, n, spec, 3, v, "image"))
        return false;
    if ((v[0].present && d->has_width) || (v[1].present && d->has_height) || (v[2].present && d->has_spp))
        return fail(pc, t[0].column, "image size or samples given twice");
    if (v[0].present)
        d->width = (int)v[0].v[0], d->has_width = true;
    if (v[1].present)
        d->height = (int)v[1].v[0], d->has_height = true;
    if (v[2].present)
        d->spp = (int)v[2].v[0], d->has_spp = true;
    return true;
}

/* "background R G B", "ambient R G B" */
static bool statement_colour(const parse_context *pc, const token *t, int n, vec3 *out)
{
    if (n != 4)
        return fail(pc, t[0].column, "'%.*s' takes three numbers: R G B", t[0].length, t[0].text);
    double c[3];
    for (int k = 0; k < 3; k++)
        if (!parse_number(pc, &t[1 + k], RADIANCE, &c[k]))
            return false;
    *out = vec3_make((float)c[0], (float)c[1], (float)c[2]);
    return true;
}

static bool statement_material(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    static const key_spec spec[SCENE_KEY_COUNT] = {
        [SCENE_KEY_ALBEDO] = {"albedo", ARG_VEC3, REFLECTANCE},
        [SCENE_KEY_DIFFUSE] = {"diffuse", ARG_VEC3, REFLECTANCE},
        [SCENE_KEY_SPECULAR] = {"specular", ARG_VEC3, REFLECTANCE},
        [SCENE_KEY_SHININESS] = {"shininess", ARG_NUMBER, 0.0, 1e5},
        [SCENE_KEY_CHECKER] = {"checker", ARG_VEC3, REFLECTANCE},
        [SCENE_KEY_SIZE] = {"size", ARG_NUMBER, SCENE_MIN_LENGTH, SCENE_MAX_COORDINATE},
        [SCENE_KEY_IOR] = {"ior", ARG_NUMBER, 1.0, 10.0},
        [SCENE_KEY_ROUGHNESS] = {"roughness", ARG_NUMBER, SCENE_MIN_ROUGHNESS, 1.0},
        [SCENE_KEY_EMISSION] = {"emission", ARG_VEC3, RADIANCE},
    };
    enum { ALBEDO = SCENE_KEY_ALBEDO, DIFFUSE = SCENE_KEY_DIFFUSE, SPECULAR = SCENE_KEY_SPECULAR,
           SHININESS = SCENE_KEY_SHININESS, CHECKER = SCENE_KEY_CHECKER, SIZE = SCENE_KEY_SIZE, IOR = SCENE_KEY_IOR,
           ROUGHNESS = SCENE_KEY_ROUGHNESS, EMISSION = SCENE_KEY_EMISSION, KEYS = SCENE_KEY_COUNT };
    /* Which keys each kind takes, and which it needs: the list's columns. */
    static const struct {
        unsigned allowed, required;
    } kinds[SCENE_MATERIAL_KIND_COUNT] = {
#define KIND_KEYS(id, keyword, effects, keys, needs) [SCENE_MATERIAL_##id] = {keys, needs},
        SCENE_MATERIAL_KINDS(KIND_KEYS)
#undef KIND_KEYS
    };
    if (n < 3)
        return fail(pc, t[0].column, "material needs a name and a kind: material NAME KIND key value ...");
    if (t[1].quoted || t[1].length >= SCENE_NAME_SIZE)
        return fail(pc, t[1].column, "a material's name is a word of at most %d characters", SCENE_NAME_SIZE - 1);
    int kind = -1;
    char known[128] = "";
    for (int k = 0; k < SCENE_MATERIAL_KIND_COUNT; k++) {
        const char *keyword = scene_material_kind_name((scene_material_kind)k);
        if (token_is(&t[2], keyword))
            kind = k;
        snprintf(known + strlen(known), sizeof known - strlen(known), "%s%s", k > 0 ? ", " : "", keyword);
    }
    if (kind < 0)
        return fail(pc, t[2].column, "unknown material kind '%.*s' (%s)", t[2].length > 40 ? 40 : t[2].length,
                    t[2].text, known);
    if (d->material_count >= SCENE_MAX_MATERIALS)
        return fail(pc, t[0].column, "too many materials (at most %d)", SCENE_MAX_MATERIALS);
    /* Only this kind's keys are known to it: a glass with "roughness" is an
     * error, not a silently ignored wish. */
    key_spec own[KEYS];
    int map[KEYS], own_count = 0;
    for (int k = 0; k < KEYS; k++)
        if (kinds[kind].allowed & (1u << k)) {
            map[k] = own_count;
            own[own_count++] = spec[k];
        } else {
            map[k] = -1;
        }
    key_value got[KEYS];
    char statement[96];
    snprintf(statement, sizeof statement, "a %s material", scene_material_kind_name((scene_material_kind)kind));
    if (!parse_keys(pc, t, 3, n, own, own_count, got, statement))
        return false;
    for (int k = 0; k < KEYS; k++)
        if ((kinds[kind].required & (1u << k)) && !got[map[k]].present)
            return fail(pc, t[2].column, "%s needs '%s'", statement, spec[k].key);

    scene_material m;
    memset(&m, 0, sizeof m);
    memcpy(m.name, t[1].text, (size_t)t[1].length);
    m.name[t[1].length] = '\0';
    if (find_material(d, m.name) >= 0)
        return fail(pc, t[1].column, "material '%s' is defined twice", m.name);
    m.kind = (scene_material_kind)kind;
    m.albedo = kind == SCENE_MATERIAL_EMISSIVE ? vec3_splat(0.0f) : vec3_splat(1.0f);
    m.shininess = 1.0f;
    m.ior = 1.0f;
    m.line = pc->line;
    m.column = t[0].column;
#define GOT(k) (map[k] >= 0 && got[map[k]].present)
    if (GOT(ALBEDO))
        m.albedo = value_vec3(&got[map[ALBEDO]]);
    if (GOT(DIFFUSE))
        m.albedo = value_vec3(&got[map[DIFFUSE]]);
    if (GOT(SPECULAR))
        m.specular = value_vec3(&got[map[SPECULAR]]);
    if (GOT(SHININESS))
        m.shininess = (float)got[map[SHININESS]].v[0];
    if (GOT(CHECKER) != GOT(SIZE))
        return fail(pc, t[2].column, "a checkerboard needs both 'checker R G B' and 'size S'");
    if (GOT(CHECKER)) {
        m.checker = value_vec3(&got[map[CHECKER]]);
        m.checker_size = (float)got[map[SIZE]].v[0];
    }
    if (GOT(IOR))
        m.ior = (float)got[map[IOR]].v[0];
    if (GOT(ROUGHNESS))
        m.roughness = (float)got[map[ROUGHNESS]].v[0];
    if (GOT(EMISSION))
        m.emission = value_vec3(&got[map[EMISSION]]);
#undef GOT
    d->materials = memory_grow(d->materials, &d->material_capacity, d->material_count + 1, sizeof m);
    d->materials[d->material_count++] = m;
    return true;
}

static bool statement_light(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    if (n < 2)
        return fail(pc, t[0].column, "light needs a kind: light point ... or light area ...");
    if (d->light_count >= SCENE_MAX_LIGHTS)
        return fail(pc, t[0].column, "too many lights (at most %d)", SCENE_MAX_LIGHTS);
    scene_light l;
    memset(&l, 0, sizeof l);
    l.line = pc->line;
    l.column = t[0].column;
    if (token_is(&t[1], "point")) {
        static const key_spec spec[] = {{"position", ARG_VEC3, COORD}, {"intensity", ARG_VEC3, RADIANCE}};
        key_value v[2];
        if (!parse_keys(pc, t, 2, n, spec, 2, v, "a point light") ||
            !require(pc, v, spec, 0, t[1].column, "a point light") ||
            !require(pc, v, spec, 1, t[1].column, "a point light"))
            return false;
        l.kind = SCENE_LIGHT_POINT;
        l.position = value_vec3(&v[0]);
        l.intensity = value_vec3(&v[1]);
    } else if (token_is(&t[1], "area")) {
        static const key_spec spec[] = {{"p0", ARG_VEC3, COORD},
                                        {"p1", ARG_VEC3, COORD},
                                        {"p2", ARG_VEC3, COORD},
                                        {"p3", ARG_VEC3, COORD},
                                        {"emission", ARG_VEC3, RADIANCE}};
        key_value v[5];
        if (!parse_keys(pc, t, 2, n, spec, 5, v, "an area light"))
            return false;
        for (int k = 0; k < 5; k++)
            if (!require(pc, v, spec, k, t[1].column, "an area light"))
                return false;
        l.kind = SCENE_LIGHT_AREA;
        for (int k = 0; k < 4; k++)
            l.corners[k] = value_vec3(&v[k]);
        l.emission = value_vec3(&v[4]);
        if (!scene_corners_have_area(l.corners))
            return fail(pc, t[1].column, "the area light has no area (p0, p1, p2 on a line)");
    } else {
        return fail(pc, t[1].column, "unknown light kind '%.*s' (point, area)", t[1].length > 40 ? 40 : t[1].length,
                    t[1].text);
    }
    d->lights = memory_grow(d->lights, &d->light_capacity, d->light_count + 1, sizeof l);
    d->lights[d->light_count++] = l;
    return true;
}

static bool statement_sphere(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    static const key_spec spec[] = {{"center", ARG_VEC3, COORD},
                                    {"radius", ARG_NUMBER, SCENE_MIN_LENGTH, SCENE_MAX_COORDINATE},
                                    {"material", ARG_WORD, 0, 0},
                                    {"inside_out", ARG_FLAG, 0, 0}};
    key_value v[4];
    scene_shape s;
    memset(&s, 0, sizeof s);
    if (!parse_keys(pc, t, 1, n, spec, 4, v, "sphere"))
        return false;
    for (int k = 0; k < 3; k++)
        if (!require(pc, v, spec, k, t[0].column, "sphere"))
            return false;
    if (!resolve_material(pc, d, &v[2], &s.material))
        return false;
    s.kind = SCENE_SHAPE_SPHERE;
    s.center = value_vec3(&v[0]);
    s.radius = (float)v[1].v[0];
    s.inside_out = v[3].present;
    return add_shape(pc, d, &s, t[0].column);
}

static bool statement_plane(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    static const key_spec spec[] = {
        {"point", ARG_VEC3, COORD}, {"normal", ARG_VEC3, COORD}, {"material", ARG_WORD, 0, 0}};
    key_value v[3];
    scene_shape s;
    memset(&s, 0, sizeof s);
    if (!parse_keys(pc, t, 1, n, spec, 3, v, "plane"))
        return false;
    for (int k = 0; k < 3; k++)
        if (!require(pc, v, spec, k, t[0].column, "plane"))
            return false;
    if (!resolve_material(pc, d, &v[2], &s.material))
        return false;
    s.kind = SCENE_SHAPE_PLANE;
    s.point = value_vec3(&v[0]);
    s.normal = value_vec3(&v[1]);
    if (!(vec3_length_squared(s.normal) > 0.0f))
        return fail(pc, v[1].column, "a plane's normal must not be zero");
    s.normal = vec3_normalize(s.normal);
    return add_shape(pc, d, &s, t[0].column);
}

/* "triangle p0 .. p1 .. p2 .. material M" and "quad ... p3 .. material M" */
static bool statement_polygon(const parse_context *pc, scene_desc *d, const token *t, int n, int corners)
{
    static const key_spec spec[] = {{"p0", ARG_VEC3, COORD},
                                    {"p1", ARG_VEC3, COORD},
                                    {"p2", ARG_VEC3, COORD},
                                    {"material", ARG_WORD, 0, 0},
                                    {"p3", ARG_VEC3, COORD}};
    const char *name = corners == 3 ? "triangle" : "quad";
    key_value v[5];
    scene_shape s;
    memset(&s, 0, sizeof s);
    if (!parse_keys(pc, t, 1, n, spec, corners + 1, v, name))
        return false;
    for (int k = 0; k < corners + 1; k++)
        if (!require(pc, v, spec, k, t[0].column, name))
            return false;
    if (!resolve_material(pc, d, &v[3], &s.material))
        return false;
    s.kind = corners == 3 ? SCENE_SHAPE_TRIANGLE : SCENE_SHAPE_QUAD;
    for (int k = 0; k < 3; k++)
        s.p[k] = value_vec3(&v[k]);
    if (corners == 4)
        s.p[3] = value_vec3(&v[4]);
    /* An emitting shape is a light: like an area light it must have area
     * (its power is L_e times its area; without, a scene lit by it renders
     * black). A shape that only reflects may be degenerate: it is never hit. */
    if (scene_material_emits(&d->materials[s.material]) && !scene_corners_have_area(s.p))
        return fail(pc, t[0].column, "the %s emits light (material '%s') but has no area (p0, p1, p2 on a line)", name,
                    d->materials[s.material].name);
    return add_shape(pc, d, &s, t[0].column);
}

static bool statement_implicit(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    static const key_spec spec[] = {{"center", ARG_VEC3, COORD},
                                    {"major", ARG_NUMBER, SCENE_MIN_LENGTH, SCENE_MAX_COORDINATE},
                                    {"minor", ARG_NUMBER, SCENE_MIN_LENGTH, SCENE_MAX_COORDINATE},
                                    {"material", ARG_WORD, 0, 0}};
    if (n < 2 || !token_is(&t[1], "torus"))
        return fail(pc, n < 2 ? t[0].column : t[1].column, "implicit surfaces known: torus (implicit torus center .. "
                                                           "major R minor r material M)");
    key_value v[4];
    scene_shape s;
    memset(&s, 0, sizeof s);
    if (!parse_keys(pc, t, 2, n, spec, 4, v, "an implicit torus"))
        return false;
    for (int k = 0; k < 4; k++)
        if (!require(pc, v, spec, k, t[1].column, "an implicit torus"))
            return false;
    if (!resolve_material(pc, d, &v[3], &s.material))
        return false;
    s.kind = SCENE_SHAPE_TORUS;
    s.center = value_vec3(&v[0]);
    s.major = (float)v[1].v[0];
    s.minor = (float)v[2].v[0];
    if (!(s.minor < s.major))
        return fail(pc, v[2].column, "a torus needs minor < major (otherwise it intersects itself)");
    return add_shape(pc, d, &s, t[0].column);
}

static bool statement_mesh(const parse_context *pc, scene_desc *d, const token *t, int n, const char *base_dir)
{
    static const key_spec spec[] = {{"path", ARG_STRING, 0, 0},
                                    {"generator", ARG_WORD, 0, 0},
                                    {"triangles", ARG_INT, 1, SCENE_MAX_GENERATED_TRIANGLES},
                                    {"material", ARG_WORD, 0, 0}};
    key_value v[4];
    scene_shape s;
    memset(&s, 0, sizeof s);
    s.material = -1;
    if (!parse_keys(pc, t, 1, n, spec, 4, v, "mesh"))
        return false;
    if (v[0].present == v[1].present)
        return fail(pc, t[0].column, "a mesh needs either path \"FILE.obj\" or generator tori_field");
    if (v[3].present && !resolve_material(pc, d, &v[3], &s.material))
        return false;
    if (v[0].present) {
        if (v[2].present)
            return fail(pc, v[2].column, "'triangles' is for generated meshes, not OBJ files");
        s.kind = SCENE_SHAPE_MESH_OBJ;
        char path[SCENE_PATH_SIZE];
        int written;
        if (v[0].text[0] == '/' || base_dir == NULL || base_dir[0] == '\0')
            written = snprintf(path, sizeof path, "%s", v[0].text);
        else
            written = snprintf(path, sizeof path, "%s/%s", base_dir, v[0].text);
        if (written < 0 || written >= (int)sizeof path)
            return fail(pc, v[0].column, "the mesh path is too long");
        s.path = memory_allocate((size_t)written + 1, 1);
        memcpy(s.path, path, (size_t)written + 1);
    } else {
        if (strcmp(v[1].text, "tori_field") != 0)
            return fail(pc, v[1].value_column, "unknown mesh generator '%s' (tori_field)", v[1].text);
        s.kind = SCENE_SHAPE_MESH_TORI;
        s.triangles = v[2].present ? (int)v[2].v[0] : 10240;
    }
    return add_shape(pc, d, &s, t[0].column);
}

static const char *const effect_names[] = {"shadows", "reflection", "refraction", "glossy", "indirect"};

/* "effects all", "effects only NAME ...", "effects without NAME ..." */
static bool statement_effects(const parse_context *pc, scene_desc *d, const token *t, int n)
{
    if (n == 2 && token_is(&t[1], "all")) {
        d->effects_allowed = EFFECT_ALL;
        return true;
    }
    if (n < 3 || !(token_is(&t[1], "only") || token_is(&t[1], "without")))
        return fail(pc, n < 2 ? t[0].column : t[1].column,
                    "write 'effects all', 'effects only NAME ...' or 'effects without NAME ...' "
                    "(names: shadows, reflection, refraction, glossy, indirect)");
    unsigned listed = 0;
    for (int i = 2; i < n; i++) {
        int k = 0;
        while (k < 5 && !token_is(&t[i], effect_names[k]))
            k++;
        if (k == 5)
            return fail(pc, t[i].column, "unknown effect '%.*s' (shadows, reflection, refraction, glossy, indirect)",
                        t[i].length > 40 ? 40 : t[i].length, t[i].text);
        listed |= 1u << k;
    }
    d->effects_allowed = token_is(&t[1], "only") ? listed : (EFFECT_ALL & ~listed);
    return true;
}

static bool parse_line(const parse_context *pc, scene_desc *d, const token *t, int n, const char *base_dir,
                       bool *seen_effects)
{
    if (token_is(&t[0], "camera"))
        return statement_camera(pc, d, t, n);
    if (token_is(&t[0], "image"))
        return statement_image(pc, d, t, n);
    if (token_is(&t[0], "background"))
        return statement_colour(pc, t, n, &d->background);
    if (token_is(&t[0], "ambient"))
        return statement_colour(pc, t, n, &d->ambient);
    if (token_is(&t[0], "material"))
        return statement_material(pc, d, t, n);
    if (token_is(&t[0], "light"))
        return statement_light(pc, d, t, n);
    if (token_is(&t[0], "sphere"))
        return statement_sphere(pc, d, t, n);
    if (token_is(&t[0], "plane"))
        return statement_plane(pc, d, t, n);
    if (token_is(&t[0], "triangle"))
        return statement_polygon(pc, d, t, n, 3);
    if (token_is(&t[0], "quad"))
        return statement_polygon(pc, d, t, n, 4);
    if (token_is(&t[0], "implicit"))
        return statement_implicit(pc, d, t, n);
    if (token_is(&t[0], "mesh"))
        return statement_mesh(pc, d, t, n, base_dir);
    if (token_is(&t[0], "integrator")) {
        if (n != 2 || t[1].quoted || t[1].length >= SCENE_NAME_SIZE)
            return fail(pc, t[0].column, "write 'integrator NAME'");
        if (d->integrator[0] != '\0')
            return fail(pc, t[0].column, "integrator given twice");
        memcpy(d->integrator, t[1].text, (size_t)t[1].length);
        d->integrator[t[1].length] = '\0';
        d->integrator_line = pc->line;
        d->integrator_column = t[1].column;
        return true;
    }
    if (token_is(&t[0], "max_depth")) {
        double v;
        if (n != 2)
            return fail(pc, t[0].column, "write 'max_depth N'");
        if (!parse_number(pc, &t[1], 0, 1000, &v))
            return false;
        if (v != floor(v))
            return fail(pc, t[1].column, "max_depth must be a whole number");
        d->max_depth = (int)v;
        return true;
    }
    if (token_is(&t[0], "effects")) {
        if (*seen_effects)
            return fail(pc, t[0].column, "effects given twice");
        *seen_effects = true;
        return statement_effects(pc, d, t, n);
    }
    /* Before any statement, an unknown word says the file is of another
     * kind (an OBJ file, an image, anything named by mistake): say so, and
     * print nothing of what it holds. After one, it is a typo, shown. */
    if (!pc->recognised)
        return fail(pc, t[0].column,
                    "not a scene file (this line starts with none of camera, image, background, ambient, material, "
                    "light, sphere, plane, triangle, quad, implicit, mesh, integrator, max_depth, effects)");
    return fail(pc, t[0].column,
                "unknown statement '%.*s' (camera, image, background, ambient, material, light, sphere, plane, "
                "triangle, quad, implicit, mesh, integrator, max_depth, effects)",
                t[0].length > 40 ? 40 : t[0].length, t[0].text);
}

bool scene_desc_parse(scene_desc *d, const char *text, size_t length, const char *name, const char *base_dir,
                      char *err, size_t err_size)
{
    scene_desc_init(d);
    snprintf(d->source, sizeof d->source, "%s", name);
    parse_context pc = {name, 0, err, err_size, false};
    if (length > (size_t)SCENE_MAX_FILE_BYTES) {
        snprintf(err, err_size, "%s: larger than %d bytes", name, SCENE_MAX_FILE_BYTES);
        return false;
    }
    token tokens[MAX_TOKENS];
    bool seen_effects = false;
    size_t at = 0;
    while (at < length) {
        size_t end = at;
        while (end < length && text[end] != '\n')
            end++;
        pc.line++;
        bool ok = true;
        if (end - at > (size_t)SCENE_MAX_LINE) {
            ok = fail(&pc, SCENE_MAX_LINE + 1, "line longer than %d characters", SCENE_MAX_LINE);
        } else {
            int count;
            ok = tokenize(&pc, text + at, (int)(end - at), tokens, &count);
            if (ok && count > 0) {
                ok = parse_line(&pc, d, tokens, count, base_dir, &seen_effects);
                pc.recognised = true;
            }
        }
        if (!ok) {
            scene_desc_free(d);
            return false;
        }
        at = end + 1;
    }
    return true;
}

bool scene_desc_load(scene_desc *d, const char *path, char *err, size_t err_size)
{
    scene_desc_init(d);
    /* Scene files are written by hand: their fixed limit is far above any
     * of them, and geometry of any size belongs in an OBJ file. */
    char *text, why[INPUT_ERROR_SIZE];
    size_t length;
    if (!input_file_read(path, "scene", (uint64_t)SCENE_MAX_FILE_BYTES, false, &text, &length, why, sizeof why)) {
        snprintf(err, err_size, "%s: %s", path, why);
        return false;
    }
    /* Mesh paths are relative to the scene file's directory. */
    char base[SCENE_PATH_SIZE];
    const char *slash = strrchr(path, '/');
    if (slash == NULL)
        base[0] = '\0';
    else
        snprintf(base, sizeof base, "%.*s", (int)(slash - path == 0 ? 1 : slash - path), path);
    bool ok = scene_desc_parse(d, text, length, path, base, err, err_size);
    free(text);
    return ok;
}

/* obj.c -- Wavefront OBJ (with the colours of its MTL files) in; OBJ out
 * is obj_write.c.
 *
 * The grammar read, one statement per line. Fields are separated by spaces
 * or tabs, a line may end in CRLF, '#' starts a comment (at the start of a
 * line or of a field), blank lines are skipped, a UTF-8 byte order mark at
 * the very start is skipped:
 *
 *   v  x y z [w]           a position (w, and the r g b of the common
 *                          "v x y z r g b" colour extension, are dropped)
 *   vn x y z               a normal
 *   vt u [v [w]]           a texture coordinate (v defaults to 0, w dropped)
 *   f  c c c [c ...]       a polygon; each corner c is one of
 *                            v   v/vt   v//vn   v/vt/vn
 *                          (forms may be mixed), 1-based, or negative to
 *                          count back from the last element defined so far
 *                          (-1 = the latest). Fan-triangulated:
 *                          (c0,c1,c2), (c0,c2,c3), ...
 *   mtllib a.mtl [b.mtl]   material files, relative to base_dir, read at
 *                          once (so their materials exist for later usemtl)
 *   usemtl name            the material of the faces that follow
 *   o g s l p              ignored: names, groups, smoothing, lines, points
 *
 * and in an MTL file:
 *
 *   newmtl name            starts a material: Kd 0.8 grey, Ks 0, Ns 1, Ke 0, Ni 1, d 1
 *   Kd/Ks/Ke r g b         diffuse, specular, emitted colour (one number = grey)
 *   Ns s, Ni n             shininess, index of refraction
 *   d a, Tr t              dissolve (1 opaque), transparency (Tr = 1 - d), in [0, 1]
 *   illum n                illumination model 0-10 (4, 6, 7, 9: transparent)
 *   Pm m, Pr r             the PBR extension's metallic and roughness, in [0, 1]
 *   Ka Tf map_* bump ...   ignored (common, and nothing here uses them)
 *
 * Any other statement is an error rather than silently skipped: a typo such
 * as "vv 1 2 3" should not quietly lose geometry. Before the file has shown
 * it is OBJ (or MTL) with a statement of data, an unknown word means a file
 * of another kind, and the message says so without quoting it: an mtllib,
 * or a scene's mesh path, may name any file. A face whose material emits
 * (Ke > 0) must have area, as a scene file's emitting quad must. Every error
 * reads "file:line: what is wrong", and a failed call leaves the mesh
 * exactly as it found it (we remember the counts at entry and cut back to
 * them). Files are read through input_file_read (input_file.h): regular
 * files only, within the mesh limit (--max-input-mb).
 *
 * The text is never copied or modified: lines and fields are spans of the
 * caller's buffer, which need not be NUL-terminated. Only a single number
 * is copied (into a small buffer) for strtof. So the only memory a file
 * costs is what the mesh itself grows to hold.
 */
#include "obj.h"

#include "input_file.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    /* Longest number text we accept. Far beyond anything an exporter writes
     * (%.9g needs 15 characters), and it lets strtof work on a stack copy. */
    NUMBER_TEXT_SIZE = 256,
    /* A field quoted in an error message is cut to this many characters, so
     * a megabyte of garbage on one line makes a readable message. */
    QUOTE_SIZE = 48,
};

/* ---- errors ------------------------------------------------------------ */

/* One line into err (which may be NULL / empty: callers that don't care). */
static void set_error(char *err, size_t err_size, const char *format, ...)
{
    if (err == NULL || err_size == 0)
        return;
    va_list args;
    va_start(args, format);
    vsnprintf(err, err_size, format, args);
    va_end(args);
}

/* Where we are: the file name for messages and the current line, plus
 * where messages go. Shared by the OBJ and the MTL reader. */
typedef struct {
    const char *name;
    long line;
    char *err;
    size_t err_size;
} source;

/* "name:line: message"; always returns false so callers can `return fail_at(...)`. */
static bool fail_at(const source *s, const char *format, ...)
{
    if (s->err == NULL || s->err_size == 0)
        return false;
    int n = snprintf(s->err, s->err_size, "%s:%ld: ", s->name, s->line);
    if (n >= 0 && (size_t)n < s->err_size) {
        va_list args;
        va_start(args, format);
        vsnprintf(s->err + n, s->err_size - (size_t)n, format, args);
        va_end(args);
    }
    return false;
}

/* A field as it can safely be printed: bytes outside printable ASCII shown
 * as \xNN (a message must not carry raw control bytes to a terminal), cut
 * to QUOTE_SIZE with "..." when longer. */
static const char *quote(const char *start, size_t length, char out[QUOTE_SIZE])
{
    static const char hex[] = "0123456789abcdef";
    size_t n = 0;
    for (size_t i = 0; i < length; i++) {
        unsigned char c = (unsigned char)start[i];
        size_t need = (c >= 0x20 && c < 0x7f) ? 1 : 4;
        if (n + need + 4 > QUOTE_SIZE) { /* room for "..." and the NUL */
            memcpy(out + n, "...", 3);
            n += 3;
            break;
        }
        if (need == 1) {
            out[n++] = (char)c;
        } else {
            out[n++] = '\\';
            out[n++] = 'x';
            out[n++] = hex[c >> 4];
            out[n++] = hex[c & 15];
        }
    }
    out[n] = '\0';
    return out;
}

/* ---- lines and fields -------------------------------------------------- */

typedef struct {
    const char *start;
    size_t length;
} field;

/* The unread part of one line, [cursor, end), without its '\n'. */
typedef struct {
    const char *cursor, *end;
} line_reader;

/* '\r' counts as a blank so that CRLF files (and stray CRs) need no special case. */
static bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* The next field, or false at the end of the line or at a comment. */
static bool next_field(line_reader *r, field *f)
{
    while (r->cursor < r->end && is_blank(*r->cursor))
        r->cursor++;
    if (r->cursor == r->end || *r->cursor == '#') {
        r->cursor = r->end;
        return false;
    }
    f->start = r->cursor;
    while (r->cursor < r->end && !is_blank(*r->cursor))
        r->cursor++;
    f->length = (size_t)(r->cursor - f->start);
    return true;
}

/* Everything left on the line (blanks inside kept, ends trimmed, a trailing
 * comment dropped): material names may contain spaces. Empty if nothing. */
static field rest_of_line(line_reader *r)
{
    field all = {r->cursor, 0}, f;
    bool any = false;
    while (next_field(r, &f)) {
        if (!any)
            all.start = f.start;
        all.length = (size_t)(f.start + f.length - all.start);
        any = true;
    }
    return all;
}

static bool field_is(field f, const char *word)
{
    size_t n = strlen(word);
    return f.length == n && memcmp(f.start, word, n) == 0;
}

static bool field_starts_with(field f, const char *prefix)
{
    size_t n = strlen(prefix);
    return f.length >= n && memcmp(f.start, prefix, n) == 0;
}

/* Text files have no control bytes but tab, CR, VT and FF. Checking each
 * line up front turns binary input (or a UTF-16 file, all NULs) into one
 * clear message instead of a confusing one about the first field. Bytes of
 * 0x80 and up pass: they are UTF-8 in names and comments. */
static bool check_text(const source *s, const char *start, const char *end)
{
    for (const char *p = start; p < end; p++) {
        unsigned char c = (unsigned char)*p;
        if ((c < 0x20 && !is_blank((char)c)) || c == 0x7f)
            return fail_at(s, "unexpected byte 0x%02x (not a text file?)", c);
    }
    return true;
}

/* Calls `statement` for each line of text, keeping s->line current. Stops
 * at the first line it rejects. */
typedef bool (*statement_reader)(void *context, source *s, line_reader *r, field keyword);

static bool read_lines(const char *text, size_t length, source *s, statement_reader statement, void *context)
{
    const char *p = text, *end = text + length;
    /* A UTF-8 byte order mark, as some Windows tools write. */
    if (length >= 3 && memcmp(p, "\xEF\xBB\xBF", 3) == 0)
        p += 3;
    s->line = 0;
    while (p < end) {
        s->line++;
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        if (eol == NULL)
            eol = end;
        if (!check_text(s, p, eol))
            return false;
        line_reader r = {p, eol};
        field keyword;
        if (next_field(&r, &keyword) && !statement(context, s, &r, keyword))
            return false;
        p = eol < end ? eol + 1 : end;
    }
    return true;
}

/* ---- numbers ----------------------------------------------------------- */

/* A whole field as a finite float. strtof rather than strtod + cast: one
 * correct rounding, so what %.9g wrote comes back bit for bit. */
static bool parse_float(const source *s, field f, const char *keyword, float *out)
{
    char shown[QUOTE_SIZE];
    char text[NUMBER_TEXT_SIZE];
    if (f.length >= sizeof text)
        return fail_at(s, "'%s' after '%s' is too long for a number", quote(f.start, f.length, shown), keyword);
    memcpy(text, f.start, f.length);
    text[f.length] = '\0';
    char *stop;
    float value = strtof(text, &stop);
    /* stop short of the end: "1.0abc", "1,5", "--1" are typos, not 1.0, 1 or 0.
     * ERANGE is not checked: overflow gives inf (caught below) and an
     * underflow to a tiny or zero value is a fine reading of the text. */
    if (stop == text || *stop != '\0')
        return fail_at(s, "'%s' after '%s' is not a number", quote(f.start, f.length, shown), keyword);
    if (!isfinite(value))
        return fail_at(s, "'%s' after '%s' is not a finite number", quote(f.start, f.length, shown), keyword);
    *out = value;
    return true;
}

/* All the numbers left on the line: the first `max` into values, the rest
 * only checked. Returns how many there were (capped at max + 1, which is all
 * a caller needs to say "too many"), or -1 after an error. */
static int read_numbers(const source *s, line_reader *r, const char *keyword, float *values, int max)
{
    int count = 0;
    field f;
    while (next_field(r, &f)) {
        float value;
        if (!parse_float(s, f, keyword, &value))
            return -1;
        if (count < max)
            values[count] = value;
        if (count <= max)
            count++;
    }
    return count;
}

/* ---- MTL --------------------------------------------------------------- */

typedef struct {
    mesh *m;
    int current; /* index of the material being described, or -1 before any newmtl */
} mtl_reader;

static const mesh_material default_material = {
    .name = "",
    .diffuse = {0.8f, 0.8f, 0.8f},
    .specular = {0.0f, 0.0f, 0.0f},
    .emission = {0.0f, 0.0f, 0.0f},
    .shininess = 1.0f,
    .ior = 1.0f,
    .dissolve = 1.0f,
    .illum = -1,
    .metallic = -1.0f,
    .roughness = -1.0f,
};

bool mesh_material_transparent(const mesh_material *m)
{
    return m->illum == 4 || m->illum == 6 || m->illum == 7 || m->illum == 9 || m->dissolve < 1.0f;
}

bool mesh_material_emits(const mesh_material *m)
{
    return m->emission.x > 0.0f || m->emission.y > 0.0f || m->emission.z > 0.0f;
}

/* Statements we know and deliberately skip: exporters write them all the
 * time (Blender, 3ds Max, Maya), and a renderer of colours has no use for
 * them. A name not here and not handled is an error, as in the OBJ reader. */
static bool mtl_ignored(field keyword)
{
    static const char *const words[] = {"Ka",   "Tf",  "sharpness", "bump",  "disp",  "decal",
                                        "refl", "norm", "Ps",       "Pc",    "Pcr",   "aniso", "anisor"};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++)
        if (field_is(keyword, words[i]))
            return true;
    return field_starts_with(keyword, "map_");
}

/* "Kd r g b", or "Kd g" for a grey: the MTL format allows g and b to be left out. */
static bool mtl_colour(const source *s, line_reader *r, const char *keyword, vec3 *out)
{
    float c[3];
    int n = read_numbers(s, r, keyword, c, 3);
    if (n < 0)
        return false;
    if (n == 1)
        c[1] = c[2] = c[0];
    else if (n == 0 || n == 2)
        return fail_at(s, "expected 3 numbers after '%s'", keyword);
    else if (n > 3)
        return fail_at(s, "too many numbers after '%s'", keyword);
    *out = vec3_make(c[0], c[1], c[2]);
    return true;
}

static bool mtl_scalar(const source *s, line_reader *r, const char *keyword, float *out)
{
    float value;
    int n = read_numbers(s, r, keyword, &value, 1);
    if (n < 0)
        return false;
    if (n != 1)
        return fail_at(s, n == 0 ? "expected 1 number after '%s'" : "too many numbers after '%s'", keyword);
    *out = value;
    return true;
}

static bool mtl_statement(void *context, source *s, line_reader *r, field keyword)
{
    mtl_reader *mtl = context;
    char shown[QUOTE_SIZE];
    if (field_is(keyword, "newmtl")) {
        field name = rest_of_line(r);
        if (name.length == 0)
            return fail_at(s, "expected a material name after 'newmtl'");
        if (name.length >= MESH_NAME_SIZE)
            return fail_at(s, "material name '%s' is longer than %d characters", quote(name.start, name.length, shown),
                           MESH_NAME_SIZE - 1);
        mesh_material material = default_material;
        memcpy(material.name, name.start, name.length);
        material.name[name.length] = '\0';
        mtl->current = mesh_add_material(mtl->m, &material);
        return true;
    }
    if (mtl_ignored(keyword))
        return true;

    bool colour = field_is(keyword, "Kd") || field_is(keyword, "Ks") || field_is(keyword, "Ke");
    bool scalar = field_is(keyword, "Ns") || field_is(keyword, "Ni") || field_is(keyword, "Tr") ||
                  field_is(keyword, "d") || field_is(keyword, "illum") || field_is(keyword, "Pm") ||
                  field_is(keyword, "Pr");
    /* An unknown word before the first newmtl: the file is of another kind
     * (an OBJ, an image, or any file an OBJ names, such as a private key).
     * Say so without printing what it holds; after newmtl it is a typo. */
    if (!colour && !scalar && mtl->current < 0)
        return fail_at(s, "not an MTL file (a material library starts with 'newmtl'; this line starts with no MTL "
                          "statement)");
    if (!colour && !scalar)
        return fail_at(s, "unknown statement '%s'", quote(keyword.start, keyword.length, shown));
    /* keyword is one of the ten words above: safe to print as a string. */
    char word[6] = {0};
    memcpy(word, keyword.start, keyword.length);
    if (mtl->current < 0)
        return fail_at(s, "'%s' before any 'newmtl'", word);

    /* Parsed into locals first, so a bad number leaves the material as it was. */
    mesh_material *material = &mtl->m->materials[mtl->current];
    if (colour) {
        vec3 c;
        if (!mtl_colour(s, r, word, &c))
            return false;
        /* A light gives light: a negative Ke would be dropped as "emits
         * nothing" (mesh_material_emits), the material printed as a plain
         * diffuse one, where the scene file refuses a negative emission. */
        if (word[1] == 'e' && !(c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f))
            return fail_at(s, "'Ke %g %g %g': an emission cannot be negative", (double)c.x, (double)c.y,
                           (double)c.z);
        if (word[1] == 'd')
            material->diffuse = c;
        else if (word[1] == 's')
            material->specular = c;
        else
            material->emission = c;
    } else {
        float value = 0.0f;
        if (!mtl_scalar(s, r, word, &value))
            return false;
        bool fraction = word[0] == 'd' || word[0] == 'T' || word[0] == 'P';
        if (fraction && !(value >= 0.0f && value <= 1.0f))
            return fail_at(s, "'%s %g': expected a number from 0 to 1", word, (double)value);
        if (word[0] == 'i' && !(value >= 0.0f && value <= 10.0f && value == (float)(int)value))
            return fail_at(s, "'illum %g': expected an illumination model, 0 to 10", (double)value);
        if (word[0] == 'd')
            material->dissolve = value;
        else if (word[0] == 'T')
            material->dissolve = 1.0f - value;
        else if (word[0] == 'i')
            material->illum = (int)value;
        else if (word[0] == 'P')
            *(word[1] == 'm' ? &material->metallic : &material->roughness) = value;
        else if (word[1] == 's')
            material->shininess = value;
        else
            material->ior = value;
    }
    return true;
}

/* ---- reading files ----------------------------------------------------- */

/* base_dir/name, or name itself when it is absolute or base_dir is "" (the
 * current directory). malloc'ed; NULL when out of memory. */
static char *join_path(const char *base_dir, const char *name, size_t name_length)
{
    size_t base_length = (name_length > 0 && name[0] == '/') ? 0 : strlen(base_dir);
    bool slash = base_length > 0 && base_dir[base_length - 1] != '/';
    char *path = malloc(base_length + slash + name_length + 1);
    if (path == NULL)
        return NULL;
    memcpy(path, base_dir, base_length);
    if (slash)
        path[base_length] = '/';
    memcpy(path + base_length + slash, name, name_length);
    path[base_length + slash + name_length] = '\0';
    return path;
}

/* ---- OBJ --------------------------------------------------------------- */

typedef struct {
    mesh *m;
    const char *base_dir;
    /* The counts when the call began: indices in this file are relative to
     * them, since the mesh may already hold other files or generated shapes. */
    int position_base, normal_base, texcoord_base;
    int material;        /* for the faces that follow: from usemtl, -1 before */
    bool skipped_mtllib; /* an mtllib was not read because base_dir is NULL */
    bool recognised;     /* a statement with data (v, vn, vt, f, mtllib, usemtl) was read */
} obj_reader;

typedef struct {
    int position, texcoord, normal; /* global indices; -1 when absent */
} corner;

/* One index of a corner, "12" or "-3", turned into a global index. `what`
 * names the kind in messages ("face", "texture coordinate", "normal") and
 * `plural` the elements ("vertices", ...). */
static bool resolve_index(const source *s, field f, int count_now, int base, const char *what, const char *singular,
                          const char *plural, int *out)
{
    char shown[QUOTE_SIZE];
    size_t i = 0;
    bool negative = false;
    if (i < f.length && (f.start[i] == '-' || f.start[i] == '+'))
        negative = f.start[i++] == '-';
    if (i == f.length)
        return fail_at(s, "'%s' is not a %s index", quote(f.start, f.length, shown), what);
    /* Digits by hand rather than strtol: the field is not NUL-terminated,
     * and we want "1.5" or "1x" rejected, not read as 1. Saturating at
     * INT_MAX + 1 is enough to know the index is out of range. */
    long long value = 0;
    for (; i < f.length; i++) {
        if (f.start[i] < '0' || f.start[i] > '9')
            return fail_at(s, "'%s' is not a %s index", quote(f.start, f.length, shown), what);
        if (value <= INT_MAX)
            value = value * 10 + (f.start[i] - '0');
    }
    if (value == 0)
        return fail_at(s, "%s index 0 is invalid (OBJ indices start at 1)", what);
    long long available = (long long)count_now - base;
    if (value > available)
        return fail_at(s, "%s index %s is out of range (%lld %s so far)", what, quote(f.start, f.length, shown),
                       available, available == 1 ? singular : plural);
    *out = negative ? (int)(count_now - value) : (int)(base + value - 1);
    return true;
}

/* One face corner: v, v/vt, v//vn or v/vt/vn. */
static bool parse_corner(const obj_reader *obj, const source *s, field f, corner *c)
{
    char shown[QUOTE_SIZE];
    field part[3];
    int parts = 0;
    const char *p = f.start, *end = f.start + f.length;
    for (;;) {
        const char *slash = memchr(p, '/', (size_t)(end - p));
        const char *stop = slash != NULL ? slash : end;
        if (parts == 3)
            return fail_at(s, "'%s' is not a face vertex (v, v/vt, v//vn or v/vt/vn)", quote(f.start, f.length, shown));
        part[parts++] = (field){p, (size_t)(stop - p)};
        if (slash == NULL)
            break;
        p = slash + 1;
    }
    /* Only the texture coordinate may be empty, and only in v//vn. A
     * trailing slash ("1/", "1/2/") is a cut-off line, not "absent". */
    if (part[0].length == 0 || (parts == 2 && part[1].length == 0) || (parts == 3 && part[2].length == 0))
        return fail_at(s, "'%s' is not a face vertex (v, v/vt, v//vn or v/vt/vn)", quote(f.start, f.length, shown));

    const mesh *m = obj->m;
    c->texcoord = c->normal = -1;
    if (!resolve_index(s, part[0], m->position_count, obj->position_base, "face", "vertex", "vertices", &c->position))
        return false;
    if (parts >= 2 && part[1].length > 0 &&
        !resolve_index(s, part[1], m->texcoord_count, obj->texcoord_base, "texture coordinate", "texture coordinate",
                       "texture coordinates", &c->texcoord))
        return false;
    if (parts == 3 &&
        !resolve_index(s, part[2], m->normal_count, obj->normal_base, "normal", "normal", "normals", &c->normal))
        return false;
    return true;
}

static void add_face(obj_reader *obj, const corner *a, const corner *b, const corner *c)
{
    int i = mesh_add_triangle(obj->m, a->position, b->position, c->position, obj->material);
    if (i < 0)
        return;
    mesh_face *face = &obj->m->faces[i];
    const corner *corners[3] = {a, b, c};
    for (int k = 0; k < 3; k++) {
        face->normal[k] = corners[k]->normal;
        face->texcoord[k] = corners[k]->texcoord;
    }
}

/* Streams the corners: a fan needs only the first and the previous one, so
 * a polygon of any size costs no memory of its own. */
static bool obj_face(obj_reader *obj, const source *s, line_reader *r)
{
    corner first = {0, 0, 0}, previous = {0, 0, 0}, current;
    int count = 0;
    bool has_area = false;
    field f;
    while (next_field(r, &f)) {
        if (!parse_corner(obj, s, f, &current))
            return false;
        if (count == 0) {
            first = current;
        } else if (count >= 2) {
            add_face(obj, &first, &previous, &current);
            const vec3 *p = obj->m->positions;
            vec3 n = vec3_cross(vec3_sub(p[previous.position], p[first.position]),
                                vec3_sub(p[current.position], p[first.position]));
            has_area = has_area || vec3_length_squared(n) > 0.0f;
        }
        previous = current;
        if (count < 3)
            count++;
    }
    if (count < 3)
        return fail_at(s, "a face needs at least 3 vertices");
    /* An emitting face must have area, as a scene file's emitting quad or
     * area light must: one without gives no light (its power is L_e times
     * its area) and a scene lit only by it renders black. A fan triangle
     * without area inside a face with area (three corners of a polygon on
     * a line) is harmless: it is never hit and never sampled. */
    const mesh_material *material = obj->material >= 0 ? &obj->m->materials[obj->material] : NULL;
    if (material != NULL && vec3_max_component(material->emission) > 0.0f && !has_area) {
        char shown[QUOTE_SIZE];
        return fail_at(s, "the face emits light (material '%s', Ke > 0) but has no area: its corners are on a line",
                       quote(material->name, strlen(material->name), shown));
    }
    return true;
}

static bool obj_mtllib(obj_reader *obj, const source *s, line_reader *r)
{
    field f;
    int count = 0;
    while (next_field(r, &f)) {
        count++;
        if (obj->base_dir == NULL) {
            obj->skipped_mtllib = true;
            continue;
        }
        char *path = join_path(obj->base_dir, f.start, f.length);
        if (path == NULL)
            return fail_at(s, "%s", strerror(ENOMEM));
        char *text, why[INPUT_ERROR_SIZE];
        size_t length;
        if (!input_file_read(path, "MTL", input_file_mesh_limit(), true, &text, &length, why, sizeof why)) {
            fail_at(s, "cannot read material library '%s': %s", path, why);
            free(path);
            return false;
        }
        mtl_reader mtl = {obj->m, -1};
        source mtl_source = {path, 0, s->err, s->err_size};
        bool ok = read_lines(text, length, &mtl_source, mtl_statement, &mtl);
        free(text);
        free(path);
        if (!ok)
            return false;
    }
    if (count == 0)
        return fail_at(s, "expected a file name after 'mtllib'");
    return true;
}

/* The latest material of that name: one defined in this file's libraries
 * comes after any already in the mesh, so it wins, and a name defined
 * twice means its last definition. Materials the caller put in the mesh
 * before the call can be used by name too. */
static int find_material(const mesh *m, field name)
{
    for (int i = m->material_count - 1; i >= 0; i--) {
        const char *candidate = m->materials[i].name;
        if (strnlen(candidate, MESH_NAME_SIZE) == name.length && memcmp(candidate, name.start, name.length) == 0)
            return i;
    }
    return -1;
}

static bool obj_usemtl(obj_reader *obj, const source *s, line_reader *r)
{
    char shown[QUOTE_SIZE];
    field name = rest_of_line(r);
    if (name.length == 0)
        return fail_at(s, "expected a material name after 'usemtl'");
    int i = find_material(obj->m, name);
    /* Without base_dir the libraries were skipped on purpose, so an unknown
     * name is expected there: those faces simply get no material. */
    if (i < 0 && !obj->skipped_mtllib)
        return fail_at(s, "unknown material '%s' (no 'newmtl' of that name in the material libraries)",
                       quote(name.start, name.length, shown));
    obj->material = i;
    return true;
}

/* v, vn, vt, f, mtllib, usemtl: the statements that carry data. */
static bool obj_data_statement(obj_reader *obj, source *s, line_reader *r, field keyword)
{
    mesh *m = obj->m;
    float x[6];

    if (field_is(keyword, "v")) {
        int n = read_numbers(s, r, "v", x, 6);
        if (n < 0)
            return false;
        if (n < 3)
            return fail_at(s, "expected 3 numbers after 'v'");
        if (n == 5 || n > 6)
            return fail_at(s, "too many numbers after 'v' (x y z [w], or x y z r g b)");
        mesh_add_position(m, vec3_make(x[0], x[1], x[2]));
        return true;
    }
    if (field_is(keyword, "vn")) {
        int n = read_numbers(s, r, "vn", x, 3);
        if (n < 0)
            return false;
        if (n != 3)
            return fail_at(s, n < 3 ? "expected 3 numbers after 'vn'" : "too many numbers after 'vn'");
        mesh_add_normal(m, vec3_make(x[0], x[1], x[2]));
        return true;
    }
    if (field_is(keyword, "vt")) {
        int n = read_numbers(s, r, "vt", x, 3);
        if (n < 0)
            return false;
        if (n < 1)
            return fail_at(s, "expected 1 to 3 numbers after 'vt'");
        if (n > 3)
            return fail_at(s, "too many numbers after 'vt'");
        mesh_add_texcoord(m, x[0], n >= 2 ? x[1] : 0.0f);
        return true;
    }
    if (field_is(keyword, "f"))
        return obj_face(obj, s, r);
    if (field_is(keyword, "mtllib"))
        return obj_mtllib(obj, s, r);
    return obj_usemtl(obj, s, r);
}

static bool obj_statement(void *context, source *s, line_reader *r, field keyword)
{
    obj_reader *obj = context;
    char shown[QUOTE_SIZE];
    if (field_is(keyword, "v") || field_is(keyword, "vn") || field_is(keyword, "vt") || field_is(keyword, "f") ||
        field_is(keyword, "mtllib") || field_is(keyword, "usemtl")) {
        if (!obj_data_statement(obj, s, r, keyword))
            return false;
        obj->recognised = true;
        return true;
    }
    if (field_is(keyword, "o") || field_is(keyword, "g") || field_is(keyword, "s") || field_is(keyword, "l") ||
        field_is(keyword, "p"))
        return true;
    /* Before any data, an unknown word says the file is of another kind
     * (an image, a scene file, a private key named by mistake or by a
     * hostile scene): say so, and print nothing of what it holds. After
     * data, it is a typo in an OBJ file ("vv 1 2 3"), shown to be found. */
    if (!obj->recognised)
        return fail_at(s, "not an OBJ file (this line starts with none of v, vn, vt, f, mtllib, usemtl, o, g, s, l, p)");
    return fail_at(s, "unknown statement '%s'", quote(keyword.start, keyword.length, shown));
}

bool mesh_parse_obj(mesh *m, const char *text, size_t length, const char *name, const char *base_dir, char *err,
                    size_t err_size)
{
    if (text == NULL)
        length = 0;
    obj_reader obj = {
        .m = m,
        .base_dir = base_dir,
        .position_base = m->position_count,
        .normal_base = m->normal_count,
        .texcoord_base = m->texcoord_count,
        .material = -1,
        .skipped_mtllib = false,
    };
    int face_base = m->face_count, material_base = m->material_count;
    source s = {name != NULL ? name : "(obj text)", 0, err, err_size};
    if (read_lines(text, length, &s, obj_statement, &obj))
        return true;
    /* Nothing half-loaded: everything this call appended is dropped (the
     * arrays keep their grown capacity, which is harmless). */
    m->position_count = obj.position_base;
    m->normal_count = obj.normal_base;
    m->texcoord_count = obj.texcoord_base;
    m->face_count = face_base;
    m->material_count = material_base;
    return false;
}

bool mesh_load_obj(mesh *m, const char *path, char *err, size_t err_size)
{
    char *text, why[INPUT_ERROR_SIZE];
    size_t length;
    if (!input_file_read(path, "OBJ", input_file_mesh_limit(), true, &text, &length, why, sizeof why)) {
        set_error(err, err_size, "%s: %s", path, why);
        return false;
    }
    /* MTL files are named relative to the OBJ file, not to the current
     * directory: base_dir is the path up to its last '/' ("" when there is
     * none, meaning here; "/" for a file in the root). */
    const char *slash = strrchr(path, '/');
    size_t dir_length = slash == NULL ? 0 : slash == path ? 1 : (size_t)(slash - path);
    char *base_dir = malloc(dir_length + 1);
    if (base_dir == NULL) {
        free(text);
        set_error(err, err_size, "%s: %s", path, strerror(ENOMEM));
        return false;
    }
    memcpy(base_dir, path, dir_length);
    base_dir[dir_length] = '\0';
    bool ok = mesh_parse_obj(m, text, length, path, base_dir, err, err_size);
    free(base_dir);
    free(text);
    return ok;
}

/* test_obj.c -- tests for common/program/obj.c: the OBJ/MTL reader and the writer.
 *
 * Most tests parse strings with mesh_parse_obj. Material libraries, loading
 * from a path and writing use files in a fresh mkdtemp directory under
 * /tmp, removed at the end.
 *
 * Every error test first loads a valid file into the mesh and then checks
 * that the bad one left every count exactly where it was, besides the
 * "name:LINE:" prefix of the message.
 *
 * Build: gcc -std=c11 -D_DEFAULT_SOURCE -Icommon/core -Icommon/program -Itests tests/test_obj.c \
 *          common/program/obj.c common/core/mesh.c common/core/memory.c -lcmocka -lm
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "mesh.h"
#include "obj.h"
#include "test_support.h"
#include "test_temp_dir.h"

#include <dirent.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum { PATH_SIZE = 4096 };

static char test_dir[] = "/tmp/test_obj.XXXXXX";

/* ---- helpers ----------------------------------------------------------- */

#define assert_contains(haystack, needle)                                                                 \
    do {                                                                                                  \
        if (strstr((haystack), (needle)) == NULL)                                                         \
            fail_msg("\"%s\" does not contain \"%s\"", (haystack), (needle));                             \
    } while (0)

#define assert_starts_with(text, prefix)                                                                  \
    do {                                                                                                  \
        if (strncmp((text), (prefix), strlen(prefix)) != 0)                                               \
            fail_msg("\"%s\" does not start with \"%s\"", (text), (prefix));                              \
    } while (0)

static const char *in_dir(char *buf, const char *name)
{
    snprintf(buf, PATH_SIZE, "%s/%s", test_dir, name);
    return buf;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

static bool file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0)
            count++;
    closedir(d);
    return count;
}

/* mesh_write_obj names its temporary files "<target>.tmp.<...>"; none may
 * outlive a call, successful or not. */
static int count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;)
        if (strstr(e->d_name, ".tmp.") != NULL)
            count++;
    closedir(d);
    return count;
}

TEST_TEMP_DIR_FIXTURES(test_dir)

/* Parses NUL-terminated text that must be valid. */
static void parse_ok(mesh *m, const char *text, const char *base_dir)
{
    char err[MESH_ERROR_SIZE] = "";
    if (!mesh_parse_obj(m, text, strlen(text), "t.obj", base_dir, err, sizeof err))
        fail_msg("unexpected error: %s", err);
}

static void assert_vec3_equal(vec3 actual, float x, float y, float z)
{
    assert_close(actual.x, x, 0);
    assert_close(actual.y, y, 0);
    assert_close(actual.z, z, 0);
}

static void assert_positions(const mesh *m, int face, int a, int b, int c)
{
    assert_int_equal(m->faces[face].position[0], a);
    assert_int_equal(m->faces[face].position[1], b);
    assert_int_equal(m->faces[face].position[2], c);
}

static void assert_normals(const mesh *m, int face, int a, int b, int c)
{
    assert_int_equal(m->faces[face].normal[0], a);
    assert_int_equal(m->faces[face].normal[1], b);
    assert_int_equal(m->faces[face].normal[2], c);
}

static void assert_texcoords(const mesh *m, int face, int a, int b, int c)
{
    assert_int_equal(m->faces[face].texcoord[0], a);
    assert_int_equal(m->faces[face].texcoord[1], b);
    assert_int_equal(m->faces[face].texcoord[2], c);
}

typedef struct {
    int positions, normals, texcoords, faces, materials;
} counts;

static counts counts_of(const mesh *m)
{
    return (counts){m->position_count, m->normal_count, m->texcoord_count, m->face_count, m->material_count};
}

static void assert_counts_equal(counts a, counts b)
{
    assert_int_equal(a.positions, b.positions);
    assert_int_equal(a.normals, b.normals);
    assert_int_equal(a.texcoords, b.texcoords);
    assert_int_equal(a.faces, b.faces);
    assert_int_equal(a.materials, b.materials);
}

/* Four vertices, two normals, two texcoords, a material and two faces: the
 * "previous file" every error test loads first, so that a failed load has
 * something to leave alone (and offsets that are not zero). */
static const char valid_obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                "vn 0 0 1\nvn 1 0 0\nvt 0 0\nvt 1 1\n"
                                "f 1/1/1 2/2/1 3/1/2\nf 1 3 4\n";

/* `length` bytes of text (may hold NULs) must fail with a message that
 * starts with "bad.obj:<line>:" and contains `needle`, leaving a mesh that
 * already holds valid_obj (and a material) exactly as it was. */
static void expect_error_n(const char *text, size_t length, int line, const char *needle)
{
    mesh m;
    mesh_init(&m);
    parse_ok(&m, valid_obj, NULL);
    mesh_material red = {.name = "red", .diffuse = {1, 0, 0}, .shininess = 1, .ior = 1};
    mesh_add_material(&m, &red);
    counts before = counts_of(&m);
    mesh_face first_face = m.faces[0];

    char err[MESH_ERROR_SIZE] = "";
    bool ok = mesh_parse_obj(&m, text, length, "bad.obj", NULL, err, sizeof err);
    if (ok)
        fail_msg("parsing succeeded, expected an error on line %d", line);
    char prefix[64];
    snprintf(prefix, sizeof prefix, "bad.obj:%d: ", line);
    assert_starts_with(err, prefix);
    assert_contains(err, needle);
    assert_counts_equal(counts_of(&m), before);
    assert_memory_equal(&m.faces[0], &first_face, sizeof first_face);
    mesh_free(&m);
}

static void expect_error(const char *text, int line, const char *needle)
{
    expect_error_n(text, strlen(text), line, needle);
}

/* ---- faces and indices ------------------------------------------------- */

static void test_all_four_index_forms(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m,
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
             "vt 0 0\nvt 1 0\nvt 0 1\n"
             "vn 0 0 1\nvn 0 1 0\nvn 1 0 0\n"
             "f 1 2 3\n"
             "f 2/3 3/2 4/1\n"
             "f 4//3 1//2 2//1\n"
             "f 3/1/2 4/2/3 1/3/1\n",
             NULL);
    assert_int_equal(m.face_count, 4);
    assert_positions(&m, 0, 0, 1, 2);
    assert_texcoords(&m, 0, -1, -1, -1);
    assert_normals(&m, 0, -1, -1, -1);

    assert_positions(&m, 1, 1, 2, 3);
    assert_texcoords(&m, 1, 2, 1, 0);
    assert_normals(&m, 1, -1, -1, -1);

    assert_positions(&m, 2, 3, 0, 1);
    assert_texcoords(&m, 2, -1, -1, -1);
    assert_normals(&m, 2, 2, 1, 0);

    assert_positions(&m, 3, 2, 3, 0);
    assert_texcoords(&m, 3, 0, 1, 2);
    assert_normals(&m, 3, 1, 2, 0);

    /* The values behind the indices are the ones on the lines. */
    assert_vec3_equal(m.positions[3], 1, 1, 0);
    assert_close(m.texcoords[2 * 2 + 1], 1, 0);
    assert_vec3_equal(m.normals[2], 1, 0, 0);
    mesh_free(&m);
}

static void test_mixed_index_forms_in_one_face(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\nvn 0 0 1\nf 1 2/1 3//1\n", NULL);
    assert_int_equal(m.face_count, 1);
    assert_positions(&m, 0, 0, 1, 2);
    assert_texcoords(&m, 0, -1, 0, -1);
    assert_normals(&m, 0, -1, -1, 0);
    mesh_free(&m);
}

static void test_negative_indices_count_back_from_latest(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m,
             "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
             "vt 0 0\nvt 1 0\nvn 0 0 1\n"
             "f -3/-2/-1 -2/-1/-1 -1/-2/-1\n"
             /* three more vertices: -1 now means the sixth */
             "v 5 5 5\nv 6 6 6\nv 7 7 7\nvn 1 0 0\n"
             "f -1//-1 -2//-2 -6//-1\n",
             NULL);
    assert_int_equal(m.face_count, 2);
    assert_positions(&m, 0, 0, 1, 2);
    assert_texcoords(&m, 0, 0, 1, 0);
    assert_normals(&m, 0, 0, 0, 0);
    assert_positions(&m, 1, 5, 4, 0);
    assert_normals(&m, 1, 1, 0, 1);
    assert_vec3_equal(mesh_vertex(&m, 1, 0), 7, 7, 7);
    mesh_free(&m);
}

static void test_quad_fan_triangulates_into_two(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n", NULL);
    assert_int_equal(m.face_count, 2);
    assert_positions(&m, 0, 0, 1, 2);
    assert_positions(&m, 1, 0, 2, 3);
    assert_normals(&m, 1, 0, 0, 0);
    mesh_free(&m);
}

static void test_pentagon_fan_triangulates_into_three(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 5 4 3 2 1\n", NULL);
    assert_int_equal(m.face_count, 3);
    assert_positions(&m, 0, 4, 3, 2);
    assert_positions(&m, 1, 4, 2, 1);
    assert_positions(&m, 2, 4, 1, 0);
    mesh_free(&m);
}

/* A polygon of 10000 corners on one line: streamed, 9998 triangles. */
static void test_huge_polygon(void **state)
{
    (void)state;
    enum { N = 10000 };
    size_t size = (size_t)N * 24 + 64;
    char *text = malloc(size);
    assert_non_null(text);
    size_t n = 0;
    for (int i = 0; i < N; i++)
        n += (size_t)snprintf(text + n, size - n, "v %d 0 0\n", i);
    n += (size_t)snprintf(text + n, size - n, "f");
    for (int i = 1; i <= N; i++)
        n += (size_t)snprintf(text + n, size - n, " %d", i);
    mesh m;
    mesh_init(&m);
    parse_ok(&m, text, NULL);
    assert_int_equal(m.face_count, N - 2);
    assert_positions(&m, N - 3, 0, N - 2, N - 1);
    mesh_free(&m);
    free(text);
}

/* A second file's indices start at its own first vertex, not the mesh's. */
static void test_indices_are_offset_by_what_the_mesh_holds(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    mesh_add_position(&m, vec3_make(9, 9, 9));
    mesh_add_normal(&m, vec3_make(0, 1, 0));
    parse_ok(&m, valid_obj, NULL);
    assert_int_equal(m.position_count, 5);
    assert_positions(&m, 0, 1, 2, 3);
    assert_normals(&m, 0, 1, 1, 2);
    assert_texcoords(&m, 0, 0, 1, 0);
    parse_ok(&m, "v 2 0 0\nv 3 0 0\nv 4 0 0\nf 1 2 -1\n", NULL);
    assert_positions(&m, 2, 5, 6, 7);
    mesh_free(&m);
}

static void test_vertex_w_colour_and_short_texcoord(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "v 1 2 3 0.5\nv 4 5 6 1 0 0\nvt 0.25\nvt 0.5 0.75 1\n", NULL);
    assert_int_equal(m.position_count, 2);
    assert_vec3_equal(m.positions[0], 1, 2, 3);
    assert_vec3_equal(m.positions[1], 4, 5, 6);
    assert_int_equal(m.texcoord_count, 2);
    assert_close(m.texcoords[0], 0.25, 0);
    assert_close(m.texcoords[1], 0, 0);
    assert_close(m.texcoords[3], 0.75, 0);
    mesh_free(&m);
}

/* ---- text conventions -------------------------------------------------- */

static void test_crlf_and_tabs(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "v\t1\t2\t3\r\nv 4  5 \t6\r\n\tv 7 8 9 \r\n\r\nf\t1 2\t3\r\ng\tgroup\r\n", NULL);
    assert_int_equal(m.position_count, 3);
    assert_vec3_equal(m.positions[1], 4, 5, 6);
    assert_vec3_equal(m.positions[2], 7, 8, 9);
    assert_int_equal(m.face_count, 1);
    mesh_free(&m);
}

static void test_comments_and_ignored_statements(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m,
             "# a comment\n"
             "o cube\ng side one\ns 1\ns off\n"
             "v 0 0 0 # trailing comment\nv 1 0 0\nv 0 1 0\n"
             "   # indented comment with junk: f 9 9 9\n"
             "l 1 2\np 1\n"
             "f 1 2 3 # done\n"
             "#f 1 2 3\n",
             NULL);
    assert_int_equal(m.position_count, 3);
    assert_int_equal(m.face_count, 1);
    mesh_free(&m);
}

static void test_empty_text_gives_an_empty_mesh(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    char err[MESH_ERROR_SIZE] = "untouched";
    assert_true(mesh_parse_obj(&m, "", 0, "empty.obj", NULL, err, sizeof err));
    assert_true(mesh_parse_obj(&m, NULL, 0, "empty.obj", NULL, err, sizeof err));
    parse_ok(&m, "\n\n  \r\n# only comments\n", NULL);
    assert_int_equal(m.face_count, 0);
    assert_int_equal(m.position_count, 0);
    mesh_free(&m);
}

/* The text is a span, not a C string: nothing past `length` is read. */
static void test_length_bounds_the_text(void **state)
{
    (void)state;
    const char text[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nthis is past the end";
    mesh m;
    mesh_init(&m);
    char err[MESH_ERROR_SIZE] = "";
    size_t length = strlen("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3");
    if (!mesh_parse_obj(&m, text, length, "t.obj", NULL, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(m.face_count, 1);
    mesh_free(&m);
}

static void test_utf8_byte_order_mark_is_skipped(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "\xEF\xBB\xBFv 1 2 3\n", NULL);
    assert_int_equal(m.position_count, 1);
    mesh_free(&m);
}

/* ---- errors ------------------------------------------------------------ */

static void test_error_index_out_of_range(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", 5, "face index 4 is out of range (3 vertices so far)");
    /* Counted per file: the 4 vertices of valid_obj already in the mesh don't count. */
    expect_error("v 0 0 0\nf 1 1 2\n", 2, "(1 vertex so far)");
    /* A vertex defined after the face does not count yet. */
    expect_error("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", 3, "face index 3 is out of range");
}

static void test_error_negative_index_out_of_range(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", 4, "face index -4 is out of range");
}

static void test_error_normal_and_texcoord_index_out_of_range(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", 5,
                 "normal index 2 is out of range (1 normal so far)");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", 4,
                 "texture coordinate index 1 is out of range (0 texture coordinates so far)");
}

static void test_error_huge_index(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999999\n", 4, "is out of range");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -2147483648\n", 4, "is out of range");
}

static void test_error_index_zero(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 0 2\n", 4, "face index 0 is invalid");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//0 3//1\n", 5, "normal index 0 is invalid");
}

static void test_error_too_few_vertices(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "a face needs at least 3 vertices");
    expect_error("v 0 0 0\nf # 1 2 3\n", 2, "a face needs at least 3 vertices");
}

static void test_error_bad_number(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 x 0\n", 2, "'x' after 'v' is not a number");
    expect_error("vn 0 0 1\nvn 0,5 0 1\n", 2, "'0,5' after 'vn' is not a number");
    expect_error("\n\n\nv 1 2\n", 4, "expected 3 numbers after 'v'");
    expect_error("vt\n", 1, "expected 1 to 3 numbers after 'vt'");
    expect_error("v 1 2 3 4 5\n", 1, "too many numbers after 'v'");
}

static void test_error_trailing_junk(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1.0abc 0 0\n", 2, "'1.0abc' after 'v' is not a number");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", 4, "'3x' is not a face index");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1.5\n", 4, "'1.5' is not a face index");
}

static void test_error_nan_and_inf(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv nan 0 0\n", 2, "'nan' after 'v' is not a finite number");
    expect_error("v 0 0 0\nv 0 0 0\nv 0 -inf 0\n", 3, "'-inf' after 'v' is not a finite number");
    /* Overflow is inf too. */
    expect_error("vn 1e39 0 0\n", 1, "'1e39' after 'vn' is not a finite number");
}

static void test_error_unknown_statement(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nvv 1 2 3\n", 2, "unknown statement 'vv'");
    expect_error("v 0 0 0\nV 0 0 0\n", 2, "unknown statement 'V'");
}

/* A file of another kind (named by mistake, or by a hostile scene or
 * mtllib: a private key, a password file) fails at the line where that
 * shows, naming the file and the line and nothing of what the file holds. */
static void test_a_file_of_another_kind_is_named_not_quoted(void **state)
{
    (void)state;
    static const char *const texts[] = {
        "SECRET-KEY-0123 abc\n",
        "# a comment first\n\nSECRET-KEY-0123 abc\n",
        "o name\ng group\ns 1\nSECRET-KEY-0123\n", /* names and groups are no OBJ data yet */
        "camera eye 0 0 5 target 0 0 0 SECRET-KEY-0123\n",
    };
    static const int lines[] = {1, 3, 4, 1};
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        expect_error(texts[i], lines[i], "not an OBJ file");
        mesh m;
        mesh_init(&m);
        char err[MESH_ERROR_SIZE] = "";
        assert_false(mesh_parse_obj(&m, texts[i], strlen(texts[i]), "bad.obj", NULL, err, sizeof err));
        if (strstr(err, "SECRET") != NULL || strstr(err, "camera") != NULL)
            fail_msg("the message quotes the file: %s", err);
        mesh_free(&m);
    }

    /* An mtllib naming a file that is not a material library: the OBJ
     * itself, or any other file. The MTL file and its line are named. */
    char path[PATH_SIZE], obj_path[PATH_SIZE], expected[2 * PATH_SIZE];
    write_text(in_dir(path, "secret.txt"), "SECRET-KEY-0123 abc\nmore\n");
    write_text(in_dir(obj_path, "names_secret.obj"), "v 0 0 0\nmtllib secret.txt\n");
    mesh m;
    mesh_init(&m);
    char err[MESH_ERROR_SIZE] = "";
    assert_false(mesh_load_obj(&m, obj_path, err, sizeof err));
    snprintf(expected, sizeof expected, "%s:1: not an MTL file", path);
    assert_starts_with(err, expected);
    assert_null(strstr(err, "SECRET"));
    write_text(obj_path, "mtllib names_secret.obj\n");
    assert_false(mesh_load_obj(&m, obj_path, err, sizeof err));
    snprintf(expected, sizeof expected, "%s:1: not an MTL file", obj_path);
    assert_starts_with(err, expected);
    assert_null(strstr(err, "mtllib"));
    assert_int_equal(m.position_count, 0);
    mesh_free(&m);
}

static void test_error_garbage_bytes(void **state)
{
    (void)state;
    expect_error("v 0 0 0\n\x01\x02\xff\n", 2, "unexpected byte 0x01");
    /* High bytes alone are allowed in names, so they make an unknown
     * statement, printed escaped. */
    expect_error("v 0 0 0\nv 1 0 0\n\xff\xfe\n", 3, "unknown statement '\\xff\\xfe'");
    static const char nul[] = "v 0 0 0\nv 1 0 0\0\nv 0 1 0\n";
    expect_error_n(nul, sizeof nul - 1, 2, "unexpected byte 0x00");
}

static void test_error_truncated_face_vertex(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/", 4, "'1/' is not a face vertex");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3//\n", 4, "'3//' is not a face vertex");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 /1\n", 4, "'/1' is not a face vertex");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/1/1\n", 4, "'3/1/1/1' is not a face vertex");
}

/* The quad's first triangle is added before the bad corner is seen: it
 * must be taken back. */
static void test_error_mid_polygon_adds_no_faces(void **state)
{
    (void)state;
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4 9\n", 5, "face index 9 is out of range");
}

static void test_error_unknown_usemtl_names_the_material(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    char path[PATH_SIZE], err[MESH_ERROR_SIZE] = "";
    write_text(in_dir(path, "one.mtl"), "newmtl red\nKd 1 0 0\n");
    const char *text = "mtllib one.mtl\nv 0 0 0\nusemtl blue\n";
    assert_false(mesh_parse_obj(&m, text, strlen(text), "m.obj", test_dir, err, sizeof err));
    assert_starts_with(err, "m.obj:3: ");
    assert_contains(err, "'blue'");
    /* The library's material was taken back with everything else. */
    assert_int_equal(m.material_count, 0);
    assert_int_equal(m.position_count, 0);
    mesh_free(&m);
}

/* Without base_dir no MTL file is read, on purpose; usemtl names that it
 * would have defined must then not be errors. With no mtllib at all, an
 * unknown name still is. */
static void test_mtllib_skipped_without_base_dir(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "mtllib does_not_exist.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n", NULL);
    assert_int_equal(m.material_count, 0);
    assert_int_equal(m.faces[0].material, -1);
    mesh_free(&m);
    expect_error("v 0 0 0\nusemtl blue\n", 2, "unknown material 'blue'");
}

/* ---- materials --------------------------------------------------------- */

static void test_mtl_values_and_defaults(void **state)
{
    (void)state;
    char path[PATH_SIZE];
    write_text(in_dir(path, "values.mtl"), "# made by hand\r\n"
                                           "newmtl shiny\r\n"
                                           "\tKa 0.1 0.1 0.1\n"
                                           "Kd 0.5 0.25 0.125\n"
                                           "Ks 0.9 0.8 0.7\n"
                                           "Ns 250\n"
                                           "Ke 2 3 4\n"
                                           "Ni 1.5\n"
                                           "d 1\nTr 0\nillum 2\nmap_Kd tex.png\nmap_Bump -bm 1 n.png\n"
                                           "\n"
                                           "newmtl plain\n"
                                           "newmtl grey\n"
                                           "Kd 0.3\n");
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "mtllib values.mtl\n", test_dir);
    assert_int_equal(m.material_count, 3);
    const mesh_material *shiny = &m.materials[0], *plain = &m.materials[1], *grey = &m.materials[2];
    assert_string_equal(shiny->name, "shiny");
    assert_vec3_equal(shiny->diffuse, 0.5f, 0.25f, 0.125f);
    assert_vec3_equal(shiny->specular, 0.9f, 0.8f, 0.7f);
    assert_close(shiny->shininess, 250, 0);
    assert_vec3_equal(shiny->emission, 2, 3, 4);
    assert_close(shiny->ior, 1.5, 0);

    assert_string_equal(plain->name, "plain");
    assert_vec3_equal(plain->diffuse, 0.8f, 0.8f, 0.8f);
    assert_vec3_equal(plain->specular, 0, 0, 0);
    assert_vec3_equal(plain->emission, 0, 0, 0);
    assert_close(plain->shininess, 1, 0);
    assert_close(plain->ior, 1, 0);

    assert_vec3_equal(grey->diffuse, 0.3f, 0.3f, 0.3f);
    mesh_free(&m);
}

static void test_usemtl_assigns_following_faces(void **state)
{
    (void)state;
    char path[PATH_SIZE];
    write_text(in_dir(path, "two.mtl"), "newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\n");
    mesh m;
    mesh_init(&m);
    /* A material already in the mesh, with a name the file defines again:
     * the file's materials get indices after it, and its "red" wins. */
    mesh_material old_red = {.name = "red", .shininess = 1, .ior = 1};
    mesh_add_material(&m, &old_red);
    parse_ok(&m,
             "mtllib two.mtl\n"
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
             "f 1 2 3\n"
             "usemtl green\n"
             "f 1 2 3 4\n"
             "usemtl red\n"
             "f 2 3 4\n"
             "usemtl green\n"
             "g next\n"
             "f 1 3 4\n",
             test_dir);
    assert_int_equal(m.material_count, 3);
    assert_string_equal(m.materials[1].name, "red");
    assert_string_equal(m.materials[2].name, "green");
    assert_int_equal(m.face_count, 5);
    assert_int_equal(m.faces[0].material, -1);
    assert_int_equal(m.faces[1].material, 2);
    assert_int_equal(m.faces[2].material, 2);
    assert_int_equal(m.faces[3].material, 1);
    assert_int_equal(m.faces[4].material, 2);
    assert_vec3_equal(m.materials[m.faces[3].material].diffuse, 1, 0, 0);

    /* A later file without mtllib may use materials already in the mesh. */
    parse_ok(&m, "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl green\nf 1 2 3\n", NULL);
    assert_int_equal(m.faces[5].material, 2);
    mesh_free(&m);
}

/* A face that emits (its material's Ke > 0) must have area, like a scene
 * file's emitting quad: without, it gives no light. A polygon with some
 * corners on a line still has area; a face that does not emit may be
 * degenerate (it is never hit). The error leaves the mesh as it was. */
static void test_an_emitting_face_without_area_is_an_error(void **state)
{
    (void)state;
    char path[PATH_SIZE];
    write_text(in_dir(path, "lamp.mtl"), "newmtl lamp\nKe 0 0 2\nnewmtl dark\nKe 0 0 0\nnewmtl paint\nKd 1 1 1\n");
    static const char corners[] = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n";
    char text[512], err[MESH_ERROR_SIZE] = "";
    mesh m;
    mesh_init(&m);
    parse_ok(&m, valid_obj, NULL);
    counts before = counts_of(&m);
    /* Corners 1 2 3 are on a line (as is 1 2 1, and a face on one point). */
    static const char *const degenerate[] = {"f 1 2 3", "f 1 2 3 2", "f 4 4 4"};
    for (size_t i = 0; i < sizeof degenerate / sizeof degenerate[0]; i++) {
        snprintf(text, sizeof text, "mtllib lamp.mtl\n%susemtl lamp\n%s\n", corners, degenerate[i]);
        assert_false(mesh_parse_obj(&m, text, strlen(text), "e.obj", test_dir, err, sizeof err));
        assert_string_equal(err, "e.obj:7: the face emits light (material 'lamp', Ke > 0) but has no area: its corners "
                                 "are on a line");
        assert_counts_equal(counts_of(&m), before);
    }
    /* With area: a triangle, and a quad whose first fan triangle has none. */
    snprintf(text, sizeof text, "mtllib lamp.mtl\n%susemtl lamp\nf 1 2 4\nf 1 2 3 4\n", corners);
    parse_ok(&m, text, test_dir);
    assert_int_equal(m.face_count, before.faces + 3);
    /* Not emitting: no material, Ke 0, a diffuse paint. */
    snprintf(text, sizeof text, "mtllib lamp.mtl\n%sf 1 2 3\nusemtl dark\nf 1 2 3\nusemtl paint\nf 1 2 3\n", corners);
    parse_ok(&m, text, test_dir);
    assert_int_equal(m.face_count, before.faces + 6);
    mesh_free(&m);
}

static void test_mtllib_several_files_on_one_line(void **state)
{
    (void)state;
    char path[PATH_SIZE];
    write_text(in_dir(path, "a.mtl"), "newmtl a\nKd 0.1 0.1 0.1\n");
    write_text(in_dir(path, "b.mtl"), "newmtl b\nKd 0.2 0.2 0.2\n");
    mesh m;
    mesh_init(&m);
    parse_ok(&m, "mtllib a.mtl\tb.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl b\nf 1 2 3\n", test_dir);
    assert_int_equal(m.material_count, 2);
    assert_int_equal(m.faces[0].material, 1);
    mesh_free(&m);
}

static void test_error_missing_mtl_file(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    char err[MESH_ERROR_SIZE] = "";
    const char *text = "v 0 0 0\n\nmtllib nowhere.mtl\n";
    assert_false(mesh_parse_obj(&m, text, strlen(text), "m.obj", test_dir, err, sizeof err));
    assert_starts_with(err, "m.obj:3: ");
    assert_contains(err, "nowhere.mtl");
    assert_contains(err, "No such file or directory");
    assert_int_equal(m.position_count, 0);
    mesh_free(&m);
}

/* An error inside the MTL file names the MTL file and its own line. */
static void test_error_in_mtl_names_mtl_file_and_line(void **state)
{
    (void)state;
    char path[PATH_SIZE], expected[PATH_SIZE + 32], err[MESH_ERROR_SIZE] = "";
    write_text(in_dir(path, "bad.mtl"), "newmtl red\n\nKd 1 0 zero\n");
    mesh m;
    mesh_init(&m);
    const char *text = "v 0 0 0\nmtllib bad.mtl\n";
    assert_false(mesh_parse_obj(&m, text, strlen(text), "m.obj", test_dir, err, sizeof err));
    snprintf(expected, sizeof expected, "%s:3: ", path);
    assert_starts_with(err, expected);
    assert_contains(err, "'zero' after 'Kd' is not a number");

    write_text(in_dir(path, "typo.mtl"), "newmtl red\nKdd 1 0 0\n");
    text = "mtllib typo.mtl\n";
    assert_false(mesh_parse_obj(&m, text, strlen(text), "m.obj", test_dir, err, sizeof err));
    snprintf(expected, sizeof expected, "%s:2: unknown statement 'Kdd'", path);
    assert_string_equal(err, expected);

    write_text(in_dir(path, "early.mtl"), "Kd 1 0 0\n");
    text = "mtllib early.mtl\n";
    assert_false(mesh_parse_obj(&m, text, strlen(text), "m.obj", test_dir, err, sizeof err));
    assert_contains(err, "early.mtl:1: 'Kd' before any 'newmtl'");
    assert_int_equal(m.material_count, 0);
    mesh_free(&m);
}

/* A negative Ke is an error naming the MTL file and line, as a scene
 * file's negative emission is (it was dropped as "emits nothing", the
 * material printed as a plain diffuse). The twin: Ke 0 and Ke 5 load. */
static void test_negative_emission_in_mtl_is_an_error(void **state)
{
    (void)state;
    char path[PATH_SIZE], expected[PATH_SIZE + 64], err[MESH_ERROR_SIZE] = "";
    static const char *const negative[] = {"Ke -5", "Ke 1 -0.5 1", "Ke 0 0 -1e-3"};
    mesh m;
    mesh_init(&m);
    for (size_t i = 0; i < sizeof negative / sizeof negative[0]; i++) {
        char mtl[128];
        snprintf(mtl, sizeof mtl, "newmtl lamp\nKd 1 1 1\n%s\n", negative[i]);
        write_text(in_dir(path, "negative.mtl"), mtl);
        const char *text = "mtllib negative.mtl\n";
        assert_false(mesh_parse_obj(&m, text, strlen(text), "m.obj", test_dir, err, sizeof err));
        snprintf(expected, sizeof expected, "%s:3: '", path);
        assert_starts_with(err, expected);
        assert_contains(err, "an emission cannot be negative");
        assert_int_equal(m.material_count, 0);
    }
    write_text(in_dir(path, "negative.mtl"), "newmtl dark\nKe 0\nnewmtl lamp\nKe 5\n");
    parse_ok(&m, "mtllib negative.mtl\n", test_dir);
    assert_int_equal(m.material_count, 2);
    assert_true(m.materials[1].emission.x == 5.0f);
    mesh_free(&m);
}

/* ---- files ------------------------------------------------------------- */

static void test_load_missing_file(void **state)
{
    (void)state;
    char path[PATH_SIZE], expected[PATH_SIZE + 128], err[MESH_ERROR_SIZE] = "";
    mesh m;
    mesh_init(&m);
    in_dir(path, "no_such.obj");
    assert_false(mesh_load_obj(&m, path, err, sizeof err));
    snprintf(expected, sizeof expected, "%s: No such file or directory", path);
    assert_string_equal(err, expected);
    /* A directory is not a file either. */
    assert_false(mesh_load_obj(&m, test_dir, err, sizeof err));
    assert_starts_with(err, test_dir);
    assert_int_equal(m.position_count, 0);
    mesh_free(&m);
}

/* mtllib is found beside the OBJ file, wherever the current directory is. */
static void test_load_finds_mtl_beside_the_obj(void **state)
{
    (void)state;
    char sub[PATH_SIZE], path[PATH_SIZE + 32], err[MESH_ERROR_SIZE] = "";
    in_dir(sub, "model");
    assert_int_equal(mkdir(sub, 0777), 0);
    snprintf(path, sizeof path, "%s/cube.mtl", sub);
    write_text(path, "newmtl glow\nKe 5 5 5\n");
    snprintf(path, sizeof path, "%s/cube.obj", sub);
    write_text(path, "mtllib cube.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glow\nf 1 2 3\n");
    mesh m;
    mesh_init(&m);
    if (!mesh_load_obj(&m, path, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(m.face_count, 1);
    assert_int_equal(m.faces[0].material, 0);
    assert_vec3_equal(m.materials[0].emission, 5, 5, 5);

    /* Errors from a loaded file carry its path as given. */
    write_text(path, "v 0 0 0\n\nf 1 1\n");
    char expected[PATH_SIZE + 128];
    snprintf(expected, sizeof expected, "%s:3: a face needs at least 3 vertices", path);
    assert_false(mesh_load_obj(&m, path, err, sizeof err));
    assert_string_equal(err, expected);
    assert_int_equal(m.face_count, 1);
    mesh_free(&m);
}

/* Awkward floats: %.9g must bring every one back bit for bit. */
static void test_write_then_load_round_trip(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[MESH_ERROR_SIZE] = "";
    mesh a, b;
    mesh_init(&a);
    mesh_init(&b);
    const float values[] = {0.1f, -0.0f, 1.0f / 3.0f, 16777217.0f, FLT_MAX, -FLT_MIN, 1e-40f /* subnormal */,
                            FLT_TRUE_MIN, 123456.789f, -2.5e-7f, 3.14159274f, 0.0f};
    int count = (int)(sizeof values / sizeof values[0]);
    for (int i = 0; i < count; i++)
        mesh_add_position(&a, vec3_make(values[i], values[(i + 1) % count], values[(i + 5) % count]));
    for (int i = 0; i + 2 < count; i++)
        mesh_add_triangle(&a, i, (i + 2) % count, count - 1 - i, -1);
    in_dir(path, "round.obj");
    if (!mesh_write_obj(&a, path, err, sizeof err))
        fail_msg("%s", err);
    if (!mesh_load_obj(&b, path, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(b.position_count, a.position_count);
    assert_memory_equal(b.positions, a.positions, (size_t)a.position_count * sizeof(vec3));
    assert_int_equal(b.face_count, a.face_count);
    for (int i = 0; i < a.face_count; i++)
        assert_memory_equal(b.faces[i].position, a.faces[i].position, sizeof a.faces[i].position);

    /* Writing over an existing file replaces it and leaves no temporary file. */
    mesh_add_position(&a, vec3_make(7, 8, 9));
    if (!mesh_write_obj(&a, path, err, sizeof err))
        fail_msg("%s", err);
    mesh_free(&b);
    mesh_init(&b);
    if (!mesh_load_obj(&b, path, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(b.position_count, count + 1);
    assert_vec3_equal(b.positions[count], 7, 8, 9);
    assert_int_equal(count_temp_files(test_dir), 0);
    mesh_free(&a);
    mesh_free(&b);
}

static void test_write_into_missing_directory_fails_cleanly(void **state)
{
    (void)state;
    char dir[PATH_SIZE], path[PATH_SIZE + 16], err[MESH_ERROR_SIZE] = "";
    in_dir(dir, "missing");
    snprintf(path, sizeof path, "%s/out.obj", dir);
    int before = count_entries(test_dir);
    mesh m;
    mesh_init(&m);
    mesh_add_position(&m, vec3_make(0, 0, 0));
    mesh_add_position(&m, vec3_make(1, 0, 0));
    mesh_add_position(&m, vec3_make(0, 1, 0));
    mesh_add_triangle(&m, 0, 1, 2, -1);
    assert_false(mesh_write_obj(&m, path, err, sizeof err));
    char expected[PATH_SIZE + 128];
    snprintf(expected, sizeof expected, "cannot write '%s': No such file or directory", path);
    assert_string_equal(err, expected);
    assert_false(file_exists(path));
    assert_false(file_exists(dir));
    assert_int_equal(count_entries(test_dir), before);
    mesh_free(&m);
}

/* The temporary file is written, then rename(2) fails (the target is a
 * directory): the temporary file must be removed, the target untouched. */
static void test_failed_rename_leaves_no_temporary_file(void **state)
{
    (void)state;
    char path[PATH_SIZE], inside[PATH_SIZE + 16], err[MESH_ERROR_SIZE] = "";
    in_dir(path, "taken.obj");
    assert_int_equal(mkdir(path, 0777), 0);
    snprintf(inside, sizeof inside, "%s/keep", path);
    write_text(inside, "x");
    mesh m;
    mesh_init(&m);
    mesh_add_position(&m, vec3_make(1, 2, 3));
    assert_false(mesh_write_obj(&m, path, err, sizeof err));
    assert_contains(err, path);
    assert_int_equal(count_temp_files(test_dir), 0);
    assert_true(file_exists(inside));
    mesh_free(&m);
}

/* What the reader would reject is not written: no file appears at all. */
static void test_write_refuses_what_cannot_be_read_back(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[MESH_ERROR_SIZE] = "";
    in_dir(path, "refused.obj");
    mesh m;
    mesh_init(&m);
    mesh_add_position(&m, vec3_make(0, NAN, 0));
    assert_false(mesh_write_obj(&m, path, err, sizeof err));
    assert_starts_with(err, path);
    assert_contains(err, "not finite");
    m.positions[0] = vec3_make(0, 0, 0);
    mesh_add_triangle(&m, 0, 0, 1, -1);
    assert_false(mesh_write_obj(&m, path, err, sizeof err));
    assert_starts_with(err, path);
    assert_false(file_exists(path));
    mesh_free(&m);
}

/* ---- robustness -------------------------------------------------------- */

/* Random bytes, and random mutations of a valid file: never a crash (the
 * sanitizer build is what really checks this), and every failure is a
 * "name:line:" message with the mesh unchanged. */
static void test_random_input_fails_cleanly(void **state)
{
    (void)state;
    static const char alphabet[] = "vtnf/-0123456789. \n\r\t#eE+ximusl\x01\xff";
    uint64_t seed = 0x0B1EC7ull;
    char text[256];
    mesh m;
    mesh_init(&m);
    parse_ok(&m, valid_obj, NULL);
    counts before = counts_of(&m);
    for (int round = 0; round < 20000; round++) {
        size_t length = 0;
        if (round % 2 == 0) {
            /* Mutate a valid file: the interesting errors are near-misses. */
            length = sizeof valid_obj - 1;
            memcpy(text, valid_obj, length);
            for (int k = 0; k < 3; k++) {
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                text[(seed >> 33) % length] = alphabet[(seed >> 17) % (sizeof alphabet - 1)];
            }
        } else {
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            length = (size_t)(seed >> 33) % sizeof text;
            for (size_t i = 0; i < length; i++) {
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                text[i] = (seed >> 60) < 12 ? alphabet[(seed >> 17) % (sizeof alphabet - 1)] : (char)(seed >> 40);
            }
        }
        char err[MESH_ERROR_SIZE] = "";
        counts at_entry = counts_of(&m);
        if (mesh_parse_obj(&m, text, length, "r.obj", NULL, err, sizeof err))
            continue;
        assert_starts_with(err, "r.obj:");
        assert_counts_equal(counts_of(&m), at_entry);
    }
    assert_true(m.position_count >= before.positions);
    mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_all_four_index_forms),
        cmocka_unit_test(test_mixed_index_forms_in_one_face),
        cmocka_unit_test(test_negative_indices_count_back_from_latest),
        cmocka_unit_test(test_quad_fan_triangulates_into_two),
        cmocka_unit_test(test_pentagon_fan_triangulates_into_three),
        cmocka_unit_test(test_huge_polygon),
        cmocka_unit_test(test_indices_are_offset_by_what_the_mesh_holds),
        cmocka_unit_test(test_vertex_w_colour_and_short_texcoord),
        cmocka_unit_test(test_crlf_and_tabs),
        cmocka_unit_test(test_comments_and_ignored_statements),
        cmocka_unit_test(test_empty_text_gives_an_empty_mesh),
        cmocka_unit_test(test_length_bounds_the_text),
        cmocka_unit_test(test_utf8_byte_order_mark_is_skipped),
        cmocka_unit_test(test_error_index_out_of_range),
        cmocka_unit_test(test_error_negative_index_out_of_range),
        cmocka_unit_test(test_error_normal_and_texcoord_index_out_of_range),
        cmocka_unit_test(test_error_huge_index),
        cmocka_unit_test(test_error_index_zero),
        cmocka_unit_test(test_error_too_few_vertices),
        cmocka_unit_test(test_error_bad_number),
        cmocka_unit_test(test_error_trailing_junk),
        cmocka_unit_test(test_error_nan_and_inf),
        cmocka_unit_test(test_error_unknown_statement),
        cmocka_unit_test(test_a_file_of_another_kind_is_named_not_quoted),
        cmocka_unit_test(test_error_garbage_bytes),
        cmocka_unit_test(test_error_truncated_face_vertex),
        cmocka_unit_test(test_error_mid_polygon_adds_no_faces),
        cmocka_unit_test(test_error_unknown_usemtl_names_the_material),
        cmocka_unit_test(test_mtllib_skipped_without_base_dir),
        cmocka_unit_test(test_mtl_values_and_defaults),
        cmocka_unit_test(test_usemtl_assigns_following_faces),
        cmocka_unit_test(test_an_emitting_face_without_area_is_an_error),
        cmocka_unit_test(test_mtllib_several_files_on_one_line),
        cmocka_unit_test(test_error_missing_mtl_file),
        cmocka_unit_test(test_error_in_mtl_names_mtl_file_and_line),
        cmocka_unit_test(test_negative_emission_in_mtl_is_an_error),
        cmocka_unit_test(test_load_missing_file),
        cmocka_unit_test(test_load_finds_mtl_beside_the_obj),
        cmocka_unit_test(test_write_then_load_round_trip),
        cmocka_unit_test(test_write_into_missing_directory_fails_cleanly),
        cmocka_unit_test(test_failed_rename_leaves_no_temporary_file),
        cmocka_unit_test(test_write_refuses_what_cannot_be_read_back),
        cmocka_unit_test(test_random_input_fails_cleanly),
    };
    return cmocka_run_group_tests(tests, make_test_dir, remove_test_dir);
}

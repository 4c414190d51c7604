/* test_scene_file.c -- the scene file parser, the effects analysis, the
 * counters file and the --scene / --explain flags (all in common/). Every
 * error test checks the message names the file, the line and the column of
 * the offending token, and that nothing is left half-built. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "counters.h"
#include "counters_file.h"
#include "effects.h"
#include "scene_file.h"
#include "test_support.h"

static bool parse(scene_desc *d, const char *text, char *err)
{
    return scene_desc_parse(d, text, strlen(text), "t.scene", "base", err, SCENE_ERROR_SIZE);
}

/* ---- a full scene ------------------------------------------------------------------ */

static const char *const FULL =
    "# every statement once\n"
    "camera eye 0 1 5 target 0 0 0 up 0 1 0 fov 45\n"
    "image width 320 height 240 spp 8\n"
    "background 0.1 0.2 0.3   # sky\n"
    "ambient 0.05 0.05 0.05\n"
    "material white diffuse albedo 0.8 0.8 0.8\n"
    "material floor blinn_phong diffuse 0.7 0.7 0.7 specular 0.2 0.2 0.2 shininess 16 checker 0.1 0.1 0.1 size 2\n"
    "material m mirror\n"
    "material g glass ior 1.33\n"
    "material metal glossy albedo 0.9 0.6 0.5 roughness 0.2\n"
    "material lamp emissive emission 10 9 8\n"
    "light point position 1 2 3 intensity 5 5 5\n"
    "light area p0 0 4 0 p1 1 4 0 p2 1 4 1 p3 0 4 1 emission 3 3 3\n"
    "sphere center 0 1 0 radius 1 material white\n"
    "sphere center 0 0 0 radius 10 material lamp inside_out\n"
    "plane point 0 0 0 normal 0 2 0 material floor\n"
    "triangle p0 0 0 0 p1 1 0 0 p2 0 1 0 material g\n"
    "quad p0 0 0 0 p1 1 0 0 p2 1 1 0 p3 0 1 0 material m\n"
    "implicit torus center 0 0.3 0 major 0.75 minor 0.3 material metal\n"
    "mesh path \"meshes/bunny one.obj\" material white\n"
    "mesh generator tori_field triangles 1024\n"
    "integrator mis\n"
    "max_depth 12\n"
    "effects without indirect glossy\n";

static void test_full_scene_parses_every_statement(void **state)
{
    (void)state;
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!parse(&d, FULL, err))
        fail_msg("%s", err);
    assert_true(d.has_camera);
    assert_close(d.eye.z, 5.0, 0);
    assert_close(d.fov_degrees, 45.0, 0);
    assert_int_equal(d.width, 320);
    assert_int_equal(d.height, 240);
    assert_int_equal(d.spp, 8);
    assert_close(d.background.z, 0.3, 1e-7);
    assert_int_equal(d.material_count, 6);
    assert_int_equal(d.materials[1].kind, SCENE_MATERIAL_BLINN_PHONG);
    assert_close(d.materials[1].checker_size, 2.0, 0);
    assert_close(d.materials[1].shininess, 16.0, 0);
    assert_int_equal(d.materials[3].kind, SCENE_MATERIAL_GLASS);
    assert_close(d.materials[3].ior, 1.33, 1e-6);
    assert_close(d.materials[4].roughness, 0.2, 1e-7);
    assert_close(d.materials[5].emission.x, 10.0, 0);
    assert_int_equal(d.light_count, 2);
    assert_int_equal(d.lights[1].kind, SCENE_LIGHT_AREA);
    assert_int_equal(d.shape_count, 8);
    assert_true(d.shapes[1].inside_out);
    assert_close(d.shapes[2].normal.y, 1.0, 0); /* normalised */
    assert_int_equal(d.shapes[3].kind, SCENE_SHAPE_TRIANGLE);
    assert_int_equal(d.shapes[3].material, 3);
    assert_int_equal(d.shapes[4].kind, SCENE_SHAPE_QUAD);
    assert_int_equal(d.shapes[5].kind, SCENE_SHAPE_TORUS);
    assert_string_equal(d.shapes[6].path, "base/meshes/bunny one.obj"); /* relative to the scene file */
    assert_int_equal(d.shapes[6].line, 20);
    assert_int_equal(d.shapes[7].kind, SCENE_SHAPE_MESH_TORI);
    assert_int_equal(d.shapes[7].material, -1);
    assert_string_equal(d.integrator, "mis");
    assert_int_equal(d.max_depth, 12);
    assert_int_equal(d.effects_allowed, EFFECT_SHADOWS | EFFECT_REFLECTION | EFFECT_REFRACTION);
    scene_desc_free(&d);
}

/* ---- errors: file:line:col, and nothing half-built ----------------------------------- */

typedef struct {
    const char *text;
    const char *expected; /* the start of the message */
} bad_case;

static void test_errors_name_line_and_column(void **state)
{
    (void)state;
    const char *m = "material w diffuse albedo 0.5 0.5 0.5\n";
    char text[1024];
    static const bad_case cases[] = {
        {"sphere center 0 0 0 radius 1 material w colour 1\n", "t.scene:2:41: unknown key 'colour' for sphere"},
        {"cube size 1\n", "t.scene:2:1: unknown statement 'cube'"},
        {"sphere center 0 0 nan radius 1 material w\n", "t.scene:2:19: expected a number, got 'nan'"},
        {"sphere center 0 0 inf radius 1 material w\n", "t.scene:2:19: expected a number, got 'inf'"},
        {"sphere center 0 0 1e999 radius 1 material w\n", "t.scene:2:19: number '1e999' is out of range"},
        {"sphere center 0 0 0x10 radius 1 material w\n", "t.scene:2:19: expected a number, got '0x10'"},
        {"sphere center 0 0 0 radius -1 material w\n", "t.scene:2:28: -1 must be from"},
        {"sphere center 0 0 0 radius 1\n", "t.scene:2:1: sphere needs 'material'"},
        {"sphere center 0 0 0 radius 1 material nope\n", "t.scene:2:39: unknown material 'nope'"},
        {"sphere center 0 0 0 radius 1 radius 2 material w\n", "t.scene:2:30: 'radius' given twice"},
        {"sphere center 0 0 radius 1 material w\n", "t.scene:2:19: expected a number, got 'radius'"},
        {"sphere center 0 0 0 radius\n", "t.scene:2:21: 'radius' needs 1 value"},
        {"material w diffuse albedo 1 1 1\n", "t.scene:2:10: material 'w' is defined twice"},
        {"material x glass ior 1.5 roughness 0.1\n", "t.scene:2:26: unknown key 'roughness' for a glass material"},
        {"material x glass\n", "t.scene:2:12: a glass material needs 'ior'"},
        {"material x diffuse albedo 2 0 0\n", "t.scene:2:27: 2 must be from 0 to 1"},
        {"material x plastic\n", "t.scene:2:12: unknown material kind 'plastic'"},
        {"mesh path \"a.obj\n", "t.scene:2:11: unterminated string"},
        {"mesh generator teapot\n", "t.scene:2:16: unknown mesh generator 'teapot'"},
        {"camera eye 0 0 0 target 0 0 0\n", "t.scene:2:18: the camera's target is its eye"},
        {"camera eye 0 0 5 target 0 0 0\ncamera eye 0 0 5 target 0 0 0\n", "t.scene:3:1: a second camera"},
        {"effects without shadow\n", "t.scene:2:17: unknown effect 'shadow'"},
        {"plane point 0 0 0 normal 0 0 0 material w\n", "t.scene:2:19: a plane's normal must not be zero"},
        {"implicit torus center 0 0 0 major 1 minor 2 material w\n", "t.scene:2:37: a torus needs minor < major"},
        {"light area p0 0 0 0 p1 1 0 0 p2 2 0 0 p3 0 0 1 emission 1 1 1\n", "t.scene:2:7: the area light has no area"},
        /* The same corners on an emitting quad or triangle: also a light without area. */
        {"material e emissive emission 1 1 1\nquad p0 0 0 0 p1 1 0 0 p2 2 0 0 p3 0 0 1 material e\n",
         "t.scene:3:1: the quad emits light (material 'e') but has no area (p0, p1, p2 on a line)"},
        {"material e emissive emission 0 0 5\ntriangle p0 1 1 1 p1 1 1 1 p2 0 0 0 material e\n",
         "t.scene:3:1: the triangle emits light (material 'e') but has no area (p0, p1, p2 on a line)"},
        {"image width 0\n", "t.scene:2:13: 0 must be from 1 to 16384"},
        {"max_depth 2.5\n", "t.scene:2:11: max_depth must be a whole number"},
        {"sphere center 0 0 0 radius 1 material w\x01\n", "t.scene:2:40: unexpected character"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(text, sizeof text, "%s%s", m, cases[i].text);
        scene_desc d;
        char err[SCENE_ERROR_SIZE] = "";
        if (parse(&d, text, err))
            fail_msg("case %zu parsed: %s", i, cases[i].text);
        if (strncmp(err, cases[i].expected, strlen(cases[i].expected)) != 0)
            fail_msg("case %zu: got '%s', expected '%s...'", i, err, cases[i].expected);
        /* Nothing half-built: the description is empty. */
        assert_int_equal(d.material_count, 0);
        assert_int_equal(d.shape_count, 0);
        assert_null(d.materials);
        assert_null(d.shapes);
        assert_null(d.lights);
    }
}

/* A degenerate shape that does not emit is harmless (it is never hit), and
 * an emissive material with zero emission does not emit. */
static void test_only_emitting_shapes_must_have_area(void **state)
{
    (void)state;
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    const char *text = "material w diffuse albedo 0.5 0.5 0.5\n"
                       "material off emissive emission 0 0 0\n"
                       "material e emissive emission 1 1 1\n"
                       "quad p0 0 0 0 p1 1 0 0 p2 2 0 0 p3 0 0 1 material w\n"
                       "triangle p0 0 0 0 p1 0 0 0 p2 0 0 0 material off\n"
                       "quad p0 0 0 0 p1 1 0 0 p2 1 1 0 p3 1 1 0 material e\n";
    if (!parse(&d, text, err))
        fail_msg("%s", err);
    assert_int_equal(d.shape_count, 3);
    scene_desc_free(&d);
}

/* A file of another kind given as a scene (an OBJ, a password file): the
 * file and the line, nothing of its content. After a statement, an unknown
 * word is a typo and is shown. */
static void test_a_file_of_another_kind_is_named_not_quoted(void **state)
{
    (void)state;
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    assert_false(parse(&d, "# first\nroot:x:0:0:SECRET /bin/sh\n", err));
    assert_non_null(strstr(err, "t.scene:2:1: not a scene file"));
    assert_null(strstr(err, "root"));
    assert_null(strstr(err, "SECRET"));
    assert_false(parse(&d, "v 0 0 0\nv 1 0 0\n", err));
    assert_non_null(strstr(err, "t.scene:1:1: not a scene file"));
    assert_false(parse(&d, "camera eye 0 0 5 target 0 0 0\ncube size 1\n", err));
    assert_non_null(strstr(err, "t.scene:2:1: unknown statement 'cube'"));
}

static void test_long_line_and_missing_file_are_errors(void **state)
{
    (void)state;
    size_t n = SCENE_MAX_LINE + 10;
    char *text = malloc(n + 1);
    memset(text, ' ', n);
    text[n] = '\0';
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    assert_false(scene_desc_parse(&d, text, n, "t.scene", NULL, err, sizeof err));
    assert_non_null(strstr(err, "t.scene:1:"));
    assert_non_null(strstr(err, "line longer than"));
    free(text);
    assert_false(scene_desc_load(&d, "/nonexistent/x.scene", err, sizeof err));
    assert_string_equal(err, "/nonexistent/x.scene: No such file or directory");
    /* A NUL byte inside the text is an error, not the end of the file. */
    const char with_nul[] = "camera eye 0 0 5 target 0 0 0\n\0sphere";
    assert_false(scene_desc_parse(&d, with_nul, sizeof with_nul - 1, "t.scene", NULL, err, sizeof err));
    assert_non_null(strstr(err, "t.scene:2:1: unexpected character"));
}

/* A mesh is loaded relative to the scene file, with its MTL; a missing one
 * is reported at the scene line that asked for it. */
static void test_mesh_paths_are_relative_to_the_scene_file(void **state)
{
    (void)state;
    char dir[] = "/tmp/test_scene_XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[512];
    snprintf(path, sizeof path, "%s/quad.obj", dir);
    FILE *f = fopen(path, "w");
    fprintf(f, "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl red\nf 1 2 3 4\n");
    fclose(f);
    snprintf(path, sizeof path, "%s/quad.mtl", dir);
    f = fopen(path, "w");
    fprintf(f, "newmtl red\nKd 0.8 0.1 0.1\n");
    fclose(f);
    snprintf(path, sizeof path, "%s/s.scene", dir);
    f = fopen(path, "w");
    fprintf(f, "mesh path \"quad.obj\"\nmesh path \"missing.obj\"\n");
    fclose(f);

    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_load(&d, path, err, sizeof err))
        fail_msg("%s", err);
    mesh m;
    mesh_init(&m);
    assert_true(scene_desc_load_mesh(&d, 0, &m, err, sizeof err));
    assert_int_equal(m.face_count, 2);
    assert_int_equal(m.material_count, 1);
    assert_close(m.materials[0].diffuse.x, 0.8, 1e-6);
    assert_false(scene_desc_load_mesh(&d, 1, &m, err, sizeof err));
    char expected[1400]; /* two paths of up to 512 and the message */
    snprintf(expected, sizeof expected, "%s:2:1: mesh: ", path);
    assert_memory_equal(err, expected, strlen(expected));
    assert_int_equal(m.face_count, 2); /* unchanged */
    scene_desc_free(&d);

    /* A mesh given an emitting material is a light: it must have area. */
    snprintf(path, sizeof path, "%s/line.obj", dir);
    f = fopen(path, "w");
    fprintf(f, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    fclose(f);
    snprintf(path, sizeof path, "%s/s.scene", dir);
    f = fopen(path, "w");
    fprintf(f, "material e emissive emission 1 1 1\nmaterial w diffuse albedo 1 1 1\n"
               "mesh path \"line.obj\" material w\nmesh path \"line.obj\" material e\n"
               "mesh path \"quad.obj\" material e\n");
    fclose(f);
    if (!scene_desc_load(&d, path, err, sizeof err))
        fail_msg("%s", err);
    assert_true(scene_desc_load_mesh(&d, 0, &m, err, sizeof err));
    assert_int_equal(m.face_count, 3);
    int positions = m.position_count, materials = m.material_count;
    assert_false(scene_desc_load_mesh(&d, 1, &m, err, sizeof err));
    snprintf(expected, sizeof expected, "%s:4:1: mesh: %s/line.obj: emits light (material 'e') but no triangle of it "
                                        "has area", path, dir);
    assert_string_equal(err, expected);
    assert_int_equal(m.face_count, 3);
    assert_int_equal(m.position_count, positions);
    assert_int_equal(m.material_count, materials);
    assert_true(scene_desc_load_mesh(&d, 2, &m, err, sizeof err));
    assert_int_equal(m.face_count, 5);
    mesh_free(&m);
    scene_desc_free(&d);
    snprintf(path, sizeof path, "rm -r '%s'", dir);
    assert_int_equal(system(path), 0);
}

/* ---- effects analysis -------------------------------------------------------------- */

static effects_report analyse(const char *text)
{
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!parse(&d, text, err))
        fail_msg("%s", err);
    effects_report e = effects_analyse(&d);
    scene_desc_free(&d);
    return e;
}

#define CAMERA "camera eye 0 0 5 target 0 0 0\n"
#define WHITE "material w diffuse albedo 0.5 0.5 0.5\n"
#define SPHERE "sphere center 0 0 0 radius 1 material w\n"
#define POINT_LIGHT "light point position 3 3 3 intensity 10 10 10\n"

static void test_effects_follow_from_the_scene(void **state)
{
    (void)state;
    /* One sphere from outside, one light: nothing can be blocked, no light
     * bounces back to the sphere. */
    effects_report e = analyse(CAMERA WHITE SPHERE POINT_LIGHT);
    assert_int_equal(e.needed, 0);
    /* A floor: shadows (hard) and interreflection. */
    e = analyse(CAMERA WHITE SPHERE POINT_LIGHT "plane point 0 -1 0 normal 0 1 0 material w\n");
    assert_int_equal(e.needed, EFFECT_SHADOWS | EFFECT_INDIRECT);
    assert_true(e.hard_shadows);
    assert_false(e.soft_shadows);
    /* An area light: soft shadows. */
    e = analyse(CAMERA WHITE SPHERE "light area p0 -1 3 -1 p1 1 3 -1 p2 1 3 1 p3 -1 3 1 emission 1 1 1\n");
    assert_true(e.needed & EFFECT_SHADOWS);
    assert_true(e.soft_shadows);
    assert_false(e.hard_shadows);
    /* Mirror: reflection, no refraction. Glass: both. Glossy: glossy. */
    e = analyse(CAMERA "material m mirror\nsphere center 0 0 0 radius 1 material m\n" POINT_LIGHT);
    assert_int_equal(e.needed, EFFECT_REFLECTION);
    e = analyse(CAMERA "material g glass ior 1.5\nsphere center 0 0 0 radius 1 material g\n" POINT_LIGHT);
    assert_int_equal(e.needed, EFFECT_REFLECTION | EFFECT_REFRACTION);
    e = analyse(CAMERA "material g glossy albedo 1 1 1 roughness 0.3\nsphere center 0 0 0 radius 1 material g\n"
                POINT_LIGHT);
    assert_int_equal(e.needed, EFFECT_GLOSSY);
    /* A material defined but used by no shape calls for nothing. */
    e = analyse(CAMERA WHITE "material g glass ior 1.5\n" SPHERE POINT_LIGHT);
    assert_false(e.needed & EFFECT_REFRACTION);
    /* Inside a sphere with the light inside too: nothing blocks it, but the
     * sphere lights itself. With the light outside, the sphere blocks it. */
    e = analyse(CAMERA WHITE "sphere center 0 0 0 radius 9 material w inside_out\n" POINT_LIGHT);
    assert_int_equal(e.needed, EFFECT_INDIRECT);
    e = analyse(CAMERA WHITE "sphere center 0 0 0 radius 2 material w inside_out\n" POINT_LIGHT);
    assert_int_equal(e.needed, EFFECT_SHADOWS | EFFECT_INDIRECT);
    /* A torus shadows itself. No light at all: no shadows. */
    e = analyse(CAMERA WHITE "implicit torus center 0 0 0 major 1 minor 0.3 material w\n" POINT_LIGHT);
    assert_true(e.needed & EFFECT_SHADOWS);
    e = analyse(CAMERA WHITE SPHERE "plane point 0 -1 0 normal 0 1 0 material w\n");
    assert_false(e.needed & EFFECT_SHADOWS);
    /* A sky lights a lone sphere by indirect rays. */
    e = analyse(CAMERA WHITE SPHERE "background 1 1 1\n");
    assert_int_equal(e.needed, EFFECT_INDIRECT);
}

static void test_effects_statement_narrows_and_chapters_limit(void **state)
{
    (void)state;
    const char *scene = CAMERA WHITE "material g glass ior 1.5\n" SPHERE
        "sphere center 2 0 0 radius 1 material g\n" POINT_LIGHT "effects only shadows refraction\n";
    effects_report e = analyse(scene);
    assert_int_equal(e.needed, EFFECT_SHADOWS | EFFECT_REFLECTION | EFFECT_REFRACTION | EFFECT_INDIRECT);
    assert_int_equal(e.simulated, EFFECT_SHADOWS | EFFECT_REFRACTION);
    assert_int_equal(effects_decide(&e, EFFECT_SHADOWS), EFFECT_SHADOWS);
    /* The printed list says which is which. */
    char buffer[4096] = "";
    FILE *out = fmemopen(buffer, sizeof buffer, "w");
    effects_print(out, &e, "prog");
    fclose(out);
    assert_non_null(strstr(buffer, "shadows    simulated"));
    assert_non_null(strstr(buffer, "reflection off (the scene's effects statement)"));
    assert_non_null(strstr(buffer, "refraction NOT SIMULATED by this chapter"));
    assert_non_null(strstr(buffer, "glossy     not needed"));
}

/* ---- counters file and flags -------------------------------------------------------- */

static void test_counters_are_written_beside_the_image(void **state)
{
    (void)state;
    char path[256];
    counters_path_for_image("build/out/ch01.exr", path, sizeof path);
    assert_string_equal(path, "build/out/ch01.counters.json");
    counters_path_for_image("a.b/img", path, sizeof path);
    assert_string_equal(path, "a.b/img.counters.json");

    char dir[] = "/tmp/test_counters_XXXXXX";
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/x.counters.json", dir);
    ray_counters c = {.camera_rays = 10, .shadow_rays = 7, .refraction_rays = 0, .nonfinite_samples = 2};
    char err[256];
    assert_true(counters_write_json(path, &c, 1.5, "\"program\": \"t\"", err, sizeof err));
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char text[2048];
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = '\0';
    fclose(f);
    assert_non_null(strstr(text, "\"camera_rays\": 10,"));
    assert_non_null(strstr(text, "\"shadow_rays\": 7,"));
    assert_non_null(strstr(text, "\"nonfinite_samples_dropped\": 2,"));
    assert_non_null(strstr(text, "\"program\": \"t\"\n}"));
    /* Only the final file is left: the temporary was renamed. */
    char command[512];
    snprintf(command, sizeof command, "test $(ls '%s' | wc -l) -eq 1 && rm -r '%s'", dir, dir);
    assert_int_equal(system(command), 0);
    /* An unwritable place fails with the file's name. */
    assert_false(counters_write_json("/nonexistent/dir/c.json", &c, 1.0, NULL, err, sizeof err));
    assert_non_null(strstr(err, "/nonexistent/dir/c.json"));
}

static void test_scene_and_explain_flags(void **state)
{
    (void)state;
    cli_options o = cli_defaults("/tmp/x.png", 64, 48, 1);
    cli_spec spec = {"t", "t", NULL, 0, "the path of a pixel"};
    char err[512];
    char *argv[] = {"t", "--scene", "a.scene", "--explain", "3,4", "--spp", "2"};
    assert_int_equal(cli_parse(7, argv, &spec, &o, err, sizeof err), CLI_OK);
    assert_string_equal(o.scene, "a.scene");
    assert_true(o.explain);
    assert_int_equal(o.explain_x, 3);
    assert_int_equal(o.explain_y, 4);
    assert_true(o.spp_given);
    assert_false(o.width_given);
    const char *bad[] = {"3", "3,", ",4", "-1,2", "a,b", "3,4,5"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        cli_options p = cli_defaults("/tmp/x.png", 64, 48, 1);
        char *args[] = {"t", "--explain", (char *)bad[i]};
        assert_int_equal(cli_parse(3, args, &spec, &p, err, sizeof err), CLI_ERROR);
        assert_non_null(strstr(err, "--explain"));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_scene_parses_every_statement),
        cmocka_unit_test(test_errors_name_line_and_column),
        cmocka_unit_test(test_only_emitting_shapes_must_have_area),
        cmocka_unit_test(test_a_file_of_another_kind_is_named_not_quoted),
        cmocka_unit_test(test_long_line_and_missing_file_are_errors),
        cmocka_unit_test(test_mesh_paths_are_relative_to_the_scene_file),
        cmocka_unit_test(test_effects_follow_from_the_scene),
        cmocka_unit_test(test_effects_statement_narrows_and_chapters_limit),
        cmocka_unit_test(test_counters_are_written_beside_the_image),
        cmocka_unit_test(test_scene_and_explain_flags),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

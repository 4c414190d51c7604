/* fuzz_scene.c -- a libFuzzer target for the scene file parser (make fuzz).
 *
 * Every input must either parse or fail with a "fuzz.scene:line:col:"
 * message and an empty description (nothing half-built), and never crash,
 * read out of bounds or leak (the target is built with AddressSanitizer and
 * UndefinedBehaviorSanitizer). What parses must be consistent: every shape's
 * material exists (or is -1 for a mesh keeping its MTL), every number is
 * finite, and the effects analysis runs on it.
 *
 * Each input is then read again as a file, through scene_desc_load, with
 * the files it holds written beside it (fuzz_files.h: "...\n%%m.obj\nv 0 0 0
 * ..." is a scene and its m.obj), and its OBJ meshes are loaded through
 * scene_desc_load_mesh: opening, the checks on what a file is and how
 * large, and mesh paths resolved beside the scene are fuzzed too. The file
 * must parse as the text in memory does, with the same message. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "effects.h"
#include "fuzz_files.h"
#include "scene_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_finite(vec3 v)
{
    if (!vec3_is_finite(v))
        abort();
}

/* The input as files: the scene must read as it parses from memory, and
 * each OBJ mesh must load, or fail naming the scene line and changing
 * nothing. */
static void fuzz_as_files(const uint8_t *data, size_t size)
{
    char path[FUZZ_PATH_SIZE];
    size_t scene_size;
    fuzz_write_files(data, size, "fuzz.scene", path, &scene_size);
    scene_desc from_file, from_memory;
    char file_err[SCENE_ERROR_SIZE] = "", memory_err[SCENE_ERROR_SIZE] = "";
    bool file_ok = scene_desc_load(&from_file, path, file_err, sizeof file_err);
    bool memory_ok = scene_desc_parse(&from_memory, (const char *)data, scene_size, path, fuzz_scratch_dir(),
                                      memory_err, sizeof memory_err);
    if (file_ok != memory_ok || strcmp(file_err, memory_err) != 0 || from_file.shape_count != from_memory.shape_count) {
        fprintf(stderr, "file and memory differ: '%s' / '%s'\n", file_err, memory_err);
        abort();
    }
    scene_desc_free(&from_memory);
    if (!file_ok)
        return;
    char prefix[FUZZ_PATH_SIZE + 16];
    snprintf(prefix, sizeof prefix, "%s:", path);
    mesh m;
    mesh_init(&m);
    for (int i = 0, loaded = 0; i < from_file.shape_count && loaded < 4; i++) {
        if (from_file.shapes[i].kind != SCENE_SHAPE_MESH_OBJ)
            continue; /* generated meshes take no input but their size */
        loaded++;
        int faces = m.face_count, positions = m.position_count, materials = m.material_count;
        char err[SCENE_ERROR_SIZE] = "";
        if (!scene_desc_load_mesh(&from_file, i, &m, err, sizeof err) &&
            (strncmp(err, prefix, strlen(prefix)) != 0 || m.face_count != faces || m.position_count != positions ||
             m.material_count != materials)) {
            fprintf(stderr, "bad mesh failure: '%s'\n", err);
            abort();
        }
    }
    mesh_free(&m);
    scene_desc_free(&from_file);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_as_files(data, size);

    scene_desc d;
    char err[SCENE_ERROR_SIZE] = "";
    bool ok = scene_desc_parse(&d, (const char *)data, size, "fuzz.scene", "dir", err, sizeof err);
    if (!ok) {
        if (strncmp(err, "fuzz.scene:", 11) != 0 || d.material_count != 0 || d.shape_count != 0 ||
            d.light_count != 0 || d.materials != NULL || d.shapes != NULL || d.lights != NULL) {
            fprintf(stderr, "bad failure: '%s'\n", err);
            abort();
        }
        return 0;
    }
    if (d.material_count > SCENE_MAX_MATERIALS || d.shape_count > SCENE_MAX_SHAPES || d.light_count > SCENE_MAX_LIGHTS)
        abort();
    check_finite(d.eye);
    check_finite(d.target);
    check_finite(d.background);
    for (int i = 0; i < d.material_count; i++) {
        check_finite(d.materials[i].albedo);
        check_finite(d.materials[i].emission);
    }
    for (int i = 0; i < d.shape_count; i++) {
        const scene_shape *s = &d.shapes[i];
        bool mesh = s->kind == SCENE_SHAPE_MESH_OBJ || s->kind == SCENE_SHAPE_MESH_TORI;
        if (s->material >= d.material_count || s->material < (mesh ? -1 : 0))
            abort();
        check_finite(s->center);
        for (int k = 0; k < 4; k++)
            check_finite(s->p[k]);
        if (s->kind == SCENE_SHAPE_PLANE && !(vec3_length(s->normal) > 0.99f))
            abort();
    }
    effects_report e = effects_analyse(&d);
    (void)e;
    scene_desc_free(&d);
    return 0;
}

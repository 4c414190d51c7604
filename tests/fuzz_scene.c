/* fuzz_scene.c -- a libFuzzer target for the scene file parser (make fuzz).
 *
 * Every input must either parse or fail with a "fuzz.scene:line:col:"
 * message and an empty description (nothing half-built), and never crash,
 * read out of bounds or leak (the target is built with AddressSanitizer and
 * UndefinedBehaviorSanitizer). What parses must be consistent: every shape's
 * material exists (or is -1 for a mesh keeping its MTL), every number is
 * finite, and the effects analysis runs on it. Mesh files are not opened:
 * the parser only records their paths. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "effects.h"
#include "scene_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_finite(vec3 v)
{
    if (!vec3_is_finite(v))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
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

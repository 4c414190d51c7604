/* fuzz_obj.c -- a libFuzzer target for the OBJ parser (make fuzz).
 *
 * Every input must either load or fail with a "name:line:" message, leave
 * the mesh exactly as it was on failure, and never crash, read out of
 * bounds or leak (the target is built with AddressSanitizer and
 * UndefinedBehaviorSanitizer). Each input is parsed into a mesh that already
 * holds one triangle, so "nothing half-loaded" is checked too. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    mesh m;
    mesh_init(&m);
    int a = mesh_add_position(&m, vec3_make(0, 0, 0));
    int b = mesh_add_position(&m, vec3_make(1, 0, 0));
    int c = mesh_add_position(&m, vec3_make(0, 1, 0));
    mesh_add_triangle(&m, a, b, c, -1);
    char err[MESH_ERROR_SIZE] = "";
    bool ok = mesh_parse_obj(&m, (const char *)data, size, "fuzz.obj", NULL, err, sizeof err);
    if (!ok) {
        /* A failure names the input and a line, and changes nothing. */
        if (strncmp(err, "fuzz.obj:", 9) != 0 || m.face_count != 1 || m.position_count != 3) {
            fprintf(stderr, "bad failure: '%s' faces=%d positions=%d\n", err, m.face_count, m.position_count);
            abort();
        }
    } else {
        /* Every face refers to existing elements. */
        for (int i = 0; i < m.face_count; i++)
            for (int k = 0; k < 3; k++) {
                const mesh_face *f = &m.faces[i];
                if (f->position[k] < 0 || f->position[k] >= m.position_count || f->normal[k] >= m.normal_count ||
                    f->texcoord[k] >= m.texcoord_count || f->material >= m.material_count)
                    abort();
            }
    }
    mesh_free(&m);
    return 0;
}

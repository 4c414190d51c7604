/* fuzz_obj.c -- a libFuzzer target for the OBJ and MTL readers (make fuzz).
 *
 * Every input must either load or fail with a "name:line:" message, leave
 * the mesh exactly as it was on failure, and never crash, hang, read out of
 * bounds or leak (the target is built with AddressSanitizer and
 * UndefinedBehaviorSanitizer). Each input is parsed into a mesh that already
 * holds one triangle, so "nothing half-loaded" is checked too.
 *
 * Each input is read twice: from memory (mesh_parse_obj), and as a file
 * through mesh_load_obj, with the files it holds written beside it
 * (fuzz_files.h: "...\n%%m.mtl\nnewmtl a\n" is an OBJ and its m.mtl), so
 * that opening, the checks on what a file is and how large, and mtllib
 * paths resolved beside the OBJ file are fuzzed too. Both must give the same
 * result and the same message: the file path adds refusals, never changes
 * what the text means. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_files.h"
#include "mesh.h"
#include "obj.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void start(mesh *m)
{
    mesh_init(m);
    int a = mesh_add_position(m, vec3_make(0, 0, 0));
    int b = mesh_add_position(m, vec3_make(1, 0, 0));
    int c = mesh_add_position(m, vec3_make(0, 1, 0));
    mesh_add_triangle(m, a, b, c, -1);
}

/* A failure changes nothing; a success refers only to what exists. */
static void check(const mesh *m, bool ok, const char *err, const char *name)
{
    if (!ok) {
        /* The message names a file (the OBJ, or an MTL it names) and a line,
         * or the OBJ file alone when it could not be read at all. */
        const char *colon = strchr(err, ':');
        if (colon == NULL || m->face_count != 1 || m->position_count != 3 || m->material_count != 0) {
            fprintf(stderr, "bad failure for %s: '%s' faces=%d positions=%d\n", name, err, m->face_count,
                    m->position_count);
            abort();
        }
        return;
    }
    for (int i = 0; i < m->face_count; i++)
        for (int k = 0; k < 3; k++) {
            const mesh_face *f = &m->faces[i];
            if (f->position[k] < 0 || f->position[k] >= m->position_count || f->normal[k] >= m->normal_count ||
                f->texcoord[k] >= m->texcoord_count || f->material >= m->material_count)
                abort();
        }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* From memory, without MTL files: the parser alone. */
    mesh m;
    start(&m);
    char err[MESH_ERROR_SIZE] = "";
    bool ok = mesh_parse_obj(&m, (const char *)data, size, "fuzz.obj", NULL, err, sizeof err);
    if (!ok && strncmp(err, "fuzz.obj:", 9) != 0) {
        fprintf(stderr, "bad failure: '%s'\n", err);
        abort();
    }
    check(&m, ok, err, "fuzz.obj");
    mesh_free(&m);

    /* As files: the OBJ (the input up to its first "%%" line) and what follows. */
    char path[FUZZ_PATH_SIZE];
    size_t obj_size;
    fuzz_write_files(data, size, "fuzz.obj", path, &obj_size);
    mesh from_file, from_memory;
    start(&from_file);
    start(&from_memory);
    char file_err[MESH_ERROR_SIZE] = "", memory_err[MESH_ERROR_SIZE] = "";
    bool file_ok = mesh_load_obj(&from_file, path, file_err, sizeof file_err);
    bool memory_ok =
        mesh_parse_obj(&from_memory, (const char *)data, obj_size, path, fuzz_scratch_dir(), memory_err, sizeof memory_err);
    check(&from_file, file_ok, file_err, path);
    /* (Past the limit, only the file is refused: -max_len over 1 MB.) */
    if (obj_size <= input_file_mesh_limit() && (file_ok != memory_ok || strcmp(file_err, memory_err) != 0 || from_file.face_count != from_memory.face_count ||
        from_file.position_count != from_memory.position_count ||
        from_file.material_count != from_memory.material_count)) {
        fprintf(stderr, "file and memory differ: '%s' / '%s'\n", file_err, memory_err);
        abort();
    }
    mesh_free(&from_file);
    mesh_free(&from_memory);
    return 0;
}

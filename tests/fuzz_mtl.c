/* fuzz_mtl.c -- a libFuzzer target for the MTL reader (make fuzz).
 *
 * Each input is an MTL file (the text up to a line "%%NAME"; files after
 * it are written beside it, fuzz_files.h) named by an OBJ file's mtllib,
 * which then uses the material named on the MTL's first newmtl line. The
 * OBJ must load, or fail with a message that names a file and a line and
 * leave the mesh as it was (it holds one triangle before). What loads
 * must be what the format allows: every colour finite and no emission
 * negative, d in [0, 1], illum -1 or 0 to 10, Pm and Pr -1 or in [0, 1],
 * every face's material one that exists.
 *
 * The fuzz_obj target reaches the MTL reader too, through an OBJ the
 * fuzzer must first write; this one starts inside it. Seeds: the MTL
 * files of tests/fuzz/mtl/ (exporters' habits: Blender's, 3ds Max's, the
 * PBR extension, and what bench scenes write). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_files.h"
#include "mesh.h"
#include "obj.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static bool in_unit(float x) { return x >= 0.0f && x <= 1.0f; }

static void check_material(const mesh_material *m)
{
    bool ok = vec3_is_finite(m->diffuse) && vec3_is_finite(m->specular) && vec3_is_finite(m->emission) &&
              m->emission.x >= 0.0f && m->emission.y >= 0.0f && m->emission.z >= 0.0f && isfinite(m->shininess) &&
              isfinite(m->ior) && in_unit(m->dissolve) && m->illum >= -1 && m->illum <= 10 &&
              (m->metallic == -1.0f || in_unit(m->metallic)) && (m->roughness == -1.0f || in_unit(m->roughness)) &&
              strnlen(m->name, MESH_NAME_SIZE) < MESH_NAME_SIZE;
    if (!ok) {
        fprintf(stderr, "material '%.*s' holds what no MTL may give\n", MESH_NAME_SIZE, m->name);
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[FUZZ_PATH_SIZE];
    size_t mtl_size;
    fuzz_write_files(data, size, "fuzz.mtl", path, &mtl_size);

    /* The first newmtl's name, to use it (as an exporter's OBJ would). */
    char name[MESH_NAME_SIZE] = "none";
    const char *text = (const char *)data, *end = text + mtl_size;
    for (const char *p = text; p + 7 <= end; p++)
        if ((p == text || p[-1] == '\n') && memcmp(p, "newmtl ", 7) == 0) {
            size_t n = 0;
            for (p += 7; p < end && *p != '\n' && *p != '\r' && *p != ' ' && *p != '\0' && n + 1 < sizeof name; p++)
                name[n++] = *p;
            name[n] = '\0';
            break;
        }
    char obj[MESH_NAME_SIZE + 128];
    int obj_size = snprintf(obj, sizeof obj, "mtllib fuzz.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl %s\nf 1 2 3\n", name);

    mesh m;
    mesh_init(&m);
    int a = mesh_add_position(&m, vec3_make(0, 0, 0));
    int b = mesh_add_position(&m, vec3_make(1, 0, 1));
    int c = mesh_add_position(&m, vec3_make(0, 1, 0));
    mesh_add_triangle(&m, a, b, c, -1);
    char err[MESH_ERROR_SIZE] = "";
    bool ok = mesh_parse_obj(&m, obj, (size_t)obj_size, "fuzz.obj", fuzz_scratch_dir(), err, sizeof err);
    if (!ok) {
        /* "FILE:LINE: what", FILE the MTL (or the OBJ, for an unknown usemtl) */
        const char *colon = strchr(err, ':');
        bool line = colon != NULL && colon[1] >= '1' && colon[1] <= '9';
        if (strstr(err, path) == err) {
            colon = err + strlen(path);
            line = colon[0] == ':' && colon[1] >= '1' && colon[1] <= '9';
        }
        if (!line || m.face_count != 1 || m.position_count != 3 || m.material_count != 0) {
            fprintf(stderr, "bad failure: '%s' faces=%d materials=%d\n", err, m.face_count, m.material_count);
            abort();
        }
    } else {
        for (int i = 0; i < m.material_count; i++)
            check_material(&m.materials[i]);
        for (int i = 0; i < m.face_count; i++)
            if (m.faces[i].material >= m.material_count)
                abort();
    }
    mesh_free(&m);
    return 0;
}

/* obj_write.c -- a mesh out as Wavefront OBJ: positions and triangles,
 * every float as the same float read back (obj.c reads it). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "atomic_file.h"
#include "obj.h"

bool mesh_write_obj(const mesh *m, const char *path, char *err, size_t err_size)
{
    /* Refuse what could not be read back, before touching the disk: a NaN
     * prints as "nan", which the reader rightly rejects, and a face must
     * name existing vertices. */
    for (int i = 0; i < m->position_count; i++)
        if (!vec3_is_finite(m->positions[i])) {
            snprintf(err, err != NULL ? err_size : 0, "%s: position %d is not finite", path, i);
            return false;
        }
    for (int i = 0; i < m->face_count; i++)
        for (int k = 0; k < 3; k++) {
            int p = m->faces[i].position[k];
            if (p < 0 || p >= m->position_count) {
                snprintf(err, err != NULL ? err_size : 0, "%s: face %d uses position %d of %d", path, i, p, m->position_count);
                return false;
            }
        }

    /* Through a temporary file renamed into place (atomic_file.h): a reader
     * sees the old file or the whole new one, never a half-written one. */
    atomic_file out;
    if (!atomic_file_open(&out, path, err, err_size))
        return false;
    FILE *f = out.stream;

    /* %.9g: nine significant digits are enough for every float to read back
     * as exactly the same float. */
    int failure = 0;
    if (fprintf(f, "# %d vertices, %d triangles\n", m->position_count, m->face_count) < 0)
        failure = errno;
    for (int i = 0; i < m->position_count && failure == 0; i++) {
        vec3 p = m->positions[i];
        if (fprintf(f, "v %.9g %.9g %.9g\n", (double)p.x, (double)p.y, (double)p.z) < 0)
            failure = errno;
    }
    for (int i = 0; i < m->face_count && failure == 0; i++) {
        const int *p = m->faces[i].position;
        if (fprintf(f, "f %d %d %d\n", p[0] + 1, p[1] + 1, p[2] + 1) < 0)
            failure = errno;
    }
    if (failure != 0) {
        snprintf(err, err != NULL ? err_size : 0, "cannot write '%s': %s", path, strerror(failure));
        atomic_file_abandon(&out);
        return false;
    }
    return atomic_file_commit(&out, err, err_size);
}

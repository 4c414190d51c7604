/* obj.h -- a mesh (mesh.h) read from Wavefront OBJ and MTL files, or
 * written as OBJ: the file format, apart from the mesh itself.
 *
 * Usage:
 *   mesh m; mesh_init(&m);
 *   char err[MESH_ERROR_SIZE];
 *   if (!mesh_load_obj(&m, "bunny.obj", err, sizeof err)) { puts(err); ... }   "bunny.obj:12: ..."
 */
#ifndef OBJ_H
#define OBJ_H

#include <stdbool.h>
#include <stddef.h>

#include "mesh.h"

/* Reading: v, vn, vt; f with any of the index forms (v, v/vt, v//vn, v/vt/vn),
 * negative (relative) indices, polygons fan-triangulated; mtllib and usemtl
 * with Kd, Ks, Ns, Ke, Ni from the MTL file; o, g, s and comments ignored.
 * On malformed input: false, err = "file:line: what is wrong", and m is left
 * as it was before the call (nothing half-loaded). The OBJ and its MTL files
 * must be regular files within input_file_mesh_limit() (input_file.h); an
 * emitting face (Ke > 0) must have area. */
bool mesh_load_obj(mesh *m, const char *path, char *err, size_t err_size);
/* The same from text in memory (`name` is used in messages; MTL files are
 * looked up relative to base_dir, or not at all when it is NULL). */
bool mesh_parse_obj(mesh *m, const char *text, size_t length, const char *name, const char *base_dir, char *err,
                    size_t err_size);
/* Writes positions and faces (1-based), through a temporary file. */
bool mesh_write_obj(const mesh *m, const char *path, char *err, size_t err_size);

#endif

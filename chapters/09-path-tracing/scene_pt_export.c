/* scene_pt_export.c -- a path tracer's scene as Wavefront OBJ + MTL
 * (scene_pt.h): the inverse of pt_scene_load_obj, so that another renderer
 * (Blender's Cycles, in `make bench-cycles`) renders the very triangles and
 * materials this one does. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/scene_pt.h"
#include "atomic_file.h"

/* Each BSDF as the MTL statements pt_material_from_mtl() reads back into
 * the same material (scene_pt.c): illum 7 glass with index Ni, Ks larger
 * than Kd a GGX metal whose alpha comes from Ns, and Kd alone a diffuse
 * surface. False, with why, for what MTL cannot say. */
typedef bool (*mtl_writer)(FILE *f, int index, const pt_material *m, char *why, size_t why_size);

static bool mtl_diffuse(FILE *f, int index, const pt_material *m, char *why, size_t why_size)
{
    (void)index, (void)why, (void)why_size;
    fprintf(f, "Kd %.9g %.9g %.9g\nKs 0 0 0\nillum 1\n", (double)m->albedo.x, (double)m->albedo.y, (double)m->albedo.z);
    return true;
}

static bool mtl_glass(FILE *f, int index, const pt_material *m, char *why, size_t why_size)
{
    vec3 a = m->albedo;
    if (a.x != 1.0f || a.y != 1.0f || a.z != 1.0f) {
        snprintf(why, why_size, "material %d: tinted glass (MTL glass reads back untinted)", index);
        return false;
    }
    fprintf(f, "Kd 0 0 0\nKs 1 1 1\nNi %.9g\nillum 7\n", (double)m->ior);
    return true;
}

static bool mtl_glossy(FILE *f, int index, const pt_material *m, char *why, size_t why_size)
{
    (void)index, (void)why, (void)why_size;
    /* alpha = sqrt(2 / (Ns + 2)), the loader's mapping, solved for Ns */
    double alpha = (double)m->roughness, ns = 2.0 / (alpha * alpha) - 2.0;
    fprintf(f, "Kd 0 0 0\nKs %.9g %.9g %.9g\nNs %.9g\nillum 2\n", (double)m->albedo.x, (double)m->albedo.y,
            (double)m->albedo.z, ns);
    return true;
}

static bool mtl_mirror(FILE *f, int index, const pt_material *m, char *why, size_t why_size)
{
    (void)f, (void)m;
    snprintf(why, why_size, "material %d: a perfect mirror (MTL's Ns cannot make GGX's alpha 0)", index);
    return false;
}

/* By kind; a kind without a row has no MTL form, and is refused by name. */
static const mtl_writer mtl_writers[BSDF_KIND_COUNT] = {
    [BSDF_DIFFUSE] = mtl_diffuse,
    [BSDF_GLASS] = mtl_glass,
    [BSDF_GLOSSY] = mtl_glossy,
    [BSDF_MIRROR] = mtl_mirror,
};

/* A material as MTL: Ke makes an emitter (diffuse, whatever its kind
 * reflects), else its kind's writer. */
static bool write_mtl_material(FILE *f, int index, const pt_material *m, char *why, size_t why_size)
{
    vec3 a = m->albedo, e = m->emission;
    bool emits = e.x > 0.0f || e.y > 0.0f || e.z > 0.0f;
    fprintf(f, "\nnewmtl m%d\n", index);
    if (emits) {
        fprintf(f, "Kd %.9g %.9g %.9g\nKs 0 0 0\nKe %.9g %.9g %.9g\nillum 1\n", (double)a.x, (double)a.y,
                (double)a.z, (double)e.x, (double)e.y, (double)e.z);
        return true;
    }
    if ((unsigned)m->kind < BSDF_KIND_COUNT && mtl_writers[m->kind] != NULL)
        return mtl_writers[m->kind](f, index, m, why, why_size);
    snprintf(why, why_size, "material %d: %s (MTL has no such material)", index, bsdf_kind_name(m->kind));
    return false;
}

/* What OBJ cannot hold: spheres (only triangles), point lights and the
 * environment. NULL if there is none. */
static const char *export_refusal(const pt_scene *sc)
{
    if (sc->sphere_count > 0)
        return "spheres (OBJ holds triangles only: build the sphere as a mesh)";
    if (sc->point_light_count > 0)
        return "point lights (OBJ has no lights but emitting faces)";
    if (sc->environment.x != 0.0f || sc->environment.y != 0.0f || sc->environment.z != 0.0f)
        return "an environment (OBJ has no background)";
    for (int i = 0; i < sc->geometry.face_count; i++)
        if (sc->geometry.faces[i].material < 0 || sc->geometry.faces[i].material >= sc->material_count)
            return "a triangle without a material";
    return NULL;
}

/* The MTL file's name: the OBJ's with its extension replaced by .mtl. */
static void mtl_path_for(const char *obj_path, char *out, size_t out_size)
{
    snprintf(out, out_size, "%s", obj_path);
    char *dot = strrchr(out, '.'), *slash = strrchr(out, '/');
    if (dot != NULL && (slash == NULL || dot > slash))
        *dot = '\0';
    size_t n = strlen(out);
    snprintf(out + n, out_size - n, ".mtl");
}

bool pt_scene_write_obj(const pt_scene *sc, const char *obj_path, char *err, size_t err_size)
{
    const char *refusal = export_refusal(sc);
    if (refusal != NULL) {
        snprintf(err, err_size, "%s: cannot export %s", obj_path, refusal);
        return false;
    }
    char mtl_path[4096], why[256];
    mtl_path_for(obj_path, mtl_path, sizeof mtl_path);
    const char *slash = strrchr(mtl_path, '/');
    const char *mtl_name = slash != NULL ? slash + 1 : mtl_path;

    atomic_file mtl;
    if (!atomic_file_open(&mtl, mtl_path, err, err_size))
        return false;
    fprintf(mtl.stream, "# %d materials of a path tracer's scene (pt_scene_write_obj)\n", sc->material_count);
    for (int i = 0; i < sc->material_count; i++)
        if (!write_mtl_material(mtl.stream, i, &sc->materials[i], why, sizeof why)) {
            atomic_file_abandon(&mtl);
            snprintf(err, err_size, "%s: cannot export %s", obj_path, why);
            return false;
        }
    if (!atomic_file_commit(&mtl, err, err_size))
        return false;

    atomic_file obj;
    if (!atomic_file_open(&obj, obj_path, err, err_size))
        return false;
    const mesh *m = &sc->geometry;
    FILE *f = obj.stream;
    /* %.9g: enough digits for every float to read back as itself. */
    fprintf(f, "# %d vertices, %d triangles (pt_scene_write_obj)\nmtllib %s\n", m->position_count, m->face_count,
            mtl_name);
    for (int i = 0; i < m->position_count; i++)
        fprintf(f, "v %.9g %.9g %.9g\n", (double)m->positions[i].x, (double)m->positions[i].y,
                (double)m->positions[i].z);
    int current = -2;
    for (int i = 0; i < m->face_count; i++) {
        const mesh_face *face = &m->faces[i];
        if (face->material != current) {
            current = face->material;
            fprintf(f, "usemtl m%d\n", current);
        }
        fprintf(f, "f %d %d %d\n", face->position[0] + 1, face->position[1] + 1, face->position[2] + 1);
    }
    return atomic_file_commit(&obj, err, err_size);
}

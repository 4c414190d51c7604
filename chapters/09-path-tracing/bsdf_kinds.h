/* bsdf_kinds.h -- the path tracer's BSDF kinds: which of the scene format's
 * material kinds are BSDFs of their own (bsdf.c holds each one's code).
 */
#ifndef BSDF_KINDS_H
#define BSDF_KINDS_H

#include "scene_file.h"

/* The BSDFs (bsdf.c): the rows of the scene format's one list of material
 * kinds (SCENE_MATERIAL_KINDS, scene_file.h) that are BSDFs, X(ID, the
 * scene file's kind), in the enum's order; a kind's name is the scene
 * file's. Blinn-Phong is rendered as diffuse and emissive as a diffuse
 * emitter (scene_pt_file.c); every other kind of the list is a BSDF of its
 * own. A new BSDF: its row here and its functions with their row in
 * bsdf.c's table (eval, pdf, sample, and how a scene file's material
 * becomes it); the path tracer, chapter 10, the loader and the export
 * take it from there, and chapter 13 refuses it by name until its lanes
 * learn it. */
#define BSDF_KINDS(X)                                                                                        \
    X(DIFFUSE, SCENE_MATERIAL_DIFFUSE) /* Lambertian: f = albedo / pi */                                    \
    X(GLOSSY, SCENE_MATERIAL_GLOSSY)   /* GGX microfacet reflection with Schlick's Fresnel (F0 = albedo) */ \
    X(GLASS, SCENE_MATERIAL_GLASS)     /* a smooth dielectric: Fresnel-weighted reflection and refraction */ \
    X(MIRROR, SCENE_MATERIAL_MIRROR)   /* perfect reflection of albedo */

typedef enum {
#define BSDF_KIND_ENUM(id, ...) BSDF_##id,
    BSDF_KINDS(BSDF_KIND_ENUM)
#undef BSDF_KIND_ENUM
} bsdf_kind;
#define BSDF_KIND_ONE(id, ...) +1
enum { BSDF_KIND_COUNT = 0 BSDF_KINDS(BSDF_KIND_ONE) };
#undef BSDF_KIND_ONE

#endif

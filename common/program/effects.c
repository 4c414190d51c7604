/* effects.c -- the effects analysis (see effects.h). Each rule says what in
 * the scene makes an effect contribute, and drops it only when nothing does. */
#include "effects.h"

#include <string.h>

static const char *const names[EFFECT_COUNT] = {"shadows", "reflection", "refraction", "glossy", "indirect"};

const char *effect_name(unsigned effect)
{
    for (int k = 0; k < EFFECT_COUNT; k++)
        if (effect == (1u << k))
            return names[k];
    return "?";
}

static bool is_black(vec3 c) { return !(c.x > 0.0f || c.y > 0.0f || c.z > 0.0f); }

/* Can this one shape, alone, block light on its way to one of its own
 * points? A plane, a triangle or a flat quad cannot: a segment leaving a flat
 * surface never meets it again. A sphere seen from outside cannot either:
 * its lit points face lights on the outside of their tangent plane, and the
 * ball lies wholly on the other side. Seen from inside (the eye inside it,
 * or inside_out), it blocks any light outside it. A torus or a mesh may
 * shadow itself. */
static bool shape_can_shadow_itself(const scene_desc *d, const scene_shape *s)
{
    switch (s->kind) {
    case SCENE_SHAPE_PLANE:
    case SCENE_SHAPE_TRIANGLE:
    case SCENE_SHAPE_QUAD:
        return false;
    case SCENE_SHAPE_SPHERE: {
        bool eye_inside = vec3_length(vec3_sub(d->eye, s->center)) < s->radius;
        if (!eye_inside && !s->inside_out)
            return false;
        for (int i = 0; i < d->light_count; i++) {
            const scene_light *l = &d->lights[i];
            vec3 p = l->kind == SCENE_LIGHT_POINT ? l->position : l->corners[0];
            if (l->kind == SCENE_LIGHT_AREA || vec3_length(vec3_sub(p, s->center)) >= s->radius)
                return true;
        }
        return false;
    }
    case SCENE_SHAPE_TORUS:
    case SCENE_SHAPE_MESH_OBJ:
    case SCENE_SHAPE_MESH_TORI:
        break;
    }
    return true;
}

/* Can light leaving this shape reach the shape again (interreflection)? The
 * same geometry as above: flat shapes and spheres seen from outside cannot. */
static bool shape_sees_itself(const scene_desc *d, const scene_shape *s)
{
    if (s->kind == SCENE_SHAPE_SPHERE)
        return s->inside_out || vec3_length(vec3_sub(d->eye, s->center)) < s->radius;
    return !(s->kind == SCENE_SHAPE_PLANE || s->kind == SCENE_SHAPE_TRIANGLE || s->kind == SCENE_SHAPE_QUAD);
}

/* The shapes (uses: per material kind) whose kind passes on `effect`; into
 * counts (if not NULL), "N kind" for each such kind, joined by " and ". */
static int kinds_passing(const int uses[SCENE_MATERIAL_KIND_COUNT], unsigned effect, char *counts, size_t size)
{
    static const unsigned passes[SCENE_MATERIAL_KIND_COUNT] = {
#define KIND_EFFECTS(id, keyword, effects, ...) effects,
        SCENE_MATERIAL_KINDS(KIND_EFFECTS)
#undef KIND_EFFECTS
    };
    int shapes = 0, named = 0;
    for (int k = 0; k < SCENE_MATERIAL_KIND_COUNT; k++) {
        if (!(passes[k] & effect))
            continue;
        shapes += uses[k];
        if (counts != NULL) {
            size_t used = strlen(counts);
            snprintf(counts + used, size - used, "%s%d %s", named++ > 0 ? " and " : "", uses[k],
                     scene_material_kind_name((scene_material_kind)k));
        }
    }
    return shapes;
}

effects_report effects_analyse(const scene_desc *d)
{
    effects_report e;
    memset(&e, 0, sizeof e);
    e.allowed = d->effects_allowed;

    int point_lights = 0, area_lights = 0, emitting_shapes = 0, own_mtl_meshes = 0;
    int uses[SCENE_MATERIAL_KIND_COUNT] = {0}; /* shapes per material kind */
    for (int i = 0; i < d->light_count; i++)
        *(d->lights[i].kind == SCENE_LIGHT_POINT ? &point_lights : &area_lights) += 1;
    for (int i = 0; i < d->shape_count; i++) {
        const scene_shape *s = &d->shapes[i];
        if (s->material < 0) {
            own_mtl_meshes++;
            continue;
        }
        const scene_material *m = &d->materials[s->material];
        uses[m->kind]++;
        if (m->kind == SCENE_MATERIAL_EMISSIVE && !is_black(m->emission))
            emitting_shapes++;
    }
    /* Everything that can stand in a light's way: the shapes, and area
     * lights (they are geometry too). */
    int surfaces = d->shape_count + area_lights;
    /* A mesh with its own MTL materials is not read here: it may emit (Ke),
     * so it counts as a light that may cast shadows, as it counts as glass
     * that may reflect and refract and as metal that may be glossy below.
     * Kept, never dropped on a guess. */
    bool sampled_lights = point_lights + area_lights + emitting_shapes + own_mtl_meshes > 0;
    const char *mtl_note = own_mtl_meshes > 0 ? " (a mesh with its own MTL materials may hold them: kept)" : "";

    /* Shadows: a light can be occluded only if something other than the
     * lit surface itself lies between, or the surface can shadow itself. */
    bool self_shadowing = false;
    for (int i = 0; i < d->shape_count; i++)
        self_shadowing = self_shadowing || shape_can_shadow_itself(d, &d->shapes[i]);
    if (!sampled_lights) {
        snprintf(e.why[0], EFFECT_REASON_SIZE, "no light to cast them (point, area, emitting shape or mesh)");
    } else if (surfaces >= 2 || self_shadowing) {
        e.needed |= EFFECT_SHADOWS;
        e.hard_shadows = point_lights > 0;
        e.soft_shadows = area_lights + emitting_shapes + own_mtl_meshes > 0;
        snprintf(e.why[0], EFFECT_REASON_SIZE, "%s%s%s%s: %s", e.hard_shadows ? "hard (point lights)" : "",
                 e.hard_shadows && e.soft_shadows ? " and " : "", e.soft_shadows ? "soft (area lights)" : "",
                 own_mtl_meshes > 0 && area_lights + emitting_shapes == 0 ? ", if a mesh's MTL emits" : "",
                 surfaces >= 2 ? "several surfaces, one may block a light from another"
                               : "a surface that can shadow itself");
    } else {
        snprintf(e.why[0], EFFECT_REASON_SIZE,
                 "one surface that cannot shadow itself: no light can be blocked, no shadow ray needed");
    }

    /* Reflection, refraction, glossy: the shapes whose kind passes that
     * light on (SCENE_MATERIAL_KINDS' effects), named kind by kind. */
    static const struct {
        unsigned effect;
        const char *none;
    } passed[] = {
        {EFFECT_REFLECTION, "no shape is a mirror or glass"},
        {EFFECT_REFRACTION, "no glass (no dielectric), so no refraction ray"},
        {EFFECT_GLOSSY, "no glossy material"}, /* (an MTL may hold GGX metals) */
    };
    for (int i = 0; i < 3; i++) {
        char counts[EFFECT_REASON_SIZE] = "";
        int shapes = kinds_passing(uses, passed[i].effect, counts, sizeof counts);
        if (shapes > 0 || own_mtl_meshes > 0) {
            e.needed |= passed[i].effect;
            snprintf(e.why[1 + i], EFFECT_REASON_SIZE, "%s shapes%s", counts, mtl_note);
        } else {
            snprintf(e.why[1 + i], EFFECT_REASON_SIZE, "%s", passed[i].none);
        }
    }

    /* Indirect diffuse light: a diffuse surface must be able to receive
     * light that another surface (or it itself) reflected, or the sky. */
    int diffuse = kinds_passing(uses, EFFECT_INDIRECT, NULL, 0) + own_mtl_meshes;
    bool sees_itself = false;
    for (int i = 0; i < d->shape_count; i++)
        sees_itself = sees_itself || shape_sees_itself(d, &d->shapes[i]);
    if (diffuse == 0) {
        snprintf(e.why[4], EFFECT_REASON_SIZE, "no diffuse or glossy surface to receive it");
    } else if (surfaces >= 2 || sees_itself || !is_black(d->background)) {
        e.needed |= EFFECT_INDIRECT;
        snprintf(e.why[4], EFFECT_REASON_SIZE, "%s", !is_black(d->background) && surfaces < 2 && !sees_itself
                                                         ? "light from the background reaches diffuse surfaces"
                                                         : "light reflected by one surface can reach another");
    } else {
        snprintf(e.why[4], EFFECT_REASON_SIZE, "one surface that cannot see itself, under a black background");
    }
    e.supported = EFFECT_ALL;
    e.simulated = e.needed & e.allowed;
    return e;
}

unsigned effects_decide(effects_report *e, unsigned supported)
{
    e->supported = supported;
    e->simulated = e->needed & e->allowed & supported;
    return e->simulated;
}

void effects_print(FILE *out, const effects_report *e, const char *program)
{
    fprintf(out, "%s: effects\n", program);
    for (int k = 0; k < EFFECT_COUNT; k++) {
        unsigned bit = 1u << k;
        const char *status = !(e->needed & bit)      ? "not needed"
                             : !(e->allowed & bit)   ? "off (the scene's effects statement)"
                             : !(e->supported & bit) ? "NOT SIMULATED by this chapter"
                                                     : "simulated";
        fprintf(out, "  %-10s %-36s %s\n", names[k], status, e->why[k]);
    }
}

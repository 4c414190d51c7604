/* whitted.c -- lecture 13: Whitted-style (recursive) ray tracing.
 *
 * Ray casting (chapter 01) stops at the first hit. Whitted (1980) keeps
 * going where the surface is a mirror or glass: the reflected and refracted
 * rays are traced the same way, recursively, and what they bring back is
 * added at the hit. At diffuse surfaces the recursion stops and the shadow
 * rays of chapter 01 decide which lights are seen.
 */
#include "02-whitted/whitted.h"

#include <stdio.h>

#include "01-ray-casting/ray_casting.h"
#include "explain.h"

/* ---- Snell's law ------------------------------------------------------- */

bool refract_direction(vec3 d, vec3 n, float eta_ratio, vec3 *out)
{
    /* exercise: refract */
    /* Snell's law: eta_i sin(theta_i) = eta_t sin(theta_t) */
    float cos_i = -vec3_dot(d, n);
    float sin2_i = fmaxf(0.0f, 1.0f - cos_i * cos_i);
    float sin2_t = eta_ratio * eta_ratio * sin2_i;
    /* Total internal reflection: sin(theta_t) > 1 has no solution */
    if (sin2_t >= 1.0f)
        return false;
    float cos_t = sqrtf(1.0f - sin2_t);
    /* Snell's law in vector form: t = eta d + (eta cos(theta_i) - cos(theta_t)) n.
     * The part of d along the surface is scaled by eta (that is Snell's law
     * for the sines); the part along -n is whatever keeps t unit length. */
    *out = vec3_add(vec3_scale(d, eta_ratio), vec3_scale(n, eta_ratio * cos_i - cos_t));
    return true;
    /* end of exercise refract */
}

/* ---- Fresnel ------------------------------------------------------------ */

float fresnel_dielectric(float cos_i, float eta_i, float eta_t)
{
    /* exercise: fresnel */
    cos_i = fminf(1.0f, fmaxf(-1.0f, cos_i));
    /* Entering or leaving: a negative cosine means the light comes from the
     * eta_t side, so the two media trade places. */
    if (cos_i < 0.0f) {
        float swap = eta_i;
        eta_i = eta_t;
        eta_t = swap;
        cos_i = -cos_i;
    }
    /* The same index on both sides is no boundary at all: nothing reflects.
     * (Without this, grazing light, cos_i = 0, would give 0 / 0 below.) */
    if (eta_i == eta_t)
        return 0.0f;
    /* Snell's law: eta_i sin(theta_i) = eta_t sin(theta_t) */
    float eta = eta_i / eta_t;
    float sin2_t = eta * eta * fmaxf(0.0f, 1.0f - cos_i * cos_i);
    /* Total internal reflection: sin(theta_t) > 1 has no solution */
    if (sin2_t >= 1.0f)
        return 1.0f;
    float cos_t = sqrtf(1.0f - sin2_t);
    /* Fresnel: reflectance for s- and p-polarised light, averaged */
    float r_s = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    float r_p = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    return 0.5f * (r_s * r_s + r_p * r_p);
    /* end of exercise fresnel */
}

/* Schlick's approximation: R0 + (1 - R0) (1 - cos(theta))^5
 *
 * Its error, measured with this code for glass (1.5) against air: exact at
 * normal incidence, and 1 at grazing incidence like the exact R; in between
 * it is off by at most 0.036, too low around 60 degrees (0.070 for 0.089)
 * and too high near grazing (0.649 for 0.613 at 85 degrees). Coming out of
 * the glass the error is the same, at the matching angle (41.6 degrees
 * inside is 85 degrees outside: R is the same in both directions along a
 * path). Which cosine goes in matters: the angle on the low-index side,
 * theta_t when leaving glass. With theta_i there instead, light leaving glass
 * at 41 degrees would get R = 0.041 instead of 0.380. */
float fresnel_schlick(float cos_i, float eta_i, float eta_t)
{
    cos_i = fminf(1.0f, fmaxf(-1.0f, cos_i));
    /* Entering or leaving: as in fresnel_dielectric */
    if (cos_i < 0.0f) {
        float swap = eta_i;
        eta_i = eta_t;
        eta_t = swap;
        cos_i = -cos_i;
    }
    float r0 = (eta_i - eta_t) / (eta_i + eta_t);
    r0 *= r0;
    float cosine = cos_i;
    if (eta_i > eta_t) {
        /* Leaving the denser medium: use theta_t, and there may be none. */
        float eta = eta_i / eta_t;
        float sin2_t = eta * eta * fmaxf(0.0f, 1.0f - cos_i * cos_i);
        /* Total internal reflection: sin(theta_t) > 1 has no solution */
        if (sin2_t >= 1.0f)
            return 1.0f;
        cosine = sqrtf(1.0f - sin2_t);
    }
    float m = 1.0f - cosine;
    float m2 = m * m;
    return r0 + (1.0f - r0) * m2 * m2 * m;
}

/* ---- The Whitted integrator --------------------------------------------- */

/* Trace one secondary ray leaving `hit` in `direction` (unit), counted in
 * *ray_count, unless the depth limit forbids it. */
static vec3 trace_secondary(const scene *sc, const hit_record *hit, vec3 direction, int depth, int max_depth,
                            ray_counters *counters, uint64_t *ray_count, const char *kind)
{
    /* Depth limit: after max_depth bounces, return black. The light this ray
     * would have brought back (reflections of reflections, light that gets
     * through glass after more bounces) is cut off, so the image is a little
     * too dark wherever rays bounce that often. */
    if (depth >= max_depth) {
        explain_line(2 * depth + 2, "%s ray: not traced, depth limit %d reached: black", kind, max_depth);
        return vec3_splat(0.0f);
    }
    (*ray_count)++;
    /* The new ray starts on the side it leaves to (ray.h): a reflected ray
     * above the surface, a refracted ray below it. */
    ray next = ray_spawn(hit->point, hit->point_error, hit->normal_geometric, direction);
    if (explain_on()) {
        char label[64];
        snprintf(label, sizeof label, "%s ray (depth %d)", kind, depth + 1);
        explain_ray(2 * depth + 2, label, next);
    }
    return whitted_trace(sc, next, depth + 1, max_depth, counters);
}

vec3 whitted_trace(const scene *sc, ray r, int depth, int max_depth, ray_counters *counters)
{
    /* Depth limit: after max_depth bounces, return black */
    if (depth > max_depth)
        return vec3_splat(0.0f);

    /* Closest hit: the first surface along the ray (chapter 01) */
    /* --explain indents each level of the recursion by two steps. */
    int indent = 2 * depth + 1;
    hit_record hit;
    if (!scene_intersect(sc, r, &hit, counters)) {
        explain_line(indent, "missed every shape: the background");
        return sc->background;
    }
    if (explain_on())
        explain_hit(sc, &hit, indent);

    const material *m = &sc->materials[hit.material_id];
    vec3 d = vec3_normalize(r.direction);
    vec3 n = hit.normal_geometric; /* faces the incoming ray: n.d < 0 */

    switch (m->kind) {
    case MATERIAL_BLINN_PHONG:
        /* Diffuse hit: stop, shadow rays to each light, Blinn-Phong */
        return blinn_phong_shade_at(sc, &hit, vec3_neg(d), indent, counters);

    case MATERIAL_MIRROR:
        /* Reflection: r = d - 2 (d.n) n. Without the reflection effect (a
         * scene that narrowed it away) the mirror brings back nothing. */
        if (!(sc->effects & EFFECT_REFLECTION)) {
            explain_line(indent, "mirror: reflection is off (scene effects): black");
            return vec3_splat(0.0f);
        }
        return trace_secondary(sc, &hit, vec3_reflect(d, n), depth, max_depth, counters,
                               &counters->reflection_rays, "reflected");

    case MATERIAL_GLASS: {
        /* Entering or leaving: front_face says which side of the glass the ray is on */
        float eta_i = hit.front_face ? 1.0f : m->ior;
        float eta_t = hit.front_face ? m->ior : 1.0f;
        float cos_i = -vec3_dot(d, n);

        /* Snell's law: eta_i sin(theta_i) = eta_t sin(theta_t) */
        vec3 refracted;
        bool refracts = refract_direction(d, n, eta_i / eta_t, &refracted);

        /* Fresnel: reflectance for s- and p-polarised light, averaged.
         * Under total internal reflection R = 1 and no refraction ray is
         * traced; refract_direction alone decides that, so R and the
         * refraction ray cannot disagree by a rounding error. */
        float reflectance = refracts ? fresnel_dielectric(cos_i, eta_i, eta_t) : 1.0f;
        explain_line(indent, "glass %s (eta %g -> %g): Fresnel R = %.4g, T = %.4g%s",
                     hit.front_face ? "entering" : "leaving", (double)eta_i, (double)eta_t, (double)reflectance,
                     (double)(1.0f - reflectance), refracts ? "" : " (total internal reflection)");

        /* Reflection: r = d - 2 (d.n) n, weighted by R */
        vec3 radiance = vec3_splat(0.0f);
        if (sc->effects & EFFECT_REFLECTION)
            radiance = vec3_scale(trace_secondary(sc, &hit, vec3_reflect(d, n), depth, max_depth, counters,
                                                  &counters->reflection_rays, "reflected"),
                                  reflectance);
        /* Refraction: weighted by T = 1 - R. Only scenes with glass get
         * here, so a scene without glass never traces a refraction ray. */
        if (refracts && reflectance < 1.0f && (sc->effects & EFFECT_REFRACTION))
            radiance = vec3_add(radiance, vec3_scale(trace_secondary(sc, &hit, refracted, depth, max_depth, counters,
                                                                     &counters->refraction_rays, "refracted"),
                                                     1.0f - reflectance));
        if (explain_on()) {
            char c[64];
            explain_line(indent, "glass: R x reflected + T x refracted = %s", explain_vec3(c, radiance));
        }
        return radiance;
    }
    }
    return vec3_splat(0.0f);
}

vec3 whitted_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)rng; /* Whitted ray tracing is deterministic: no random choices */
    const whitted_context *w = ctx;
    return whitted_trace(w->sc, r, 0, w->max_depth, counters);
}

/* ---- The demo scene ----------------------------------------------------- */

void scene_build_whitted_demo(scene *sc)
{
    scene_init(sc);
    sc->camera = (scene_camera){vec3_make(0.0f, 3.4f, 8.0f), vec3_make(0.0f, 0.8f, -0.6f), vec3_make(0, 1, 0), 38.0f};
    sc->background = vec3_make(0.235f, 0.675f, 0.843f); /* the sky blue of assignment 5 */
    sc->ambient = vec3_splat(0.08f);

    /* The checkerboard of assignment 5: orange-red and yellow. */
    material floor = material_blinn_phong(vec3_make(0.815f, 0.235f, 0.031f), vec3_splat(0.0f), 1.0f);
    floor.checker_diffuse = vec3_make(0.937f, 0.937f, 0.231f);
    floor.checker_size = 1.0f;
    int floor_id = scene_add_material(sc, floor);
    int diffuse = scene_add_material(sc, material_blinn_phong(vec3_make(0.6f, 0.7f, 0.8f), vec3_splat(0.3f), 32.0f));
    int glass = scene_add_material(sc, material_glass(1.5f));
    int mirror = scene_add_material(sc, material_mirror());

    /* A finite floor of two triangles (counter-clockwise from above), so the
     * sky shows behind it as in assignment 5. */
    vec3 a = vec3_make(-10.0f, 0.0f, 5.0f), b = vec3_make(10.0f, 0.0f, 5.0f);
    vec3 c = vec3_make(10.0f, 0.0f, -24.0f), e = vec3_make(-10.0f, 0.0f, -24.0f);
    scene_add_triangle(sc, a, b, c, floor_id);
    scene_add_triangle(sc, a, c, e, floor_id);

    /* The spheres float 0.005 above the floor rather than touch it. Where
     * two surfaces touch or cross, they are closer than any ray offset near
     * the contact, so a ray leaving one there can start behind the other
     * (with ior 1.0, one pixel's ray left the glass 1e-5 above the floor,
     * started below it and saw the sky). A gap much wider than the offset
     * has no such spot. */
    const float gap = 0.005f;
    scene_add_sphere(sc, vec3_make(-2.1f, 1.0f + gap, -1.4f), 1.0f, diffuse);
    scene_add_sphere(sc, vec3_make(-0.2f, 0.8f + gap, 1.6f), 0.8f, glass);
    scene_add_sphere(sc, vec3_make(2.0f, 1.15f + gap, -1.8f), 1.15f, mirror);

    scene_add_point_light(sc, vec3_make(-5.0f, 12.0f, 7.0f), vec3_splat(200.0f));
    scene_add_point_light(sc, vec3_make(7.0f, 9.0f, 3.0f), vec3_make(80.0f, 76.0f, 70.0f));
}

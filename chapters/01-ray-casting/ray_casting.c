#include "01-ray-casting/ray_casting.h"

#include "explain.h"

bool light_visible(const scene *sc, const hit_record *hit, vec3 light_position, ray_counters *counters)
{
    /* The effects analysis proved that nothing can block any light (or the
     * scene turned shadows off): no shadow ray. */
    if (!scene_traces_shadows(sc))
        return true;
    /* Shadow ray from the hit point to the light: blocked if anything lies
     * strictly between them (t in (0, 1) along point -> light). */
    ray shadow = ray_spawn_to(hit->point, hit->point_error, hit->normal_geometric, light_position, 0.0f,
                              vec3_splat(0.0f));
    counters->shadow_rays++;
    return !scene_occluded(sc, shadow, counters);
}

void explain_hit(const scene *sc, const hit_record *hit, int depth)
{
    const material *m = &sc->materials[hit->material_id];
    char p[64], n[64];
    explain_line(depth, "hit %s #%d, material #%d '%s' (%s), at t = %.6g, point %s, normal %s%s",
                 shape_kind_name(sc->shapes[hit->shape_id].kind), hit->shape_id, hit->material_id, m->name,
                 material_kind_name(m->kind), (double)hit->t, explain_vec3(p, hit->point),
                 explain_vec3(n, hit->normal_shading), hit->front_face ? "" : " (inside)");
}

vec3 blinn_phong_shade(const scene *sc, const hit_record *hit, vec3 to_viewer, ray_counters *counters)
{
    return blinn_phong_shade_at(sc, hit, to_viewer, 1, counters);
}

vec3 blinn_phong_shade_at(const scene *sc, const hit_record *hit, vec3 to_viewer, int depth, ray_counters *counters)
{
    const material *m = &sc->materials[hit->material_id];
    vec3 n = hit->normal_shading; /* faces the viewer */
    vec3 k_d = material_diffuse_at(m, hit->point);
    char buffer[64];

    /* Ambient term: k_a I_a, a constant stand-in for all indirect light. */
    vec3 radiance = vec3_mul(k_d, sc->ambient);
    if (explain_on()) {
        char ambient[64];
        explain_line(depth, "Blinn-Phong with k_d %s: ambient k_a I_a = %s", explain_vec3(buffer, k_d),
                     explain_vec3(ambient, radiance));
    }

    for (int i = 0; i < sc->light_count; i++) {
        const point_light *light = &sc->lights[i];
        vec3 to_light = vec3_sub(light->position, hit->point);
        float r2 = vec3_length_squared(to_light);
        vec3 l = vec3_scale(to_light, 1.0f / sqrtf(r2));
        float n_dot_l = vec3_dot(n, l);
        /* Light behind the surface: no light arrives, and no shadow ray is
         * needed to know it. */
        if (n_dot_l <= 0.0f) {
            explain_line(depth + 1, "light %d: behind the surface (n.l = %.4g): no light, no shadow ray", i,
                         (double)n_dot_l);
            continue;
        }
        if (!light_visible(sc, hit, light->position, counters)) {
            explain_line(depth + 1, "light %d: shadow ray towards it is blocked", i);
            continue;
        }
        /* Irradiance falls off as I / r^2 (lecture 14 explains why). */
        vec3 irradiance = vec3_scale(light->intensity, 1.0f / r2);
        /* Diffuse: k_d (I / r^2) max(0, n.l) */
        vec3 diffuse = vec3_scale(vec3_mul(k_d, irradiance), n_dot_l);
        /* Specular: k_s (I / r^2) max(0, n.h)^p, with the half vector h. */
        vec3 h = vec3_normalize(vec3_add(l, to_viewer));
        float n_dot_h = fmaxf(0.0f, vec3_dot(n, h));
        vec3 specular = vec3_scale(vec3_mul(m->specular, irradiance), powf(n_dot_h, m->shininess));
        radiance = vec3_add(radiance, vec3_add(diffuse, specular));
        if (explain_on()) {
            char dbuf[64], sbuf[64];
            explain_line(depth + 1, "light %d: %s (r = %.4g, n.l = %.4g): diffuse %s + specular %s", i,
                         scene_traces_shadows(sc) ? "visible, shadow ray unblocked"
                                                  : "visible without a shadow ray (effects: nothing can block it)",
                         (double)sqrtf(r2), (double)n_dot_l, explain_vec3(dbuf, diffuse), explain_vec3(sbuf, specular));
        }
    }
    explain_line(depth, "shaded radiance %s", explain_vec3(buffer, radiance));
    return radiance;
}

vec3 ray_cast_radiance(const void *scene_ptr, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)rng; /* ray casting is deterministic: one ray through each pixel centre */
    const scene *sc = scene_ptr;
    hit_record hit;
    if (!scene_intersect(sc, r, &hit, counters)) {
        explain_line(1, "missed every shape: the background");
        return sc->background;
    }
    if (explain_on())
        explain_hit(sc, &hit, 1);
    vec3 to_viewer = vec3_normalize(vec3_neg(r.direction));
    return blinn_phong_shade(sc, &hit, to_viewer, counters);
}

void scene_build_ray_casting_demo(scene *sc)
{
    scene_init(sc);
    sc->camera = (scene_camera){vec3_make(0.0f, 2.4f, 6.5f), vec3_make(0.0f, 0.7f, 0.0f), vec3_make(0, 1, 0), 38.0f};
    sc->background = vec3_make(0.05f, 0.07f, 0.12f);
    sc->ambient = vec3_splat(0.06f);

    material floor = material_blinn_phong(vec3_splat(0.75f), vec3_splat(0.0f), 1.0f);
    floor.checker_diffuse = vec3_splat(0.15f);
    floor.checker_size = 1.0f;
    int floor_id = scene_add_material(sc, floor);
    int red = scene_add_material(sc, material_blinn_phong(vec3_make(0.75f, 0.12f, 0.1f), vec3_splat(0.5f), 64.0f));
    int gold = scene_add_material(sc, material_blinn_phong(vec3_make(0.8f, 0.6f, 0.15f), vec3_splat(0.2f), 16.0f));
    int blue = scene_add_material(sc, material_blinn_phong(vec3_make(0.15f, 0.3f, 0.8f), vec3_splat(0.6f), 128.0f));

    scene_add_plane(sc, vec3_make(0, 0, 0), vec3_make(0, 1, 0), floor_id);
    scene_add_sphere(sc, vec3_make(-1.7f, 0.9f, 0.0f), 0.9f, red);
    /* A triangle standing upright, facing the camera. */
    scene_add_triangle(sc, vec3_make(-0.6f, 0.0f, -0.8f), vec3_make(0.6f, 0.0f, -0.8f), vec3_make(0.0f, 1.8f, -1.0f),
                       gold);
    /* The implicit torus, lying on the floor. */
    scene_add_torus(sc, vec3_make(1.7f, 0.3f, 0.3f), 0.75f, 0.3f, blue);

    scene_add_point_light(sc, vec3_make(-4.0f, 6.0f, 4.0f), vec3_splat(40.0f));
    scene_add_point_light(sc, vec3_make(5.0f, 4.0f, 2.0f), vec3_make(14.0f, 13.0f, 11.0f));
}

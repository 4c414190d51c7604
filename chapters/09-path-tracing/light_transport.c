/* light_transport.c -- the lecture's light sample, in the area form
 * (light_transport.h, which holds the later rungs' pieces inline: chapter
 * 13 calls them for every lane of every bounce). */
#include "09-path-tracing/light_transport.h"

/* ---- the lecture's light sample, in the area form ---------------------------
 *   L_dir = L_i f_r cos(theta) cos(theta') / |x' - p|^2 / pdf_light
 * with theta at p and theta' at x', each against its normal. */
light_contribution direct_light_area(const pt_material *m, const hit_record *p, vec3 wo, const pt_light_sample *x)
{
    /* exercise: light_sample */
    light_contribution l = {.radiance = vec3_splat(0.0f), .weight = 1.0f};
    vec3 ws = light_towards(p, x->point, &l);
    l.cos_theta_light = -vec3_dot(x->normal, ws);
    l.adds = l.cos_theta > 0.0f && l.cos_theta_light > 0.0f;
    if (!l.adds)
        return l;
    l.radiance = vec3_scale(vec3_mul(x->emission, bsdf_eval(m, p->normal_shading, wo, ws)),
                            l.cos_theta * l.cos_theta_light / l.distance2 / x->pdf_light);
    /* the shadow ray: from p to x', stopping short of both surfaces */
    l.shadow = ray_spawn_to(p->point, p->point_error, p->normal_geometric, x->point, x->point_error, x->normal);
    return l;
    /* end of exercise light_sample */
}

/* bdpt.c -- bidirectional path tracing with multiple importance sampling
 * over every connection strategy (see bdpt.h).
 *
 * The path integral (Veach 1997, ch. 8): a pixel's value is
 *   I = sum over n of the integral over x_0 .. x_{n-1} (each over the
 *       scene's surfaces, by area) of
 *       L_e(x_0 -> x_1) G(x_0, x_1) f(x_0 -> x_1 -> x_2) G(x_1, x_2) ...
 *       f(x_{n-3} -> x_{n-2} -> x_{n-1}) G(x_{n-2}, x_{n-1}) W_e(x_{n-2} -> x_{n-1})
 * with G(x, y) = V(x, y) |cos theta_x| |cos theta_y| / |x - y|^2. Any way of
 * drawing the vertices gives an unbiased estimate f(x) / p(x) if p is the
 * density per unit area of every vertex together; the strategies differ in
 * p only, and MIS weighs them by it. */
#include "11-bidirectional/bdpt.h"

#include <string.h>

#include "09-path-tracing/bsdf.h"
#include "program.h"
#include "render.h"

bdpt bdpt_defaults(const pt_scene *scene, const camera *cam)
{
    bdpt b;
    memset(&b, 0, sizeof b);
    b.scene = scene;
    b.cam = cam;
    b.max_depth = BDPT_MAX_DEPTH;
    b.rr_start_depth = 3;
    b.heuristic = BDPT_POWER;
    b.only_s = -1;
    b.only_t = -1;
    b.unweighted = false;
    b.fault = BDPT_FAULT_NONE;
    b.film = NULL;
    return b;
}


bool bdpt_supports(const pt_scene *sc, char *err, size_t err_size)
{
    for (int i = 0; i < sc->material_count; i++)
        if (bsdf_is_delta(&sc->materials[i])) {
            snprintf(err, err_size, "material #%d is %s: bidirectional path tracing here handles diffuse and glossy "
                     "surfaces only (delta BSDFs are an exercise); use chapter 09's path tracer",
                     i, sc->materials[i].kind == BSDF_GLASS ? "glass" : "a mirror");
            return false;
        }
    if (sc->point_light_count > 0) {
        snprintf(err, err_size, "the scene has %d point light(s): only emitting triangles are lights here",
                 sc->point_light_count);
        return false;
    }
    for (int i = 0; i < sc->sphere_count; i++)
        if (!vec3_is_black(sc->materials[sc->spheres[i].material].emission)) {
            snprintf(err, err_size, "sphere #%d emits: only emitting triangles are lights here", i);
            return false;
        }
    if (!vec3_is_black(sc->environment)) {
        snprintf(err, err_size, "the scene has an environment (background) light: only emitting triangles are "
                 "lights here");
        return false;
    }
    if (sc->emitter_count == 0) {
        snprintf(err, err_size, "nothing in the scene emits light");
        return false;
    }
    return true;
}

/* ---- the pinhole camera as a sensor -------------------------------------------
 * The image plane lies at distance 1 (area A = 4 half_width half_height,
 * each pixel A_pixel = A / (width height)). A patch dA of the plane at angle
 * theta from the axis lies at distance 1 / cos(theta) and faces the eye at
 * angle theta, so it spans dw = dA cos^3(theta). A camera sample of a pixel
 * is uniform on that pixel: per unit solid angle its density is
 * 1 / (A_pixel cos^3 theta). The importance W_e that makes a pixel's value
 * the average radiance over its area is 1 / (A_pixel cos^4 theta) on the
 * pixel, 0 elsewhere, so W_e cos(theta) / pdf = 1: a camera ray carries
 * weight 1. */
bool bdpt_camera_project(const camera *cam, vec3 point, float *px, float *py)
{
    vec3 d = vec3_sub(point, cam->eye);
    float z = vec3_dot(d, cam->forward);
    if (!(z > 0.0f))
        return false;
    float sx = vec3_dot(d, cam->right) / z, sy = vec3_dot(d, cam->up) / z;
    *px = 0.5f * (sx / cam->half_width + 1.0f) * (float)cam->width;
    *py = 0.5f * (1.0f - sy / cam->half_height) * (float)cam->height;
    return *px >= 0.0f && *px < (float)cam->width && *py >= 0.0f && *py < (float)cam->height;
}

static float image_plane_area(const camera *cam) { return 4.0f * cam->half_width * cam->half_height; }

float bdpt_camera_pdf_direction(const camera *cam, vec3 direction)
{
    float px, py;
    if (!bdpt_camera_project(cam, vec3_add(cam->eye, direction), &px, &py))
        return 0.0f;
    float cos_theta = vec3_dot(vec3_normalize(direction), cam->forward);
    return 1.0f / (image_plane_area(cam) * cos_theta * cos_theta * cos_theta);
}

/* ---- densities -------------------------------------------------------------------
 * Solid angle to area: a direction drawn with density p per steradian at
 * `from` lands on `to` with density p |cos theta_to| / |to - from|^2 per unit
 * area (the eye, a point, has no area: its density stays per steradian and
 * only ever stands in the ratio of a strategy that cannot be used). */
static float to_area(const bdpt_vertex *from, const bdpt_vertex *to, float pdf_direction)
{
    vec3 d = vec3_sub(to->point, from->point);
    float distance2 = vec3_length_squared(d);
    if (!(distance2 > 0.0f))
        return 0.0f;
    if (to->kind == BDPT_VERTEX_CAMERA)
        return pdf_direction / distance2;
    float cos_to = fabsf(vec3_dot(to->normal, d)) / sqrtf(distance2);
    return pdf_direction * cos_to / distance2;
}

/* The density per steradian with which `from` draws the direction to `to`. */
static float pdf_direction(const bdpt *b, const bdpt_vertex *from, const bdpt_vertex *before, const bdpt_vertex *to)
{
    vec3 w = vec3_normalize(vec3_sub(to->point, from->point));
    if (from->kind == BDPT_VERTEX_CAMERA)
        return bdpt_camera_pdf_direction(b->cam, w);
    if (before == NULL) {
        /* a path's first vertex on a light: cosine-weighted about its front */
        float c = vec3_dot(from->normal, w);
        return c > 0.0f ? c / (float)PI : 0.0f;
    }
    vec3 wo = vec3_normalize(vec3_sub(before->point, from->point));
    return bsdf_pdf(&b->scene->materials[from->material], from->normal, wo, w);
}

float bdpt_pdf_area(const bdpt *b, const bdpt_vertex *from, const bdpt_vertex *before, const bdpt_vertex *to)
{
    return to_area(from, to, pdf_direction(b, from, before, to));
}

void bdpt_subpath_fill_pdfs(const bdpt *b, bdpt_vertex *v, int count)
{
    if (count <= 0)
        return;
    v[0].pdf_fwd = v[0].kind == BDPT_VERTEX_CAMERA ? 1.0f : pt_scene_emitter_pdf_area(b->scene, v[0].material);
    v[0].pdf_rev = 0.0f;
    for (int i = 1; i < count; i++) {
        v[i].pdf_fwd = bdpt_pdf_area(b, &v[i - 1], i >= 2 ? &v[i - 2] : NULL, &v[i]);
        v[i].pdf_rev = 0.0f;
        if (i + 1 < count)
            v[i - 1].pdf_rev = bdpt_pdf_area(b, &v[i], &v[i + 1], &v[i - 1]);
    }
}

/* ---- subpaths ---------------------------------------------------------------------
 * A random walk from path[count - 1], whose ray r was drawn with density
 * pdf_dir per steradian and carries throughput beta. Each new vertex stores
 * its forward density; once the walk goes on from it, the density of the
 * way back to the previous vertex is known too (reverse: the BSDF's pdf with
 * the roles of wo and wi swapped). Russian roulette on each bounce's weight
 * after rr_start_depth vertices ends walks through dark surfaces sooner; the
 * MIS weights leave it out (any weights that sum to one are unbiased). */
static int random_walk(const bdpt *b, ray r, vec3 beta, float pdf_dir, bdpt_vertex *path, int count, int max_count,
                       pcg32 *rng, ray_counters *counters)
{
    const pt_scene *sc = b->scene;
    while (count < max_count) {
        hit_record hit;
        if (!pt_scene_intersect(sc, r, &hit, counters))
            break;
        bdpt_vertex *previous = &path[count - 1], *v = &path[count];
        v->kind = BDPT_VERTEX_SURFACE;
        v->point = hit.point;
        v->point_error = hit.point_error;
        v->normal = hit.normal_shading;
        v->normal_geometric = hit.normal_geometric;
        v->material = hit.material_id;
        v->front_face = hit.front_face;
        v->beta = beta;
        v->pdf_fwd = to_area(previous, v, pdf_dir);
        v->pdf_rev = 0.0f;
        count++;
        if (count >= max_count)
            break;

        /* Scatter: the next direction from the BSDF */
        const pt_material *m = &sc->materials[v->material];
        vec3 wo = vec3_normalize(vec3_neg(r.direction));
        bsdf_sample_result s;
        /* in a written order (C leaves a call's argument order open): GCC's */
        float u_y = pcg32_float(rng), u_x = pcg32_float(rng);
        vec2 u = vec2_make(u_x, u_y);
        if (!bsdf_sample(m, v->normal, wo, u, pcg32_float(rng), v->front_face, &s) || vec3_is_black(s.weight))
            break;
        /* Russian roulette */
        if (count > b->rr_start_depth) {
            float q = fminf(1.0f, vec3_max_component(s.weight));
            if (pcg32_float(rng) >= q)
                break;
            s.weight = vec3_scale(s.weight, 1.0f / q);
        }
        /* The way back: the density of drawing wo when arriving along wi */
        previous->pdf_rev = to_area(v, previous, bsdf_pdf(m, v->normal, s.wi, wo));
        beta = vec3_mul(beta, s.weight);
        pdf_dir = s.pdf;
        counters->indirect_rays++;
        r = ray_spawn(v->point, v->point_error, v->normal_geometric, s.wi);
    }
    return count;
}

static int camera_subpath(const bdpt *b, ray r, bdpt_vertex *path, pcg32 *rng, ray_counters *counters)
{
    bdpt_vertex *z0 = &path[0];
    memset(z0, 0, sizeof *z0);
    z0->kind = BDPT_VERTEX_CAMERA;
    z0->point = b->cam->eye;
    z0->normal = b->cam->forward;
    z0->normal_geometric = b->cam->forward;
    z0->beta = vec3_splat(1.0f);
    z0->pdf_fwd = 1.0f; /* the one eye point: a delta, the same for every strategy */
    /* W_e cos / pdf = 1 (above) */
    return random_walk(b, r, vec3_splat(1.0f), bdpt_camera_pdf_direction(b->cam, r.direction), path, 1,
                       b->max_depth + 2, rng, counters);
}

/* y_0: a point on a light, picked by power (chapter 09's table), density
 * p_A; its throughput L_e / p_A. Then a direction cosine-weighted about its
 * front, pdf cos / pi: the first ray carries L_e cos / (p_A cos / pi) =
 * L_e pi / p_A. The light rays are counted as indirect rays. */
static int light_subpath(const bdpt *b, bdpt_vertex *path, pcg32 *rng, ray_counters *counters)
{
    const pt_scene *sc = b->scene;
    float u_pick = pcg32_float(rng), u1 = pcg32_float(rng), u2 = pcg32_float(rng);
    float u_dir_y = pcg32_float(rng), u_dir_x = pcg32_float(rng); /* in GCC's order, written out */
    vec2 u_dir = vec2_make(u_dir_x, u_dir_y);
    bdpt_vertex *y0 = &path[0];
    memset(y0, 0, sizeof *y0);
    if (!pt_scene_sample_emitter(sc, u_pick, u1, u2, &y0->point, &y0->point_error, &y0->normal, &y0->material))
        return 0;
    y0->kind = BDPT_VERTEX_LIGHT;
    y0->normal_geometric = y0->normal;
    y0->front_face = true;
    y0->pdf_fwd = pt_scene_emitter_pdf_area(sc, y0->material);
    y0->beta = vec3_scale(sc->materials[y0->material].emission, 1.0f / y0->pdf_fwd);
    if (b->max_depth + 1 < 2)
        return 1;
    vec3 local = sample_cosine_hemisphere(u_dir);
    if (!(local.z > 0.0f))
        return 1;
    vec3 w = frame_to_world(y0->normal, local);
    counters->indirect_rays++;
    return random_walk(b, ray_spawn(y0->point, y0->point_error, y0->normal_geometric, w),
                       vec3_scale(y0->beta, (float)PI), cosine_hemisphere_pdf(local.z), path, 1, b->max_depth + 1, rng,
                       counters);
}

/* ---- multiple importance sampling -------------------------------------------------
 * Strategy s' draws the first s' vertices from the light and the rest from
 * the eye, so its path density is
 *   p_s' = L_0 ... L_{s'-1}  E_{s'} ... E_{n-1}
 * (L_i: the density of x_i drawn from the light side, E_i: from the eye
 * side). Neighbours differ in one vertex: p_{s'+1} / p_{s'} = L_s' / E_s'.
 * The power heuristic weight of strategy s is p_s^2 / sum p_s'^2, i.e.
 * 1 / sum (p_s' / p_s)^2, and the ratios come as running products -- no
 * path density itself is ever formed (it would under- or overflow). The
 * subpaths hold every L_i and E_i except those of the four vertices around
 * the join, which depend on the other side: they are computed here. */
static float heuristic(const bdpt *b, float ratio) { return b->heuristic == BDPT_POWER ? ratio * ratio : ratio; }

float bdpt_mis_weight(const bdpt *b, const bdpt_vertex *light, int s, const bdpt_vertex *camera, int t)
{
    int n = s + t;
    const bdpt_vertex *x[2 * BDPT_MAX_VERTICES];
    float from_light[2 * BDPT_MAX_VERTICES], from_eye[2 * BDPT_MAX_VERTICES];
    for (int i = 0; i < s; i++) {
        x[i] = &light[i];
        from_light[i] = light[i].pdf_fwd;
        from_eye[i] = light[i].pdf_rev;
    }
    for (int j = 0; j < t; j++) {
        x[n - 1 - j] = &camera[j];
        from_eye[n - 1 - j] = camera[j].pdf_fwd;
        from_light[n - 1 - j] = camera[j].pdf_rev;
    }
    bool solid_angle_fault = b->fault == BDPT_FAULT_SOLID_ANGLE_PDF;
    if (s == 0) {
        /* The camera path found a light: the light would have picked this
         * point with the emitter table's density, and left it by cosine. */
        from_light[0] = pt_scene_emitter_pdf_area(b->scene, x[0]->material);
        from_light[1] = solid_angle_fault ? pdf_direction(b, x[0], NULL, x[1]) : bdpt_pdf_area(b, x[0], NULL, x[1]);
    } else {
        /* y_{s-1} as the eye side would draw it, from z_{t-1}; y_{s-2} as
         * the eye side would draw it from y_{s-1}; and the same for the
         * light side at z_{t-1} and z_{t-2}. */
        const bdpt_vertex *z_before = t >= 2 ? x[s + 1] : NULL;
        from_eye[s - 1] = solid_angle_fault ? pdf_direction(b, x[s], z_before, x[s - 1])
                                            : bdpt_pdf_area(b, x[s], z_before, x[s - 1]);
        if (s >= 2)
            from_eye[s - 2] = bdpt_pdf_area(b, x[s - 1], x[s], x[s - 2]);
        from_light[s] = bdpt_pdf_area(b, x[s - 1], s >= 2 ? x[s - 2] : NULL, x[s]);
        if (t >= 2)
            from_light[s + 1] = bdpt_pdf_area(b, x[s], x[s - 1], x[s + 1]);
    }
    /* Every s' from 0 (the eye path hits the light) to n - 1 (light
     * tracing, t' = 1); t' = 0 would need a light path to hit the pinhole. */
    float sum = 1.0f, ratio = 1.0f;
    for (int k = s - 1; k >= 0; k--) {
        ratio *= from_eye[k] / from_light[k];
        sum += heuristic(b, ratio);
    }
    ratio = 1.0f;
    for (int k = s + 1; k <= n - 1; k++) {
        ratio *= from_light[k - 1] / from_eye[k - 1];
        sum += heuristic(b, ratio);
    }
    return 1.0f / sum;
}

/* ---- joining the subpaths -----------------------------------------------------------
 * The unweighted contribution of strategy (s, t):
 *   s = 0:  beta(z_{t-1}) L_e, if z_{t-1} is the front of a light
 *   else:   beta(y_{s-1}) f(y_{s-2} -> y_{s-1} -> z_{t-1}) G(y_{s-1}, z_{t-1})
 *           f(y_{s-1} -> z_{t-1} -> z_{t-2}) beta(z_{t-1})
 * where at y_0 "f" is the light's directional factor (1 in front, 0
 * behind: L_e itself is in beta(y_0)), and at z_0 it is W_e, with t = 1
 * splatted to the pixel the eye sees y_{s-1} in. */

/* The scattering factor at a subpath's last vertex v towards `to`, with
 * `before` the vertex it was reached from (NULL at an end). */
static vec3 end_factor(const bdpt *b, const bdpt_vertex *v, const bdpt_vertex *before, vec3 to)
{
    vec3 w = vec3_normalize(vec3_sub(to, v->point));
    if (before == NULL) /* a light's first vertex: one-sided */
        return vec3_splat(vec3_dot(v->normal, w) > 0.0f ? 1.0f : 0.0f);
    vec3 wo = vec3_normalize(vec3_sub(before->point, v->point));
    /* light flows from `before` to `to`, or from `to` to `before`: the same for
     * our reciprocal BSDFs */
    return bsdf_eval(&b->scene->materials[v->material], v->normal, w, wo);
}

/* The shadow ray between two vertices. It leaves from the eye side and ends
 * at the light side, as chapter 09's light samples do. (Shot the other way
 * it once lost 0.6 % of the Cornell box's direct light, at the green wall in
 * the plane x = 0: the far end was pulled off its surface too little; the
 * README's hard cases, and ray_offset_far_end in ray.h.) */
static bool visible(const bdpt *b, const bdpt_vertex *a, const bdpt_vertex *c, ray_counters *counters)
{
    counters->shadow_rays++;
    vec3 target_normal = c->kind == BDPT_VERTEX_CAMERA ? vec3_splat(0.0f) : c->normal_geometric;
    ray shadow = ray_spawn_to(a->point, a->point_error, a->normal_geometric, c->point, c->point_error, target_normal);
    return !pt_scene_occluded(b->scene, shadow, counters);
}

/* Light tracing's join (t = 1): y_{s-1} seen by the eye, added to the film. */
static void connect_to_camera(const bdpt *b, const bdpt_vertex *light, int s, const bdpt_vertex *eye,
                              ray_counters *counters)
{
    const bdpt_vertex *y = &light[s - 1];
    float px, py;
    if (!bdpt_camera_project(b->cam, y->point, &px, &py))
        return;
    vec3 f = end_factor(b, y, s >= 2 ? &light[s - 2] : NULL, eye->point);
    if (vec3_is_black(f))
        return;
    vec3 d = vec3_sub(eye->point, y->point);
    float distance2 = vec3_length_squared(d), distance = sqrtf(distance2);
    float cos_y = fabsf(vec3_dot(y->normal, d)) / distance;
    float cos_eye = -vec3_dot(b->cam->forward, d) / distance;
    if (b->fault == BDPT_FAULT_NO_LIGHT_COSINE)
        cos_y = 1.0f;
    /* G W_e = cos_y cos_eye / d^2 / (A_pixel cos_eye^4), averaged over the
     * spp x width x height light paths; since A_pixel x width x height = A,
     * that is cos_y / (d^2 A cos_eye^3) here and the film divided by spp
     * when resolved (bdpt_render) */
    float importance = cos_y / (distance2 * image_plane_area(b->cam) * cos_eye * cos_eye * cos_eye);
    if (!(importance > 0.0f) || !visible(b, y, eye, counters))
        return;
    vec3 value = vec3_scale(vec3_mul(y->beta, f), importance);
    if (!b->unweighted)
        value = vec3_scale(value, bdpt_mis_weight(b, light, s, eye, 1));
    splat_film_add(b->film, px, py, value, counters);
}

/* The join itself: the light subpath's last vertex y and the camera
 * subpath's last vertex z, each with the scattering factor of its own
 * BSDF towards the other, and the geometry term between them:
 *   beta(y) f(y_before -> y -> z) G(y, z) f(y -> z -> z_before) beta(z),
 *   G(y, z) = |cos theta_y| |cos theta_z| / |y - z|^2
 * without G's visibility V, which the shadow ray decides (connect, below:
 * a join that adds nothing costs no ray). */
vec3 bdpt_connect(const bdpt *b, const bdpt_vertex *y, const bdpt_vertex *y_before, const bdpt_vertex *z,
                  const bdpt_vertex *z_before)
{
    /* exercise: bdpt_connect */
    vec3 f_y = end_factor(b, y, y_before, z->point);
    vec3 f_z = end_factor(b, z, z_before, y->point);
    if (vec3_is_black(f_y) || vec3_is_black(f_z))
        return vec3_splat(0.0f);
    vec3 d = vec3_sub(z->point, y->point);
    float distance2 = vec3_length_squared(d), distance = sqrtf(distance2);
    float cos_y = fabsf(vec3_dot(y->normal, d)) / distance, cos_z = fabsf(vec3_dot(z->normal, d)) / distance;
    float g = cos_y * cos_z / distance2;
    if (!(g > 0.0f))
        return vec3_splat(0.0f);
    return vec3_scale(vec3_mul(vec3_mul(y->beta, f_y), vec3_mul(f_z, z->beta)), g);
    /* end of exercise bdpt_connect */
}

/* The twin BDPT_FAULT_NO_LIGHT_COSINE at a join on the light (s = 1): the
 * join's value with cos theta_y divided out, as if it were 1. */
static vec3 without_light_cosine(vec3 c, const bdpt_vertex *y, const bdpt_vertex *z)
{
    vec3 d = vec3_sub(z->point, y->point);
    float cos_y = fabsf(vec3_dot(y->normal, d)) / sqrtf(vec3_length_squared(d));
    return cos_y > 0.0f ? vec3_scale(c, 1.0f / cos_y) : c;
}

static vec3 connect(const bdpt *b, const bdpt_vertex *light, int s, const bdpt_vertex *camera, int t,
                    ray_counters *counters)
{
    const pt_scene *sc = b->scene;
    const bdpt_vertex *z = &camera[t - 1];
    vec3 c;
    if (s == 0) {
        const pt_material *m = &sc->materials[z->material];
        if (!z->front_face || vec3_is_black(m->emission))
            return vec3_splat(0.0f);
        c = vec3_mul(z->beta, m->emission);
    } else {
        const bdpt_vertex *y = &light[s - 1];
        c = bdpt_connect(b, y, s >= 2 ? &light[s - 2] : NULL, z, &camera[t - 2]);
        if (b->fault == BDPT_FAULT_NO_LIGHT_COSINE && s == 1)
            c = without_light_cosine(c, y, z);
        if (vec3_is_black(c) || !visible(b, z, y, counters))
            return vec3_splat(0.0f);
    }
    if (b->unweighted)
        return c;
    return vec3_scale(c, bdpt_mis_weight(b, light, s, camera, t));
}

static bool strategy_wanted(const bdpt *b, int s, int t)
{
    return (b->only_s < 0 || b->only_s == s) && (b->only_t < 0 || b->only_t == t);
}

vec3 bdpt_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters)
{
    const bdpt *b = ctx;
    bdpt_vertex camera[BDPT_MAX_VERTICES], light[BDPT_MAX_VERTICES];
    int t_count = camera_subpath(b, r, camera, rng, counters);
    int s_count = light_subpath(b, light, rng, counters);
    vec3 radiance = vec3_splat(0.0f);
    for (int t = 1; t <= t_count; t++) {
        for (int s = 0; s <= s_count; s++) {
            int n = s + t;
            if (n < 2 || n - 2 > b->max_depth || !strategy_wanted(b, s, t))
                continue;
            if (t == 1)
                connect_to_camera(b, light, s, &camera[0], counters);
            else
                radiance = vec3_add(radiance, connect(b, light, s, camera, t, counters));
        }
    }
    return radiance;
}

/* The job both the render and its pilot run: every camera sample through
 * bdpt_radiance, with b's film for the splats. */
static render_job bdpt_job(const bdpt *b, int spp, uint64_t seed, int threads, bool quiet, image *standard_error)
{
    render_job job = {.cam = b->cam, .spp = spp, .seed = seed, .threads = threads, .quiet = quiet,
                      .label = "bidirectional", .radiance = bdpt_radiance, .scene = b,
                      .standard_error = standard_error, .jitter = true};
    return job;
}

double bdpt_pilot_seconds(const bdpt *b, int spp, uint64_t seed)
{
    splat_film scratch;
    if (!splat_film_init(&scratch, b->cam->width, b->cam->height))
        return 0.0;
    bdpt with_film = *b;
    with_film.film = &scratch;
    render_job job = bdpt_job(&with_film, spp, seed, 1, true, NULL);
    double seconds = program_pilot_seconds(&job);
    splat_film_free(&scratch);
    return seconds;
}

bool bdpt_render(const bdpt *b, int spp, uint64_t seed, int threads, bool quiet, estimate_image *out)
{
    const camera *cam = b->cam;
    splat_film film;
    if (!splat_film_init(&film, cam->width, cam->height))
        return false;
    bdpt with_film = *b;
    with_film.film = &film;
    out->mean = image_make(cam->width, cam->height);
    out->standard_error = image_make(cam->width, cam->height);
    render_job job = bdpt_job(&with_film, spp, seed, threads, quiet, &out->standard_error);
    render_stats stats;
    render_image(&job, &out->mean, &stats);
    /* Light tracing's share: one light path per camera sample, so each
     * pixel's splats are divided by its spp. */
    for (int y = 0; y < cam->height; y++)
        for (int x = 0; x < cam->width; x++)
            image_set(&out->mean, x, y, vec3_add(image_get(&out->mean, x, y),
                                                 splat_film_get(&film, x, y, 1.0 / (double)spp)));
    splat_film_free(&film);
    out->spp = spp;
    out->seconds = stats.seconds;
    out->counters = stats.counters;
    return true;
}

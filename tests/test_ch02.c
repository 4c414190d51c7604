/* test_ch02.c -- chapter 02, Whitted-style ray tracing: each test checks what
 * the optics predicts (Snell's law, the Fresnel equations, total internal
 * reflection, the depth limit), and where a check could pass by accident it
 * also runs on a deliberately wrong implementation and must fail there. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "02-whitted/whitted.h"
#include "effects.h"
#include "render.h"
#include "scene_file.h"
#include "rng.h"
#include "test_support.h"

static const double DEG = PI / 180.0;
static const float GLASS = 1.5f;

static vec3 random_unit(pcg32 *rng)
{
    float z = 1.0f - 2.0f * pcg32_float(rng);
    float phi = 2.0f * (float)PI * pcg32_float(rng);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return vec3_make(s * cosf(phi), s * sinf(phi), z);
}

/* ---- Fresnel ---------------------------------------------------------------- */

/* Mirror reflection keeps the part of d along the surface and flips the
 * part along n: at 45 degrees onto the floor, (1, -1, 0)/sqrt 2 leaves as
 * (1, 1, 0)/sqrt 2; at any angle the angle out equals the angle in, r stays
 * unit and in the plane of d and n. */
static void test_reflection_keeps_the_angle_and_flips_the_normal_part(void **state)
{
    (void)state;
    exercise_checks("reflect");
    float h = 1.0f / sqrtf(2.0f);
    vec3 r = vec3_reflect(vec3_make(h, -h, 0), vec3_make(0, 1, 0));
    assert_close(r.x, h, 1e-6);
    assert_close(r.y, h, 1e-6);
    assert_close(r.z, 0.0, 1e-6);
    vec3 n = vec3_normalize(vec3_make(0.3f, 0.9f, -0.2f));
    vec3 d = vec3_normalize(vec3_make(0.5f, -0.7f, 0.4f));
    vec3 t = vec3_reflect(d, n);
    assert_close(vec3_length(t), 1.0, 1e-6);
    assert_close(vec3_dot(t, n), -vec3_dot(d, n), 1e-6);             /* the angle out is the angle in */
    assert_close(vec3_dot(vec3_cross(d, n), t), 0.0, 1e-6);            /* in the plane of d and n */
}

/* R at normal incidence is ((eta_i - eta_t) / (eta_i + eta_t))^2 = (0.5 / 2.5)^2 = 0.04,
 * the same from either side. */
static void test_fresnel_is_four_percent_at_normal_incidence(void **state)
{
    (void)state;
    exercise_checks("fresnel");
    assert_close(fresnel_dielectric(1.0f, 1.0f, GLASS), 0.04, 1e-6);
    assert_close(fresnel_dielectric(1.0f, GLASS, 1.0f), 0.04, 1e-6);
    /* cos_i < 0: the light comes from the eta_t side; still normal incidence. */
    assert_close(fresnel_dielectric(-1.0f, 1.0f, GLASS), 0.04, 1e-6);
}

/* Leaving glass, sin(theta_t) = 1.5 sin(theta_i) exceeds 1 beyond the critical
 * angle arcsin(1 / 1.5) = 41.81 degrees: everything is reflected. */
static void test_fresnel_is_one_beyond_the_critical_angle(void **state)
{
    (void)state;
    exercise_checks("fresnel");
    double critical = asin(1.0 / GLASS);
    assert_close(critical / DEG, 41.81, 0.005);
    for (double degrees = 41.9; degrees < 90.0; degrees += 0.5) {
        float cos_i = (float)cos(degrees * DEG);
        assert_close(fresnel_dielectric(cos_i, GLASS, 1.0f), 1.0, 0.0);
        /* The same light described from the other side's normal. */
        assert_close(fresnel_dielectric(-cos_i, 1.0f, GLASS), 1.0, 0.0);
    }
    /* Just below it some light still gets out, and R climbs steeply towards 1. */
    float below = fresnel_dielectric((float)cos(critical - 0.1 * DEG), GLASS, 1.0f);
    assert_true(below < 1.0f);
    assert_true(below > 0.5f);
    /* Entering glass there is no critical angle: R < 1 up to grazing. */
    assert_true(fresnel_dielectric((float)cos(89.0 * DEG), 1.0f, GLASS) < 1.0f);
}

typedef float (*fresnel_fn)(float cos_i, float eta_i, float eta_t);

/* A deliberately wrong Fresnel: only the s-polarised reflectance. */
static float fresnel_s_only(float cos_i, float eta_i, float eta_t)
{
    float sin2_t = (eta_i / eta_t) * (eta_i / eta_t) * (1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f)
        return 1.0f;
    float cos_t = sqrtf(1.0f - sin2_t);
    float r_s = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    return r_s * r_s;
}

/* The largest |R + T - 1| over angles of incidence from 0 to 89.9 degrees,
 * where T comes independently from the Fresnel transmission amplitudes
 *   t_s = 2 eta_i cos_i / (eta_i cos_i + eta_t cos_t)
 *   t_p = 2 eta_i cos_i / (eta_t cos_i + eta_i cos_t)
 *   T = (eta_t cos_t) / (eta_i cos_i) * (t_s^2 + t_p^2) / 2
 * (the factor converts amplitudes to power through a beam whose cross-section
 * changes on refraction). Angles with total internal reflection are skipped. */
static double energy_error(fresnel_fn fresnel, double eta_i, double eta_t)
{
    double worst = 0.0;
    for (double degrees = 0.0; degrees < 90.0; degrees += 0.1) {
        double cos_i = cos(degrees * DEG);
        double sin_t = eta_i / eta_t * sin(degrees * DEG);
        if (sin_t >= 1.0)
            continue;
        double cos_t = sqrt(1.0 - sin_t * sin_t);
        double t_s = 2.0 * eta_i * cos_i / (eta_i * cos_i + eta_t * cos_t);
        double t_p = 2.0 * eta_i * cos_i / (eta_t * cos_i + eta_i * cos_t);
        double transmitted = (eta_t * cos_t) / (eta_i * cos_i) * 0.5 * (t_s * t_s + t_p * t_p);
        double reflected = fresnel((float)cos_i, (float)eta_i, (float)eta_t);
        worst = fmax(worst, fabs(reflected + transmitted - 1.0));
    }
    return worst;
}

/* Energy is conserved at the boundary: R + T = 1 at every angle, both ways. */
static void test_fresnel_reflected_plus_transmitted_is_one(void **state)
{
    (void)state;
    exercise_checks("fresnel");
    assert_close(energy_error(fresnel_dielectric, 1.0, 1.5), 0.0, 1e-5);
    assert_close(energy_error(fresnel_dielectric, 1.5, 1.0), 0.0, 1e-5);
    assert_close(energy_error(fresnel_dielectric, 1.0, 2.4), 0.0, 1e-5);
    /* The check catches a Fresnel that forgets the p polarisation. */
    assert_true(energy_error(fresnel_s_only, 1.0, 1.5) > 1e-2);
}

/* A deliberately wrong Schlick: theta_i in the formula even when leaving glass. */
static float schlick_wrong_cosine(float cos_i, float eta_i, float eta_t)
{
    if ((eta_i / eta_t) * (eta_i / eta_t) * (1.0f - cos_i * cos_i) >= 1.0f)
        return 1.0f;
    float r0 = (eta_i - eta_t) / (eta_i + eta_t);
    r0 *= r0;
    return r0 + (1.0f - r0) * powf(1.0f - cos_i, 5.0f);
}

/* The largest |Schlick - exact| from 0 to 90 degrees. */
static double schlick_error(fresnel_fn schlick, float eta_i, float eta_t)
{
    double worst = 0.0;
    for (double degrees = 0.0; degrees <= 90.0; degrees += 0.01) {
        float cos_i = (float)cos(degrees * DEG);
        worst = fmax(worst, fabs(schlick(cos_i, eta_i, eta_t) - fresnel_dielectric(cos_i, eta_i, eta_t)));
    }
    return worst;
}

/* Schlick is exact at normal incidence and close elsewhere: for glass its
 * largest error is 0.036 (near 85 degrees outside, 41.6 inside), so 0.04
 * bounds it. It is an approximation: at 60 degrees it is off by 0.019. */
static void test_schlick_matches_exact_at_normal_incidence_and_is_close_elsewhere(void **state)
{
    (void)state;
    assert_close(fresnel_schlick(1.0f, 1.0f, GLASS), fresnel_dielectric(1.0f, 1.0f, GLASS), 1e-7);
    assert_close(fresnel_schlick(1.0f, GLASS, 1.0f), fresnel_dielectric(1.0f, GLASS, 1.0f), 1e-7);
    assert_close(schlick_error(fresnel_schlick, 1.0f, GLASS), 0.0, 0.04);
    assert_close(schlick_error(fresnel_schlick, GLASS, 1.0f), 0.0, 0.04);
    float cos60 = (float)cos(60.0 * DEG);
    assert_true(fabsf(fresnel_schlick(cos60, 1.0f, GLASS) - fresnel_dielectric(cos60, 1.0f, GLASS)) > 0.01f);
    /* The bound catches Schlick evaluated with the wrong cosine inside glass. */
    assert_true(schlick_error(schlick_wrong_cosine, GLASS, 1.0f) > 0.5);
}

/* ---- Snell's law ------------------------------------------------------------ */

typedef bool (*refract_fn)(vec3 d, vec3 n, float eta_ratio, vec3 *out);

/* A deliberately wrong refraction: eta_t / eta_i where eta_i / eta_t belongs. */
static bool refract_inverted_eta(vec3 d, vec3 n, float eta_ratio, vec3 *out)
{
    return refract_direction(d, n, 1.0f / eta_ratio, out);
}

/* Refract many random directions through random normals and return the
 * largest violation of: t unit length; t in the plane of d and n; t on the
 * far side; eta_i sin(theta_i) = eta_t sin(theta_t); refraction refused
 * exactly when eta_i / eta_t sin(theta_i) > 1. */
static double snell_violation(refract_fn refract, float eta_ratio, uint64_t seed)
{
    pcg32 rng;
    pcg32_seed(&rng, test_seed(seed), 7);
    double worst = 0.0;
    for (int i = 0; i < 2000; i++) {
        vec3 d = random_unit(&rng);
        vec3 n = random_unit(&rng);
        if (vec3_dot(d, n) > 0.0f)
            n = vec3_neg(n); /* the normal faces the incoming ray */
        double sin_i = vec3_length(vec3_cross(d, n));
        vec3 t;
        if (!refract(d, n, eta_ratio, &t)) {
            /* Refused: must be beyond the critical angle (up to rounding). */
            worst = fmax(worst, fmax(0.0, 1.0 - eta_ratio * sin_i - 1e-6));
            continue;
        }
        double sin_t = vec3_length(vec3_cross(t, n));
        worst = fmax(worst, fabs(vec3_length(t) - 1.0));                    /* unit */
        worst = fmax(worst, fabs(vec3_dot(t, vec3_cross(d, n))));           /* coplanar */
        worst = fmax(worst, fmax(0.0, (double)vec3_dot(t, n)));             /* goes through */
        worst = fmax(worst, fabs(eta_ratio * sin_i - sin_t));               /* Snell */
    }
    return worst;
}

static void test_refraction_obeys_snells_law(void **state)
{
    (void)state;
    exercise_checks("refract");
    const float ratios[] = {1.0f / GLASS, GLASS, 1.0f / 1.33f, 1.33f, 1.0f};
    for (size_t k = 0; k < sizeof ratios / sizeof ratios[0]; k++)
        assert_close(snell_violation(refract_direction, ratios[k], 100 + k), 0.0, 1e-5);
    /* The check catches eta_i / eta_t upside down. */
    assert_true(snell_violation(refract_inverted_eta, 1.0f / GLASS, 1) > 0.1);
}

/* At normal incidence the ray goes straight through. */
static void test_refraction_at_normal_incidence_goes_straight(void **state)
{
    (void)state;
    exercise_checks("refract");
    vec3 t;
    assert_true(refract_direction(vec3_make(0, -1, 0), vec3_make(0, 1, 0), 1.0f / GLASS, &t));
    assert_close(t.x, 0.0, 0.0);
    assert_close(t.y, -1.0, 1e-7);
    assert_close(t.z, 0.0, 0.0);
}

/* Direction after crossing a glass slab: the closest hit on the slab's two
 * parallel faces (a scene of two planes), refracting at each with the
 * indices chosen from hit.front_face as whitted_trace does. With
 * exit_swaps_indices false, the exit uses eta_i / eta_t of the entry again
 * (a wrong implementation). Returns false if the ray missed or was
 * refracted nowhere. */
static bool through_slab(const scene *sc, vec3 origin, vec3 d, bool exit_swaps_indices, vec3 *out)
{
    ray_counters counters;
    memset(&counters, 0, sizeof counters);
    ray r = ray_make(origin, d);
    for (int face = 0; face < 2; face++) {
        hit_record hit;
        if (!scene_intersect(sc, r, &hit, &counters))
            return false;
        if (face == 0 && !hit.front_face)
            return false;
        float eta_i = hit.front_face ? 1.0f : GLASS;
        float eta_t = hit.front_face ? GLASS : 1.0f;
        float ratio = exit_swaps_indices || face == 0 ? eta_i / eta_t : 1.0f / GLASS;
        vec3 t;
        if (!refract_direction(r.direction, hit.normal_geometric, ratio, &t))
            return false;
        r = ray_spawn(hit.point, hit.point_error, hit.normal_geometric, t);
    }
    *out = r.direction;
    return true;
}

/* A slab with parallel faces shifts a ray sideways but does not turn it:
 * sin(theta) in air is the same on both sides. */
static void test_glass_slab_exits_parallel_to_the_entering_ray(void **state)
{
    (void)state;
    exercise_checks("refract");
    scene sc;
    scene_init(&sc);
    int glass = scene_add_material(&sc, material_glass(GLASS));
    vec3 up = vec3_normalize(vec3_make(0.3f, 1.0f, -0.2f));
    /* Outward normals: up on the top face, down on the bottom face. */
    scene_add_plane(&sc, vec3_make(0, 0, 0), up, glass);
    scene_add_plane(&sc, vec3_scale(up, -0.5f), vec3_neg(up), glass);

    pcg32 rng;
    pcg32_seed(&rng, test_seed(2024), 1);
    int crossed = 0, wrong_differs = 0;
    for (int i = 0; i < 500; i++) {
        vec3 d = random_unit(&rng);
        if (vec3_dot(d, up) > -0.05f)
            continue; /* must head down into the slab, not graze it */
        vec3 origin = vec3_add(vec3_scale(up, 3.0f), vec3_scale(random_unit(&rng), 2.0f));
        vec3 out;
        assert_true(through_slab(&sc, origin, d, true, &out));
        assert_close(out.x, d.x, 1e-5);
        assert_close(out.y, d.y, 1e-5);
        assert_close(out.z, d.z, 1e-5);
        crossed++;
        /* Exiting with the entry's indices bends the ray further instead of back. */
        if (through_slab(&sc, origin, d, false, &out) && vec3_length(vec3_sub(out, d)) > 1e-3f)
            wrong_differs++;
    }
    assert_true(crossed > 200);
    assert_true(wrong_differs > crossed / 2);
    scene_free(&sc);
}

/* ---- Total internal reflection --------------------------------------------- */

static void test_refraction_is_refused_beyond_the_critical_angle(void **state)
{
    (void)state;
    exercise_checks("refract");
    vec3 n = vec3_make(0, 1, 0);
    double critical = asin(1.0 / GLASS);
    for (double degrees = 0.0; degrees < 90.0; degrees += 0.25) {
        double theta = degrees * DEG;
        if (fabs(theta - critical) < 0.01 * DEG)
            continue; /* too close to call in float */
        vec3 d = vec3_make((float)sin(theta), -(float)cos(theta), 0.0f);
        vec3 t;
        bool refracts = refract_direction(d, n, GLASS / 1.0f, &t); /* leaving glass */
        if (theta > critical)
            assert_false(refracts);
        else
            assert_true(refracts);
        /* Entering glass always refracts. */
        assert_true(refract_direction(d, n, 1.0f / GLASS, &t));
    }
}

/* A glass sphere alone, and a ray inside it along a chord whose distance
 * from the centre is b (radius 1): every hit on the inside meets the surface
 * at sin(theta) = b, and reflection keeps that angle. */
static void trace_inside_glass_sphere(float b, int max_depth, ray_counters *counters, vec3 *radiance)
{
    scene sc;
    scene_init(&sc);
    sc.background = vec3_splat(1.0f);
    scene_add_sphere(&sc, vec3_make(0, 0, 0), 1.0f, scene_add_material(&sc, material_glass(GLASS)));
    memset(counters, 0, sizeof *counters);
    *radiance = whitted_trace(&sc, ray_make(vec3_make(0.0f, b, 0.0f), vec3_make(1, 0, 0)), 0, max_depth, counters);
    scene_free(&sc);
}

/* b = 0.9: theta = 64.2 degrees > 41.8 at every bounce, so the light is
 * trapped: only reflection rays, none refracted, and nothing gets out. */
static void test_inside_glass_beyond_the_critical_angle_no_refraction_rays(void **state)
{
    (void)state;
    ray_counters counters;
    vec3 radiance;
    trace_inside_glass_sphere(0.9f, 5, &counters, &radiance);
    assert_int_equal(counters.refraction_rays, 0);
    assert_int_equal(counters.reflection_rays, 5);
    assert_true(vec3_is_black(radiance));
    /* b = 0.5: theta = 30 degrees, below the critical angle: light gets out. */
    trace_inside_glass_sphere(0.5f, 5, &counters, &radiance);
    assert_int_equal(counters.refraction_rays, 5);
    assert_true(radiance.x > 0.5f);
}

/* ---- Fresnel weights conserve energy along a whole path --------------------- */

/* A "white furnace": a glass sphere alone under a background of radiance 1,
 * and no lights. A ray through the centre meets the glass at normal
 * incidence each time, R = 0.04, T = 0.96. With max_depth 2 it returns
 *   R * 1 (reflected outside) + T * (R * 0 (cut off) + T * 1) = R + T^2,
 * and with a deep limit every bit of light gets out: 1. */
static void test_glass_in_a_white_furnace(void **state)
{
    (void)state;
    scene sc;
    scene_init(&sc);
    sc.background = vec3_splat(1.0f);
    scene_add_sphere(&sc, vec3_make(0, 0, -5), 1.0f, scene_add_material(&sc, material_glass(GLASS)));
    ray r = ray_make(vec3_make(0, 0, 0), vec3_make(0, 0, -1));
    ray_counters counters;
    memset(&counters, 0, sizeof counters);
    double R = 0.04, T = 0.96;
    assert_close(whitted_trace(&sc, r, 0, 1, &counters).x, R, 1e-5);
    assert_close(whitted_trace(&sc, r, 0, 2, &counters).x, R + T * T, 1e-5);
    assert_close(whitted_trace(&sc, r, 0, 20, &counters).x, 1.0, 1e-5);
    assert_true(vec3_is_black(whitted_trace(&sc, r, 0, 0, &counters)));
    scene_free(&sc);
}

/* ---- Depth limit ------------------------------------------------------------ */

/* Two facing mirrors, z = -1 and z = +1, and a ray between them: it bounces
 * forever, so exactly max_depth reflection rays are traced and the result is
 * the black returned beyond the limit (the white background is never seen). */
static void test_depth_limit_between_parallel_mirrors(void **state)
{
    (void)state;
    scene sc;
    scene_init(&sc);
    sc.background = vec3_splat(1.0f);
    int mirror = scene_add_material(&sc, material_mirror());
    scene_add_plane(&sc, vec3_make(0, 0, -1), vec3_make(0, 0, 1), mirror);
    scene_add_plane(&sc, vec3_make(0, 0, 1), vec3_make(0, 0, -1), mirror);
    scene_add_point_light(&sc, vec3_make(0, 0, 0), vec3_splat(10.0f));
    const int depths[] = {0, 1, 5, 64};
    for (size_t k = 0; k < sizeof depths / sizeof depths[0]; k++) {
        ray_counters counters;
        memset(&counters, 0, sizeof counters);
        ray r = ray_make(vec3_make(0, 0, 0), vec3_normalize(vec3_make(0.1f, 0.05f, 1.0f)));
        vec3 radiance = whitted_trace(&sc, r, 0, depths[k], &counters);
        assert_int_equal(counters.reflection_rays, depths[k]);
        assert_int_equal(counters.refraction_rays, 0);
        assert_int_equal(counters.shadow_rays, 0);
        assert_true(vec3_is_black(radiance));
    }
    scene_free(&sc);
}

/* ---- Rendering -------------------------------------------------------------- */

static void render_small(const scene *sc, int threads, image *img, render_stats *stats)
{
    camera cam = scene_make_camera(sc, 64, 36);
    whitted_context ctx = {sc, 5};
    render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = threads, .quiet = true,
                      .radiance = whitted_radiance, .scene = &ctx};
    *img = image_make(cam.width, cam.height);
    assert_non_null(img->rgb);
    render_image(&job, img, stats);
}

/* Work a scene does not need is not done: no glass, no refraction rays. */
static void test_scene_without_glass_traces_no_refraction_rays(void **state)
{
    (void)state;
    scene sc;
    scene_build_whitted_demo(&sc);
    /* The same scene with the glass turned into a mirror. */
    for (int i = 0; i < sc.material_count; i++)
        if (sc.materials[i].kind == MATERIAL_GLASS)
            sc.materials[i] = material_mirror();
    image img;
    render_stats stats;
    render_small(&sc, 2, &img, &stats);
    assert_int_equal(stats.counters.camera_rays, 64 * 36);
    assert_int_equal(stats.counters.refraction_rays, 0);
    assert_true(stats.counters.reflection_rays > 0);
    assert_true(stats.counters.shadow_rays > 0);
    image_free(&img);
    scene_free(&sc);

    /* And the demo scene, with its glass, does trace them. */
    scene_build_whitted_demo(&sc);
    render_small(&sc, 2, &img, &stats);
    assert_true(stats.counters.refraction_rays > 0);
    assert_int_equal(stats.counters.nonfinite_samples, 0);
    image_free(&img);
    scene_free(&sc);
}

/* Same seed, same image, bit for bit, whatever the thread count. */
static void test_image_is_identical_for_one_and_two_threads(void **state)
{
    (void)state;
    scene sc;
    scene_build_whitted_demo(&sc);
    image one, two;
    render_stats stats_one, stats_two;
    render_small(&sc, 1, &one, &stats_one);
    render_small(&sc, 2, &two, &stats_two);
    assert_memory_equal(one.rgb, two.rgb, sizeof(float) * 3 * 64 * 36);
    assert_int_equal(stats_one.counters.reflection_rays, stats_two.counters.reflection_rays);
    assert_int_equal(stats_one.counters.refraction_rays, stats_two.counters.refraction_rays);
    assert_int_equal(stats_one.counters.shadow_rays, stats_two.counters.shadow_rays);
    image_free(&one);
    image_free(&two);
    scene_free(&sc);
}


/* ---- scene files and effects -------------------------------------------------- */

static const unsigned WHITTED_EFFECTS = EFFECT_SHADOWS | EFFECT_REFLECTION | EFFECT_REFRACTION;

static void scene_from_text(scene *sc, const char *text)
{
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_parse(&d, text, strlen(text), "test.scene", NULL, err, sizeof err))
        fail_msg("%s", err);
    assert_true(scene_from_desc(sc, &d, "test", err, sizeof err));
    effects_report e = effects_analyse(&d);
    sc->effects = effects_decide(&e, WHITTED_EFFECTS);
    scene_desc_free(&d);
}

static image render_whitted(const scene *sc, int width, int height, ray_counters *counters)
{
    camera cam = scene_make_camera(sc, width, height);
    whitted_context ctx = {sc, 5};
    render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 2, .quiet = true, .radiance = whitted_radiance,
                      .scene = &ctx};
    image img = image_make(width, height);
    render_stats stats;
    render_image(&job, &img, &stats);
    *counters = stats.counters;
    return img;
}

static void test_default_scene_file_renders_the_built_in_image(void **state)
{
    (void)state;
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_load(&d, "chapters/02-whitted/scenes/default.scene", err, sizeof err))
        fail_msg("%s", err);
    scene from_file, built_in;
    assert_true(scene_from_desc(&from_file, &d, "test", err, sizeof err));
    effects_report e = effects_analyse(&d);
    from_file.effects = effects_decide(&e, WHITTED_EFFECTS);
    assert_int_equal(from_file.effects, WHITTED_EFFECTS);
    assert_int_equal(d.max_depth, 5);
    scene_desc_free(&d);
    scene_build_whitted_demo(&built_in);
    ray_counters c1, c2;
    image a = render_whitted(&from_file, 128, 72, &c1), b = render_whitted(&built_in, 128, 72, &c2);
    assert_memory_equal(a.rgb, b.rgb, 128 * 72 * 3 * sizeof(float));
    assert_memory_equal(&c1, &c2, sizeof c1);
    image_free(&a);
    image_free(&b);
    scene_free(&from_file);
    scene_free(&built_in);
}

#define MIRROR_SCENE_HEAD                                                                     \
    "camera eye 0 2 6 target 0 0.5 0 fov 45\n"                                                \
    "background 0.3 0.5 0.8\nambient 0.05 0.05 0.05\n"                                        \
    "material floor blinn_phong diffuse 0.8 0.8 0.8 checker 0.2 0.2 0.2 size 1\n"             \
    "material blue blinn_phong diffuse 0.1 0.2 0.8 specular 0.4 0.4 0.4 shininess 32\n"        \
    "plane point 0 0 0 normal 0 1 0 material floor\n"                                          \
    "sphere center -1.2 0.8 0 radius 0.8 material blue\n"                                      \
    "light point position 2 5 4 intensity 60 60 60\n"

/* A mirror but no glass: reflection rays, and not one refraction ray. The
 * twin (the same scene with a glass sphere) does trace refraction rays. */
static void test_no_glass_means_no_refraction_rays(void **state)
{
    (void)state;
    scene sc;
    scene_from_text(&sc, MIRROR_SCENE_HEAD "material m mirror\nsphere center 1.2 0.8 0 radius 0.8 material m\n");
    assert_false(sc.effects & EFFECT_REFRACTION);
    ray_counters c;
    image a = render_whitted(&sc, 64, 48, &c);
    assert_int_equal(c.refraction_rays, 0);
    assert_true(c.reflection_rays > 0);
    image_free(&a);
    scene_free(&sc);

    scene_from_text(&sc, MIRROR_SCENE_HEAD "material g glass ior 1.5\nsphere center 1.2 0.8 0 radius 0.8 material g\n");
    assert_true(sc.effects & EFFECT_REFRACTION);
    a = render_whitted(&sc, 64, 48, &c);
    assert_true(c.refraction_rays > 0);
    image_free(&a);
    scene_free(&sc);
}

/* Narrowing: "effects without reflection" on a scene with a mirror gives the
 * same image as the scene built with a black, highlight-free material in the
 * mirror's place -- and traces no reflection ray. */
static void test_narrowing_reflection_equals_a_scene_without_the_mirror(void **state)
{
    (void)state;
    scene narrowed, black;
    scene_from_text(&narrowed, MIRROR_SCENE_HEAD "effects without reflection\n"
                               "material m mirror\nsphere center 1.2 0.8 0 radius 0.8 material m\n");
    scene_from_text(&black, MIRROR_SCENE_HEAD "material m blinn_phong diffuse 0 0 0\n"
                            "sphere center 1.2 0.8 0 radius 0.8 material m\n");
    ray_counters c_narrowed, c_black;
    image a = render_whitted(&narrowed, 64, 48, &c_narrowed), b = render_whitted(&black, 64, 48, &c_black);
    assert_int_equal(c_narrowed.reflection_rays, 0);
    assert_memory_equal(a.rgb, b.rgb, 64 * 48 * 3 * sizeof(float));
    image_free(&a);
    image_free(&b);
    /* The twin: without the narrowing the mirror shows the scene, not black. */
    scene_free(&narrowed);
    scene_from_text(&narrowed, MIRROR_SCENE_HEAD "material m mirror\nsphere center 1.2 0.8 0 radius 0.8 material m\n");
    a = render_whitted(&narrowed, 64, 48, &c_narrowed);
    b = render_whitted(&black, 64, 48, &c_black);
    assert_true(memcmp(a.rgb, b.rgb, 64 * 48 * 3 * sizeof(float)) != 0);
    image_free(&a);
    image_free(&b);
    scene_free(&narrowed);
    scene_free(&black);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reflection_keeps_the_angle_and_flips_the_normal_part),
        cmocka_unit_test(test_fresnel_is_four_percent_at_normal_incidence),
        cmocka_unit_test(test_default_scene_file_renders_the_built_in_image),
        cmocka_unit_test(test_no_glass_means_no_refraction_rays),
        cmocka_unit_test(test_narrowing_reflection_equals_a_scene_without_the_mirror),
        cmocka_unit_test(test_fresnel_is_one_beyond_the_critical_angle),
        cmocka_unit_test(test_fresnel_reflected_plus_transmitted_is_one),
        cmocka_unit_test(test_schlick_matches_exact_at_normal_incidence_and_is_close_elsewhere),
        cmocka_unit_test(test_refraction_obeys_snells_law),
        cmocka_unit_test(test_refraction_at_normal_incidence_goes_straight),
        cmocka_unit_test(test_glass_slab_exits_parallel_to_the_entering_ray),
        cmocka_unit_test(test_refraction_is_refused_beyond_the_critical_angle),
        cmocka_unit_test(test_inside_glass_beyond_the_critical_angle_no_refraction_rays),
        cmocka_unit_test(test_glass_in_a_white_furnace),
        cmocka_unit_test(test_depth_limit_between_parallel_mirrors),
        cmocka_unit_test(test_scene_without_glass_traces_no_refraction_rays),
        cmocka_unit_test(test_image_is_identical_for_one_and_two_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* radiometry.c -- lectures 14-15's quantities, each as a closed form and as
 * the integral that defines it (see radiometry.h). */
#include "07-radiometry/radiometry.h"

#include <stdio.h>
#include <stdlib.h>

#include "memory.h"
#include "vec3.h"

/* ---- Solid angle ---------------------------------------------------------- */

/* Solid angle: the area an object covers on the unit sphere of directions.
 * For a cone of half-angle alpha, integrate d omega = sin theta d theta d phi
 * over theta in [0, alpha], phi in [0, 2 pi). */
double solid_angle_cone(double alpha) { return 2.0 * PI * (1.0 - cos(alpha)); }

double solid_angle_sphere(double r, double d)
{
    double s = r / d; /* sin of the half-angle of the touching cone */
    return 2.0 * PI * (1.0 - sqrt(1.0 - s * s));
}

/* Van Oosterom-Strackee: the numerator and denominator of tan(Omega / 2). */
static void oosterom_strackee(dvec3 p, dvec3 a, dvec3 b, dvec3 c, double *numerator, double *denominator)
{
    dvec3 A = dvec3_sub(a, p), B = dvec3_sub(b, p), C = dvec3_sub(c, p);
    double la = dvec3_length(A), lb = dvec3_length(B), lc = dvec3_length(C);
    *numerator = dvec3_dot(A, dvec3_cross(B, C));
    *denominator = la * lb * lc + dvec3_dot(A, B) * lc + dvec3_dot(A, C) * lb + dvec3_dot(B, C) * la;
}

double solid_angle_triangle_signed(dvec3 p, dvec3 a, dvec3 b, dvec3 c)
{
    double numerator, denominator;
    oosterom_strackee(p, a, b, c, &numerator, &denominator);
    /* atan2 keeps the quadrant: a negative denominator means Omega/2 > pi/2. */
    return 2.0 * atan2(numerator, denominator);
}

double solid_angle_triangle(dvec3 p, dvec3 a, dvec3 b, dvec3 c)
{
    return fabs(solid_angle_triangle_signed(p, a, b, c));
}

double solid_angle_triangle_naive(dvec3 p, dvec3 a, dvec3 b, dvec3 c)
{
    double numerator, denominator;
    oosterom_strackee(p, a, b, c, &numerator, &denominator);
    return 2.0 * atan(fabs(numerator) / denominator);
}

typedef struct {
    dvec3 p;      /* the point that sees the surface */
    dvec3 n;      /* the receiver's normal (irradiance only) */
    dvec3 normal; /* the light's or triangle's unit normal */
    double L;     /* radiance (1 for a solid angle) */
    bool receiver_cosine;
} area_integrand;

/* d omega = cos theta' dA / r^2: a small area dA at distance r, tilted by
 * theta' from facing p, covers this much solid angle. With the receiver's
 * cos theta (clamped at 0) and the radiance L, it is the area form of
 * irradiance. Radiance: the light's exiting radiance L is the radiance
 * arriving at p, because radiance does not change along a ray. */
static double area_to_solid_angle(const void *ctx, dvec3 x)
{
    const area_integrand *a = ctx;
    dvec3 d = dvec3_sub(x, a->p);
    double r2 = dvec3_dot(d, d), r = sqrt(r2);
    double cos_light = fabs(dvec3_dot(a->normal, d)) / r;
    double cos_receiver = a->receiver_cosine ? fmax(0.0, dvec3_dot(a->n, d) / r) : 1.0;
    return a->L * cos_receiver * cos_light / r2;
}

static dvec3 triangle_unit_normal(dvec3 a, dvec3 b, dvec3 c)
{
    return dvec3_normalize(dvec3_cross(dvec3_sub(b, a), dvec3_sub(c, a)));
}

quadrature_result solid_angle_triangle_numeric(dvec3 p, dvec3 a, dvec3 b, dvec3 c, int level, int n)
{
    area_integrand ctx = {p, dvec3_make(0, 0, 1), triangle_unit_normal(a, b, c), 1.0, false};
    return integrate_over_triangle(area_to_solid_angle, &ctx, a, b, c, level, n);
}

/* ---- Radiant flux and intensity ------------------------------------------- */

/* Radiant intensity: power per unit solid angle, I = d Phi / d omega. An
 * isotropic point spreads Phi over 4 pi steradians. */
double intensity_isotropic_point(double flux) { return flux / (4.0 * PI); }

double intensity_lambertian_emitter(double L, double area, double cos_theta)
{
    return L * area * fmax(0.0, cos_theta);
}

double flux_lambertian_emitter(double L, double area) { return PI * L * area; }

typedef struct {
    double scale; /* the integrand is scale * cos theta */
} cosine_integrand;

static double scaled_cosine(const void *ctx, dvec3 w)
{
    const cosine_integrand *c = ctx;
    return c->scale * fmax(0.0, w.z);
}

/* Flux = integral of the intensity over the hemisphere in front. */
quadrature_result flux_lambertian_emitter_numeric(double L, double area, int n)
{
    cosine_integrand ctx = {L * area};
    return integrate_over_hemisphere(scaled_cosine, &ctx, dvec3_make(0, 0, 1), QUADRATURE_GAUSS_LEGENDRE, n);
}

double intensity_sphere_emitter(double L, double r) { return PI * r * r * L; }

/* Looking along -z at the sphere: the visible points are c + r m for normals
 * m with m.z > 0, dA = r^2 d omega(m), and each is seen at cos theta = m.z. */
quadrature_result intensity_sphere_emitter_numeric(double L, double r, int n)
{
    cosine_integrand ctx = {L * r * r};
    return integrate_over_hemisphere(scaled_cosine, &ctx, dvec3_make(0, 0, 1), QUADRATURE_GAUSS_LEGENDRE, n);
}

/* ---- Irradiance ----------------------------------------------------------- */

/* Irradiance: power per unit area arriving at a surface, E = d Phi / dA,
 * collected from every direction: E = integral of L_i(w) cos theta d omega.
 * The cos theta is Lambert's cosine law: a beam tilted by theta spreads over
 * 1 / cos theta more area. */
double irradiance_uniform_sky(double L) { return PI * L; }

double irradiance_disk_on_axis(double L, double R, double h) { return PI * L * R * R / (R * R + h * h); }

double irradiance_sphere_light(double L, double r, double d, double cos_theta)
{
    double s = r / d;
    if (cos_theta <= -s)
        return 0.0; /* wholly below the horizon */
    if (cos_theta < s)
        return NAN; /* straddles the horizon: no simple closed form */
    return PI * L * s * s * cos_theta;
}

double irradiance_point_light(double I, double d, double cos_theta)
{
    return I * fmax(0.0, cos_theta) / (d * d);
}

double irradiance_polygon(double L, const dvec3 *vertices, int count, dvec3 p, dvec3 n)
{
    double sum = 0.0;
    for (int i = 0; i < count; i++) {
        dvec3 u0 = dvec3_normalize(dvec3_sub(vertices[i], p));
        dvec3 u1 = dvec3_normalize(dvec3_sub(vertices[(i + 1) % count], p));
        dvec3 c = dvec3_cross(u0, u1);
        double s = dvec3_length(c);
        if (s == 0.0)
            continue; /* an edge seen end-on covers no angle */
        double angle = atan2(s, dvec3_dot(u0, u1));
        sum += angle * dvec3_dot(n, c) / s;
    }
    return 0.5 * L * fabs(sum);
}

typedef struct {
    double L;
    dvec3 n;
} cone_integrand;

static double radiance_times_cosine(const void *ctx, dvec3 w)
{
    const cone_integrand *c = ctx;
    return c->L * fmax(0.0, dvec3_dot(c->n, w));
}

quadrature_result irradiance_from_cone(double L, dvec3 n, dvec3 axis, double alpha, quadrature_rule rule,
                                       int quadrature_n)
{
    cone_integrand ctx = {L, n};
    return integrate_over_cone(radiance_times_cosine, &ctx, axis, alpha, rule, quadrature_n);
}

quadrature_result irradiance_from_disk_area(double L, dvec3 centre, dvec3 disk_normal, double radius, dvec3 p,
                                            dvec3 n, quadrature_rule rule, int quadrature_n)
{
    area_integrand ctx = {p, n, disk_normal, L, true};
    return integrate_over_disk(area_to_solid_angle, &ctx, centre, disk_normal, radius, rule, quadrature_n);
}

quadrature_result irradiance_from_triangle_area(double L, dvec3 a, dvec3 b, dvec3 c, dvec3 p, dvec3 n, int level,
                                                int quadrature_n)
{
    area_integrand ctx = {p, n, triangle_unit_normal(a, b, c), L, true};
    return integrate_over_triangle(area_to_solid_angle, &ctx, a, b, c, level, quadrature_n);
}

/* ---- The BRDF ------------------------------------------------------------- */

brdf brdf_lambertian(double rho) { return (brdf){BRDF_LAMBERTIAN, rho, 0.0, 0.0}; }
brdf brdf_blinn_phong(double kd, double ks, double shininess) { return (brdf){BRDF_BLINN_PHONG, kd, ks, shininess}; }
brdf brdf_blinn_phong_as_shaded(double kd, double ks, double shininess)
{
    return (brdf){BRDF_BLINN_PHONG_AS_SHADED, kd, ks, shininess};
}
brdf brdf_glossy_mirror(double rho, double shininess) { return (brdf){BRDF_GLOSSY_MIRROR, rho, 0.0, shininess}; }

void brdf_describe(const brdf *f, char *text, int size)
{
    switch (f->kind) {
    case BRDF_LAMBERTIAN:
        snprintf(text, (size_t)size, "Lambertian rho=%g", f->kd);
        break;
    case BRDF_BLINN_PHONG:
        snprintf(text, (size_t)size, "Blinn-Phong kd=%g ks=%g p=%g", f->kd, f->ks, f->shininess);
        break;
    case BRDF_BLINN_PHONG_AS_SHADED:
        snprintf(text, (size_t)size, "ch01 shading kd=%g ks=%g p=%g", f->kd, f->ks, f->shininess);
        break;
    case BRDF_GLOSSY_MIRROR:
        snprintf(text, (size_t)size, "glossy mirror rho=%g p=%g", f->kd, f->shininess);
        break;
    }
}

/* The BRDF: how much of the irradiance arriving from w_i leaves as radiance
 * towards w_o, f_r(w_i -> w_o) = dL_r(w_o) / dE_i(w_i), in 1/sr. */
double brdf_eval(const brdf *f, dvec3 wi, dvec3 wo)
{
    if (wi.z <= 0.0 || wo.z <= 0.0)
        return 0.0; /* below the horizon (or grazing): no reflection */
    switch (f->kind) {
    case BRDF_LAMBERTIAN:
        /* Lambertian: the same radiance in every direction, rho / pi. */
        return f->kd / PI;
    case BRDF_BLINN_PHONG:
    case BRDF_BLINN_PHONG_AS_SHADED: {
        /* Half vector h = unit(w_i + w_o); the highlight is (n . h)^p. */
        dvec3 h = dvec3_normalize(dvec3_add(wi, wo));
        double specular = f->ks * pow(h.z, f->shininess);
        if (f->kind == BRDF_BLINN_PHONG)
            return f->kd / PI + specular;
        /* Chapter 01: L = kd E + ks (n.h)^p (I / r^2) with E = (I / r^2) cos theta_i. */
        return f->kd + specular / wi.z;
    }
    case BRDF_GLOSSY_MIRROR: {
        /* The mirror direction of w_o about n = +z, and a lobe around it,
         * normalised so that at normal viewing the albedo is exactly rho. */
        dvec3 r = dvec3_make(-wo.x, -wo.y, wo.z);
        double c = fmax(0.0, dvec3_dot(r, wi));
        return f->kd * (f->shininess + 2.0) / (2.0 * PI) * pow(c, f->shininess);
    }
    }
    return 0.0;
}

dvec3 direction_at_polar_angle(double theta) { return dvec3_make(sin(theta), 0.0, cos(theta)); }

typedef struct {
    const brdf *f;
    dvec3 wo;
    direction_fn incident; /* NULL: uniform incident radiance 1 */
    const void *incident_ctx;
    bool with_cosine;
} reflection_integrand;

/* The integrand of the reflection equation: f_r(w_i -> w_o) L_i(w_i) cos theta_i. */
static double reflection_term(const void *ctx, dvec3 wi)
{
    const reflection_integrand *r = ctx;
    double L = r->incident == NULL ? 1.0 : r->incident(r->incident_ctx, wi);
    double cos_theta = r->with_cosine ? wi.z : 1.0;
    return brdf_eval(r->f, wi, r->wo) * L * cos_theta;
}

/* The energy check: the albedo, integral of f_r cos theta_i d omega_i. */
quadrature_result brdf_albedo(const brdf *f, double theta_o, int n)
{
    reflection_integrand ctx = {f, direction_at_polar_angle(theta_o), NULL, NULL, true};
    return integrate_over_hemisphere(reflection_term, &ctx, dvec3_make(0, 0, 1), QUADRATURE_GAUSS_LEGENDRE, n);
}

quadrature_result brdf_albedo_without_cosine(const brdf *f, double theta_o, int n)
{
    reflection_integrand ctx = {f, direction_at_polar_angle(theta_o), NULL, NULL, false};
    return integrate_over_hemisphere(reflection_term, &ctx, dvec3_make(0, 0, 1), QUADRATURE_GAUSS_LEGENDRE, n);
}

double brdf_albedo_at_normal(const brdf *f)
{
    double p = f->shininess;
    switch (f->kind) {
    case BRDF_LAMBERTIAN:
    case BRDF_GLOSSY_MIRROR:
        return f->kd;
    case BRDF_BLINN_PHONG:
        /* n.h = cos(theta_i / 2); substitute c = cos(theta_i / 2). */
        return f->kd + 8.0 * PI * f->ks *
                           (2.0 * (1.0 - pow(2.0, -(p + 4.0) / 2.0)) / (p + 4.0) -
                            (1.0 - pow(2.0, -(p + 2.0) / 2.0)) / (p + 2.0));
    case BRDF_BLINN_PHONG_AS_SHADED:
        return PI * f->kd + 8.0 * PI * f->ks * (1.0 - pow(2.0, -(p + 2.0) / 2.0)) / (p + 2.0);
    }
    return NAN;
}

energy_check brdf_check_energy(const brdf *f, int angles, int n)
{
    energy_check e = {-INFINITY, 0.0, 0.0, true};
    for (int i = 0; i < angles; i++) {
        double theta_o = 0.5 * PI * ((double)i + 0.5) / angles;
        quadrature_result a = brdf_albedo(f, theta_o, n);
        if (a.value > e.worst_albedo) {
            e.worst_albedo = a.value;
            e.worst_theta_o = theta_o;
            e.worst_error = a.error_estimate;
        }
    }
    e.conserves_energy = e.worst_albedo <= 1.0 + e.worst_error;
    return e;
}

/* ---- The reflection equation ---------------------------------------------- */

quadrature_result reflected_radiance(const brdf *f, direction_fn incident, const void *ctx, dvec3 wr, int n)
{
    reflection_integrand r = {f, wr, incident, ctx, true};
    return integrate_over_hemisphere(reflection_term, &r, dvec3_make(0, 0, 1), QUADRATURE_GAUSS_LEGENDRE, n);
}

/* ---- The rendering equation ----------------------------------------------- */

/* The closed furnace: L = E + K L with K L = rho L for a uniform field, so
 * bounce k is K^k E = Le rho^k. */
double furnace_bounce(double Le, double rho, int k) { return Le * pow(rho, k); }

double furnace_partial_sum(double Le, double rho, int k)
{
    double sum = 0.0;
    for (int j = 0; j <= k; j++)
        sum += furnace_bounce(Le, rho, j);
    return sum;
}

double furnace_partial_sum_closed(double Le, double rho, int k)
{
    if (rho == 1.0)
        return Le * (k + 1);
    return Le * (1.0 - pow(rho, k + 1)) / (1.0 - rho);
}

double furnace_radiance(double Le, double rho) { return Le / (1.0 - rho); }

typedef struct {
    double L;
} uniform_field;

static double uniform_radiance(const void *ctx, dvec3 w)
{
    (void)w;
    return ((const uniform_field *)ctx)->L;
}

quadrature_result furnace_step_quadrature(double Le, double rho, double L, int n)
{
    brdf f = brdf_lambertian(rho);
    uniform_field field = {L};
    quadrature_result q = reflected_radiance(&f, uniform_radiance, &field, dvec3_make(0, 0, 1), n);
    q.value += Le;
    q.coarse += Le;
    return q;
}

void sphere_patches_build(sphere_patches *s, double radius, int rings, int segments)
{
    s->radius = radius;
    s->rings = rings;
    s->segments = segments;
    s->count = rings * segments;
    s->area = memory_allocate((size_t)s->count, sizeof *s->area);
    s->centre = memory_allocate((size_t)s->count, sizeof *s->centre);
    s->form_factor = memory_allocate((size_t)s->count * (size_t)s->count, sizeof *s->form_factor);
    double d_theta = PI / rings, d_phi = 2.0 * PI / segments;
    for (int i = 0; i < rings; i++) {
        double theta0 = i * d_theta, theta1 = (i + 1) * d_theta, theta = (i + 0.5) * d_theta;
        for (int j = 0; j < segments; j++) {
            int k = i * segments + j;
            double phi = (j + 0.5) * d_phi;
            /* The patch's area: integral of R^2 sin theta d theta d phi. */
            s->area[k] = radius * radius * d_phi * (cos(theta0) - cos(theta1));
            s->centre[k] = dvec3_scale(dvec3_make(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)), radius);
        }
    }
    /* F_ij = A_j / (4 pi R^2), i = j included: a point of a concave sphere
     * sees the rest of its own patch too. */
    double sphere_area = 4.0 * PI * radius * radius;
    for (int i = 0; i < s->count; i++)
        for (int j = 0; j < s->count; j++)
            s->form_factor[(size_t)i * (size_t)s->count + (size_t)j] = s->area[j] / sphere_area;
}

void sphere_patches_free(sphere_patches *s)
{
    free(s->area);
    free(s->centre);
    free(s->form_factor);
    s->area = NULL;
    s->centre = NULL;
    s->form_factor = NULL;
    s->count = 0;
}

double form_factor_kernel(dvec3 x, dvec3 nx, dvec3 y, dvec3 ny)
{
    dvec3 d = dvec3_sub(y, x);
    double r2 = dvec3_dot(d, d), r = sqrt(r2);
    double cos_x = fmax(0.0, dvec3_dot(nx, d) / r);
    double cos_y = fmax(0.0, -dvec3_dot(ny, d) / r);
    return cos_x * cos_y / (PI * r2);
}

/* L = E + K L discretized: the radiance leaving patch i is its emission plus
 * rho times the average radiance it sees, weighted by the form factors. */
void rendering_operator_apply(const sphere_patches *s, double rho, const double *E, const double *L, double *out)
{
    for (int i = 0; i < s->count; i++) {
        const double *row = s->form_factor + (size_t)i * (size_t)s->count;
        double gathered = 0.0;
        for (int j = 0; j < s->count; j++)
            gathered += row[j] * L[j];
        out[i] = E[i] + rho * gathered;
    }
}

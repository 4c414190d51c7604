/* shapes.c -- lecture 13: the ray r(t) = o + t d meets a surface. */
#include "01-ray-casting/shapes.h"

/* ---- Ray-sphere: solve |o + t d - c|^2 - R^2 = 0 --------------------------
 * The lecture's quadratic a t^2 + b t + c = 0 with a = d.d, b = 2 (o-c).d,
 * c = (o-c).(o-c) - R^2, solved as the lecture writes it. */
bool sphere_intersect_naive(const sphere *s, ray r, hit_record *hit)
{
    vec3 oc = vec3_sub(r.origin, s->center);
    float a = vec3_dot(r.direction, r.direction);
    float b = 2.0f * vec3_dot(oc, r.direction);
    float c = vec3_dot(oc, oc) - s->radius * s->radius;
    float discriminant = b * b - 4.0f * a * c;
    if (discriminant < 0.0f)
        return false;
    float root = sqrtf(discriminant);
    float t = (-b - root) / (2.0f * a);
    if (!(t > r.t_min && t < r.t_max))
        t = (-b + root) / (2.0f * a);
    if (!(t > r.t_min && t < r.t_max))
        return false;
    hit->t = t;
    hit->point = ray_at(r, t);
    vec3 outward = vec3_scale(vec3_sub(hit->point, s->center), 1.0f / s->radius);
    /* o + t d: its rounding grows with the distance travelled, hence that
     * distance in the size (a rough bound: far from the sphere this
     * formula's t itself is far worse, which is what it is kept to show). */
    float travelled = vec3_max_component(vec3_abs(vec3_sub(hit->point, r.origin)));
    hit->point_error = ray_point_error(hit->point, outward, s->radius + travelled);
    hit_set_normal(hit, r, outward);
    hit->u = hit->v = 0.0f;
    return true;
}

/* Why not the formula above: for a sphere of radius 1 at distance 1e4, b^2 and
 * 4ac are both 4e8, and a float near 4e8 is only accurate to 32. Their
 * difference, which should be 4, comes out as 0 or 32: the ray misses, or hits
 * at the wrong place. Two changes fix it (Haines et al., "Precision
 * Improvements for Ray/Sphere Intersection", Ray Tracing Gems, 2019):
 *  1. the discriminant as R^2 - |f - (f.d) d|^2 (f = o - c, d unit): the
 *     squared distance from the centre to the ray's closest point, which has
 *     no cancellation of large terms;
 *  2. the near root via q = b' + sign(b') sqrt(disc), t0 = c/q, t1 = q/a, so
 *     -b and the square root are never subtracted when they are nearly equal.
 * Hit points are then re-projected onto the sphere, so their error is one
 * rounding of their coordinates and a few of the radius, which the ray
 * offsets in ray.h rely on (ray_point_error with size = the radius). */
/* Both roots t0 <= t1 of the ray-sphere quadratic, in the ray's own t units;
 * false if the ray's line misses the sphere. */
static bool sphere_roots(vec3 center, float radius, ray r, float *t0, float *t1)
{
    /* exercise: ray_sphere */
    float length = vec3_length(r.direction);
    vec3 d = vec3_scale(r.direction, 1.0f / length);
    vec3 f = vec3_sub(r.origin, center);
    float b_half = -vec3_dot(f, d); /* -b/2 for a unit direction */
    vec3 perpendicular = vec3_add(f, vec3_scale(d, b_half));
    float radius2 = radius * radius;
    float discriminant = radius2 - vec3_dot(perpendicular, perpendicular);
    if (discriminant < 0.0f)
        return false;
    float c = vec3_dot(f, f) - radius2;
    float q = b_half + copysignf(sqrtf(discriminant), b_half);
    /* q == 0 only for a ray starting at the centre of a sphere of radius 0. */
    float near = q != 0.0f ? c / q : 0.0f, far = q;
    *t0 = fminf(near, far) / length;
    *t1 = fmaxf(near, far) / length;
    return true;
    /* end of exercise ray_sphere */
}

bool sphere_intersect(const sphere *s, ray r, hit_record *hit)
{
    float t0, t1;
    if (!sphere_roots(s->center, s->radius, r, &t0, &t1))
        return false;
    float t = t0;
    if (!(t > r.t_min && t < r.t_max))
        t = t1;
    if (!(t > r.t_min && t < r.t_max))
        return false;
    hit->t = t;
    vec3 outward = vec3_normalize(vec3_sub(ray_at(r, t), s->center));
    hit->point = vec3_add(s->center, vec3_scale(outward, s->radius)); /* re-projected */
    hit->point_error = ray_point_error(hit->point, outward, s->radius);
    hit_set_normal(hit, r, outward);
    hit->u = hit->v = 0.0f;
    return true;
}

/* ---- Ray-plane: (o + t d - p') . N = 0  =>  t = (p' - o) . N / (d . N) ---- */
bool plane_intersect(const plane *p, ray r, hit_record *hit)
{
    float denominator = vec3_dot(r.direction, p->normal);
    if (denominator == 0.0f) /* parallel: no hit (or the whole ray lies in it) */
        return false;
    float t = vec3_dot(vec3_sub(p->point, r.origin), p->normal) / denominator;
    if (!(t > r.t_min && t < r.t_max))
        return false;
    hit->t = t;
    hit->point = ray_at(r, t);
    /* Snap the hit point exactly onto an axis-aligned plane, where that is
     * representable, so offsets start from the surface itself. */
    if (p->normal.x == 0.0f && p->normal.z == 0.0f)
        hit->point.y = p->point.y;
    /* An infinite plane has no size: what the rounding scales with is the
     * distance travelled (o + t d) and, for the test from a nearby origin,
     * the distance to the plane's own point. */
    float size = vec3_max_component(vec3_abs(vec3_sub(hit->point, r.origin))) +
                 vec3_max_component(vec3_abs(vec3_sub(hit->point, p->point)));
    hit->point_error = ray_point_error(hit->point, p->normal, size);
    hit_set_normal(hit, r, p->normal);
    hit->u = hit->v = 0.0f;
    return true;
}

/* ---- Ray-triangle: Moller-Trumbore (the test itself is in shapes.h,
 * triangle_intersect_edges(), so that the accelerators' plain C kernels
 * inline the very same arithmetic on the edges they store) ---------------- */
bool triangle_intersect_barycentric(const triangle *tri, const ray *r, float *t_out, float *b1_out, float *b2_out)
{
    return triangle_intersect_edges(tri->p0, vec3_sub(tri->p1, tri->p0), vec3_sub(tri->p2, tri->p0), r, r->t_max,
                                    t_out, b1_out, b2_out);
}

void triangle_fill_hit(const triangle *tri, ray r, float t, float b1, float b2, hit_record *hit)
{
    triangle_fill_hit_normal(tri, triangle_unit_normal(tri), &r, t, b1, b2, hit);
}

bool triangle_intersect(const triangle *tri, ray r, hit_record *hit)
{
    float t, b1, b2;
    if (!triangle_intersect_barycentric(tri, &r, &t, &b1, &b2))
        return false;
    triangle_fill_hit(tri, r, t, b1, b2, hit);
    return true;
}

/* ---- Ray-triangle, watertight (Woop, Benthin and Wald, 2013) -------------
 * Moller-Trumbore decides "inside" from barycentrics computed separately for
 * each triangle. A ray through an edge shared by two triangles gets two
 * different roundings of (nearly) zero, and both triangles can say "just
 * outside": the ray leaks through a closed mesh (measured: about 5 % of rays
 * aimed at the float points of shared edges, docs/hard-cases.md). The
 * watertight test instead moves into a frame where the ray runs along +z
 * from the origin, and decides from the three 2D edge functions U, V, W of
 * the projected vertices. An edge function computed for a shared edge in one
 * triangle is exactly the negation of the one computed in the other (the
 * same products, subtracted the other way round), so at least one of the two
 * triangles sees the ray inside or on its edge. That holds only if a*b - c*d
 * is rounded the same way in both, which fused multiply-add would break:
 * geometry is compiled with -ffp-contract=off. The test itself is
 * watertight_intersect() in shapes.h, inline, so that every accelerator's
 * loop runs the same arithmetic. */

/* Exactly zero may be a rounding of a tiny value of either sign: redo all
 * three in double, where these products of floats are exact (24-bit
 * significands multiply into 48 bits) and their differences are rounded
 * once, to the nearest double, then to float: a sign that float lost comes
 * back. Out of line: it runs for rays through edges and vertices, rarely. */
void watertight_edges_in_double(float ax, float ay, float bx, float by, float cx, float cy, float *u, float *v,
                                float *w)
{
    *u = (float)((double)cx * (double)by - (double)cy * (double)bx);
    *v = (float)((double)ax * (double)cy - (double)ay * (double)cx);
    *w = (float)((double)bx * (double)ay - (double)by * (double)ax);
}

/* A triangle whose three points lie on one line (or coincide) has no plane
 * and no normal: no ray hits it. The watertight test cannot see that by
 * itself: after the shear its projected vertices are rounded and no longer
 * collinear, so U + V + W is rounding noise instead of zero and some rays
 * aimed at the segment "hit" (measured: 2,644 and 1,131 of 20,000 rays on two
 * collinear triangles). So ask, in double, whether the cross product of
 * two edges is zero. Differences of floats are exact in double over the
 * coordinate ranges a scene has; the products then carry one rounding of
 * 2^-53, and equal exact products round equally, so a collinear triangle
 * always gives exactly zero. A float triangle that is not collinear has a
 * vertex at least about one float step (2^-24 of its size) off the line,
 * far above that rounding, so it is never mistaken for a degenerate one.
 * Structures that store their own copies of the triangles ask once, at
 * build time, and store a degenerate one as a lane no ray hits. */
bool triangle_is_degenerate(const triangle *tri)
{
    double e1x = (double)tri->p1.x - tri->p0.x, e1y = (double)tri->p1.y - tri->p0.y, e1z = (double)tri->p1.z - tri->p0.z;
    double e2x = (double)tri->p2.x - tri->p0.x, e2y = (double)tri->p2.y - tri->p0.y, e2z = (double)tri->p2.z - tri->p0.z;
    return e1y * e2z - e1z * e2y == 0.0 && e1z * e2x - e1x * e2z == 0.0 && e1x * e2y - e1y * e2x == 0.0;
}

bool triangle_intersect_watertight(const triangle *tri, const ray *r, float *t_out, float *b1_out, float *b2_out)
{
    watertight_ray wr = watertight_ray_make(r);
    return watertight_intersect_triangle(&wr, tri, r->t_max, t_out, b1_out, b2_out);
}

bool triangle_intersect_watertight_hit(const triangle *tri, ray r, hit_record *hit)
{
    float t, b1, b2;
    if (!triangle_intersect_watertight(tri, &r, &t, &b1, &b2))
        return false;
    triangle_fill_hit(tri, r, t, b1, b2, hit);
    return true;
}

/* ---- Inside or outside a closed mesh: count the crossings ------------------
 * A ray from p leaves a closed surface once more than it enters it if p is
 * inside, as often as it enters if p is outside: p is inside iff the ray
 * crosses the surface an odd number of times. Every triangle the ray meets
 * at t > 0 counts, not only the closest. The one trap is a ray through an
 * edge or a vertex, where the watertight test lets two triangles (or more)
 * report the same crossing: the direction must be one no edge lies on,
 * which a random direction is with probability 1 (the test draws them). */
bool closed_mesh_contains(const triangle *triangles, int count, vec3 p, vec3 direction)
{
    ray r = ray_make(p, direction);
    int crossings = 0;
    for (int i = 0; i < count; i++) {
        float t, b1, b2;
        if (triangle_intersect_watertight(&triangles[i], &r, &t, &b1, &b2))
            crossings++;
    }
    return crossings % 2 == 1;
}

/* ---- Implicit surface f(p) = 0: sphere tracing --------------------------
 * For a general implicit surface there is no formula for t: we walk along the
 * ray looking for where f(o + t d) reaches 0. A fixed step is the obvious root
 * finder and the wrong one: any part of the surface thinner than the step is
 * stepped over. Sphere tracing (Hart, 1996) takes each step from f itself: if
 * f is Lipschitz with constant L (|f(a) - f(b)| <= L |a - b|), the surface is
 * at least |f(p)| / L away from p, so a step of that length cannot cross it,
 * however thin it is. Our torus's f is an exact distance (L = 1). The walk
 * stops when |f| falls below a tolerance, and the point is then projected
 * onto the surface along the gradient (p - f grad f), so that hit points are
 * as exact as the sphere's and ray offsets (ray.h) work the same. */

/* Stop when the surface is closer than this fraction of the torus's size:
 * ~20 float ulps of the coordinates, far below a pixel, and above the float
 * noise in f (a few ulps), which would otherwise stop the walk at random. */
static const float IMPLICIT_HIT_TOLERANCE = 1e-6f;
/* Grazing rays approach the surface slowly; this many steps reach 1e-6 of
 * the size at grazing angles down to about 0.1 degree. */
static const int IMPLICIT_MAX_STEPS = 1024;
/* A ray that starts this close to the surface is leaving it (a shadow or
 * reflected ray): its first hit only counts once it has got farther away,
 * or it would find the surface it starts on. 40x the tolerance is well above
 * the ray offset of ray.h (ray_point_error: 64 roundings of the size, 4e-6
 * relative, and 2 of the coordinates). */
static const float IMPLICIT_LEAVING_DISTANCE = 40.0f * 1e-6f;

float implicit_torus_value(const implicit_torus *torus, vec3 p)
{
    vec3 q = vec3_sub(p, torus->center);
    float ring = sqrtf(q.x * q.x + q.z * q.z) - torus->major;
    return sqrtf(ring * ring + q.y * q.y) - torus->minor;
}

static vec3 implicit_torus_gradient(const implicit_torus *torus, vec3 p)
{
    /* Analytic gradient: the direction from the nearest point of the core
     * circle to p (any point of the circle if p is on the axis). */
    vec3 q = vec3_sub(p, torus->center);
    float rho = sqrtf(q.x * q.x + q.z * q.z);
    vec3 core = rho > 0.0f ? vec3_make(q.x * torus->major / rho, 0.0f, q.z * torus->major / rho)
                           : vec3_make(torus->major, 0.0f, 0.0f);
    return vec3_normalize(vec3_sub(q, core));
}

bool implicit_intersect(const implicit_torus *torus, ray r, hit_record *hit)
{
    float length = vec3_length(r.direction);
    float size = torus->major + torus->minor;
    float tolerance = IMPLICIT_HIT_TOLERANCE * size;
    /* March only inside the torus's bounding sphere: from far away, sphere
     * tracing would spend many steps crossing empty space. */
    float t_enter, t_exit;
    if (!sphere_roots(torus->center, size * 1.001f, r, &t_enter, &t_exit))
        return false;
    float t = fmaxf(r.t_min, t_enter);
    float t_end = fminf(r.t_max, t_exit);
    bool leaving = fabsf(implicit_torus_value(torus, ray_at(r, t))) < IMPLICIT_LEAVING_DISTANCE * size;
    for (int step = 0; step < IMPLICIT_MAX_STEPS && t < t_end; step++) {
        vec3 p = ray_at(r, t);
        float distance = fabsf(implicit_torus_value(torus, p)); /* inside the tube too */
        if (leaving) {
            leaving = distance < IMPLICIT_LEAVING_DISTANCE * size;
        } else if (distance < tolerance && t > r.t_min) {
            vec3 gradient = implicit_torus_gradient(torus, p);
            hit->t = t;
            hit->point = vec3_sub(p, vec3_scale(gradient, implicit_torus_value(torus, p)));
            hit->point_error = ray_point_error(hit->point, gradient, size);
            hit_set_normal(hit, r, gradient);
            hit->u = hit->v = 0.0f;
            return true;
        }
        /* The surface is at least `distance` away (L = 1): a safe step. */
        t += fmaxf(distance, tolerance) / length;
    }
    return false;
}

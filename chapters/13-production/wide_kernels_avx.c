/* wide_kernels_avx.c -- the eight-path renderer's diffuse lanes eight per
 * AVX2 instruction (wide_lanes.h): the light sample, the bounce of each
 * rung and the hit records, each operation for operation the scalar
 * function it vectorises (wide_vertex.c's, and through them chapter 09's
 * light_transport.h and bsdf.c), so every lane gets the very bits of the
 * scalar code; tests/test_ch13.c compares them value by value. Compiled
 * for AVX2 alone (SPAWN_TARGET), called only where the processor has it
 * (wide_avx_runs()). */
#include "13-production/wide_lanes.h"

#if WIDE_HAVE_AVX
#include "08-monte-carlo/sampling.h"

/* The AVX kernels' constants, as chapter 08's sampling.c and chapter 09's
 * bsdf.c round them: cosine_hemisphere_pdf()'s 1 / pi, and the Lambertian
 * f = rho x (1 / pi). */
static const float INV_PI_F = (float)(1.0 / PI);
static const float DIFFUSE_INV_PI_F = 1.0f / (float)PI;

/* For light_math_avx and bounce_math_avx: a field of L for eight lanes, and
 * vec3_dot()'s sum, in its order. */
#define LOAD3(v, i) _mm256_load_ps(L->v[i])
#define DOT(ax, ay, az, bx, by, bz)                                                                          \
    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)), _mm256_mul_ps(az, bz))


/* light_math_lane() of the diffuse lanes of `lanes`, eight per AVX
 * instruction: direct_light_solid_angle()'s operations, with bsdf_eval()
 * and bsdf_pdf() of a diffuse surface, in the same order (sqrt and
 * division are exact in IEEE, so every lane gets the very bits of the
 * scalar function; tests/test_ch13.c compares them value by value). */
SPAWN_TARGET int light_math_avx(vertex_lanes *L, int lanes, bool mis)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 tx = _mm256_sub_ps(LOAD3(x_light, 0), LOAD3(p, 0)), ty = _mm256_sub_ps(LOAD3(x_light, 1), LOAD3(p, 1)),
           tz = _mm256_sub_ps(LOAD3(x_light, 2), LOAD3(p, 2));
    __m256 distance2 = DOT(tx, ty, tz, tx, ty, tz);
    __m256 inverse = _mm256_div_ps(_mm256_set1_ps(1.0f), _mm256_sqrt_ps(distance2));
    __m256 wx = _mm256_mul_ps(tx, inverse), wy = _mm256_mul_ps(ty, inverse), wz = _mm256_mul_ps(tz, inverse);
    __m256 nx = LOAD3(n, 0), ny = LOAD3(n, 1), nz = LOAD3(n, 2);
    __m256 cos_theta = DOT(nx, ny, nz, wx, wy, wz);
    __m256 cos_theta_light = _mm256_sub_ps(zero, DOT(LOAD3(n_light, 0), LOAD3(n_light, 1), LOAD3(n_light, 2), wx, wy, wz));
    __m256 cos_wo = DOT(nx, ny, nz, LOAD3(wo, 0), LOAD3(wo, 1), LOAD3(wo, 2));
    __m256 ok = _mm256_and_ps(_mm256_cmp_ps(cos_theta_light, zero, _CMP_GT_OQ), _mm256_cmp_ps(cos_theta, zero, _CMP_GT_OQ));
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(cos_wo, zero, _CMP_GT_OQ));
    const __m256 inv_pi = _mm256_set1_ps(DIFFUSE_INV_PI_F);
    __m256 fx = _mm256_mul_ps(LOAD3(albedo, 0), inv_pi), fy = _mm256_mul_ps(LOAD3(albedo, 1), inv_pi),
           fz = _mm256_mul_ps(LOAD3(albedo, 2), inv_pi);
    __m256 black = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(fx, zero, _CMP_EQ_OQ), _mm256_cmp_ps(fy, zero, _CMP_EQ_OQ)),
                                 _mm256_cmp_ps(fz, zero, _CMP_EQ_OQ));
    ok = _mm256_andnot_ps(black, ok);
    __m256 pdf_light = _mm256_div_ps(_mm256_mul_ps(distance2, _mm256_load_ps(L->pdf_area)), cos_theta_light);
    __m256 scale = _mm256_div_ps(cos_theta, pdf_light);
    if (mis) { /* power_heuristic(pdf_light, cos(theta) / pi); without it the weight is 1, and x 1 changes no bit */
        __m256 pdf_bsdf = _mm256_mul_ps(cos_theta, _mm256_set1_ps(INV_PI_F));
        __m256 a2 = _mm256_mul_ps(pdf_light, pdf_light), b2 = _mm256_mul_ps(pdf_bsdf, pdf_bsdf);
        __m256 sum = _mm256_add_ps(a2, b2);
        __m256 weight = _mm256_and_ps(_mm256_div_ps(a2, sum), _mm256_cmp_ps(sum, zero, _CMP_GT_OQ));
        scale = _mm256_mul_ps(scale, weight);
    }
    _mm256_store_ps(L->contribution[0], _mm256_mul_ps(LOAD3(throughput, 0), _mm256_mul_ps(_mm256_mul_ps(LOAD3(le, 0), fx), scale)));
    _mm256_store_ps(L->contribution[1], _mm256_mul_ps(LOAD3(throughput, 1), _mm256_mul_ps(_mm256_mul_ps(LOAD3(le, 1), fy), scale)));
    _mm256_store_ps(L->contribution[2], _mm256_mul_ps(LOAD3(throughput, 2), _mm256_mul_ps(_mm256_mul_ps(LOAD3(le, 2), fz), scale)));
    /* the shadow ray: ray_spawn_to() */
    const __m256 p[3] = {LOAD3(p, 0), LOAD3(p, 1), LOAD3(p, 2)}, ng[3] = {LOAD3(ng, 0), LOAD3(ng, 1), LOAD3(ng, 2)};
    const __m256 x_light[3] = {LOAD3(x_light, 0), LOAD3(x_light, 1), LOAD3(x_light, 2)};
    const __m256 n_light[3] = {LOAD3(n_light, 0), LOAD3(n_light, 1), LOAD3(n_light, 2)};
    __m256 origin[3], direction[3], t_min, t_max;
    ray_spawn_to8(p, _mm256_load_ps(L->p_error), ng, x_light, _mm256_load_ps(L->x_error), n_light, origin, direction,
                  &t_min, &t_max);
    for (int c = 0; c < 3; c++) {
        _mm256_store_ps(L->shadow_origin[c], origin[c]);
        _mm256_store_ps(L->shadow_direction[c], direction[c]);
    }
    _mm256_store_ps(L->shadow_t_min, t_min);
    _mm256_store_ps(L->shadow_t_max, t_max);
    int mask = _mm256_movemask_ps(ok) & lanes;
    _mm256_zeroupper();
    return mask;
}

/* fast_sincos_turns() of eight numbers, operation for operation. */
SPAWN_TARGET static inline void fast_sincos_turns8(__m256 u, __m256 *sin_out, __m256 *cos_out)
{
    const __m256 one = _mm256_set1_ps(1.0f), sign_bit = _mm256_set1_ps(-0.0f);
    __m256 q = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(4.0f), u),
                                                                     _mm256_set1_ps(0.5f))));
    __m256 rest = _mm256_sub_ps(u, _mm256_mul_ps(_mm256_set1_ps(0.25f), q));
    __m256 r2 = _mm256_mul_ps(rest, rest);
#define POLY_STEP(acc, c) _mm256_add_ps(_mm256_mul_ps(acc, r2), _mm256_set1_ps(c))
    __m256 p = _mm256_set1_ps(0x1.4bbc38p+5f);
    p = _mm256_mul_ps(POLY_STEP(POLY_STEP(POLY_STEP(p, -0x1.32ca6cp+6f), 0x1.466bbap+6f), -0x1.4abbcep+5f), r2);
    __m256 sin_r = _mm256_add_ps(_mm256_mul_ps(rest, _mm256_set1_ps(0x1.921fb6p+2f)), _mm256_mul_ps(rest, p));
    __m256 c = _mm256_set1_ps(0x1.d9f7b2p+5f);
    c = _mm256_mul_ps(POLY_STEP(POLY_STEP(POLY_STEP(c, -0x1.55c664p+6f), 0x1.03c1dep+6f), -0x1.3bd3ccp+4f), r2);
    __m256 cos_r = _mm256_add_ps(one, c);
#undef POLY_STEP
    /* the quarter turn: odd ones swap, 2 and 3 negate the sine, 1 and 2 the cosine */
    __m256 q1 = _mm256_cmp_ps(q, one, _CMP_EQ_OQ), q2 = _mm256_cmp_ps(q, _mm256_set1_ps(2.0f), _CMP_EQ_OQ),
           q3 = _mm256_cmp_ps(q, _mm256_set1_ps(3.0f), _CMP_EQ_OQ);
    __m256 odd = _mm256_or_ps(q1, q3);
    *sin_out = _mm256_xor_ps(_mm256_blendv_ps(sin_r, cos_r, odd), _mm256_and_ps(_mm256_or_ps(q2, q3), sign_bit));
    *cos_out = _mm256_xor_ps(_mm256_blendv_ps(cos_r, sin_r, odd), _mm256_and_ps(_mm256_or_ps(q1, q2), sign_bit));
}

/* frame_to_world(n, local) of eight lanes: vec3_basis(n), operation for
 * operation, then t x + b y + n z. */
SPAWN_TARGET static inline void frame_to_world8(const __m256 n[3], const __m256 local[3], __m256 w[3])
{
    const __m256 one = _mm256_set1_ps(1.0f), sign_bit = _mm256_set1_ps(-0.0f);
    __m256 nx = n[0], ny = n[1], nz = n[2];
    __m256 sign = _mm256_or_ps(_mm256_and_ps(nz, sign_bit), one);
    __m256 a = _mm256_div_ps(_mm256_set1_ps(-1.0f), _mm256_add_ps(sign, nz));
    __m256 cc = _mm256_mul_ps(_mm256_mul_ps(nx, ny), a);
    __m256 tx = _mm256_add_ps(one, _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(sign, nx), nx), a));
    __m256 ty = _mm256_mul_ps(sign, cc), tz = _mm256_mul_ps(_mm256_xor_ps(sign, sign_bit), nx);
    __m256 bx = cc, by = _mm256_add_ps(sign, _mm256_mul_ps(_mm256_mul_ps(ny, ny), a)), bz = _mm256_xor_ps(ny, sign_bit);
#define TO_WORLD(t, b, n)                                                                                    \
    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(t, local[0]), _mm256_mul_ps(b, local[1])), _mm256_mul_ps(n, local[2]))
    w[0] = TO_WORLD(tx, bx, nx);
    w[1] = TO_WORLD(ty, by, ny);
    w[2] = TO_WORLD(tz, bz, nz);
#undef TO_WORLD
}

/* What every bounce in AVX ends with, for all eight lanes: the next ray
 * from p along wi (ray_spawn()), its wo, and the throughput times f cos /
 * pdf (weight) times rr_scale. */
SPAWN_TARGET static inline void bounce_store8(vertex_lanes *L, const __m256 wi[3], const __m256 weight[3])
{
    const __m256 sign_bit = _mm256_set1_ps(-0.0f);
    const __m256 point[3] = {LOAD3(p, 0), LOAD3(p, 1), LOAD3(p, 2)}, ng[3] = {LOAD3(ng, 0), LOAD3(ng, 1), LOAD3(ng, 2)};
    __m256 origin[3], t_min;
    ray_spawn8(point, _mm256_load_ps(L->p_error), ng, wi, origin, &t_min);
    __m256 rr_scale = _mm256_load_ps(L->rr_scale);
    for (int c = 0; c < 3; c++) {
        _mm256_store_ps(L->ray.origin[c], origin[c]);
        _mm256_store_ps(L->ray.direction[c], wi[c]);
        _mm256_store_ps(L->throughput[c], _mm256_mul_ps(_mm256_mul_ps(LOAD3(throughput, c), weight[c]), rr_scale));
        _mm256_store_ps(L->wo[c], _mm256_xor_ps(wi[c], sign_bit));
    }
    _mm256_storeu_ps(L->ray.t_min, t_min);
}

/* f cos / pdf of a diffuse surface (rho / pi where both directions are
 * above it, as bsdf_eval() says, times `scale` = cos / pdf) into weight;
 * the mask of the lanes where it is black. */
SPAWN_TARGET static inline __m256 diffuse_weight8(const vertex_lanes *L, const __m256 n[3], const __m256 wi[3],
                                                  __m256 scale, __m256 weight[3])
{
    const __m256 zero = _mm256_setzero_ps();
    const __m256 wo[3] = {LOAD3(wo, 0), LOAD3(wo, 1), LOAD3(wo, 2)};
    __m256 above = _mm256_and_ps(_mm256_cmp_ps(spawn_dot8(n, wi), zero, _CMP_GT_OQ),
                                 _mm256_cmp_ps(spawn_dot8(n, wo), zero, _CMP_GT_OQ));
    const __m256 inv_pi = _mm256_set1_ps(DIFFUSE_INV_PI_F);
    __m256 black = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    for (int c = 0; c < 3; c++) {
        weight[c] = _mm256_mul_ps(_mm256_and_ps(_mm256_mul_ps(LOAD3(albedo, c), inv_pi), above), scale);
        black = _mm256_and_ps(black, _mm256_cmp_ps(weight[c], zero, _CMP_EQ_OQ));
    }
    return black;
}

/* The same as bounce_math_lane for the lanes of `lanes`, eight per AVX
 * instruction, operation for operation: sample_uniform_hemisphere() with
 * fast_sincos_turns(), frame_to_world() with vec3_basis(), bsdf_eval(). */
SPAWN_TARGET int bounce_math_avx(vertex_lanes *L, int lanes)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    /* sample_uniform_hemisphere: z = u_x, r = sqrt(max(0, 1 - z^2)), phi = 2 pi u_y */
    __m256 z = _mm256_load_ps(L->u_x);
    __m256 r = _mm256_sqrt_ps(_mm256_max_ps(_mm256_sub_ps(one, _mm256_mul_ps(z, z)), zero));
    __m256 sin_phi, cos_phi;
    fast_sincos_turns8(_mm256_load_ps(L->u_y), &sin_phi, &cos_phi);
    const __m256 local[3] = {_mm256_mul_ps(r, cos_phi), _mm256_mul_ps(r, sin_phi), z};
    const __m256 n[3] = {LOAD3(n, 0), LOAD3(n, 1), LOAD3(n, 2)};
    __m256 wi[3], weight[3];
    frame_to_world8(n, local, wi);
    __m256 black = diffuse_weight8(L, n, wi, _mm256_div_ps(z, _mm256_set1_ps(uniform_hemisphere_pdf())), weight);
    bounce_store8(L, wi, weight);
    int mask = ~_mm256_movemask_ps(black) & lanes;
    _mm256_zeroupper();
    return mask;
}

/* sample_cosine_hemisphere_fast() of eight lanes, operation for operation:
 * the branches on the triangle become blends, and the centre's 0 / 0 a
 * mask. */
SPAWN_TARGET static inline void cosine_hemisphere8(__m256 u_x, __m256 u_y, __m256 local[3])
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), two = _mm256_set1_ps(2.0f);
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 ox = _mm256_sub_ps(_mm256_mul_ps(two, u_x), one), oy = _mm256_sub_ps(_mm256_mul_ps(two, u_y), one);
    __m256 sides = _mm256_cmp_ps(_mm256_and_ps(ox, abs_mask), _mm256_and_ps(oy, abs_mask), _CMP_GT_OQ);
    __m256 r = _mm256_blendv_ps(oy, ox, sides);
    __m256 top = _mm256_and_ps(_mm256_div_ps(ox, oy), _mm256_cmp_ps(oy, zero, _CMP_NEQ_OQ));
    __m256 ratio = _mm256_blendv_ps(top, _mm256_div_ps(oy, ox), sides);
    __m256 u = _mm256_blendv_ps(u_y, u_x, sides);
    __m256 one_minus_r = _mm256_mul_ps(two, _mm256_min_ps(u, _mm256_sub_ps(one, u)));
    __m256 s, c;
    fast_sincos_turns8(_mm256_mul_ps(_mm256_set1_ps(0.125f), ratio), &s, &c);
    local[0] = _mm256_mul_ps(r, _mm256_blendv_ps(s, c, sides));
    local[1] = _mm256_mul_ps(r, _mm256_blendv_ps(c, s, sides));
    __m256 z2 = _mm256_mul_ps(one_minus_r, _mm256_sub_ps(two, one_minus_r));
    local[2] = _mm256_sqrt_ps(_mm256_max_ps(z2, zero));
}

/* The same as bounce_cosine_lane for the lanes of `lanes`, eight per AVX
 * instruction, operation for operation. */
SPAWN_TARGET int bounce_cosine_avx(vertex_lanes *L, int lanes, bool mis)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 local[3], wi[3], weight[3];
    cosine_hemisphere8(_mm256_load_ps(L->u_x), _mm256_load_ps(L->u_y), local);
    const __m256 n[3] = {LOAD3(n, 0), LOAD3(n, 1), LOAD3(n, 2)};
    frame_to_world8(n, local, wi);
    __m256 pdf = _mm256_mul_ps(_mm256_max_ps(local[2], zero), _mm256_set1_ps(INV_PI_F));
    __m256 on, black;
    if (mis) { /* bsdf_sample(): z > 0, and f cos / pdf = rho */
        on = _mm256_cmp_ps(local[2], zero, _CMP_GT_OQ);
        black = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        for (int c = 0; c < 3; c++) {
            weight[c] = LOAD3(albedo, c);
            black = _mm256_and_ps(black, _mm256_cmp_ps(weight[c], zero, _CMP_EQ_OQ));
        }
    } else { /* pdf > 0, and bsdf_eval() cos / pdf */
        on = _mm256_cmp_ps(pdf, zero, _CMP_GT_OQ);
        black = diffuse_weight8(L, n, wi, _mm256_div_ps(local[2], pdf), weight);
    }
    bounce_store8(L, wi, weight);
    _mm256_store_ps(L->pdf, pdf);
    int mask = _mm256_movemask_ps(_mm256_andnot_ps(black, on)) & lanes;
    _mm256_zeroupper();
    return mask;
}

/* hit_record_lane() for the lanes of `lanes`, eight per instruction, the
 * triangles' corners, normals and materials gathered by index (AVX2). Only
 * where the triangles have no vertex normals: then the shading normal is
 * the geometric one. */
SPAWN_TARGET int hit_records_avx(const pt_scene *sc, const hits8 *hits, int lanes,
                                        vertex_lanes *L, int material[LANES])
{
    const triangle_set *set = &sc->triangles;
    _Static_assert(sizeof(triangle) == 9 * sizeof(float), "a triangle is its nine coordinates");
    _Static_assert(sizeof(triangle_surface) == 4 * sizeof(float), "a surface is a normal and a material");
    _Static_assert(sizeof(pt_material) % sizeof(float) == 0, "materials are a whole number of floats");
    const __m256i lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    __m256i hit_mask = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(lanes), lane_bits), lane_bits);
    /* lanes without a hit read triangle 0, and their answers are not used */
    __m256i index = _mm256_and_si256(_mm256_load_si256((const __m256i *)hits->index), hit_mask);
    __m256i corner = _mm256_mullo_epi32(index, _mm256_set1_epi32(9)), surface = _mm256_slli_epi32(index, 2);
    const float *t0 = &set->triangles[0].p0.x;
    __m256 b1 = _mm256_load_ps(hits->b1), b2 = _mm256_load_ps(hits->b2);
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    /* triangle_fill_hit_normal: P0 + (b1 E1 + b2 E2), and the size of the
     * edges for the error bound (triangle_edge_size) */
    __m256 point[3], size = _mm256_setzero_ps();
    for (int c = 0; c < 3; c++) {
        __m256 p0 = _mm256_i32gather_ps(t0 + c, corner, 4), p1 = _mm256_i32gather_ps(t0 + 3 + c, corner, 4),
               p2 = _mm256_i32gather_ps(t0 + 6 + c, corner, 4);
        __m256 e1 = _mm256_sub_ps(p1, p0), e2 = _mm256_sub_ps(p2, p0);
        point[c] = _mm256_add_ps(p0, _mm256_add_ps(_mm256_mul_ps(e1, b1), _mm256_mul_ps(e2, b2)));
        size = _mm256_max_ps(size, _mm256_max_ps(_mm256_and_ps(e1, abs_mask), _mm256_and_ps(e2, abs_mask)));
    }
    const float *s0 = &set->surfaces[0].normal.x;
    __m256 normal[3], direction[3];
    for (int c = 0; c < 3; c++) {
        normal[c] = _mm256_i32gather_ps(s0 + c, surface, 4);
        direction[c] = _mm256_load_ps(L->ray.direction[c]);
    }
    _mm256_store_ps(L->p_error, spawn_point_error8(point, normal, size));
    __m256i materials = _mm256_i32gather_epi32(&set->surfaces[0].material, surface, 4);
    /* hit_set_normal: the front if the ray comes against the outward normal */
    __m256 front = _mm256_cmp_ps(spawn_dot8(direction, normal), _mm256_setzero_ps(), _CMP_LT_OQ);
    __m256 flip = _mm256_andnot_ps(front, _mm256_set1_ps(-0.0f));
    const int material_floats = (int)(sizeof(pt_material) / sizeof(float));
    __m256i albedo_at = _mm256_mullo_epi32(materials, _mm256_set1_epi32(material_floats));
    const float *a0 = &sc->materials[0].albedo.x;
    for (int c = 0; c < 3; c++) {
        __m256 ng = _mm256_xor_ps(normal[c], flip);
        _mm256_store_ps(L->p[c], point[c]);
        _mm256_store_ps(L->ng[c], ng);
        _mm256_store_ps(L->n[c], ng);
        _mm256_store_ps(L->albedo[c], _mm256_i32gather_ps(a0 + c, albedo_at, 4));
    }
    _mm256_storeu_si256((__m256i *)material, materials);
    int front_bits = _mm256_movemask_ps(front) & lanes;
    _mm256_zeroupper();
    return front_bits;
}

#undef LOAD3
#undef DOT
#endif

/* flat.h -- below a few dozen triangles the best tree is no tree.
 *
 * A tree pays for itself by the triangles it lets a ray skip. Each node it
 * visits costs a box test, a decision and a fetch that waits for the one
 * before it; on a scene of 32 triangles (the Cornell box) a ray visits a
 * node or two and still tests about ten triangles, a packet of four at a
 * time, each packet behind a branch. Testing all 32 costs more arithmetic
 * but none of the waiting: eight triangles per AVX instruction, four
 * blocks, no branch until the end. That is chapter 03's brute force again,
 * with the arithmetic of chapter 06's 4-wide leaves made 8 wide.
 *
 * The triangles are kept in blocks of eight, structure of arrays (as
 * wide_bvh_packet, twice as wide). Four kernels give the same answers: AVX
 * where the processor has it (asked at run time, so one binary runs
 * everywhere; compiled once more for AVX-512's 32 registers, where it has
 * those), SSE (each block as two halves), and a plain C loop. Each
 * lane does exactly the arithmetic of chapter 01's watertight test
 * (watertight_intersect()), so every t is the scalar test's, bit for bit;
 * of equal t the lower triangle index wins, as in chapter 03's brute force.
 * On request (accel_use_triangle_test) the blocks hold what
 * Moller-Trumbore reads, and every kernel runs it instead, lane for lane
 * triangle_intersect_barycentric(): the benchmark's column beside the
 * watertight one, and the leak test's twin.
 *
 * Usage:
 *   accel *a = flat_build(&set);
 *   if (accel_closest_hit(a, r, &hit, &counters)) ...   same as any accel
 *   flat_set_kernel(a, FLAT_KERNEL_SCALAR);              the plain C path (tests)
 *   accel_destroy(a);
 *
 * Counters: primitive_tests counts the triangles tested (all of them for a
 * closest hit; any hit stops after the first block with a hit); no boxes.
 */
#ifndef FLAT_H
#define FLAT_H

#include <stdbool.h>
#include <stdint.h>

#include "03-aabb-slabs/accel.h"
#include "13-production/rays8.h"

/* Eight triangles by coordinate, then by lane, and which triangle each
 * lane is (-1: an empty lane). The lanes hold what the triangle
 * test reads, as wide_bvh_packet's do (wide_bvh.h, wide_bvh_lane_coordinates()): the
 * corners P0, P1, P2 (empty and degenerate lanes NaN, which no ray hits),
 * or P0, E1 = P1 - P0 and E2 = P2 - P0 (empty lanes all zeros, whose
 * determinant 0 never hits). 416 bytes. */
enum { FLAT_LANES = 8 };
_Static_assert((int)FLAT_LANES == (int)RAYS8_LANES, "the eight-ray kernels take a bundle's lanes");

typedef struct {
    _Alignas(32) float p0[3][FLAT_LANES];
    union {
        struct {
            float p1[3][FLAT_LANES], p2[3][FLAT_LANES]; /* the watertight test's */
        };
        struct {
            float e1[3][FLAT_LANES], e2[3][FLAT_LANES]; /* Moller-Trumbore's */
        };
    };
    /* the watertight test's N = (P1 - P0) x (P2 - P0), which its t needs
     * (shapes.h, watertight_plane_t), made once with its operations */
    float n[3][FLAT_LANES];
    int32_t index[FLAT_LANES];
} flat_block;

/* A run of consecutive triangles and their box, for the eight-ray kernels
 * (flat_closest_hit8, flat_any_hit8): a packet whose rays all miss the box
 * skips the run. The box is padded (flat.c, "Groups") so that a hit the
 * triangle test finds is inside it. */
typedef struct {
    float lo[3], hi[3];
    int first, count;
} flat_group;

/* AVX512: the AVX code with AVX-512's 32 registers (still 8 lanes). */
typedef enum { FLAT_KERNEL_AVX512, FLAT_KERNEL_AVX, FLAT_KERNEL_SSE, FLAT_KERNEL_SCALAR } flat_kernel;

typedef struct {
    accel base;
    flat_block *blocks;
    int block_count;
    /* Triangle i's corners once more, one after the other, each followed
     * by a coordinate of the normal N = (P1 - P0) x (P2 - P0): p0.x, p0.y,
     * p0.z, N.x, p1.x, p1.y, p1.z, N.y, p2.x, p2.y, p2.z, N.z (NaN for a
     * degenerate triangle, as in the blocks), 16-byte aligned. The
     * eight-ray packets' watertight test reads a corner's three
     * coordinates with one load (flat.c, FLAT_CORNER8), and N, which the
     * scalar test computes for t, made once here with its operations. */
    float (*corners)[12];
    flat_group *groups; /* in triangle order, covering every triangle once */
    int group_count;
    flat_kernel kernel;
} flat;

/* The blocks of set's triangles, in order; the kernel is the widest the
 * processor runs. */
accel *flat_build(const triangle_set *set);
/* Does this processor (and build) run the kernel? */
bool flat_kernel_runs(flat_kernel kernel);
/* Switch the kernel; false (and nothing changed) if this processor or
 * build cannot run it. */
bool flat_set_kernel(accel *a, flat_kernel kernel);
/* The widest kernel this processor runs. */
flat_kernel flat_best_kernel(void);
/* Was `a` built by flat_build()? */
bool flat_is(const accel *a);

/* Eight rays at once, the other way round: each lane a ray, each step one
 * triangle for all eight (a path tracer that follows eight paths at once,
 * this chapter's path_tracer_wide.c). Lane k, if bit k of `active` is set,
 * gets what accel_closest_hit() gives rays[k] alone, bit for bit (found[k],
 * hits[k]); other lanes are left as they were. With the AVX kernel, eight
 * rays per instruction, and a group (flat_group) whose box none of the
 * eight meets is skipped; else each ray alone. The one exception: a ray
 * lying in a triangle's plane, within rounding, for which the triangle
 * test reports a "hit" outside the triangle's box; the packet may have
 * skipped that box and give the true nearest hit (flat.c, "Groups").
 * primitive_tests counts the triangles tested for every active ray,
 * box_tests the group boxes. */
void flat_closest_hit8(const accel *a, const ray rays[FLAT_LANES], int active, hit_record hits[FLAT_LANES],
                       bool found[FLAT_LANES], ray_counters *counters);
/* The same for any hit: found[k] is accel_any_hit() of rays[k]. The eight
 * stop together, once every active ray has found a hit. */
void flat_any_hit8(const accel *a, const ray rays[FLAT_LANES], int active, bool found[FLAT_LANES],
                   ray_counters *counters);

/* flat_closest_hit8() with the eight rays as the kernels hold them
 * (rays8.h; a caller that keeps its rays this way hands them over as they
 * are, path_tracer_wide.c; the two functions above copy theirs in), stopped
 * before the hit records are made: the bits of the lanes that hit, and
 * their nearest hits in `hits`. */
int flat_closest_hit8_raw(const accel *a, const rays8 *rays, int active, hits8 *hits,
                          ray_counters *counters);
/* flat_any_hit8() as bits: bit k set if rays lane k is blocked. */
int flat_any_hit8_raw(const accel *a, const rays8 *rays, int active, ray_counters *counters);

#endif

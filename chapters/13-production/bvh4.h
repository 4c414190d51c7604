/* bvh4.h -- what production kernels do: a 4-wide BVH (the last section of
 * this chapter's README). The lecture's binary BVH answers every question a
 * ray asks of it with one box at a time: fetch a node, test its box, decide
 * which way to go. Each decision waits for the fetch before it, and the
 * "which way" is a branch the processor guesses wrong about half the time
 * on incoherent rays. A 4-wide BVH asks four questions at once: a node holds
 * the boxes of up to four children side by side (structure of arrays), one
 * SSE slab test checks all four, and the children hit are visited nearest
 * first. Half as many levels, so half as many dependent fetches, and the
 * four answers come back as one 4-bit mask instead of four branches.
 *
 * Built by collapsing the binary SAH tree (bvh_build.c): each 4-wide node
 * takes a binary node and pulls up grandchildren, the one with the largest
 * surface area first, until it has four children. Leaves hold triangles in
 * packets of four, also structure of arrays, tested by a 4-lane watertight
 * test (chapter 01's, what every renderer uses) that does, per lane,
 * exactly the scalar test's arithmetic: the same t, bit for bit. On request
 * (accel_use_triangle_test) the packets hold what Moller-Trumbore reads
 * instead, and a 4-lane Moller-Trumbore tests them: the benchmark's
 * column beside the watertight one, and the leak test's twin.
 *
 * The width is a compile-time constant, BVH4_WIDTH: 8 by default, or 4
 * (build with -DBVH4_WIDTH=4; `make test-bvh4`). An 8-wide node is two
 * groups of four boxes, each tested by the same SSE slab test (or one AVX
 * test of eight): a tree half as deep again, so fewer dependent fetches.
 * Measured on the tori field, single rays, one thread, CPU time: 8-wide
 * traced 3-6 % faster than 4-wide on coherent rays and 11-18 % faster on
 * incoherent ones, at 10k and 100k triangles. The name stays bvh4.
 *
 * Usage:
 *   accel *a = bvh4_build(&set, BVH_SPLIT_SAH);
 *   if (accel_closest_hit(a, r, &hit, &counters)) ...   same as any accel
 *   bvh4_set_kernel(a, BVH4_KERNEL_SCALAR);              the plain C path (tests)
 *   accel_destroy(a);
 *
 * Counters: box_tests counts the child boxes slab-tested (2 to BVH4_WIDTH
 * per node visited: the real children, not the empty slots of a node with
 * fewer);
 * primitive_tests the triangles tested (not the empty lanes of a packet).
 * Both are therefore comparable with the binary BVH's; the number of nodes
 * fetched is about box_tests / 3.5 (4-wide).
 */
#ifndef BVH4_H
#define BVH4_H

#include <stdbool.h>
#include <stdint.h>

#include "06-bvh/bvh.h"

/* Is the SSE path compiled in? (x86-64 always has SSE2.) Without it, only
 * the plain C loops exist; both give the same answers. */
#if defined(__SSE2__) && !defined(BVH4_NO_SIMD)
#define BVH4_HAVE_SSE 1
#else
#define BVH4_HAVE_SSE 0
#endif

/* A child reference, 32 bits:
 *   bit 31 clear   an interior node: the index of the node
 *   bit 31 set     a leaf: bits 23..30 its triangle count (0..255), bits
 *                  0..22 the index of its first packet; its triangles fill
 *                  packets first, first + 1, ... in order
 * An empty slot is a leaf with no triangles (BVH4_EMPTY), under a box
 * (lo = +inf, hi = -inf) that no ray hits. */
#define BVH4_LEAF 0x80000000u
#define BVH4_EMPTY BVH4_LEAF
enum { BVH4_LEAF_MAX = 255, BVH4_PACKET_SHIFT = 23 };

static inline bool bvh4_is_leaf(uint32_t ref) { return (ref & BVH4_LEAF) != 0; }
static inline int bvh4_leaf_triangles(uint32_t ref) { return (int)((ref >> BVH4_PACKET_SHIFT) & 0xFFu); }
static inline int bvh4_leaf_first_packet(uint32_t ref) { return (int)(ref & ((1u << BVH4_PACKET_SHIFT) - 1u)); }

/* One node: the boxes of its BVH4_WIDTH children, by plane then by child
 * (bounds[0][k] is child k's lo.x; 0..2 lo x, y, z, 3..5 hi x, y, z, the
 * order of bvh_node.bounds), the child references, children first, empty
 * slots last, and how many are children. Aligned to a cache line and a
 * whole number of them: 128 bytes for 4 children (116 would do, but then
 * half the nodes would straddle three cache lines instead of two), 256 for
 * 8 (228). */
#ifndef BVH4_WIDTH
#define BVH4_WIDTH 8
#endif
_Static_assert(BVH4_WIDTH == 4 || BVH4_WIDTH == 8, "a node holds 4 or 8 children");
/* How the program names the tree it built, by its width. */
#if BVH4_WIDTH == 8
#define BVH4_NAME "8-wide BVH"
#else
#define BVH4_NAME "4-wide BVH"
#endif

typedef struct {
    _Alignas(64) float bounds[6][BVH4_WIDTH]; /* one SSE load per plane and group of 4 */
    uint32_t child[BVH4_WIDTH];
    uint32_t children; /* how many slots are not empty (in the padding: for the counters) */
} bvh4_node;

_Static_assert(sizeof(bvh4_node) % 64 == 0, "a node is whole cache lines");

/* Four triangles as the 4-lane test reads them, by coordinate then by lane
 * (p0[1][k] is lane k's P0.y), and which triangle of the set each lane is
 * (right there, in the cache lines just read, when a hit needs it). 160
 * bytes. What the lanes hold depends on the tree's triangle test:
 *   watertight       the corners P0, P1, P2. An empty lane (index -1) and a
 *                    degenerate triangle (triangle_is_degenerate) are NaN:
 *                    no comparison with NaN holds, so no ray hits them, and
 *                    their edge functions are never exactly 0 (which would
 *                    send the lane to the test's double-precision path at
 *                    every visit).
 *   Moller-Trumbore  P0, E1 = P1 - P0 and E2 = P2 - P0. An empty lane is all
 *                    zeros: its determinant is 0, so it never hits.
 *
 * A lane's index also carries BVH4_LANE_EXACT when the packet gives back
 * the set's triangle bit for bit: always for the watertight test's
 * corners; for Moller-Trumbore when P0 + E1 and P0 + E2 give back P1 and
 * P2 (the subtractions were exact, as they are for most small triangles:
 * Sterbenz's lemma). The hit record of such a lane is made from the packet
 * alone; for the others the set's copy of the triangle is read, elsewhere
 * in memory. */
enum { BVH4_LANE_EXACT = 0x40000000 };
static inline int bvh4_lane_triangle(int32_t index) { return index < 0 ? index : index & (BVH4_LANE_EXACT - 1); }
typedef struct {
    _Alignas(16) float p0[3][4];
    union {
        struct {
            float p1[3][4], p2[3][4]; /* the watertight test's */
        };
        struct {
            float e1[3][4], e2[3][4]; /* Moller-Trumbore's */
        };
    };
    int32_t index[4];
} bvh4_packet;

/* What a lane of a SIMD kernel holds for triangle tri (NULL: an empty
 * lane) and `test`, as above (bvh4's packets, and flat.h's blocks): P0 in
 * p0, P1 and P2 or E1 and E2 in v1 and v2. Returns whether they give the
 * triangle back bit for bit (BVH4_LANE_EXACT). */
bool bvh4_lane_coordinates(const triangle *tri, triangle_test test, float p0[3], float v1[3], float v2[3]);
/* Lane k of a packet as `test` reads it: triangle `index` of the set (-1
 * and tri NULL: an empty lane), with its BVH4_LANE_EXACT mark. */
void bvh4_packet_set_lane(bvh4_packet *packet, int k, const triangle *tri, int index, triangle_test test);
/* The bvh4's accel_ops.use_triangle_test: rewrites every lane for `test`. */
bool bvh4_use_triangle_test(accel *a, triangle_test test);

/* Is the AVX path compiled in? It is chosen at run time, where the
 * processor has AVX (bvh4_set_kernel). */
#if BVH4_HAVE_SSE && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define BVH4_HAVE_AVX 1
#else
#define BVH4_HAVE_AVX 0
#endif

/* Which code tests boxes and triangles: the SSE intrinsics, or a plain C
 * loop over the four lanes with the same arithmetic (the same answers), or
 * AVX: the eight boxes of an 8-wide node in one slab test of eight lanes,
 * the same operations lane by lane, so again the same answers (triangles
 * as with SSE, in AVX's encoding). */
typedef enum { BVH4_KERNEL_SSE, BVH4_KERNEL_SCALAR, BVH4_KERNEL_AVX } bvh4_kernel;

typedef struct {
    accel base;
    bvh4_node *nodes; /* nodes[0] is the root */
    int node_count;
    bvh4_packet *packets; /* a leaf's packets are consecutive */
    int packet_count;
    int triangle_count;
    bvh4_kernel kernel;
} bvh4;

/* Build the binary tree with `split` (for BVH_SPLIT_SAH with leaf costs in
 * blocks of four triangles, what a packet costs), then collapse it. The
 * build time in stats includes both. */
accel *bvh4_build(const triangle_set *set, bvh_split split);
/* The same with the lower C_t near the root (bvh4_build.c's BVH4_SAH) for
 * the sets with at least top_area_fraction of the root's surface area; 0:
 * none, C_t = 1 everywhere (the tests' twin). */
accel *bvh4_build_with_top(const triangle_set *set, bvh_split split, float top_area_fraction);

/* Was `a` built by bvh4_build()? */
bool bvh4_is(const accel *a);

/* Switch the kernel of a built bvh4; returns false (and changes nothing)
 * for a kernel not compiled in or that this processor cannot run
 * (bvh4_kernel_runs). The default is the fastest that runs: AVX, SSE,
 * scalar. */
bool bvh4_set_kernel(accel *a, bvh4_kernel kernel);
bool bvh4_kernel_runs(bvh4_kernel kernel);

/* The two tests the traversal runs, on their own (for the tests): the slab
 * test of a node's BVH4_WIDTH boxes, as bvh_slab_test() does for one, returning
 * the mask of boxes hit and their t_enter; and the triangle test `test` on a
 * packet's four lanes (filled for that test) in (r.t_min, t_max), as the
 * scalar test, returning the mask of lanes hit and their t, b1, b2 (lanes
 * not hit are left as they were). */
int bvh4_slab_test(const bvh4_node *node, ray r, float t_min, float t_max, float t_enter[BVH4_WIDTH], bvh4_kernel kernel);
int bvh4_triangle_test(const bvh4_packet *packet, ray r, float t_max, float t[4], float b1[4], float b2[4],
                       bvh4_kernel kernel, triangle_test test);

/* Closest hits of a stream of independent rays: hit_found[i] and hits[i]
 * are what accel_closest_hit() gives for rays[i], bit for bit, but
 * BVH4_STREAM_LANES rays walk the tree at once, taking turns node by node,
 * so that one ray's wait for memory overlaps the others' work (see
 * bvh4_traverse.c). Pays on meshes larger than the cache. */
#ifndef BVH4_STREAM_LANES
#define BVH4_STREAM_LANES 16
#endif
void bvh4_closest_hit_stream(const accel *a, const ray *rays, int count, hit_record *hits, bool *hit_found,
                             ray_counters *counters);
/* The same for any hit: hit_found[i] is accel_any_hit() of rays[i]. */
void bvh4_any_hit_stream(const accel *a, const ray *rays, int count, bool *hit_found, ray_counters *counters);

/* The closest hits of a stream before their hit records are made: the
 * triangle's index in the set (-1: no hit), t and the barycentrics b1, b2,
 * from which triangle_set_fill_hit() makes what bvh4_closest_hit_stream()
 * gives, bit for bit. For a caller that makes its own records (chapter
 * 13's eight-path renderer, wide_trace.h). */
typedef struct {
    int index;
    float t, b1, b2;
} bvh4_raw_hit;
void bvh4_closest_hit_stream_raw(const accel *a, const ray *rays, int count, bvh4_raw_hit *hits, bool *hit_found,
                                 ray_counters *counters);
/* The same for one ray, walked alone. */
void bvh4_closest_hit_raw(const accel *a, ray r, bvh4_raw_hit *hit, ray_counters *counters);

/* The traversal's stack: each node pushes at most BVH4_WIDTH - 1 entries,
 * and the wide tree is no deeper than the binary one plus the levels that split
 * leaves of more than BVH4_LEAF_MAX triangles. */
enum { BVH4_STACK_SIZE = (BVH4_WIDTH - 1) * BVH_STACK_SIZE + 64 };

#endif

/* wide_bvh.h -- what production kernels do: a wide BVH, each node with
 * WIDE_BVH_WIDTH children (8, or 4; the last section of this chapter's
 * README). It was first written 4 wide, as the text below explains it. The lecture's binary BVH answers every question a
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
 * The width is a compile-time constant, WIDE_BVH_WIDTH: 8 by default, or 4
 * (build with -DWIDE_BVH_WIDTH=4; `make test-wide-bvh` runs the suite so;
 * the old name, -DBVH4_WIDTH=4, still works). An 8-wide node is two
 * groups of four boxes, each tested by the same SSE slab test (or one AVX
 * test of eight): a tree half as deep again, so fewer dependent fetches.
 * Measured on the tori field, single rays, one thread, CPU time: 8-wide
 * traced 3-6 % faster than 4-wide on coherent rays and 11-18 % faster on
 * incoherent ones, at 10k and 100k triangles.
 *
 * Usage:
 *   accel *a = wide_bvh_build(&set, BVH_SPLIT_SAH);
 *   if (accel_closest_hit(a, r, &hit, &counters)) ...   same as any accel
 *   wide_bvh_set_kernel(a, WIDE_BVH_KERNEL_SCALAR);      the plain C path (tests)
 *   accel_destroy(a);
 *
 * Counters: box_tests counts the child boxes slab-tested (2 to WIDE_BVH_WIDTH
 * per node visited: the real children, not the empty slots of a node with
 * fewer);
 * primitive_tests the triangles tested (not the empty lanes of a packet).
 * Both are therefore comparable with the binary BVH's; the number of nodes
 * fetched is about box_tests / 3.5 (4-wide).
 */
#ifndef WIDE_BVH_H
#define WIDE_BVH_H

#include <stdbool.h>
#include <stdint.h>

#include "06-bvh/bvh.h"

/* Is the SSE path compiled in? (x86-64 always has SSE2.) Without it, only
 * the plain C loops exist; both give the same answers. */
#if defined(__SSE2__) && !defined(WIDE_BVH_NO_SIMD)
#define WIDE_BVH_HAVE_SSE 1
#else
#define WIDE_BVH_HAVE_SSE 0
#endif

/* A child reference, 32 bits:
 *   bit 31 clear   an interior node: the index of the node
 *   bit 31 set     a leaf: bits 23..30 its triangle count (0..255), bits
 *                  0..22 the index of its first packet; its triangles fill
 *                  packets first, first + 1, ... in order
 * An empty slot is a leaf with no triangles (WIDE_BVH_EMPTY), under a box
 * (lo = +inf, hi = -inf) that no ray hits. */
#define WIDE_BVH_LEAF 0x80000000u
#define WIDE_BVH_EMPTY WIDE_BVH_LEAF
enum { WIDE_BVH_LEAF_MAX = 255, WIDE_BVH_PACKET_SHIFT = 23 };

static inline bool wide_bvh_is_leaf(uint32_t ref) { return (ref & WIDE_BVH_LEAF) != 0; }
static inline int wide_bvh_leaf_triangles(uint32_t ref) { return (int)((ref >> WIDE_BVH_PACKET_SHIFT) & 0xFFu); }
static inline int wide_bvh_leaf_first_packet(uint32_t ref) { return (int)(ref & ((1u << WIDE_BVH_PACKET_SHIFT) - 1u)); }

/* One node: the boxes of its WIDE_BVH_WIDTH children, by plane then by child
 * (bounds[0][k] is child k's lo.x; 0..2 lo x, y, z, 3..5 hi x, y, z, the
 * order of bvh_node.bounds), the child references, children first, empty
 * slots last, and how many are children. Aligned to a cache line and a
 * whole number of them: 128 bytes for 4 children (116 would do, but then
 * half the nodes would straddle three cache lines instead of two), 256 for
 * 8 (228). */
#if !defined(WIDE_BVH_WIDTH) && defined(BVH4_WIDTH)
#define WIDE_BVH_WIDTH BVH4_WIDTH /* the option's name when the tree was bvh4 */
#endif
#ifndef WIDE_BVH_WIDTH
#define WIDE_BVH_WIDTH 8
#endif
_Static_assert(WIDE_BVH_WIDTH == 4 || WIDE_BVH_WIDTH == 8, "a node holds 4 or 8 children");
/* How the program names the tree it built, by its width. */
#if WIDE_BVH_WIDTH == 8
#define WIDE_BVH_NAME "8-wide BVH"
#else
#define WIDE_BVH_NAME "4-wide BVH"
#endif

typedef struct {
    _Alignas(64) float bounds[6][WIDE_BVH_WIDTH]; /* one SSE load per plane and group of 4 */
    uint32_t child[WIDE_BVH_WIDTH];
    uint32_t children; /* how many slots are not empty (in the padding: for the counters) */
} wide_bvh_node;

_Static_assert(sizeof(wide_bvh_node) % 64 == 0, "a node is whole cache lines");

/* The same node with its children's boxes quantized (Embree's compressed
 * nodes; Ylitie et al., "Efficient incoherent ray traversal on GPUs through
 * compressed wide BVHs", 2017): each plane of each child as one byte q on a
 * grid over the node's own box, origin + q 2^e per axis, with the node's
 * box's lower corner as origin and the smallest power of two 2^e whose
 * grid of 255 steps reaches its upper corner. A child's lower planes are
 * rounded down onto the grid and its upper planes up, so the box the
 * traversal tests contains the exact one: it may let a ray in that the
 * exact box would not, never the other way round. The traversal turns the
 * bytes back into floats (wide_bvh_dequantize) and runs the same slab test
 * on them. 96 bytes for 8 children (the exact node's 256), 64 for 4 (128);
 * an 8-wide node is aligned to half a cache line, so it spans two lines
 * wherever it starts, as the exact one spans four. Empty slots have
 * q lo 255, hi 0, and are masked by `children` as well. */
#if WIDE_BVH_WIDTH == 8
#define WIDE_BVH_QNODE_ALIGN 32
#else
#define WIDE_BVH_QNODE_ALIGN 64
#endif
typedef struct {
    _Alignas(WIDE_BVH_QNODE_ALIGN) uint8_t bounds[6][WIDE_BVH_WIDTH]; /* the planes of bvh_node.bounds, by child */
    float origin[3];
    int8_t exponent[3]; /* the grid's step per axis is 2^exponent */
    uint8_t children;   /* how many slots are not empty */
    uint32_t child[WIDE_BVH_WIDTH];
} wide_bvh_qnode;

_Static_assert(sizeof(wide_bvh_qnode) == (WIDE_BVH_WIDTH == 8 ? 96 : 64), "a quantized node is 96 or 64 bytes");

/* Which nodes a tree is made of (wide_bvh_build_layout). */
typedef enum { WIDE_BVH_EXACT, WIDE_BVH_QUANTIZED } wide_bvh_layout;

/* The grid's step 2^e as a float, for e in [-126, 127]: built from its
 * bits, as the SIMD kernels build it. */
static inline float wide_bvh_step(int exponent)
{
    union {
        uint32_t bits;
        float value;
    } u = {(uint32_t)(exponent + 127) << 23};
    return u.value;
}

/* Plane q of an axis with this origin and exponent, exactly as every
 * kernel computes it: (float)q times the step (exact), plus the origin
 * (rounded). Non-decreasing in q; never NaN for a finite origin. */
static inline float wide_bvh_dequantize(float origin, int exponent, int q)
{
    float offset = (float)q * wide_bvh_step(exponent);
    return origin + offset;
}

/* How a plane goes onto the grid: outward (lower planes down, upper planes
 * up: what the tree does) or to the nearest grid plane (the tests' twin,
 * whose boxes do not always contain the exact ones). */
typedef enum { WIDE_BVH_ROUND_OUTWARD, WIDE_BVH_ROUND_NEAREST } wide_bvh_rounding;

/* The exact node quantized into q: its children's references, and the
 * boxes of its first `children` slots; the other slots empty. Returns
 * false (q undefined) if their union is not finite: such a node cannot be
 * put on a grid, and the tree keeps exact nodes. */
bool wide_bvh_quantize_node(const wide_bvh_node *exact, wide_bvh_rounding rounding, wide_bvh_qnode *q);
/* Child k's box as the traversal tests it. */
aabb wide_bvh_qnode_box(const wide_bvh_qnode *q, int k);

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
 * A lane's index also carries WIDE_BVH_LANE_EXACT when the packet gives back
 * the set's triangle bit for bit: always for the watertight test's
 * corners; for Moller-Trumbore when P0 + E1 and P0 + E2 give back P1 and
 * P2 (the subtractions were exact, as they are for most small triangles:
 * Sterbenz's lemma). The hit record of such a lane is made from the packet
 * alone; for the others the set's copy of the triangle is read, elsewhere
 * in memory. */
enum { WIDE_BVH_LANE_EXACT = 0x40000000 };
static inline int wide_bvh_lane_triangle(int32_t index) { return index < 0 ? index : index & (WIDE_BVH_LANE_EXACT - 1); }
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
} wide_bvh_packet;

/* What a lane of a SIMD kernel holds for triangle tri (NULL: an empty
 * lane) and `test`, as above (the wide BVH's packets, and flat.h's blocks): P0 in
 * p0, P1 and P2 or E1 and E2 in v1 and v2. Returns whether they give the
 * triangle back bit for bit (WIDE_BVH_LANE_EXACT). */
bool wide_bvh_lane_coordinates(const triangle *tri, triangle_test test, float p0[3], float v1[3], float v2[3]);
/* Lane k of a packet as `test` reads it: triangle `index` of the set (-1
 * and tri NULL: an empty lane), with its WIDE_BVH_LANE_EXACT mark. */
void wide_bvh_packet_set_lane(wide_bvh_packet *packet, int k, const triangle *tri, int index, triangle_test test);
/* The wide BVH's accel_ops.use_triangle_test: rewrites every lane for `test`. */
bool wide_bvh_use_triangle_test(accel *a, triangle_test test);

/* Is the AVX path compiled in? It is chosen at run time, where the
 * processor has AVX (wide_bvh_set_kernel). */
#if WIDE_BVH_HAVE_SSE && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define WIDE_BVH_HAVE_AVX 1
#else
#define WIDE_BVH_HAVE_AVX 0
#endif

/* Which code tests boxes and triangles: the SSE intrinsics, or a plain C
 * loop over the four lanes with the same arithmetic (the same answers), or
 * AVX: the eight boxes of an 8-wide node in one slab test of eight lanes,
 * the same operations lane by lane, so again the same answers (triangles
 * as with SSE, in AVX's encoding). */
typedef enum { WIDE_BVH_KERNEL_SSE, WIDE_BVH_KERNEL_SCALAR, WIDE_BVH_KERNEL_AVX } wide_bvh_kernel;

typedef struct {
    accel base;
    wide_bvh_node *nodes;   /* nodes[0] is the root; NULL when quantized */
    wide_bvh_qnode *qnodes; /* the same nodes, quantized; NULL when exact */
    wide_bvh_layout layout;
    int node_count;
    wide_bvh_packet *packets; /* a leaf's packets are consecutive */
    int packet_count;
    int triangle_count;
    wide_bvh_kernel kernel;
} wide_bvh;

/* Build the binary tree with `split` (for BVH_SPLIT_SAH with leaf costs in
 * blocks of four triangles, what a packet costs), then collapse it. The
 * build time in stats includes both. */
accel *wide_bvh_build(const triangle_set *set, bvh_split split);
/* The same with the lower C_t near the root (wide_bvh_build.c's WIDE_BVH_SAH) for
 * the sets with at least top_area_fraction of the root's surface area; 0:
 * none, C_t = 1 everywhere (the tests' twin). */
accel *wide_bvh_build_with_top(const triangle_set *set, bvh_split split, float top_area_fraction);

/* The same tree with nodes of the given layout. A tree whose boxes are
 * not finite stays exact: ask b->layout. wide_bvh_build's layout is
 * WIDE_BVH_DEFAULT_LAYOUT: exact, since on the tori field the quantized
 * nodes traced coherent rays about a fifth slower (the bytes turned back
 * into floats lengthen every node's test), incoherent ones on a million
 * triangles 4 % slower on a quiet machine and faster only while other
 * jobs filled the caches (README). -DWIDE_BVH_DEFAULT_LAYOUT=
 * WIDE_BVH_QUANTIZED builds everything on quantized nodes. */
accel *wide_bvh_build_layout(const triangle_set *set, bvh_split split, wide_bvh_layout layout);
#ifndef WIDE_BVH_DEFAULT_LAYOUT
#define WIDE_BVH_DEFAULT_LAYOUT WIDE_BVH_EXACT
#endif

/* Node n's child k as the traversal sees it, whatever the layout: its
 * reference, and its box (dequantized); and how many children it has. */
uint32_t wide_bvh_child(const wide_bvh *b, int n, int k);
aabb wide_bvh_child_box(const wide_bvh *b, int n, int k);
int wide_bvh_children(const wide_bvh *b, int n);

/* Was `a` built by wide_bvh_build()? */
bool wide_bvh_is(const accel *a);

/* Switch the kernel of a built wide BVH; returns false (and changes nothing)
 * for a kernel not compiled in or that this processor cannot run
 * (wide_bvh_kernel_runs). The default is the fastest that runs: AVX, SSE,
 * scalar. */
bool wide_bvh_set_kernel(accel *a, wide_bvh_kernel kernel);
bool wide_bvh_kernel_runs(wide_bvh_kernel kernel);

/* The two tests the traversal runs, on their own (for the tests): the slab
 * test of a node's WIDE_BVH_WIDTH boxes, as bvh_slab_test() does for one, returning
 * the mask of boxes hit and their t_enter; and the triangle test `test` on a
 * packet's four lanes (filled for that test) in (r.t_min, t_max), as the
 * scalar test, returning the mask of lanes hit and their t, b1, b2 (lanes
 * not hit are left as they were). */
int wide_bvh_slab_test(const wide_bvh_node *node, ray r, float t_min, float t_max, float t_enter[WIDE_BVH_WIDTH], wide_bvh_kernel kernel);
/* The same for a quantized node's boxes (the AVX kernel needs AVX2 here). */
int wide_bvh_qslab_test(const wide_bvh_qnode *node, ray r, float t_min, float t_max, float t_enter[WIDE_BVH_WIDTH],
                        wide_bvh_kernel kernel);
int wide_bvh_triangle_test(const wide_bvh_packet *packet, ray r, float t_max, float t[4], float b1[4], float b2[4],
                       wide_bvh_kernel kernel, triangle_test test);

/* Closest hits of a stream of independent rays: hit_found[i] and hits[i]
 * are what accel_closest_hit() gives for rays[i], bit for bit, but
 * WIDE_BVH_STREAM_LANES rays walk the tree at once, taking turns node by node,
 * so that one ray's wait for memory overlaps the others' work (see
 * wide_bvh_traverse.c). Pays on meshes larger than the cache. */
#ifndef WIDE_BVH_STREAM_LANES
#define WIDE_BVH_STREAM_LANES 16
#endif
void wide_bvh_closest_hit_stream(const accel *a, const ray *rays, int count, hit_record *hits, bool *hit_found,
                             ray_counters *counters);
/* The same for any hit: hit_found[i] is accel_any_hit() of rays[i]. */
void wide_bvh_any_hit_stream(const accel *a, const ray *rays, int count, bool *hit_found, ray_counters *counters);

/* The closest hits of a stream before their hit records are made: the
 * triangle's index in the set (-1: no hit), t and the barycentrics b1, b2,
 * from which triangle_set_fill_hit() makes what wide_bvh_closest_hit_stream()
 * gives, bit for bit. For a caller that makes its own records (chapter
 * 13's eight-path renderer, wide_trace.h). */
typedef struct {
    int index;
    float t, b1, b2;
} wide_bvh_raw_hit;
void wide_bvh_closest_hit_stream_raw(const accel *a, const ray *rays, int count, wide_bvh_raw_hit *hits, bool *hit_found,
                                 ray_counters *counters);
/* The same for one ray, walked alone. */
void wide_bvh_closest_hit_raw(const accel *a, ray r, wide_bvh_raw_hit *hit, ray_counters *counters);

/* wide_bvh_traverse.c's accel_ops for the default kernel (wide_bvh_build.c
 * sets it). */
const accel_ops *wide_bvh_default_ops(void);

/* The traversal's stack: each node pushes at most WIDE_BVH_WIDTH - 1 entries,
 * and the wide tree is no deeper than the binary one plus the levels that split
 * leaves of more than WIDE_BVH_LEAF_MAX triangles. */
enum { WIDE_BVH_STACK_SIZE = (WIDE_BVH_WIDTH - 1) * BVH_STACK_SIZE + 64 };

#endif

/* wide_bvh_traverse.c -- a ray through the wide BVH: at each node, slab-test
 * the children's boxes at once (eight, or four: WIDE_BVH_WIDTH), go on with
 * the nearest child hit and put the others on the stack, farthest deepest; in
 * a leaf, test its triangles four at a time, with the watertight test (or
 * Moller-Trumbore, when asked). The tests themselves are
 * wide_bvh_kernels.h's, each with SSE intrinsics and as a plain C loop
 * (the same answers; test_ch13 runs both). */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "13-production/wide_bvh.h"
#include "13-production/wide_bvh_kernels.h"

/* ---- the node's and the leaf's tests on their own (wide_bvh.h; for the tests) ---- */

int wide_bvh_slab_test(const wide_bvh_node *node, ray r, float t_min, float t_max, float t_enter[WIDE_BVH_WIDTH], wide_bvh_kernel kernel)
{
    wide_bvh_ray r4 = wide_bvh_ray_make(&r);
#if WIDE_BVH_HAVE_AVX
    if (kernel == WIDE_BVH_KERNEL_AVX)
        return slab_test_avx_alone(node, &r4, t_min, t_max, t_enter);
#endif
#if WIDE_BVH_HAVE_SSE
    if (kernel == WIDE_BVH_KERNEL_SSE)
        return slab_test4_sse(node, &r4, t_min, t_max, t_enter);
#endif
    (void)kernel;
    return slab_test4_scalar(node, &r4, t_min, t_max, t_enter);
}

int wide_bvh_qslab_test(const wide_bvh_qnode *node, ray r, float t_min, float t_max, float t_enter[WIDE_BVH_WIDTH],
                        wide_bvh_kernel kernel)
{
    wide_bvh_ray r4 = wide_bvh_ray_make(&r);
#if WIDE_BVH_HAVE_AVX
    if (kernel == WIDE_BVH_KERNEL_AVX)
        return qslab_test_avx2_alone(node, &r4, t_min, t_max, t_enter);
#endif
#if WIDE_BVH_HAVE_SSE
    if (kernel == WIDE_BVH_KERNEL_SSE)
        return qslab_test_sse(node, &r4, t_min, t_max, t_enter);
#endif
    (void)kernel;
    return qslab_test_scalar(node, &r4, t_min, t_max, t_enter);
}

int wide_bvh_triangle_test(const wide_bvh_packet *packet, ray r, float t_max, float t[4], float b1[4], float b2[4],
                       wide_bvh_kernel kernel, triangle_test test)
{
    wide_bvh_ray r4 = wide_bvh_ray_make(&r);
    float lane_t[4], lane_b1[4], lane_b2[4];
    int mask = triangle_test4(packet, &r4, &r, t_max, lane_t, lane_b1, lane_b2, kernel != WIDE_BVH_KERNEL_SCALAR,
                              test == TRIANGLE_TEST_WATERTIGHT);
    for (int k = 0; k < 4; k++) /* lanes not hit keep what they had */
        if (mask >> k & 1) {
            t[k] = lane_t[k];
            b1[k] = lane_b1[k];
            b2[k] = lane_b2[k];
        }
    return mask;
}

/* ---- traversal ------------------------------------------------------------------- */


/* What a traversal found: the closest triangle so far (4 packet + lane),
 * its index in the set, and the t below which a triangle is still tested:
 * the ray's t_max until a hit, then the hit's t (an exact tree) or the
 * float just above it (a quantized tree: a triangle at the very same t is
 * tested too, and the lower index wins; test_leaf4). */
typedef struct {
    int lane; /* -1: none */
    float t, b1, b2;
    int index;
    float t_test;
} wide_bvh_found;

typedef struct {
    uint32_t ref;
    float t_enter;
} wide_bvh_entry;

static inline int lowest_bit(unsigned mask) { return __builtin_ctz(mask); }

/* Ask for a child's memory before it is needed: a node's cache lines,
 * or a leaf's packets (160 bytes each). The children hit at a node are all
 * fetched at once, in parallel, instead of one after the other as the
 * traversal reaches them.
 *
 * Always inlined, and that matters: GCC counts __builtin_prefetch as having
 * no effect, so it takes a function made of prefetches for a pure one, and
 * a call to a pure function whose result is unused for dead code. Where
 * this function was not inlined early, as in the closest-hit traversal, the
 * call and every prefetch in it silently vanished (objdump showed none). */
static ALWAYS_INLINE void prefetch_child(const wide_bvh *b, uint32_t ref, bool quantized)
{
#if defined(__GNUC__)
    if (!wide_bvh_is_leaf(ref)) {
        /* a quantized 8-wide node, 96 bytes from a multiple of 32: two lines,
         * at p and p + 64, wherever it starts */
        const char *p = quantized ? (const char *)&b->qnodes[ref] : (const char *)&b->nodes[ref];
        size_t size = quantized ? sizeof(wide_bvh_qnode) : sizeof(wide_bvh_node);
        for (size_t line = 0; line < size; line += 64)
            __builtin_prefetch(p + line);
        return;
    }
    const char *p = (const char *)&b->packets[wide_bvh_leaf_first_packet(ref)];
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
    __builtin_prefetch(p + 128);
    if (wide_bvh_leaf_triangles(ref) > 4) {
        __builtin_prefetch(p + 192);
        __builtin_prefetch(p + 256);
    }
#else
    (void)b;
    (void)ref;
    (void)quantized;
#endif
}

/* A hit will be turned into a hit record from the set's material and unit
 * normal of the triangle (and the mesh's face, for vertex normals) and,
 * unless the packet gives the vertices back exactly (WIDE_BVH_LANE_EXACT), the
 * set's copy of the triangle: ask for them as soon as a hit is found, so
 * they are in the cache by the end of the traversal (usually the first hit
 * found is the closest). */
static ALWAYS_INLINE void prefetch_hit(const wide_bvh *b, int32_t lane_index)
{
#if defined(__GNUC__)
    int index = wide_bvh_lane_triangle(lane_index);
    if (!(lane_index & WIDE_BVH_LANE_EXACT))
        __builtin_prefetch(&b->base.set->triangles[index]);
    const triangle_set *set = b->base.set;
    __builtin_prefetch(&set->surfaces[index]);
    if (set->source != NULL && set->vertex_normals)
        __builtin_prefetch(&set->source->faces[index]);
#else
    (void)b;
    (void)lane_index;
#endif
}

/* The float just above a hit's t: one more in its bit pattern where t is
 * positive and finite (every hit the walk keeps), nextafterf elsewhere.
 * libm's nextafterf is a call, and this runs on every closer hit. */
static ALWAYS_INLINE float float_above(float t)
{
    if (!(t > 0.0f && t < INFINITY))
        return nextafterf(t, INFINITY);
    uint32_t bits;
    memcpy(&bits, &t, sizeof bits);
    bits += 1;
    memcpy(&t, &bits, sizeof t);
    return t;
}

/* The leaf's packets against (t_min, found->t_test). The closest lane hit
 * wins. In a quantized tree, of equal t the lower triangle index wins too,
 * as in brute force: which triangle a ray through a shared edge reports
 * then depends on the triangles alone, not on the order the walk met them.
 * That order depends on the boxes (the same tree with larger boxes may let
 * a ray enter the children in another order), and the hits must not. The
 * exact tree's walk meets them in chapter 06's order, which gives brute
 * force's answer already (the differential tests), so it keeps the
 * cheaper test: no index to load on every hit. */
static ALWAYS_INLINE bool test_leaf4(const wide_bvh *b, uint32_t ref, const wide_bvh_ray *r4, const ray *r, wide_bvh_found *found,
                              bool stop_at_first, bool sse, bool watertight, bool quantized, uint64_t *primitive_tests)
{
    int count = wide_bvh_leaf_triangles(ref), first = wide_bvh_leaf_first_packet(ref);
    for (int p = 0; p * 4 < count; p++) {
        float t[4], b1[4], b2[4];
        const wide_bvh_packet *packet = &b->packets[first + p];
        int mask = triangle_test4(packet, r4, r, found->t_test, t, b1, b2, sse, watertight);
        *primitive_tests += (uint64_t)(count - 4 * p < 4 ? count - 4 * p : 4);
        if (mask == 0)
            continue;
        while (mask != 0) {
            int k = lowest_bit((unsigned)mask);
            mask &= mask - 1;
            if (!quantized) {
                if (t[k] < found->t)
                    *found = (wide_bvh_found){4 * (first + p) + k, t[k], b1[k], b2[k], -1, t[k]};
                continue;
            }
            int index = wide_bvh_lane_triangle(packet->index[k]);
            if (t[k] < found->t || (t[k] == found->t && index < found->index))
                *found = (wide_bvh_found){4 * (first + p) + k, t[k], b1[k], b2[k], index,
                                          float_above(t[k])};
        }
        if (stop_at_first)
            return true;
        prefetch_hit(b, packet->index[found->lane % 4]);
    }
    return false;
}

/* One ray's walk through the tree, as data: what the loop of a traversal
 * keeps between one node and the next. Kept in a struct, rather than in
 * local variables, so that several rays can take turns (the stream below);
 * for one ray alone the compiler keeps the scalars in registers all the
 * same. */
typedef struct {
    wide_bvh_ray r4;
    ray r;
    wide_bvh_found found;
    uint32_t current; /* the node or leaf to visit next */
    int top;          /* entries on the stack */
    uint64_t box_tests, primitive_tests;
    wide_bvh_entry stack[WIDE_BVH_STACK_SIZE];
} wide_bvh_traversal;

/* Start at the root; false if there is no tree to walk. */
static ALWAYS_INLINE bool traversal_begin(const wide_bvh *b, const ray *r, wide_bvh_traversal *w)
{
    w->r = *r;
    w->r4 = wide_bvh_ray_make(r);
    w->found = (wide_bvh_found){-1, r->t_max, 0.0f, 0.0f, -1, r->t_max};
    w->current = 0; /* the root */
    w->top = 0;
    w->box_tests = w->primitive_tests = 0;
    return b->node_count > 0;
}

/* Visit w->current -- slab-test a node's children, or test a leaf's
 * triangles -- and choose the next one to visit. Returns false when the
 * walk is over: the stack is empty, or (any hit) a triangle was hit. */
/* The slab test of node n's children, by layout and kernel: the mask of
 * those hit, their t_enter, and where their references are. */
static ALWAYS_INLINE int node_test(const wide_bvh *b, uint32_t n, const wide_bvh_traversal *w, float cull,
                                   float t_enter[WIDE_BVH_WIDTH], const uint32_t **child, int *children, bool sse,
                                   bool avx, bool quantized)
{
    if (quantized) {
        const wide_bvh_qnode *node = &b->qnodes[n];
        *child = node->child;
        *children = node->children;
#if WIDE_BVH_HAVE_AVX
        if (avx)
            return qslab_test_avx2(node, &w->r4, w->r.t_min, cull, t_enter);
#endif
#if WIDE_BVH_HAVE_SSE
        if (sse)
            return qslab_test_sse(node, &w->r4, w->r.t_min, cull, t_enter);
#endif
        return qslab_test_scalar(node, &w->r4, w->r.t_min, cull, t_enter);
    }
    const wide_bvh_node *node = &b->nodes[n];
    *child = node->child;
    *children = (int)node->children;
#if WIDE_BVH_HAVE_AVX
    if (avx)
        return slab_test_avx(node, &w->r4, w->r.t_min, cull, t_enter);
#endif
#if WIDE_BVH_HAVE_SSE
    if (sse)
        return slab_test4_sse(node, &w->r4, w->r.t_min, cull, t_enter);
#endif
    (void)sse, (void)avx;
    return slab_test4_scalar(node, &w->r4, w->r.t_min, cull, t_enter);
}

static ALWAYS_INLINE bool traversal_step(const wide_bvh *b, wide_bvh_traversal *w, bool stop_at_first, bool sse, bool avx,
                                         bool watertight, bool quantized)
{
    if (!wide_bvh_is_leaf(w->current)) {
        float t_enter[WIDE_BVH_WIDTH];
        float cull = w->found.t * BVH_CULL_SLACK;
        const uint32_t *child;
        int children;
        int mask = node_test(b, w->current, w, cull, t_enter, &child, &children, sse, avx, quantized);
        w->box_tests += (uint64_t)children;
        if (mask != 0 && stop_at_first) {
            /* Any hit: every child hit may end the walk, whichever is
             * first; no order to sort. Visit the nearest (the likeliest to
             * block), push the others as they come. */
            int k = lowest_bit((unsigned)mask);
            mask &= mask - 1;
            while (mask != 0) {
                int j = lowest_bit((unsigned)mask);
                mask &= mask - 1;
                bool nearer = t_enter[j] < t_enter[k];
                int pushed = nearer ? k : j;
                k = nearer ? j : k;
                prefetch_child(b, child[pushed], quantized);
                w->stack[w->top++] = (wide_bvh_entry){child[pushed], t_enter[pushed]};
            }
            w->current = child[k];
            return true;
        }
        if (mask != 0) {
            int k = lowest_bit((unsigned)mask);
            mask &= mask - 1;
            if (mask == 0) {
                /* one child hit: no order to decide */
                w->current = child[k];
                return true;
            }
            int k2 = lowest_bit((unsigned)mask);
            mask &= mask - 1;
            if (mask == 0) {
                /* two (the commonest case): one comparison orders them */
                bool second_first = t_enter[k2] < t_enter[k];
                int near = second_first ? k2 : k, far = second_first ? k : k2;
                prefetch_child(b, child[far], quantized);
                w->stack[w->top++] = (wide_bvh_entry){child[far], t_enter[far]};
                w->current = child[near];
                return true;
            }
            mask |= 1 << k2;
            /* Three or more: sort them by t_enter, nearest last
             * (insertion sort), push all but the nearest, visit it. */
            wide_bvh_entry hits[WIDE_BVH_WIDTH];
            int n = 0;
            hits[n++] = (wide_bvh_entry){child[k], t_enter[k]};
            prefetch_child(b, child[k], quantized);
            while (mask != 0) {
                k = lowest_bit((unsigned)mask);
                mask &= mask - 1;
                wide_bvh_entry e = {child[k], t_enter[k]};
                prefetch_child(b, e.ref, quantized);
                int j = n++;
                while (j > 0 && hits[j - 1].t_enter < e.t_enter) {
                    hits[j] = hits[j - 1];
                    j--;
                }
                hits[j] = e;
            }
            for (int j = 0; j < n - 1; j++)
                w->stack[w->top++] = hits[j];
            w->current = hits[n - 1].ref;
            return true;
        }
    } else if (test_leaf4(b, w->current, &w->r4, &w->r, &w->found, stop_at_first, sse, watertight, quantized,
                          &w->primitive_tests)) {
        return false;
    }
    /* Next from the stack, skipping entries that begin beyond the
     * closest hit (their box test would fail now). */
    float cull = w->found.t * BVH_CULL_SLACK;
    while (w->top > 0 && w->stack[w->top - 1].t_enter > cull)
        w->top--;
    if (w->top == 0)
        return false;
    w->current = w->stack[--w->top].ref;
    return true;
}

static ALWAYS_INLINE wide_bvh_found traverse4(const wide_bvh *b, const ray *r, bool stop_at_first, bool sse, bool avx,
                                          bool watertight, bool quantized, ray_counters *counters)
{
    wide_bvh_traversal w;
    if (traversal_begin(b, r, &w))
        while (traversal_step(b, &w, stop_at_first, sse, avx, watertight, quantized))
            ;
    counters->box_tests += w.box_tests;
    counters->primitive_tests += w.primitive_tests;
    return w.found;
}

/* ---- the accel interface ------------------------------------------------------------- */

static bool finish_closest(const wide_bvh *b, const wide_bvh_found *found, const ray *r, hit_record *record)
{
    if (found->lane < 0)
        return false;
    const wide_bvh_packet *p = &b->packets[found->lane / 4];
    int k = found->lane % 4, index = wide_bvh_lane_triangle(p->index[k]);
    if (!(p->index[k] & WIDE_BVH_LANE_EXACT)) {
        triangle_set_fill_hit(b->base.set, index, *r, found->t, found->b1, found->b2, record);
        return true;
    }
    /* the set's triangle, bit for bit, from the cache lines the test read */
    vec3 p0 = vec3_make(p->p0[0][k], p->p0[1][k], p->p0[2][k]);
    vec3 v1 = vec3_make(p->p1[0][k], p->p1[1][k], p->p1[2][k]), v2 = vec3_make(p->p2[0][k], p->p2[1][k], p->p2[2][k]);
    triangle tri = {p0, v1, v2}; /* the watertight test's corners */
    if (b->base.triangle_test == TRIANGLE_TEST_MOLLER_TRUMBORE)
        tri = (triangle){p0, vec3_add(p0, v1), vec3_add(p0, v2)}; /* P0 + E1, P0 + E2 */
    triangle_set_fill_hit_from(b->base.set, &tri, index, *r, found->t, found->b1, found->b2, record);
    return true;
}

/* ---- a stream of rays, taking turns ---------------------------------------------------
 * On a mesh far larger than the cache, one ray's walk is a chain of waits:
 * a node must arrive from memory before its boxes can say which node comes
 * next. The processor overlaps little of that, because each fetch depends
 * on the one before. Rays of a stream do not depend on each other, so
 * WIDE_BVH_STREAM_LANES of them take turns: each visits one node, asks for
 * the memory of the node it will visit next (prefetch), and waits while the
 * others take their turn. By the time a ray's turn comes round again its
 * node has arrived. Each ray does exactly what it would alone, in the same
 * order: the same hits, bit for bit. */
static ALWAYS_INLINE void stream4(const wide_bvh *b, const ray *rays, int count, hit_record *hits, bool *hit_found,
                                  wide_bvh_found *raw, bool stop_at_first, bool sse, bool avx, bool watertight,
                                  bool quantized, ray_counters *counters)
{
    wide_bvh_traversal lanes[WIDE_BVH_STREAM_LANES];
    int ray_of[WIDE_BVH_STREAM_LANES]; /* the ray each lane walks, -1: none left */
    int next = 0, walking = 0;
    /* Closest hits found, waiting to become hit records. Making one reads
     * the triangle's material (and maybe its vertices) from the set, memory
     * that prefetch_hit() asked for when the hit was found, often just
     * before the walk ended: a ray waits here while WIDE_BVH_STREAM_LANES others
     * finish, so that the memory has arrived. */
    struct {
        int ray;
        wide_bvh_found found;
    } waiting[WIDE_BVH_STREAM_LANES];
    int waiting_count = 0, waiting_oldest = 0;
    for (int k = 0; k < WIDE_BVH_STREAM_LANES; k++)
        ray_of[k] = -1;
    /* Not needed (a lane is read only after traversal_begin() filled it),
     * but GCC cannot see that with one lane and warns. Everything but the
     * stacks: a few hundred bytes a lane. */
    for (int k = 0; k < WIDE_BVH_STREAM_LANES; k++)
        memset(&lanes[k], 0, offsetof(wide_bvh_traversal, stack));
    for (;;) {
        /* Give every idle lane the next ray; a ray with no tree to walk
         * (an empty tree) finishes at once. */
        for (int k = 0; k < WIDE_BVH_STREAM_LANES && next < count; k++) {
            if (ray_of[k] >= 0)
                continue;
            if (traversal_begin(b, &rays[next], &lanes[k])) {
                ray_of[k] = next;
                walking++;
            } else {
                hit_found[next] = false;
            }
            next++;
        }
        if (walking == 0)
            break;
        for (int k = 0; k < WIDE_BVH_STREAM_LANES; k++) {
            if (ray_of[k] < 0)
                continue;
            wide_bvh_traversal *w = &lanes[k];
            if (traversal_step(b, w, stop_at_first, sse, avx, watertight, quantized)) {
                prefetch_child(b, w->current, quantized);
                continue;
            }
            int i = ray_of[k];
            hit_found[i] = w->found.lane >= 0;
            if (raw != NULL) /* the caller makes its own records */
                raw[i] = w->found;
            else if (!stop_at_first && hit_found[i]) {
                if (waiting_count == WIDE_BVH_STREAM_LANES) {
                    int j = waiting[waiting_oldest].ray;
                    finish_closest(b, &waiting[waiting_oldest].found, &rays[j], &hits[j]);
                    waiting_oldest = (waiting_oldest + 1) % WIDE_BVH_STREAM_LANES;
                    waiting_count--;
                }
                int slot = (waiting_oldest + waiting_count++) % WIDE_BVH_STREAM_LANES;
                waiting[slot].ray = i;
                waiting[slot].found = w->found;
            }
            counters->box_tests += w->box_tests;
            counters->primitive_tests += w->primitive_tests;
            ray_of[k] = -1;
            walking--;
        }
    }
    for (; waiting_count > 0; waiting_count--) {
        int j = waiting[waiting_oldest].ray;
        finish_closest(b, &waiting[waiting_oldest].found, &rays[j], &hits[j]);
        waiting_oldest = (waiting_oldest + 1) % WIDE_BVH_STREAM_LANES;
    }
}

/* ---- one walk per kernel, layout and query -----------------------------------------
 * Each with the kernel, the layout and the query constant inside
 * (ALWAYS_INLINE), the triangle test chosen once per ray or stream. The
 * AVX ones are compiled for AVX (exact nodes) or AVX2 (quantized ones),
 * everything they call inlined (flatten), the SSE tests included, in AVX's
 * encoding. */
static ALWAYS_INLINE wide_bvh_found traverse4_with(const accel *a, const ray *r, bool stop_at_first, bool sse, bool avx,
                                               bool quantized, ray_counters *counters)
{
    const wide_bvh *b = (const wide_bvh *)a;
    if (a->triangle_test == TRIANGLE_TEST_WATERTIGHT)
        return traverse4(b, r, stop_at_first, sse, avx, true, quantized, counters);
    return traverse4(b, r, stop_at_first, sse, avx, false, quantized, counters);
}

static ALWAYS_INLINE void stream4_with(const wide_bvh *b, const ray *rays, int count, hit_record *hits, bool *hit_found,
                                       wide_bvh_found *raw, bool stop_at_first, bool sse, bool avx, bool quantized,
                                       ray_counters *counters)
{
    bool watertight = b->base.triangle_test == TRIANGLE_TEST_WATERTIGHT;
    if (stop_at_first) {
        if (watertight)
            stream4(b, rays, count, hits, hit_found, NULL, true, sse, avx, true, quantized, counters);
        else
            stream4(b, rays, count, hits, hit_found, NULL, true, sse, avx, false, quantized, counters);
    } else if (raw != NULL) {
        stream4(b, rays, count, hits, hit_found, raw, false, sse, avx, watertight, quantized, counters);
    } else if (watertight) {
        stream4(b, rays, count, hits, hit_found, NULL, false, sse, avx, true, quantized, counters);
    } else {
        stream4(b, rays, count, hits, hit_found, NULL, false, sse, avx, false, quantized, counters);
    }
}

static void wide_bvh_destroy(accel *a);

typedef wide_bvh_found (*walk_fn)(const accel *a, const ray *r, ray_counters *counters);
typedef void (*stream_fn)(const wide_bvh *b, const ray *rays, int count, hit_record *hits, bool *hit_found,
                          wide_bvh_found *raw, bool stop_at_first, ray_counters *counters);

/* A kernel's entry points for one layout: the closest-hit walk, the
 * stream, and the accel_ops (closest and any hit). */
typedef struct {
    walk_fn closest;
    stream_fn stream;
    accel_ops ops;
} entry_points;

#define WIDE_BVH_ENTRY_POINTS(NAME, TARGET, SSE, AVX, QUANTIZED)                                                  \
    TARGET static wide_bvh_found closest_##NAME(const accel *a, const ray *r, ray_counters *counters)            \
    {                                                                                                            \
        return traverse4_with(a, r, false, SSE, AVX, QUANTIZED, counters);                                       \
    }                                                                                                            \
    TARGET static wide_bvh_found any_##NAME(const accel *a, const ray *r, ray_counters *counters)                \
    {                                                                                                            \
        return traverse4_with(a, r, true, SSE, AVX, QUANTIZED, counters);                                        \
    }                                                                                                            \
    TARGET static void stream_##NAME(const wide_bvh *b, const ray *rays, int count, hit_record *hits,            \
                                     bool *hit_found, wide_bvh_found *raw, bool stop_at_first,                  \
                                     ray_counters *counters)                                                     \
    {                                                                                                            \
        stream4_with(b, rays, count, hits, hit_found, raw, stop_at_first, SSE, AVX, QUANTIZED, counters);        \
    }                                                                                                            \
    static bool closest_hit_##NAME(const accel *a, ray r, hit_record *hit, ray_counters *counters)               \
    {                                                                                                            \
        wide_bvh_found found = closest_##NAME(a, &r, counters);                                                  \
        return finish_closest((const wide_bvh *)a, &found, &r, hit);                                             \
    }                                                                                                            \
    static bool any_hit_##NAME(const accel *a, ray r, ray_counters *counters)                                    \
    {                                                                                                            \
        return any_##NAME(a, &r, counters).lane >= 0;                                                            \
    }                                                                                                            \
    static const entry_points entry_##NAME = {                                                                   \
        closest_##NAME, stream_##NAME, {closest_hit_##NAME, any_hit_##NAME, wide_bvh_destroy, wide_bvh_use_triangle_test}};

WIDE_BVH_ENTRY_POINTS(scalar, , false, false, false)
WIDE_BVH_ENTRY_POINTS(scalar_quantized, , false, false, true)
#if WIDE_BVH_HAVE_SSE
WIDE_BVH_ENTRY_POINTS(sse, , true, false, false)
WIDE_BVH_ENTRY_POINTS(sse_quantized, , true, false, true)
#endif
#if WIDE_BVH_HAVE_AVX
WIDE_BVH_ENTRY_POINTS(avx, AVX_CODE __attribute__((flatten)), true, true, false)
WIDE_BVH_ENTRY_POINTS(avx_quantized, AVX2_CODE __attribute__((flatten)), true, true, true)
#endif

/* The entry points of a layout and kernel (NULL: not compiled in). */
static const entry_points *entry_points_of(wide_bvh_layout layout, wide_bvh_kernel kernel)
{
    static const entry_points *const table[2][3] = {
        [WIDE_BVH_EXACT] =
            {
                [WIDE_BVH_KERNEL_SCALAR] = &entry_scalar,
#if WIDE_BVH_HAVE_SSE
                [WIDE_BVH_KERNEL_SSE] = &entry_sse,
#endif
#if WIDE_BVH_HAVE_AVX
                [WIDE_BVH_KERNEL_AVX] = &entry_avx,
#endif
            },
        [WIDE_BVH_QUANTIZED] =
            {
                [WIDE_BVH_KERNEL_SCALAR] = &entry_scalar_quantized,
#if WIDE_BVH_HAVE_SSE
                [WIDE_BVH_KERNEL_SSE] = &entry_sse_quantized,
#endif
#if WIDE_BVH_HAVE_AVX
                [WIDE_BVH_KERNEL_AVX] = &entry_avx_quantized,
#endif
            },
    };
    return table[layout][kernel];
}

static const entry_points *entry_points_of_tree(const wide_bvh *b) { return entry_points_of(b->layout, b->kernel); }

/* The walk of the tree's kernel. */
static wide_bvh_found closest_found(const accel *a, const ray *r, ray_counters *counters)
{
    return entry_points_of_tree((const wide_bvh *)a)->closest(a, r, counters);
}

static void stream4_with_kernel(const accel *a, const ray *rays, int count, hit_record *hits, bool *hit_found,
                                wide_bvh_found *raw, bool stop_at_first, ray_counters *counters)
{
    const wide_bvh *b = (const wide_bvh *)a;
    entry_points_of_tree(b)->stream(b, rays, count, hits, hit_found, raw, stop_at_first, counters);
}

void wide_bvh_closest_hit_stream(const accel *a, const ray *rays, int count, hit_record *hits, bool *hit_found,
                             ray_counters *counters)
{
    stream4_with_kernel(a, rays, count, hits, hit_found, NULL, false, counters);
}

void wide_bvh_any_hit_stream(const accel *a, const ray *rays, int count, bool *hit_found, ray_counters *counters)
{
    stream4_with_kernel(a, rays, count, NULL, hit_found, NULL, true, counters);
}

void wide_bvh_closest_hit_raw(const accel *a, ray r, wide_bvh_raw_hit *hit, ray_counters *counters)
{
    const wide_bvh *b = (const wide_bvh *)a;
    wide_bvh_found found = closest_found(a, &r, counters);
    hit->index = found.lane < 0 ? -1 : wide_bvh_lane_triangle(b->packets[found.lane / 4].index[found.lane % 4]);
    hit->t = found.t;
    hit->b1 = found.b1;
    hit->b2 = found.b2;
}

void wide_bvh_closest_hit_stream_raw(const accel *a, const ray *rays, int count, wide_bvh_raw_hit *hits, bool *hit_found,
                                 ray_counters *counters)
{
    enum { CHUNK = 64 };
    const wide_bvh *b = (const wide_bvh *)a;
    wide_bvh_found found[CHUNK];
    for (int first = 0; first < count; first += CHUNK) {
        int n = count - first < CHUNK ? count - first : CHUNK;
        stream4_with_kernel(a, rays + first, n, NULL, hit_found + first, found, false, counters);
        for (int i = 0; i < n; i++) {
            wide_bvh_raw_hit *h = &hits[first + i];
            h->index = found[i].lane < 0 ? -1
                                         : wide_bvh_lane_triangle(b->packets[found[i].lane / 4].index[found[i].lane % 4]);
            h->t = found[i].t;
            h->b1 = found[i].b1;
            h->b2 = found[i].b2;
        }
    }
}

static void wide_bvh_destroy(accel *a)
{
    wide_bvh *b = (wide_bvh *)a;
    free(b->nodes);
    free(b->qnodes);
    free(b->packets);
    free(b);
}

bool wide_bvh_is(const accel *a) { return a != NULL && a->ops->destroy == wide_bvh_destroy; }

const accel_ops *wide_bvh_default_ops(void)
{
    return &entry_points_of(WIDE_BVH_EXACT, WIDE_BVH_HAVE_SSE ? WIDE_BVH_KERNEL_SSE : WIDE_BVH_KERNEL_SCALAR)->ops;
}

bool wide_bvh_kernel_runs(wide_bvh_kernel kernel)
{
    switch (kernel) {
    case WIDE_BVH_KERNEL_SCALAR:
        return true;
    case WIDE_BVH_KERNEL_SSE:
        return WIDE_BVH_HAVE_SSE;
    case WIDE_BVH_KERNEL_AVX:
#if WIDE_BVH_HAVE_AVX
        return __builtin_cpu_supports("avx");
#else
        return false;
#endif
    }
    return false;
}

bool wide_bvh_set_kernel(accel *a, wide_bvh_kernel kernel)
{
    wide_bvh *b = (wide_bvh *)a;
    if (!wide_bvh_kernel_runs(kernel))
        return false;
#if WIDE_BVH_HAVE_AVX
    /* the quantized nodes' AVX test widens bytes with AVX2 */
    if (kernel == WIDE_BVH_KERNEL_AVX && b->layout == WIDE_BVH_QUANTIZED && !__builtin_cpu_supports("avx2"))
        return false;
#endif
    b->kernel = kernel;
    b->base.ops = &entry_points_of(b->layout, kernel)->ops;
    return true;
}

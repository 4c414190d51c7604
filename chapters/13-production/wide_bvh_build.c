/* wide_bvh_build.c -- a 4-wide BVH by collapsing the binary one: every 4-wide
 * node is a binary node with some of its descendants pulled up, and every
 * leaf's triangles are copied into packets of four. */
#include "13-production/wide_bvh.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "06-bvh/bvh_internal.h"
#include "memory.h"
#include "timer.h"

/* SAH constants for the binary tree the collapse starts from. A packet of
 * four triangles costs one test, so a leaf costs C_i per started block of
 * four: the SAH then prefers leaves that fill their packets (1 or 5
 * triangles cost as much as 4 or 8). C_t = 1: a 4-wide node tests four
 * boxes for the price of one, so a binary level costs less than in the
 * binary tree. At most 8 triangles (two packets) per leaf. On the tori
 * field at 100k, C_t of 0.5, 1, 1.5 and 2 and leaves of at most 4, 6 or 8
 * traced equally fast within the noise of our (loaded) machine; 8 uses the
 * least memory (53.6 bytes per triangle, 59.0 with 4).
 *
 * Except near the root: C_t = 0.25 for the sets whose box has at least a
 * tenth of the root's area. By time alone a binary level is cheap here
 * (a wide node's boxes are tested together, and a packet test costs
 * several node visits), and C_t = 0.25 would pay everywhere but for
 * memory: smaller leaves fill fewer lanes (66 bytes per triangle instead
 * of 57 on the tori field), and on a mesh larger than the cache that cost
 * more than the tests saved. Near the root the sets are few, so memory
 * does not count, and a large share of all rays enters them. What it is
 * for: a room's walls. Their triangles are large, and any two walls that
 * meet span the whole room, so with C_t = 1 the SAH keeps four walls in
 * one leaf as big as the room: every ray tests its two packets. Split,
 * each wall has a flat box of its own, and a ray from inside the room
 * meets only the one it leaves through. On the benchmark's boxes with a
 * mesh in them, packets per ray fell from 2.5 to 1.6 (2.9 to 1.5 with the
 * glass ball) and the tree of the tori field stayed the same. */
static const bvh_sah_params WIDE_BVH_SAH = {1.0f, 4, 8, 0.1f, 0.25f};

typedef struct {
    const bvh_tree *binary; /* the binary tree as chapter 06's recursion built it */
    const triangle_set *set;
    wide_bvh_node *nodes;
    int node_count, node_capacity;
    wide_bvh_packet *packets;
    int packet_count, packet_capacity;
    int leaves, max_depth;
} collapser;

static void set_child_box(wide_bvh_node *node, int k, aabb box)
{
    node->bounds[0][k] = box.lo.x;
    node->bounds[1][k] = box.lo.y;
    node->bounds[2][k] = box.lo.z;
    node->bounds[3][k] = box.hi.x;
    node->bounds[4][k] = box.hi.y;
    node->bounds[5][k] = box.hi.z;
}

/* The tree's arrays, in memory the kernel may map with 2 MB pages. With
 * 4 KB pages, 1 M triangles' 53 MB span 13 000 pages, far more than the
 * processor's address translation cache holds (about 1 500 entries): on
 * incoherent rays nearly every node fetched would first need a page-table
 * walk. In 2 MB pages they span 27. Linux grants such "transparent huge
 * pages" to memory that asks for them with madvise() (when the system
 * setting is "madvise", the common default) and that is 2 MB-aligned.
 * Embree does the same. A hint: if it is refused, nothing changes but the
 * speed. */
enum { HUGE_PAGE = 2 << 20 };

static void *huge_allocate(size_t bytes)
{
    size_t rounded = (bytes + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE;
    void *p = rounded >= HUGE_PAGE && bytes >= HUGE_PAGE / 2 ? aligned_alloc(HUGE_PAGE, rounded)
                                                             : aligned_alloc(64, (bytes + 63) / 64 * 64);
    if (p == NULL) {
        fprintf(stderr, "out of memory (asked for %zu bytes)\n", rounded);
        exit(1);
    }
#ifdef MADV_HUGEPAGE
    if (bytes >= HUGE_PAGE / 2)
        madvise(p, rounded, MADV_HUGEPAGE);
#endif
    return p;
}

static void *huge_copy(const void *data, size_t bytes)
{
    void *p = huge_allocate(bytes);
    memcpy(p, data, bytes);
    return p;
}

/* The array at *data, of *capacity elements of `size` bytes, the first
 * `count` of them in use, with room for at least `needed`: doubled, and
 * copied, when it is short. The collapse fills the tree's arrays where
 * they stay, so a copy happens only when the first guess was short. */
static void *huge_grow(void *data, int *capacity, int count, int needed, size_t size)
{
    if (needed <= *capacity)
        return data;
    int grown = *capacity > 0 ? *capacity : 16;
    while (grown < needed)
        grown *= 2;
    void *p = huge_allocate((size_t)grown * size);
    memcpy(p, data, (size_t)count * size);
    free(data);
    *capacity = grown;
    return p;
}

/* A new node, all slots empty: a box no ray hits, and no triangles. */
static int new_node(collapser *c)
{
    c->nodes = huge_grow(c->nodes, &c->node_capacity, c->node_count, c->node_count + 1, sizeof *c->nodes);
    wide_bvh_node *node = &c->nodes[c->node_count];
    memset(node, 0, sizeof *node); /* the padding too: a tree is the same bytes on every build */
    for (int k = 0; k < WIDE_BVH_WIDTH; k++) {
        set_child_box(node, k, (aabb){vec3_make(INFINITY, INFINITY, INFINITY), vec3_make(-INFINITY, -INFINITY, -INFINITY)});
        node->child[k] = WIDE_BVH_EMPTY;
    }
    return c->node_count++;
}

/* Copy triangles [first, first + count) of the binary tree's leaf order into
 * new packets; returns the leaf's reference, or, for more than WIDE_BVH_LEAF_MAX
 * triangles (only ever many coincident triangles), a node over up to
 * WIDE_BVH_WIDTH smaller leaves with the same box. */
static uint32_t emit_leaf(collapser *c, int first, int count, aabb box, int depth)
{
    if (depth > c->max_depth)
        c->max_depth = depth;
    if (count > WIDE_BVH_LEAF_MAX) {
        int n = new_node(c), part = (count + WIDE_BVH_WIDTH - 1) / WIDE_BVH_WIDTH;
        for (int k = 0; k < WIDE_BVH_WIDTH && k * part < count; k++) {
            int size = count - k * part < part ? count - k * part : part;
            uint32_t ref = emit_leaf(c, first + k * part, size, box, depth + 1);
            set_child_box(&c->nodes[n], k, box);
            c->nodes[n].child[k] = ref;
        }
        return (uint32_t)n;
    }
    int packets = (count + 3) / 4;
    int p = c->packet_count;
    if (p + packets >= (1 << WIDE_BVH_PACKET_SHIFT)) {
        fprintf(stderr, "wide BVH: more than %d packets of triangles\n", 1 << WIDE_BVH_PACKET_SHIFT);
        exit(1);
    }
    c->packets = huge_grow(c->packets, &c->packet_capacity, p, p + packets, sizeof *c->packets);
    c->packet_count += packets;
    memset(&c->packets[p], 0, (size_t)packets * sizeof *c->packets);
    for (int i = 0; i < 4 * packets; i++) {
        int lane = i % 4;
        wide_bvh_packet *packet = &c->packets[p + i / 4];
        if (i >= count) {
            packet->index[lane] = -1;
            continue;
        }
        /* the triangle's index now; its coordinates once the packets are
         * in place (wide_bvh_packets_fill) */
        packet->index[lane] = c->binary->triangle_index[first + i];
    }
    c->leaves++;
    return WIDE_BVH_LEAF | (uint32_t)count << WIDE_BVH_PACKET_SHIFT | (uint32_t)p;
}


/* Fill node n, already allocated, as the 4-wide node standing for binary
 * interior node `binary_node`: start from its two children and, while there
 * are fewer than WIDE_BVH_WIDTH, replace the interior one with the largest
 * surface area (the one a ray is most likely to enter) by its two children. Order
 * is kept: a child's two children take its place, side by side. The nodes
 * of its interior children are allocated together, before any of their
 * own children: a node's children are neighbours in memory, so the fetches
 * of the children hit at a node land on nearby lines and pages. */
static void collapse_interior(collapser *c, int binary_node, int n, int depth)
{
    if (depth > c->max_depth)
        c->max_depth = depth;
    const bvh_node *nodes = c->binary->nodes;
    int kids[WIDE_BVH_WIDTH] = {nodes[binary_node].first, nodes[binary_node].first + 1};
    int count = 2;
    while (count < WIDE_BVH_WIDTH) {
        int best = -1;
        double best_area = -1.0;
        for (int k = 0; k < count; k++) {
            const bvh_node *kid = &nodes[kids[k]];
            if (bvh_node_is_leaf(kid))
                continue;
            double area = aabb_surface_area(kid->box);
            if (area > best_area) {
                best_area = area;
                best = k;
            }
        }
        if (best < 0)
            break;
        int first = nodes[kids[best]].first;
        for (int k = count; k > best + 1; k--)
            kids[k] = kids[k - 1];
        kids[best] = first;
        kids[best + 1] = first + 1;
        count++;
    }
    int kid_node[WIDE_BVH_WIDTH];
    for (int k = 0; k < count; k++)
        kid_node[k] = bvh_node_is_leaf(&nodes[kids[k]]) ? -1 : new_node(c);
    for (int k = 0; k < count; k++) {
        const bvh_node *kid = &nodes[kids[k]];
        uint32_t ref;
        if (kid_node[k] >= 0) {
            collapse_interior(c, kids[k], kid_node[k], depth + 1);
            ref = (uint32_t)kid_node[k];
        } else {
            ref = emit_leaf(c, kid->first, bvh_node_triangles(kid), kid->box, depth + 1);
        }
        /* c->nodes may have moved: index it again */
        set_child_box(&c->nodes[n], k, kid->box);
        c->nodes[n].child[k] = ref;
    }
}

/* ---- the lanes' coordinates ------------------------------------------------------ */

bool wide_bvh_lane_coordinates(const triangle *tri, triangle_test test, float p0[3], float v1[3], float v2[3])
{
    if (test == TRIANGLE_TEST_MOLLER_TRUMBORE) {
        if (tri == NULL) {
            for (int axis = 0; axis < 3; axis++)
                p0[axis] = v1[axis] = v2[axis] = 0.0f;
            return true;
        }
        /* E1 and E2 exactly as bvh_triangle_make() and chapter 01 compute
         * them; exact if they give P1 and P2 back, the same bits (== would
         * take -0 for +0) */
        vec3 e1 = vec3_sub(tri->p1, tri->p0), e2 = vec3_sub(tri->p2, tri->p0);
        vec3 p1 = vec3_add(tri->p0, e1), p2 = vec3_add(tri->p0, e2);
        memcpy(p0, &tri->p0, 3 * sizeof(float));
        memcpy(v1, &e1, 3 * sizeof(float));
        memcpy(v2, &e2, 3 * sizeof(float));
        return memcmp(&p1, &tri->p1, sizeof p1) == 0 && memcmp(&p2, &tri->p2, sizeof p2) == 0;
    }
    if (tri == NULL || triangle_is_degenerate(tri)) {
        for (int axis = 0; axis < 3; axis++)
            p0[axis] = v1[axis] = v2[axis] = NAN;
        return true;
    }
    memcpy(p0, &tri->p0, 3 * sizeof(float));
    memcpy(v1, &tri->p1, 3 * sizeof(float));
    memcpy(v2, &tri->p2, 3 * sizeof(float));
    return true;
}

void wide_bvh_packet_set_lane(wide_bvh_packet *packet, int k, const triangle *tri, int index, triangle_test test)
{
    float p0[3], v1[3], v2[3]; /* P0 and the corners P1, P2 or the edges E1, E2 */
    bool exact = wide_bvh_lane_coordinates(tri, test, p0, v1, v2);
    for (int axis = 0; axis < 3; axis++) {
        packet->p0[axis][k] = p0[axis];
        packet->p1[axis][k] = v1[axis]; /* p1 and e1 are the same floats (wide_bvh.h) */
        packet->p2[axis][k] = v2[axis];
    }
    packet->index[k] = index < 0 ? -1 : index | (exact ? WIDE_BVH_LANE_EXACT : 0);
}

bool wide_bvh_use_triangle_test(accel *a, triangle_test test)
{
    wide_bvh *b = (wide_bvh *)a;
    a->triangle_test = test;
    /* each lane its own: any thread count writes the same packets */
#pragma omp parallel for schedule(static) if (b->packet_count >= 1024)
    for (int i = 0; i < 4 * b->packet_count; i++) {
        wide_bvh_packet *packet = &b->packets[i / 4];
        int index = wide_bvh_lane_triangle(packet->index[i % 4]);
        wide_bvh_packet_set_lane(packet, i % 4, index >= 0 ? &a->set->triangles[index] : NULL, index, test);
    }
    return true;
}

/* The exact nodes quantized, or false (and nothing changed) if a node's
 * box is not finite. The exact nodes are then freed: they are not read
 * again. */
static bool quantize_nodes(wide_bvh *b)
{
    size_t bytes = (size_t)b->node_count * sizeof(wide_bvh_qnode);
    wide_bvh_qnode *q = aligned_alloc(64, (bytes + 63) / 64 * 64);
    if (q == NULL) {
        fprintf(stderr, "out of memory (asked for %zu bytes)\n", bytes);
        exit(1);
    }
    memset(q, 0, bytes); /* the 4-wide node's padding too */
    for (int n = 0; n < b->node_count; n++) {
        const wide_bvh_node *node = &b->nodes[n];
        if (!wide_bvh_quantize_node(node, WIDE_BVH_ROUND_OUTWARD, &q[n])) {
            free(q);
            return false;
        }
    }
    b->qnodes = huge_copy(q, bytes);
    free(q);
    free(b->nodes);
    b->nodes = NULL;
    b->layout = WIDE_BVH_QUANTIZED;
    return true;
}

static accel *build_tree(const triangle_set *set, bvh_split split, float top_area_fraction, wide_bvh_layout layout);

accel *wide_bvh_build(const triangle_set *set, bvh_split split)
{
    return build_tree(set, split, WIDE_BVH_SAH.top_area_fraction, WIDE_BVH_DEFAULT_LAYOUT);
}

accel *wide_bvh_build_layout(const triangle_set *set, bvh_split split, wide_bvh_layout layout)
{
    return build_tree(set, split, WIDE_BVH_SAH.top_area_fraction, layout);
}

accel *wide_bvh_build_with_top(const triangle_set *set, bvh_split split, float top_area_fraction)
{
    return build_tree(set, split, top_area_fraction, WIDE_BVH_DEFAULT_LAYOUT);
}

static accel *build_tree(const triangle_set *set, bvh_split split, float top_area_fraction, wide_bvh_layout layout)
{
    double start = timer_seconds();
    bvh_sah_params sah = WIDE_BVH_SAH;
    sah.top_area_fraction = top_area_fraction;
    bvh_tree binary_tree;
    bvh_tree_build(set, split, &sah, &binary_tree);
    const bvh_tree *binary = &binary_tree;

    wide_bvh *b = memory_allocate(1, sizeof *b);
    b->base.ops = wide_bvh_default_ops();
    b->base.set = set;
    b->kernel = WIDE_BVH_HAVE_SSE ? WIDE_BVH_KERNEL_SSE : WIDE_BVH_KERNEL_SCALAR;
    b->triangle_count = set->count;

    collapser c = {binary, set, NULL, 0, 0, NULL, 0, 0, 0, 0};
    if (set->count >= WIDE_BVH_LANE_EXACT) {
        fprintf(stderr, "wide BVH: more than %d triangles\n", WIDE_BVH_LANE_EXACT - 1);
        exit(1);
    }
    if (set->count > 0) {
        /* A node for every sixteen triangles or fewer (leaves of four to
         * eight, up to WIDE_BVH_WIDTH children a node): room for one in
         * eight; the array grows if that is not enough. Room not used is
         * never touched, so the system gives it no memory. */
        c.node_capacity = set->count / 8 + 4;
        c.nodes = huge_allocate((size_t)c.node_capacity * sizeof *c.nodes);
        /* Leaves do not fill every packet (95 % of lanes on the tori field):
         * room for 75 %, so that the array (a copy of every triangle) is
         * not copied again as it grows, nearly always. */
        c.packet_capacity = set->count / 3 + 16;
        c.packets = huge_allocate((size_t)c.packet_capacity * sizeof *c.packets);
        const bvh_node *root = &binary->nodes[0];
        if (bvh_node_is_leaf(root)) {
            /* one leaf: a root node with one child */
            int n = new_node(&c);
            uint32_t ref = emit_leaf(&c, root->first, bvh_node_triangles(root), root->box, 1);
            set_child_box(&c.nodes[n], 0, root->box);
            c.nodes[n].child[0] = ref;
        } else {
            collapse_interior(&c, 0, new_node(&c), 0);
        }
    }
    for (int n = 0; n < c.node_count; n++) {
        wide_bvh_node *node = &c.nodes[n];
        node->children = 0;
        for (int k = 0; k < WIDE_BVH_WIDTH; k++)
            node->children += node->child[k] != WIDE_BVH_EMPTY;
    }
    b->node_count = c.node_count;
    b->packet_count = c.packet_count;
    /* in place: the arrays were allocated for the finished tree */
    b->nodes = c.node_count > 0 ? c.nodes : NULL;
    b->packets = c.packet_count > 0 ? c.packets : NULL;
    if (b->nodes == NULL)
        free(c.nodes);
    if (b->packets == NULL)
        free(c.packets);
    bvh_tree_free(&binary_tree);
    if (layout == WIDE_BVH_QUANTIZED && b->node_count > 0)
        quantize_nodes(b);
    wide_bvh_use_triangle_test(&b->base, TRIANGLE_TEST_WATERTIGHT); /* the lanes' coordinates */
    wide_bvh_set_kernel(&b->base, b->kernel); /* the kernel's ops for the layout */
    if (wide_bvh_kernel_runs(WIDE_BVH_KERNEL_AVX))
        wide_bvh_set_kernel(&b->base, WIDE_BVH_KERNEL_AVX);

    b->base.stats.name = split == BVH_SPLIT_SAH ? "wide bvh sah" : "wide bvh median";
    size_t node_bytes = b->layout == WIDE_BVH_QUANTIZED ? sizeof(wide_bvh_qnode) : sizeof(wide_bvh_node);
    b->base.stats.bytes = sizeof *b + (size_t)b->node_count * node_bytes +
                          (size_t)b->packet_count * sizeof(wide_bvh_packet);
    b->base.stats.nodes = b->node_count;
    b->base.stats.leaves = c.leaves;
    b->base.stats.max_depth = c.max_depth;
    b->base.stats.references = set->count;
    b->base.stats.build_seconds = timer_seconds() - start;
    return &b->base;
}

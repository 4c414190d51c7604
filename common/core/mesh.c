/* mesh.c -- the mesh container and the procedural meshes (OBJ is in obj.c). */
#include "mesh.h"

#include <stdlib.h>
#include <string.h>

#include "memory.h"

void mesh_init(mesh *m) { memset(m, 0, sizeof *m); }

void mesh_free(mesh *m)
{
    free(m->positions);
    free(m->normals);
    free(m->texcoords);
    free(m->faces);
    free(m->materials);
    memset(m, 0, sizeof *m);
}

int mesh_add_position(mesh *m, vec3 p)
{
    m->positions = memory_grow(m->positions, &m->position_capacity, m->position_count + 1, sizeof(vec3));
    m->positions[m->position_count] = p;
    return m->position_count++;
}

int mesh_add_normal(mesh *m, vec3 n)
{
    m->normals = memory_grow(m->normals, &m->normal_capacity, m->normal_count + 1, sizeof(vec3));
    m->normals[m->normal_count] = n;
    return m->normal_count++;
}

int mesh_add_texcoord(mesh *m, float u, float v)
{
    /* capacity counts texcoords; each takes two floats */
    m->texcoords = memory_grow(m->texcoords, &m->texcoord_capacity, m->texcoord_count + 1, 2 * sizeof(float));
    m->texcoords[2 * m->texcoord_count] = u;
    m->texcoords[2 * m->texcoord_count + 1] = v;
    return m->texcoord_count++;
}

int mesh_add_triangle(mesh *m, int a, int b, int c, int material)
{
    m->faces = memory_grow(m->faces, &m->face_capacity, m->face_count + 1, sizeof(mesh_face));
    m->faces[m->face_count] = (mesh_face){{a, b, c}, {-1, -1, -1}, {-1, -1, -1}, material};
    return m->face_count++;
}

int mesh_add_material(mesh *m, const mesh_material *material)
{
    m->materials = memory_grow(m->materials, &m->material_capacity, m->material_count + 1, sizeof(mesh_material));
    m->materials[m->material_count] = *material;
    return m->material_count++;
}

bool mesh_bounds(const mesh *m, vec3 *lo, vec3 *hi)
{
    if (m->face_count == 0)
        return false;
    *lo = vec3_splat(INFINITY);
    *hi = vec3_splat(-INFINITY);
    for (int i = 0; i < m->face_count; i++)
        for (int k = 0; k < 3; k++) {
            vec3 p = mesh_vertex(m, i, k);
            *lo = vec3_min(*lo, p);
            *hi = vec3_max(*hi, p);
        }
    return true;
}

/* ---- icosphere ------------------------------------------------------------ */

/* The midpoint of edge (a, b) pushed onto the sphere, created once per edge:
 * both triangles that share the edge must use the same vertex, or the mesh
 * would have cracks (and would not be closed). A small open-addressing table
 * keyed by the edge's two vertex indices remembers them. */
typedef struct {
    int64_t *keys;
    int *values;
    size_t capacity;
} edge_table;

static int edge_midpoint(mesh *m, edge_table *table, int a, int b, vec3 center, float radius)
{
    int lo = a < b ? a : b, hi = a < b ? b : a;
    int64_t key = ((int64_t)lo << 32) | (int64_t)hi;
    size_t slot = (size_t)((uint64_t)key * 0x9e3779b97f4a7c15ULL >> 20) & (table->capacity - 1);
    while (table->keys[slot] != -1) {
        if (table->keys[slot] == key)
            return table->values[slot];
        slot = (slot + 1) & (table->capacity - 1);
    }
    vec3 mid = vec3_scale(vec3_add(vec3_sub(m->positions[a], center), vec3_sub(m->positions[b], center)), 0.5f);
    int index = mesh_add_position(m, vec3_add(center, vec3_scale(vec3_normalize(mid), radius)));
    table->keys[slot] = key;
    table->values[slot] = index;
    return index;
}

void mesh_icosphere(mesh *m, vec3 center, float radius, int subdivisions, int material)
{
    /* The icosahedron: the 12 vertices (0, +-1, +-g) and their cyclic
     * permutations, g the golden ratio. */
    const float g = 1.6180339887f;
    const float corners[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                  {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    const int faces[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                              {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                              {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    int base = m->position_count;
    for (int i = 0; i < 12; i++)
        mesh_add_position(m, vec3_add(center, vec3_scale(vec3_normalize(vec3_make(corners[i][0], corners[i][1],
                                                                                       corners[i][2])),
                                                         radius)));
    int count = 20;
    int (*tris)[3] = memory_allocate((size_t)count, sizeof *tris);
    for (int i = 0; i < 20; i++)
        for (int k = 0; k < 3; k++)
            tris[i][k] = base + faces[i][k];

    /* Each subdivision splits every triangle into four at its edge midpoints. */
    for (int s = 0; s < subdivisions; s++) {
        edge_table table;
        table.capacity = 64;
        while (table.capacity < (size_t)count * 4)
            table.capacity *= 2;
        table.keys = memory_allocate(table.capacity, sizeof *table.keys);
        table.values = memory_allocate(table.capacity, sizeof *table.values);
        memset(table.keys, 0xff, table.capacity * sizeof *table.keys); /* all -1: empty */
        int (*next)[3] = memory_allocate((size_t)count * 4, sizeof *next);
        for (int i = 0; i < count; i++) {
            int a = tris[i][0], b = tris[i][1], c = tris[i][2];
            int ab = edge_midpoint(m, &table, a, b, center, radius);
            int bc = edge_midpoint(m, &table, b, c, center, radius);
            int ca = edge_midpoint(m, &table, c, a, center, radius);
            int *out = next[4 * i];
            out[0] = a, out[1] = ab, out[2] = ca;
            out = next[4 * i + 1];
            out[0] = b, out[1] = bc, out[2] = ab;
            out = next[4 * i + 2];
            out[0] = c, out[1] = ca, out[2] = bc;
            out = next[4 * i + 3];
            out[0] = ab, out[1] = bc, out[2] = ca;
        }
        free(table.keys);
        free(table.values);
        free(tris);
        tris = next;
        count *= 4;
    }
    for (int i = 0; i < count; i++)
        mesh_add_triangle(m, tris[i][0], tris[i][1], tris[i][2], material);
    free(tris);
}

/* ---- torus ---------------------------------------------------------------- */

void mesh_torus(mesh *m, vec3 center, vec3 axis, float major, float minor, int u_segments, int v_segments,
                int material)
{
    vec3 e1, e2;
    vec3_basis(vec3_normalize(axis), &e1, &e2);
    axis = vec3_normalize(axis);
    int base = m->position_count;
    for (int i = 0; i < u_segments; i++) {
        float a = 2.0f * (float)PI * (float)i / (float)u_segments;
        vec3 radial = vec3_add(vec3_scale(e1, cosf(a)), vec3_scale(e2, sinf(a)));
        for (int j = 0; j < v_segments; j++) {
            float b = 2.0f * (float)PI * (float)j / (float)v_segments;
            vec3 p = vec3_add(center, vec3_add(vec3_scale(radial, major + minor * cosf(b)),
                                               vec3_scale(axis, minor * sinf(b))));
            mesh_add_position(m, p);
        }
    }
    for (int i = 0; i < u_segments; i++)
        for (int j = 0; j < v_segments; j++) {
            int a = base + i * v_segments + j, b = base + ((i + 1) % u_segments) * v_segments + j;
            int c = base + ((i + 1) % u_segments) * v_segments + (j + 1) % v_segments;
            int d = base + i * v_segments + (j + 1) % v_segments;
            mesh_add_triangle(m, a, b, c, material);
            mesh_add_triangle(m, a, c, d, material);
        }
}

/* ---- the tori field of shared/anchors/embree_bench.c ----------------------
 * Reproduced operation for operation, including where the harness computes in
 * double and where in float, so that every vertex is bit-identical to the
 * one Embree is timed on (tests/test_ch03.c compares against its OBJ output
 * when the harness is available). */

static uint64_t splitmix64_next(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double splitmix64_uniform(uint64_t *state)
{
    return (double)(splitmix64_next(state) >> 11) * (1.0 / 9007199254740992.0);
}

static vec3 tori_cross(vec3 a, vec3 b)
{
    return vec3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

void mesh_tori_field(mesh *m, long target_triangles)
{
    int u, v;
    if (target_triangles <= 1024)
        u = 8, v = 4;
    else if (target_triangles <= 10240)
        u = 20, v = 16;
    else if (target_triangles <= 102400)
        u = 80, v = 40;
    else
        u = 256, v = 128;
    const int tori = 16;
    uint64_t state = 0x5EED;
    for (int k = 0; k < tori; k++) {
        /* The harness writes mk(2*urand()-1, 2*urand()-1, 2*urand()-1); GCC
         * evaluates those arguments right to left, so z is drawn first. */
        double cz = 2 * splitmix64_uniform(&state) - 1;
        double cy = 2 * splitmix64_uniform(&state) - 1;
        double cx = 2 * splitmix64_uniform(&state) - 1;
        vec3 c = vec3_make((float)cx, (float)cy, (float)cz);
        float major = (float)(0.30 + 0.20 * splitmix64_uniform(&state));
        float minor = (float)(major * (0.30 + 0.15 * splitmix64_uniform(&state)));
        float z = (float)(2 * splitmix64_uniform(&state) - 1);
        float phi = (float)(2 * PI * splitmix64_uniform(&state));
        float s = sqrtf(1 - z * z);
        vec3 axis = vec3_make(s * cosf(phi), s * sinf(phi), z);
        vec3 t0 = fabsf(axis.x) > 0.5f ? vec3_make(0, 1, 0) : vec3_make(1, 0, 0);
        vec3 e1 = tori_cross(axis, t0);
        e1 = vec3_scale(e1, 1.0f / sqrtf(vec3_dot(e1, e1)));
        vec3 e2 = tori_cross(axis, e1);
        int base = m->position_count;
        for (int i = 0; i < u; i++) {
            float a = (float)(2 * PI * i / u);
            vec3 radial = vec3_add(vec3_scale(e1, cosf(a)), vec3_scale(e2, sinf(a)));
            for (int j = 0; j < v; j++) {
                float b = (float)(2 * PI * j / v);
                vec3 p = vec3_add(c, vec3_add(vec3_scale(radial, major + minor * cosf(b)),
                                              vec3_scale(axis, minor * sinf(b))));
                mesh_add_position(m, p);
            }
        }
        for (int i = 0; i < u; i++)
            for (int j = 0; j < v; j++) {
                int a = base + i * v + j, b = base + ((i + 1) % u) * v + j;
                int c2 = base + ((i + 1) % u) * v + (j + 1) % v, d = base + i * v + (j + 1) % v;
                mesh_add_triangle(m, a, b, c2, -1);
                mesh_add_triangle(m, a, c2, d, -1);
            }
    }
}

/* ---- random soup, teapot in a stadium, coincident ------------------------- */

void mesh_random_soup(mesh *m, int n, vec3 lo, vec3 hi, float size, uint64_t seed)
{
    uint64_t state = seed;
    vec3 extent = vec3_sub(hi, lo);
    for (int i = 0; i < n; i++) {
        vec3 centre = vec3_make(lo.x + extent.x * (float)splitmix64_uniform(&state),
                                lo.y + extent.y * (float)splitmix64_uniform(&state),
                                lo.z + extent.z * (float)splitmix64_uniform(&state));
        int corner[3];
        for (int k = 0; k < 3; k++) {
            vec3 offset = vec3_make((float)splitmix64_uniform(&state) - 0.5f, (float)splitmix64_uniform(&state) - 0.5f,
                                    (float)splitmix64_uniform(&state) - 0.5f);
            corner[k] = mesh_add_position(m, vec3_add(centre, vec3_scale(offset, size)));
        }
        mesh_add_triangle(m, corner[0], corner[1], corner[2], -1);
    }
}

static void add_quad(mesh *m, vec3 a, vec3 b, vec3 c, vec3 d)
{
    int ia = mesh_add_position(m, a), ib = mesh_add_position(m, b);
    int ic = mesh_add_position(m, c), id = mesh_add_position(m, d);
    mesh_add_triangle(m, ia, ib, ic, -1);
    mesh_add_triangle(m, ia, ic, id, -1);
}

void mesh_teapot_in_stadium(mesh *m, int subdivisions, float stadium_size)
{
    /* The teapot: a dense closed mesh of radius 1 at the centre. */
    mesh_icosphere(m, vec3_make(0, 1, 0), 1.0f, subdivisions, -1);
    /* The stadium: a ground quad and four walls, each two big triangles. */
    float h = 0.5f * stadium_size;
    vec3 g0 = vec3_make(-h, 0, -h), g1 = vec3_make(h, 0, -h), g2 = vec3_make(h, 0, h), g3 = vec3_make(-h, 0, h);
    vec3 up = vec3_make(0, 0.25f * stadium_size, 0);
    add_quad(m, g3, g2, g1, g0);
    add_quad(m, g0, g1, vec3_add(g1, up), vec3_add(g0, up));
    add_quad(m, g1, g2, vec3_add(g2, up), vec3_add(g1, up));
    add_quad(m, g2, g3, vec3_add(g3, up), vec3_add(g2, up));
    add_quad(m, g3, g0, vec3_add(g0, up), vec3_add(g3, up));
}

void mesh_coincident(mesh *m, int n)
{
    int a = mesh_add_position(m, vec3_make(-1, -1, 0));
    int b = mesh_add_position(m, vec3_make(1, -1, 0));
    int c = mesh_add_position(m, vec3_make(0, 1, 0));
    for (int i = 0; i < n; i++)
        mesh_add_triangle(m, a, b, c, -1);
}

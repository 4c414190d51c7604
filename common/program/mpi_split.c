/* mpi_split.c -- one render across MPI ranks (see mpi_split.h). Without
 * RENDER_MPI every function is the one-rank case, so the programs are the
 * same source in both builds. */
#include "mpi_split.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef RENDER_MPI
#include <mpi.h>
#endif

#include "memory.h"

static int split_rank = 0, split_ranks = 1;
static bool started, in_collective;

bool mpi_split_available(void)
{
#ifdef RENDER_MPI
    return true;
#else
    return false;
#endif
}

int mpi_split_rank(void) { return split_rank; }
int mpi_split_ranks(void) { return split_ranks; }
bool mpi_split_is_root(void) { return split_rank == 0; }
bool mpi_split_owns_row(int y) { return y % split_ranks == split_rank; }

void mpi_split_enter_collective(void) { in_collective = split_ranks > 1; }
void mpi_split_exit_collective(void) { in_collective = false; }

#ifdef RENDER_MPI

/* At exit: MPI_Finalize, which waits for every rank; or, when this rank
 * leaves in the middle of a split render (an error, out of memory), the
 * others are waiting for its rows at the next gather and would wait for
 * ever, so it stops them all. */
static void split_at_exit(void)
{
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (finalized)
        return;
    if (in_collective) {
        fprintf(stderr, "rank %d of %d failed in the middle of the render: stopping every rank\n", split_rank,
                split_ranks);
        fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    MPI_Finalize();
}

void mpi_split_begin(void)
{
    if (started)
        return;
    started = true;
    int provided = 0;
    /* Funneled: OpenMP threads render, only the main thread talks MPI. */
    MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &split_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &split_ranks);
    atexit(split_at_exit);
}

/* The rows rank r owns: r, r + N, r + 2N, ... */
static int rows_of_rank(int r, int rows_count) { return r < rows_count ? (rows_count - r + split_ranks - 1) / split_ranks : 0; }

void mpi_split_gather_rows(void *rows, size_t row_bytes, int rows_count)
{
    if (split_ranks == 1)
        return;
    unsigned char *data = rows;
    /* Each rank packs its own rows one after the other; MPI_Allgatherv
     * puts rank 0's block first, then rank 1's, ...; unpacking puts block
     * r's k-th row back at row r + k N. */
    int *counts = memory_allocate((size_t)split_ranks, sizeof *counts), *offsets = memory_allocate((size_t)split_ranks, sizeof *offsets);
    size_t total = 0;
    for (int r = 0; r < split_ranks; r++) {
        size_t bytes = (size_t)rows_of_rank(r, rows_count) * row_bytes;
        if (bytes > (size_t)0x7fffffff || total > (size_t)0x7fffffff) {
            fprintf(stderr, "rank %d: an image of %zu bytes per rank is more than one MPI message holds\n", split_rank,
                    bytes);
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
        counts[r] = (int)bytes;
        offsets[r] = (int)total;
        total += bytes;
    }
    unsigned char *packed = memory_allocate(total > 0 ? total : 1, 1);
    unsigned char *mine = packed + offsets[split_rank];
    for (int y = split_rank, k = 0; y < rows_count; y += split_ranks, k++)
        memcpy(mine + (size_t)k * row_bytes, data + (size_t)y * row_bytes, row_bytes);
    MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_BYTE, packed, counts, offsets, MPI_BYTE, MPI_COMM_WORLD);
    for (int r = 0; r < split_ranks; r++)
        for (int y = r, k = 0; y < rows_count; y += split_ranks, k++)
            memcpy(data + (size_t)y * row_bytes, packed + offsets[r] + (size_t)k * row_bytes, row_bytes);
    free(packed);
    free(counts);
    free(offsets);
}

void mpi_split_barrier(void)
{
    if (split_ranks > 1)
        MPI_Barrier(MPI_COMM_WORLD);
}

void mpi_split_sum_counters(ray_counters *c)
{
    if (split_ranks == 1)
        return;
    enum { FIELDS = sizeof(ray_counters) / sizeof(uint64_t) };
    _Static_assert(sizeof(ray_counters) == FIELDS * sizeof(uint64_t), "ray_counters holds uint64_t only");
    MPI_Allreduce(MPI_IN_PLACE, c, FIELDS, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
}

void mpi_split_broadcast(void *data, size_t bytes)
{
    if (split_ranks == 1)
        return;
    unsigned char *p = data;
    /* in pieces below MPI's int count */
    for (size_t done = 0; done < bytes;) {
        size_t piece = bytes - done < (size_t)1 << 30 ? bytes - done : (size_t)1 << 30;
        MPI_Bcast(p + done, (int)piece, MPI_BYTE, 0, MPI_COMM_WORLD);
        done += piece;
    }
}

#else /* one rank */

void mpi_split_begin(void) { started = true; }
void mpi_split_gather_rows(void *rows, size_t row_bytes, int rows_count)
{
    (void)rows;
    (void)row_bytes;
    (void)rows_count;
}
void mpi_split_barrier(void) {}
void mpi_split_sum_counters(ray_counters *c) { (void)c; }
void mpi_split_broadcast(void *data, size_t bytes)
{
    (void)data;
    (void)bytes;
}

#endif

int mpi_split_broadcast_int(int value)
{
    mpi_split_broadcast(&value, sizeof value);
    return value;
}

bool mpi_split_refuse(const char *label, const char *what)
{
    if (split_ranks == 1)
        return false;
    if (split_rank == 0)
        fprintf(stderr, "%s: %s is not split across MPI ranks: run it as one process (without mpirun, or -np 1)\n",
                label, what);
    return true;
}

bool mpi_split_leave(void)
{
    bool root = split_rank == 0;
    split_rank = 0;
    split_ranks = 1;
    return root;
}

/* mpi_split.h -- one render split across processes, on one machine or many
 * (MPI, "ranks"): each rank renders some of the image's rows, and every
 * rank then holds the whole image; only rank 0 writes files and reports.
 *
 * Usage (a program that runs under `mpirun -np N`):
 *   cli_parse_or_exit(...)            starts MPI (mpi_split_begin) and makes every rank but 0 quiet
 *   if (mpi_split_refuse(PROGRAM, "--bench")) return 2;   a mode that is not split
 *   ... render_image() renders only the rows mpi_split_owns_row() gives this rank,
 *       then mpi_split_gather_rows() hands every rank all of them
 *   if (mpi_split_is_root()) write the image;
 *
 * Rows are dealt out in turn (row y to rank y mod N), so each rank gets
 * some of the sky and some of the glass. A pixel is computed whole by one
 * rank, with its own random stream (rng.h) and its samples summed in the
 * same order as in one process: gathering copies finished pixels, it adds
 * nothing, so the image is the same bit for bit for any number of ranks
 * and threads. Counters are integers, summed exactly in any order.
 *
 * Built two ways: the normal build compiles the one-rank version of every
 * function here (no MPI needed: rank 0 of 1, gathers do nothing); `make mpi`
 * builds with -DRENDER_MPI against OpenMPI into build/mpi/. A failing rank
 * (mpi_split_fail, or an exit in the middle of a split render) aborts the
 * whole run through MPI_Abort, naming its rank; a rank that is killed is
 * named by mpirun, which then stops the others. Either way rank 0 has
 * written nothing of the render, and the last checkpoint stays.
 */
#ifndef MPI_SPLIT_H
#define MPI_SPLIT_H

#include <stdbool.h>
#include <stddef.h>

#include "counters.h"

/* Starts MPI if the program was built with it (idempotent; MPI_Finalize
 * runs at exit). Called by cli_parse_or_exit. */
void mpi_split_begin(void);
/* This process's rank and the number of ranks (0 and 1 without MPI, and
 * after mpi_split_leave). */
int mpi_split_rank(void);
int mpi_split_ranks(void);
bool mpi_split_is_root(void);
/* Whether this rank renders row y. */
bool mpi_split_owns_row(int y);
/* Whether the MPI build was compiled in (for --help and the record). */
bool mpi_split_available(void);

/* Every rank passes its buffer of `rows` rows of `row_bytes` bytes, with
 * the rows it owns filled in; afterwards every rank's buffer holds every
 * row. Rank order is fixed and nothing is added, so the result is exact. */
void mpi_split_gather_rows(void *rows, size_t row_bytes, int rows_count);
/* Waits until every rank is here (for timing the gather apart from the
 * wait for the slowest rank). */
void mpi_split_barrier(void);
/* Sums every rank's counters into every rank's (exact: integers). */
void mpi_split_sum_counters(ray_counters *c);
/* Rank 0's value of a byte buffer, on every rank (a decision only rank 0
 * may take, such as one made by its clock, or a file only it read). */
void mpi_split_broadcast(void *data, size_t bytes);
/* Rank 0's int, on every rank. */
int mpi_split_broadcast_int(int value);

/* If the program runs on more than one rank, rank 0 says that `what`
 * does not split across ranks and this returns true (the caller returns
 * status 2 on every rank); false on one rank. */
bool mpi_split_refuse(const char *label, const char *what);
/* From here on this process works alone (rank 0 of 1): for what rank 0
 * does after the split part, such as measuring against a reference the
 * ranks made together. Returns whether this process is the one that goes
 * on (rank 0); the others should stop. */
bool mpi_split_leave(void);

/* Marks the part of the run in which every rank must reach the next
 * gather: an exit inside it aborts all ranks with a message naming this
 * one, rather than leaving the others waiting. */
void mpi_split_enter_collective(void);
void mpi_split_exit_collective(void);

#endif

#include "memory.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

static void out_of_memory(size_t bytes)
{
    fprintf(stderr, "out of memory (asked for %zu bytes)\n", bytes);
    exit(1);
}

/* The whole pages inside the array: madvise() takes page-aligned ranges, and
 * the kernel maps a 2 MB page only where a whole aligned 2 MB stretch lies in
 * the range, when it is first touched (calloc's fresh memory is untouched).
 * Pages shared with a neighbouring allocation only get the same hint. */
void memory_advise_huge(void *p, size_t bytes)
{
#if defined(MADV_HUGEPAGE)
    if (bytes < MEMORY_HUGE_PAGE)
        return;
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE);
    uintptr_t start = ((uintptr_t)p + page - 1) / page * page, end = (uintptr_t)p + bytes;
    if (end > start)
        madvise((void *)start, end - start, MADV_HUGEPAGE);
#else
    (void)p;
    (void)bytes;
#endif
}

void *memory_allocate(size_t count, size_t size)
{
    void *p = calloc(count == 0 ? 1 : count, size == 0 ? 1 : size);
    if (p == NULL)
        out_of_memory(count * size);
    return p;
}

void *memory_grow(void *items, int *capacity, int needed, size_t item_size)
{
    if (needed <= *capacity)
        return items;
    int grown = *capacity < 8 ? 8 : *capacity;
    while (grown < needed) {
        if (grown > INT32_MAX / 2)
            out_of_memory((size_t)needed * item_size);
        grown *= 2;
    }
    void *p = realloc(items, (size_t)grown * item_size);
    if (p == NULL)
        out_of_memory((size_t)grown * item_size);
    *capacity = grown;
    memory_advise_huge(p, (size_t)grown * item_size);
    return p;
}

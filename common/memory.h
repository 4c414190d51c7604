/* memory.h -- allocation that either succeeds or stops the program with a
 * message. A renderer out of memory has nothing sensible left to do, and
 * checking every small allocation by hand would bury the lecture's code. */
#ifndef MEMORY_H
#define MEMORY_H

#include <stddef.h>

void *memory_allocate(size_t count, size_t size); /* zeroed, like calloc */
/* Make room for at least `needed` items in a growing array: doubles the
 * capacity when it runs out. Returns the (possibly moved) array. */
void *memory_grow(void *items, int *capacity, int needed, size_t item_size);

/* Ask the kernel to back [p, p + bytes) with 2 MB pages where it can
 * (Linux's madvise(MADV_HUGEPAGE)); only a hint, ignored elsewhere and for
 * arrays smaller than a huge page. Both functions above do it for the arrays
 * they allocate: see chapter 06's README on why big arrays that rays read at
 * random want it. */
enum { MEMORY_HUGE_PAGE = 2 << 20 };
void memory_advise_huge(void *p, size_t bytes);

#endif

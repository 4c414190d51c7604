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
 * arrays smaller than a huge page. For arrays that rays read at random (see
 * chapter 06's README): memory_grow() asks for every array it grows (a
 * mesh's), triangle_set_from_mesh() for the set. Not memory_allocate(): the
 * builders' short-lived arrays would pay for 2 MB pages (the kernel may
 * compact memory to find one) and gain nothing. */
enum { MEMORY_HUGE_PAGE = 2 << 20 };
void memory_advise_huge(void *p, size_t bytes);

#endif

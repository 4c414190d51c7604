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

#endif

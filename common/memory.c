#include "memory.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static void out_of_memory(size_t bytes)
{
    fprintf(stderr, "out of memory (asked for %zu bytes)\n", bytes);
    exit(1);
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
    return p;
}

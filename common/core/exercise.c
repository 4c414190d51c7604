#include "exercise.h"

#include <stdio.h>
#include <stdbool.h>
#include <string.h>

/* Each name once: a stub runs for every ray, and the line is for a person.
 * The table is small because a chapter hands out a handful of exercises;
 * past its end a name is told again rather than forgotten silently. */
enum { EXERCISES_TOLD_MAX = 64 };

void exercise_todo(const char *name, const char *where)
{
    static const char *told[EXERCISES_TOLD_MAX];
    static int told_count;
    bool first = true;
#pragma omp critical(exercise_todo)
    {
        for (int i = 0; i < told_count && first; i++)
            first = strcmp(told[i], name) != 0;
        if (first && told_count < EXERCISES_TOLD_MAX)
            told[told_count++] = name;
    }
    if (first)
        fprintf(stderr, "exercise %s is still a stub: what it computes is missing from the result (read %s)\n", name,
                where);
}

/* exercise.h -- what a handed-out exercise's stub calls.
 *
 * `make exercise CH=NN` (tools/exercise.py) replaces the body of each
 * function a chapter marks as an exercise with a stub that returns a neutral
 * value (0, false, a zero vector) and first calls exercise_todo(). The
 * program then still runs, and draws a black or partial picture; this line
 * says why, once per exercise, on stderr. The stubs' files include this
 * header; nothing else does. */
#ifndef EXERCISE_H
#define EXERCISE_H

/* "exercise NAME is still a stub: ... (read WHERE)", once per NAME. */
void exercise_todo(const char *name, const char *where);

#endif

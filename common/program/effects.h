/* effects.h -- which light transport effects a scene calls for, derived from
 * its description before rendering, so that an integrator does no work for
 * effects the scene cannot show (no refraction rays without glass, no shadow
 * rays when nothing can block a light).
 *
 * Usage:
 *   effects_report e = effects_analyse(&desc);
 *   effects_decide(&e, EFFECT_SHADOWS | EFFECT_REFLECTION);   what the chapter can simulate
 *   effects_print(stdout, &e, "02-whitted");
 *   if (e.simulated & EFFECT_SHADOWS) ... trace shadow rays
 *
 * The analysis is conservative: an effect is dropped only when the scene
 * proves it contributes nothing (then the image is the same with or without
 * it), or when the scene's `effects` statement narrows it away (then the
 * image changes, on purpose).
 */
#ifndef EFFECTS_H
#define EFFECTS_H

#include <stdbool.h>
#include <stdio.h>

#include "scene_file.h"

enum { EFFECT_COUNT = 5, EFFECT_REASON_SIZE = 192 };

typedef struct {
    unsigned needed;    /* EFFECT_* the scene calls for */
    unsigned allowed;   /* what its `effects` statement lets through */
    unsigned supported; /* what the chapter's integrator can simulate */
    unsigned simulated; /* needed & allowed & supported */
    bool hard_shadows;  /* some point light can be occluded */
    bool soft_shadows;  /* some area light (or emitting shape) can be occluded */
    char why[EFFECT_COUNT][EFFECT_REASON_SIZE]; /* for each effect, why it is needed or not */
} effects_report;

effects_report effects_analyse(const scene_desc *d);
/* Sets supported and simulated; returns simulated. */
unsigned effects_decide(effects_report *e, unsigned supported);
/* The list, one line per effect: simulated, not needed, narrowed by the
 * scene, or beyond this chapter. */
void effects_print(FILE *out, const effects_report *e, const char *program);
/* "shadows", "reflection", ... for one EFFECT_* bit. */
const char *effect_name(unsigned effect);

#endif

/* mlt_scene.h -- the scene where Metropolis wins: light that reaches the
 * room only through a narrow gap.
 *
 * Usage: pt_scene sc; mlt_scene_build_lamp(&sc); ... pt_scene_free(&sc);
 */
#ifndef MLT_SCENE_H
#define MLT_SCENE_H

#include "09-path-tracing/scene_pt.h"

/* The Cornell box's room, but its ceiling light is shut in a housing: a
 * plate hangs 8 cm below the light, and four walls come down from the
 * ceiling to 1 cm below the plate, 2 cm outside its edge. The light falls
 * on the plate's top, and what reaches the room leaves down that 2 cm
 * channel all around the plate (the camera sees a little way up the two
 * side channels, not into the housing's top). A path tracer's light samples from the room are blocked; its paths
 * must find the channel by chance, then the light from inside the housing.
 * Once Metropolis has found such a path it explores its neighbours by
 * small steps. */
void mlt_scene_build_lamp(pt_scene *sc);

#endif

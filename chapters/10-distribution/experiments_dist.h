/* experiments_dist.h -- what rays per bounce cost: chapter 10's measurement.
 *
 * experiment_rays_per_bounce() renders the scene with N_light = N_glossy = N
 * for N = 1, 2, 4, 8, each at 1, 2, 4, ... samples per pixel, and measures
 * the RMSE against a converged reference (N = 1, many samples: every
 * setting estimates the same image) and the time taken. At equal time, is
 * it better to spend the rays on more rays per bounce (Cook's branching
 * tree) or on more samples per pixel with one ray per bounce (the path
 * tracer's choice)? Writes DIR/ch10_noise.csv and DIR/ch10_ray_counts.csv
 * (rays per camera ray for N_glossy and depth) and prints both as tables.
 * `quick`: a 32 x 32 image, a 1024-spp reference and short settings, so the
 * curves come in seconds (rough); otherwise 64 x 64 and 16384 spp.
 */
#ifndef EXPERIMENTS_DIST_H
#define EXPERIMENTS_DIST_H

#include <stdbool.h>
#include <stddef.h>

#include "10-distribution/motion_scene.h"

bool experiment_rays_per_bounce(const motion_scene *ms, int threads, bool quick, const char *dir, char *err,
                                size_t err_size);

#endif

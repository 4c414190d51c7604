/* bdpt_experiments.h -- which method to pick: relMSE against CPU time for
 * chapter 09's best path tracer (MIS, Russian roulette on the throughput)
 * and bidirectional path tracing, on the same scene and reference.
 *
 *   bdpt_experiment_equal_time()  renders at 1, 2, 4, ... spp with each
 *       method until its time budget is spent, writes
 *       DIR/ch11_equal_time_NAME.csv (method, spp, CPU seconds, relMSE,
 *       RMSE) for plots/ch11_equal_time.gp, and reports both errors at the
 *       same CPU time.
 */
#ifndef BDPT_EXPERIMENTS_H
#define BDPT_EXPERIMENTS_H

#include "11-bidirectional/bdpt.h"

enum { BDPT_EXPERIMENT_MAX_POINTS = 24 };

typedef struct {
    double seconds;              /* the CPU time both methods reached */
    double relmse_path_tracing;  /* each at that time (log-log interpolated) */
    double relmse_bidirectional;
} bdpt_experiment_result;

bool bdpt_experiment_equal_time(const pt_scene *sc, const char *name, const camera *cam,
                                const estimate_image *reference, double seconds_per_method, int threads,
                                const char *dir, bdpt_experiment_result *result, char *err, size_t err_size);

#endif

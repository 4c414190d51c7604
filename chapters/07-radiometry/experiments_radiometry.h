/* experiments_radiometry.h -- chapter 07's measurements: every radiometric
 * quantity of lectures 14-15 computed twice, by quadrature of its defining
 * integral and by its closed form.
 *
 *   radiometry_experiments_print(rho, bounces, print)  the tables: quadrature
 *       itself, solid angle, intensity and flux, irradiance, the BRDF's
 *       energy check, the reflection equation, and the closed furnace
 *       (L = E + K L bounce by bounce, with albedo rho). Prints them if
 *       `print`; returns whether every numeric value agrees with its closed
 *       form within the quadrature's own error estimate.
 *   radiometry_experiments_write_csv(dir, rho)  DIR/ch07_furnace.csv,
 *       ch07_disk_irradiance.csv and ch07_albedo.csv, which
 *       plots/ch07_*.gp draw.
 *   radiometry_scene_irradiance(desc, program)  --scene: the irradiance at
 *       the camera's target from each of the scene's lights, closed form
 *       against quadrature (no occlusion: radiometry, not visibility).
 */
#ifndef EXPERIMENTS_RADIOMETRY_H
#define EXPERIMENTS_RADIOMETRY_H

#include <stdbool.h>
#include <stddef.h>

#include "scene_file.h"

bool radiometry_experiments_print(double rho, int bounces, bool print);
/* False with err naming the file that could not be written (each file
 * is written whole or not at all, atomic_file.h). */
bool radiometry_experiments_write_csv(const char *dir, double rho, char *err, size_t err_size);
/* False (with a message on stderr, "program: ...") if the scene has no
 * camera, or if a closed form disagrees with its quadrature. */
bool radiometry_scene_irradiance(const scene_desc *d, const char *program);

#endif

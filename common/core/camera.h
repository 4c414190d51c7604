/* camera.h -- the pinhole camera of lecture 13: one eye point, an image plane
 * in front of it, and a ray from the eye through each pixel.
 *
 * Usage: camera cam = camera_look_at(eye, target, up, 40.0f, width, height);
 *        ray r = camera_ray(&cam, x + 0.5f, y + 0.5f);   (pixel centre)
 * Pixel coordinates run from (0,0) at the top-left corner of the image to
 * (width, height) at the bottom-right.
 */
#ifndef CAMERA_H
#define CAMERA_H

#include <math.h>

#include "ray.h"

typedef struct {
    vec3 eye;
    vec3 right, up, forward; /* orthonormal; the camera looks along forward */
    float half_width;        /* tan(fov/2) * aspect: image plane at distance 1 */
    float half_height;       /* tan(fov/2) */
    int width, height;
} camera;

/* vertical_fov_degrees: the full vertical field of view. */
camera camera_look_at(vec3 eye, vec3 target, vec3 up, float vertical_fov_degrees, int width, int height);

/* A camera asked for on the command line (cli.h's CLI_CAMERA_FLAGS: --eye,
 * --target, --fov). A part not given is NaN (the points) or 0 (the field
 * of view), and the scene's camera keeps that part. */
typedef struct {
    vec3 eye, target;
    float vertical_fov_degrees;
} camera_override;
#define CAMERA_NOT_OVERRIDDEN {{NAN, NAN, NAN}, {NAN, NAN, NAN}, 0.0f}

/* The scene's camera with the parts o gives replaced: the eye, the point
 * looked at (without one, the view keeps its direction), the field of view.
 * Up stays the scene camera's. */
camera camera_overridden(const camera *c, const camera_override *o);
/* The same on a scene's eye, target and field of view before its camera
 * is made. */
void camera_override_apply(const camera_override *o, vec3 *eye, vec3 *target, float *vertical_fov_degrees);

/* The eye ray through continuous pixel position (px, py); direction is unit. */
ray camera_ray(const camera *cam, float px, float py);

#endif

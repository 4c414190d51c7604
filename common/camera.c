#include "camera.h"

camera camera_look_at(vec3 eye, vec3 target, vec3 up, float vertical_fov_degrees, int width, int height)
{
    camera cam;
    cam.eye = eye;
    cam.forward = vec3_normalize(vec3_sub(target, eye));
    cam.right = vec3_normalize(vec3_cross(cam.forward, up));
    cam.up = vec3_cross(cam.right, cam.forward);
    cam.half_height = tanf(0.5f * vertical_fov_degrees * (float)PI / 180.0f);
    cam.half_width = cam.half_height * (float)width / (float)height;
    cam.width = width;
    cam.height = height;
    return cam;
}

ray camera_ray(const camera *cam, float px, float py)
{
    /* Pixel position -> [-1, 1] on the image plane (y up), then scaled by
     * the half extents of the plane at distance 1 in front of the eye. */
    float sx = (2.0f * px / (float)cam->width - 1.0f) * cam->half_width;
    float sy = (1.0f - 2.0f * py / (float)cam->height) * cam->half_height;
    vec3 d = vec3_add(cam->forward, vec3_add(vec3_scale(cam->right, sx), vec3_scale(cam->up, sy)));
    return ray_make(cam->eye, vec3_normalize(d));
}

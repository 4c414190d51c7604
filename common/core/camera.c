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
    /* exercise: eye_ray */
    /* Pixel position -> [-1, 1] on the image plane (y up), then scaled by
     * the half extents of the plane at distance 1 in front of the eye. */
    float sx = (2.0f * px / (float)cam->width - 1.0f) * cam->half_width;
    float sy = (1.0f - 2.0f * py / (float)cam->height) * cam->half_height;
    vec3 d = vec3_add(cam->forward, vec3_add(vec3_scale(cam->right, sx), vec3_scale(cam->up, sy)));
    return ray_make(cam->eye, vec3_normalize(d));
    /* end of exercise eye_ray */
}

void camera_override_apply(const camera_override *o, vec3 *eye, vec3 *target, float *vertical_fov_degrees)
{
    bool new_eye = !isnan(o->eye.x), new_target = !isnan(o->target.x);
    if (new_eye && !new_target) /* keep the direction of view from the new eye */
        *target = vec3_add(o->eye, vec3_sub(*target, *eye));
    vec3 kept_eye = *eye, kept_target = *target;
    if (new_eye)
        *eye = o->eye;
    if (new_target)
        *target = o->target;
    if (vec3_length_squared(vec3_sub(*target, *eye)) == 0.0f) { /* no direction to look in: keep the scene's */
        *target = vec3_add(*eye, vec3_sub(kept_target, kept_eye));
    }
    if (o->vertical_fov_degrees > 0.0f)
        *vertical_fov_degrees = o->vertical_fov_degrees;
}

camera camera_overridden(const camera *c, const camera_override *o)
{
    vec3 eye = c->eye, target = vec3_add(c->eye, c->forward);
    float fov = 2.0f * atanf(c->half_height) * 180.0f / (float)PI;
    if (isnan(o->eye.x) && isnan(o->target.x) && !(o->vertical_fov_degrees > 0.0f))
        return *c;
    camera_override_apply(o, &eye, &target, &fov);
    return camera_look_at(eye, target, c->up, fov, c->width, c->height);
}

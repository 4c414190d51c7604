/* image_compare YOURS.exr REFERENCE.exr DIFFERENCE.exr -- a learner's
 * picture against the reference implementation's (make chNN, when an
 * exercise is handed out; tools/exercise.py).
 *
 * Writes |yours - reference| per channel as DIFFERENCE.exr and its .png
 * preview (the preview scaled so the largest difference is white), and
 * prints one number, the relative MSE (common/image.h), with the mean
 * brightness of each picture: a path tracer that is wrong by a constant
 * factor shows it in the means, where noise alone does not. */
#include <stdio.h>

#include "image.h"

static double mean_of(const image *img)
{
    size_t count = (size_t)img->width * (size_t)img->height * 3;
    double sum = 0.0;
    for (size_t i = 0; i < count; i++)
        sum += (double)img->rgb[i];
    return count > 0 ? sum / (double)count : 0.0;
}

/* |a - b| per channel, and the largest of them (for the preview's scale). */
static image difference_of(const image *a, const image *b, float *largest)
{
    image d = image_make(a->width, a->height);
    *largest = 0.0f;
    if (d.rgb == NULL)
        return d;
    size_t count = (size_t)a->width * (size_t)a->height * 3;
    for (size_t i = 0; i < count; i++) {
        float v = fabsf(a->rgb[i] - b->rgb[i]);
        d.rgb[i] = isfinite(v) ? v : 0.0f;
        if (d.rgb[i] > *largest)
            *largest = d.rgb[i];
    }
    return d;
}

static int compare(const char *yours_path, const char *reference_path, const char *difference_path)
{
    char err[IMAGE_ERROR_SIZE];
    image yours = {0}, reference = {0};
    if (!image_read_exr(&yours, yours_path, err, sizeof err) ||
        !image_read_exr(&reference, reference_path, err, sizeof err)) {
        fprintf(stderr, "image_compare: %s\n", err);
        image_free(&yours);
        return 1;
    }
    int status = 0;
    if (yours.width != reference.width || yours.height != reference.height) {
        fprintf(stderr, "image_compare: %s is %dx%d, %s %dx%d\n", yours_path, yours.width, yours.height,
                reference_path, reference.width, reference.height);
        status = 1;
    } else {
        float largest;
        image d = difference_of(&yours, &reference, &largest);
        float stops = largest > 0.0f ? -log2f(largest) : 0.0f;
        if (d.rgb == NULL || !image_write(&d, difference_path, stops, err, sizeof err)) {
            fprintf(stderr, "image_compare: %s\n", d.rgb == NULL ? "out of memory" : err);
            status = 1;
        } else {
            printf("your picture against the reference implementation's: relative MSE %.3g "
                   "(mean %.4g against %.4g); the difference is %s, white = %.3g\n",
                   image_relmse(&yours, &reference), mean_of(&yours), mean_of(&reference), difference_path,
                   (double)largest);
        }
        image_free(&d);
    }
    image_free(&yours);
    image_free(&reference);
    return status;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: image_compare YOURS.exr REFERENCE.exr DIFFERENCE.exr\n"
                        "  writes |yours - reference| and prints the relative MSE and both means\n");
        return 2;
    }
    return compare(argv[1], argv[2], argv[3]);
}

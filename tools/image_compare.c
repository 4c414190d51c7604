/* image_compare YOURS.exr REFERENCE.exr DIFFERENCE.exr [REFERENCE2.exr] --
 * a learner's picture against the reference implementation's (make chNN,
 * when an exercise is handed out; tools/exercise.py).
 *
 * Writes |yours - reference| per channel as DIFFERENCE.exr and its .png
 * preview (the preview scaled so the largest difference is white), and
 * prints one number, the relative MSE (common/core/image.h), with the mean
 * brightness of each picture: a path tracer that is wrong by a constant
 * factor shows it in the means, where noise alone does not. With a second
 * reference (the same render with another seed), it prints how far the two
 * references are apart: the noise, the size of the difference a correct
 * exercise may still show when it draws its random numbers in another
 * order. */
#include <stdio.h>

#include "image.h"
#include "image_file.h"

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

/* How far apart two renders of the reference are (NAN if it cannot say). */
static double noise_of(const image *reference, const char *other_path)
{
    char err[IMAGE_ERROR_SIZE];
    image other = {0};
    if (other_path == NULL || !image_read_exr(&other, other_path, err, sizeof err))
        return NAN;
    double relmse = image_relmse(&other, reference);
    image_free(&other);
    return relmse;
}

static int compare(const char *yours_path, const char *reference_path, const char *difference_path,
                   const char *reference2_path)
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
            double noise = noise_of(&reference, reference2_path);
            if (noise == noise) /* not NaN */
                printf("the reference against itself with another seed: relative MSE %.3g (the noise: "
                       "a right answer differs by about as much)\n",
                       noise);
        }
        image_free(&d);
    }
    image_free(&yours);
    image_free(&reference);
    return status;
}

int main(int argc, char **argv)
{
    if (argc != 4 && argc != 5) {
        fprintf(stderr, "usage: image_compare YOURS.exr REFERENCE.exr DIFFERENCE.exr [REFERENCE2.exr]\n"
                        "  writes |yours - reference| and prints the relative MSE and both means;\n"
                        "  REFERENCE2, the reference with another seed: how far apart noise alone puts them\n");
        return 2;
    }
    return compare(argv[1], argv[2], argv[3], argc == 5 ? argv[4] : NULL);
}

/* png_shrink.c -- the committed copies of the book's figures (make figures):
 * a PNG made smaller by a whole factor, so that the READMEs show their
 * pictures on any Git host without a build, and the repository stays small.
 *
 *   png_shrink IN.png OUT.png MAX_WIDTH
 *
 * The factor is the smallest whole k with width / k <= MAX_WIDTH (1: the
 * image is copied as it is). Each output pixel is the mean of a k x k block,
 * taken in linear light (sRGB decoded, averaged, encoded again), so a
 * shrunk noisy render keeps its brightness. Not a chapter program: it exists
 * for the figures only, and uses stb and nothing of the chapters.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

static double srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static double linear_to_srgb(double c)
{
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

int main(int argc, char **argv)
{
    if (argc != 4 || atoi(argv[3]) < 1) {
        fprintf(stderr, "usage: png_shrink IN.png OUT.png MAX_WIDTH\n");
        return 2;
    }
    int w, h, channels;
    unsigned char *in = stbi_load(argv[1], &w, &h, &channels, 0);
    if (in == NULL) {
        fprintf(stderr, "png_shrink: cannot read '%s': %s\n", argv[1], stbi_failure_reason());
        return 1;
    }
    int max_width = atoi(argv[3]);
    int k = (w + max_width - 1) / max_width;
    int ow = w / k, oh = h / k;
    unsigned char *out = malloc((size_t)ow * (size_t)oh * (size_t)channels);
    if (out == NULL) {
        fprintf(stderr, "png_shrink: out of memory\n");
        return 1;
    }
    /* the alpha channel (2 or 4 channels) is averaged as it is */
    int colours = channels == 2 || channels == 4 ? channels - 1 : channels;
    for (int y = 0; y < oh; y++)
        for (int x = 0; x < ow; x++)
            for (int c = 0; c < channels; c++) {
                double sum = 0.0;
                for (int dy = 0; dy < k; dy++)
                    for (int dx = 0; dx < k; dx++) {
                        double v = in[((size_t)(y * k + dy) * (size_t)w + (size_t)(x * k + dx)) * (size_t)channels +
                                      (size_t)c] / 255.0;
                        sum += c < colours ? srgb_to_linear(v) : v;
                    }
                double mean = sum / (k * k);
                double v = c < colours ? linear_to_srgb(mean) : mean;
                out[((size_t)y * (size_t)ow + (size_t)x) * (size_t)channels + (size_t)c] =
                    (unsigned char)lround(fmin(fmax(v, 0.0), 1.0) * 255.0);
            }
    int ok = stbi_write_png(argv[2], ow, oh, channels, out, ow * channels);
    stbi_image_free(in);
    free(out);
    if (!ok) {
        fprintf(stderr, "png_shrink: cannot write '%s'\n", argv[2]);
        return 1;
    }
    return 0;
}

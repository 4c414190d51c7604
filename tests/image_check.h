/* image_check.h -- two noisy images (or one and its expected value)
 * compared so that a correct estimator fails with probability ~1e-6 even
 * when its per-sample distribution is skewed: the statistics of chapter 09's
 * tests, shared by the chapters that compare against it.
 *
 *   image_check c = check_agree(&a_mean, &a_se, &b_mean, &b_se);
 *   assert_image_check(c, 1, "what was compared");
 *
 * The standard errors must be estimated from many samples each (a pixel's
 * own samples, or many independent renders): the check treats them as
 * known. */
#ifndef IMAGE_CHECK_H
#define IMAGE_CHECK_H

#include <math.h>

#include "image.h"
#include "stats.h"

/* Standard errors below this are float rounding, not noise (zero-variance
 * estimators): compare with this instead. */
static const double ROUNDING_FLOOR = 1e-5;

/* ---- image-level statistics ------------------------------------------------
 * Why not "every pixel within 5 of its own standard errors": the lecture's
 * uniform hemisphere sampling gives a skewed per-sample distribution (rare
 * bright paths). A pixel whose 64 samples missed them has both a low mean
 * and a small estimated error, so its studentized error has a heavy tail:
 * over 200 seeds 1.5 to 3.5 % of the runs failed, against the ~1e-4 the
 * normal tail at 5 sigma promises (docs/hard-cases.md, section 9).
 *
 * What replaces it, for each colour channel separately (in a grey scene
 * the three are equal, so Sidak over them is merely conservative):
 *  - where every pixel has the same expected value (furnaces, the point
 *    light in a sphere), the per-sample variance is pooled over the pixels:
 *    V = mean over pixels of se^2, an estimate from pixels x spp samples
 *    (thousands) instead of 64, and E[V] = mean of the pixels' true
 *    variances even where they differ a little (the icosphere's facets);
 *  - two statistics, each with a p-value from a distribution that holds
 *    without normality of one pixel's mean:
 *      the image mean, z = (mean of pixel means - expected) / sqrt(V / n):
 *        the mean of n x spp samples, normal by the central limit theorem,
 *        and the most sensitive test of a bias shared by all pixels;
 *      X = sum over pixels of (m_i - expected)^2 / V, chi-square with n
 *        degrees of freedom: sees a bias in some pixels only. A pixel with
 *        a 7-sigma fluke adds 49 to it, against a 1e-7 quantile of 142 at
 *        n = 64, so one skewed pixel no longer decides the test;
 *  - the test's family-wise false-alarm budget FAMILY_ALPHA is split over
 *    all the p-values it looks at with Sidak (stats_sidak_alpha), so a
 *    correct implementation fails a test with probability ~1e-6.
 * Estimators of zero variance (glass, depth 0) are compared exactly,
 * within ROUNDING_FLOOR. */
static const double FAMILY_ALPHA = 1e-6;

typedef struct {
    double p;     /* the smallest p-value of the checks made */
    double z;     /* the image mean's z-score in the channel with the smallest p */
    double chi2;  /* and the chi-square, with its degrees of freedom */
    int dof;
} image_check;

/* Each image check looks at 2 p-values in each of 3 channels. */
enum { CHECKS_PER_IMAGE = 6 };

static void image_check_take(image_check *c, double p, double z, double chi2, int dof)
{
    if (p < c->p) {
        c->p = p;
        c->z = z;
        c->chi2 = chi2;
        c->dof = dof;
    }
}

/* Two renders of one scene (e.g. two rungs) against each other. Pixels
 * differ, so nothing can be pooled: pixel i's difference d_i has variance
 * v_i = se_a^2 + se_b^2 from its own samples. The same two statistics:
 * z = sum d_i / sqrt(sum v_i) (the image means agree; the sum of variances
 * is estimated from all samples, so it is as reliable as a pooled one), and
 * X = sum d_i^2 / v_i, chi-square with one degree of freedom per noisy
 * pixel, whose sum of many terms one underestimated v_i cannot dominate.
 * Pixels with no noise in either render must agree within ROUNDING_FLOOR. */
static image_check check_agree(const image *mean_a, const image *se_a, const image *mean_b, const image *se_b)
{
    image_check c = {.p = 2.0};
    int n = mean_a->width * mean_a->height;
    for (int ch = 0; ch < 3; ch++) {
        double sum = 0, variance = 0, chi2 = 0;
        int dof = 0, off = 0;
        for (int k = 0; k < n; k++) {
            int i = k * 3 + ch;
            double d = (double)mean_a->rgb[i] - mean_b->rgb[i];
            double v = (double)se_a->rgb[i] * se_a->rgb[i] + (double)se_b->rgb[i] * se_b->rgb[i];
            if (v <= ROUNDING_FLOOR * ROUNDING_FLOOR) {
                off += !(fabs(d) <= ROUNDING_FLOOR);
                continue;
            }
            sum += d;
            variance += v;
            chi2 += d * d / v;
            dof++;
        }
        double z = dof ? sum / sqrt(variance) : 0.0;
        double p = off ? 0.0 : dof ? fmin(erfc(fabs(z) / sqrt(2.0)), stats_chi_square_p_value(chi2, dof)) : 1.0;
        image_check_take(&c, p, z, chi2, dof);
    }
    return c;
}

/* The Sidak level for one of `images` image checks in a test. */
static double image_check_alpha(int images)
{
    return stats_sidak_alpha(FAMILY_ALPHA, CHECKS_PER_IMAGE * images);
}

#define assert_image_check(c, images, what)                                                                          \
    do {                                                                                                             \
        if (!((c).p >= image_check_alpha(images)))                                                                   \
            fail_msg("%s: p = %.3g < %.3g (image mean z = %.2f, chi-square %.1f on %d)", (what), (c).p,            \
                     image_check_alpha(images), (c).z, (c).chi2, (c).dof);                                            \
    } while (0)

#endif

/* mlt.c -- primary-sample-space Metropolis light transport (see mlt.h). */
#include "12-metropolis/mlt.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>

#include "progress.h"
#include "timer.h"

/* ---- the primary sample vector ------------------------------------------------
 * Only the coordinates a path reads exist; the vector grows when a longer
 * path asks for more. A small step should perturb *every* coordinate, used
 * or not, so that a coordinate a path starts reading again later has the
 * value the chain would have given it. Doing that eagerly would cost the
 * length of the longest path ever seen at every step; instead each
 * coordinate remembers the iteration its value belongs to, and catches up
 * when it is read: a fresh uniform number if a large step happened since,
 * then one small step for every accepted iteration it missed. */

void mlt_sampler_init(mlt_sampler *s, pcg32 rng)
{
    s->u = NULL;
    s->count = s->capacity = 0;
    s->next_index = 0;
    s->iteration = 0;
    s->last_large_step = 0;
    s->saved_last_large_step = 0;
    s->large_step = true;
    s->out_of_memory = false;
    s->rng = rng;
}

void mlt_sampler_free(mlt_sampler *s)
{
    free(s->u);
    s->u = NULL;
    s->count = s->capacity = 0;
}

void mlt_sampler_start_iteration(mlt_sampler *s, bool large_step)
{
    s->iteration++;
    s->large_step = large_step;
    s->saved_last_large_step = s->last_large_step;
    if (large_step)
        s->last_large_step = s->iteration;
    s->next_index = 0;
}

float mlt_small_step(float value, pcg32 *rng)
{
    /* exercise: mlt_small_step; a stub returns value */
    /* Kelemen's kernel: a size between s1 and s2, log-uniform, with a random
     * sign. It is symmetric -- moving from a to b is as likely as from b to
     * a -- which is what lets the acceptance be a plain ratio of f. */
    float size = MLT_SMALL_STEP_MAX * expf(-logf(MLT_SMALL_STEP_MAX / MLT_SMALL_STEP_MIN) * pcg32_float(rng));
    float moved = pcg32_float(rng) < 0.5f ? value - size : value + size;
    /* Wrap around: [0, 1) is a circle, so no coordinate gets stuck at an edge. */
    if (moved < 0.0f)
        moved += 1.0f;
    if (moved >= 1.0f)
        moved -= 1.0f;
    /* -tiny + 1 rounds to 1.0f in float: that is 0 on the circle. */
    return moved >= 1.0f ? 0.0f : moved;
    /* end of exercise mlt_small_step */
}

float mlt_sampler_next(mlt_sampler *s)
{
    int i = s->next_index++;
    if (i >= s->count) {
        if (i >= s->capacity) {
            int capacity = s->capacity ? 2 * s->capacity : 64;
            mlt_coordinate *grown = realloc(s->u, (size_t)capacity * sizeof *grown);
            if (grown == NULL) {
                s->out_of_memory = true;
                return 0.5f;
            }
            s->u = grown;
            s->capacity = capacity;
        }
        for (; s->count <= i; s->count++)
            s->u[s->count] = (mlt_coordinate){.value = 0.0f, .modified = -1};
    }
    mlt_coordinate *c = &s->u[i];
    c->saved_value = c->value;
    c->saved_modified = c->modified;
    /* Catch up. A large step since this value was set: it is a fresh
     * uniform number drawn at that step. */
    if (c->modified < s->last_large_step) {
        c->value = pcg32_float(&s->rng);
        c->modified = s->last_large_step;
    }
    /* Then one small step for each iteration since (the last one being this
     * proposal's own). */
    for (; c->modified < s->iteration; c->modified++)
        c->value = mlt_small_step(c->value, &s->rng);
    return c->value;
}

void mlt_sampler_accept(mlt_sampler *s) { (void)s; }

void mlt_sampler_reject(mlt_sampler *s)
{
    /* Undo what this proposal changed: the coordinates it brought up to
     * this iteration go back to their saved values. */
    for (int i = 0; i < s->count; i++)
        if (s->u[i].modified == s->iteration) {
            s->u[i].value = s->u[i].saved_value;
            s->u[i].modified = s->u[i].saved_modified;
        }
    s->last_large_step = s->saved_last_large_step;
    s->iteration--;
}

double mlt_acceptance(double f_current, double f_proposed)
{
    /* exercise: mlt_acceptance */
    /* Metropolis-Hastings: a = min(1, f(y) T(y->x) / (f(x) T(x->y))); both
     * mutations are symmetric (T(y->x) = T(x->y)), so only f remains. A
     * current state of f = 0 (only before the first useful path) moves on. */
    if (!(f_current > 0.0))
        return 1.0;
    return fmin(1.0, f_proposed / f_current);
    /* end of exercise mlt_acceptance */
}

/* ---- paths as functions of primary samples ------------------------------------- */

static float sampler_next_callback(void *state) { return mlt_sampler_next(state); }

mlt_path mlt_path_evaluate(const path_tracer *pt, const camera *cam, mlt_sampler *s, ray_counters *counters)
{
    mlt_path p;
    /* The first two coordinates choose the point on the film: the path
     * picks its own pixel. */
    p.x = mlt_sampler_next(s) * (float)cam->width;
    p.y = mlt_sampler_next(s) * (float)cam->height;
    ray r = camera_ray(cam, p.x, p.y);
    counters->camera_rays++;
    pt_random random = {.rng = NULL, .next = sampler_next_callback, .state = s};
    p.radiance = path_trace_radiance_from(pt, r, &random, counters);
    p.f = vec3_luminance(p.radiance);
    /* A NaN or Inf path counts as 0 (and is counted): a bias towards 0
     * the counters' nonfinite_samples_dropped measures. */
    if (!isfinite(p.f) || !isfinite(p.radiance.x) || !isfinite(p.radiance.y) || !isfinite(p.radiance.z) ||
        p.f < 0.0) {
        counters->nonfinite_samples++;
        p.radiance = vec3_splat(0.0f);
        p.f = 0.0;
    }
    return p;
}

/* ---- rendering -------------------------------------------------------------------- */

mlt_options mlt_defaults(const path_tracer *pt, const camera *cam)
{
    mlt_options o = {.pt = pt, .cam = cam, .mutations_per_pixel = 64, .p_large = 0.3f, .bootstrap = 100000,
                     .chains = 64, .seed = 1, .threads = 0, .start = MLT_START_BOOTSTRAP, .quiet = true,
                     .label = "12-metropolis", .acceptance = NULL};
    return o;
}

/* The streams: bootstrap path k and chain c each their own, from the seed. */
static const uint64_t BOOTSTRAP_STREAMS = 0xb0075ULL, CHAIN_STREAMS = 0xc4a1ULL;

static pcg32 bootstrap_rng(uint64_t seed, int k) { return pcg32_for_pixel(seed ^ BOOTSTRAP_STREAMS, (uint64_t)k); }
static pcg32 chain_rng(uint64_t seed, int c) { return pcg32_for_pixel(seed ^ CHAIN_STREAMS, (uint64_t)c); }

/* Expected-value splatting: both the current and the proposed path add to
 * the film, weighted by the probability that the chain is at each after
 * this step, (1 - a) and a. The estimate is the same as splatting only the
 * state the chain moves to, but the rejected proposals -- often paths to
 * other pixels -- are not wasted. Each path adds radiance / f: its colour at
 * unit luminance; the film is scaled by b / (mutations per pixel) at the end. */
static void splat(splat_film *film, const mlt_path *p, double weight, ray_counters *counters)
{
    if (weight > 0.0 && p->f > 0.0)
        splat_film_add(film, p->x, p->y, vec3_scale(p->radiance, (float)(weight / p->f)), counters);
}

static int pick_bootstrap(const double *cdf, int n, double u)
{
    /* the first k with cdf[k] > u: binary search */
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (cdf[mid] > u)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

typedef struct {
    long long proposed, accepted;
    bool out_of_memory;
} chain_stats;

static void run_chain(const mlt_options *o, int c, int start_index, long long mutations, splat_film *film,
                      chain_stats *stats, ray_counters *counters, progress *bar)
{
    mlt_acceptance_fn acceptance = o->acceptance ? o->acceptance : mlt_acceptance;
    /* Rebuild the starting path exactly: the bootstrap path's own stream,
     * read as one large step, gives the same u and so the same path. Then
     * the chain continues with a stream of its own, so two chains that
     * start at the same path still go separate ways. */
    mlt_sampler s;
    mlt_sampler_init(&s, bootstrap_rng(o->seed, start_index));
    ray_counters ignored = {0};
    mlt_path current = mlt_path_evaluate(o->pt, o->cam, &s, &ignored); /* counted in the bootstrap */
    s.rng = chain_rng(o->seed, c);
    pcg32 *rng = &s.rng;
    const long long progress_step = 4096;
    for (long long m = 0; m < mutations; m++) {
        /* Propose: a large step with probability p_large, else a small one. */
        bool large = pcg32_float(rng) < o->p_large;
        mlt_sampler_start_iteration(&s, large);
        mlt_path proposed = mlt_path_evaluate(o->pt, o->cam, &s, counters);
        double a = acceptance(current.f, proposed.f);
        splat(film, &current, 1.0 - a, counters);
        splat(film, &proposed, a, counters);
        stats->proposed++;
        if (pcg32_double(rng) < a) {
            mlt_sampler_accept(&s);
            current = proposed;
            stats->accepted++;
        } else {
            mlt_sampler_reject(&s);
        }
        if ((m + 1) % progress_step == 0)
            progress_advance(bar, progress_step);
    }
    progress_advance(bar, mutations % progress_step);
    if (s.out_of_memory)
        stats->out_of_memory = true;
    mlt_sampler_free(&s);
}

bool mlt_render(const mlt_options *o, image *out, mlt_result *result)
{
    const camera *cam = o->cam;
    double start = timer_seconds();
    int threads = o->threads > 0 ? o->threads : omp_get_max_threads();
    int n = o->bootstrap > 0 ? o->bootstrap : 1;
    double *f = malloc((size_t)n * sizeof *f);
    double *cdf = malloc((size_t)n * sizeof *cdf);
    splat_film film;
    bool film_ok = splat_film_init(&film, cam->width, cam->height);
    if (f == NULL || cdf == NULL || !film_ok) {
        free(f);
        free(cdf);
        if (film_ok)
            splat_film_free(&film);
        return false;
    }
    ray_counters total = {0};
    bool out_of_memory = false;

    /* ---- bootstrap: b = E[f] from n independent paths ---- */
#pragma omp parallel num_threads(threads)
    {
        ray_counters mine = {0};
        bool oom = false;
#pragma omp for schedule(dynamic, 256)
        for (int k = 0; k < n; k++) {
            mlt_sampler s;
            mlt_sampler_init(&s, bootstrap_rng(o->seed, k));
            f[k] = mlt_path_evaluate(o->pt, o->cam, &s, &mine).f;
            oom |= s.out_of_memory;
            mlt_sampler_free(&s);
        }
#pragma omp critical(mlt_counters)
        {
            counters_add(&total, &mine);
            out_of_memory |= oom;
        }
    }
    /* Summed in index order, so b does not depend on the threads. */
    double sum = 0.0, sum2 = 0.0;
    for (int k = 0; k < n; k++) {
        sum += f[k];
        sum2 += f[k] * f[k];
        cdf[k] = sum;
    }
    double b = sum / n;
    double variance = n > 1 ? fmax(0.0, (sum2 - sum * b) / (n - 1)) : 0.0;
    result->b = b;
    result->b_standard_error = sqrt(variance / n);
    result->bootstrap_seconds = timer_seconds() - start;
    result->proposed = result->accepted = 0;

    int first_useful = 0;
    while (first_useful < n && !(f[first_useful] > 0.0))
        first_useful++;
    long long mutations = (long long)o->mutations_per_pixel * cam->width * cam->height;
    int chains = o->chains > 0 ? o->chains : 1;
    if (b > 0.0 && first_useful < n) {
        progress bar;
        progress_begin(&bar, o->label ? o->label : "12-metropolis", mutations, o->quiet);
        long long proposed = 0, accepted = 0;
#pragma omp parallel num_threads(threads)
        {
            ray_counters mine = {0};
            chain_stats stats = {0, 0, false};
#pragma omp for schedule(dynamic, 1)
            for (int c = 0; c < chains; c++) {
                /* The starting state, in proportion to f among the
                 * bootstrap paths: already (nearly) a sample of f / b, so
                 * the chain need not first walk there (start-up bias). */
                int start_index = first_useful;
                if (o->start == MLT_START_BOOTSTRAP) {
                    pcg32 pick = chain_rng(o->seed ^ 0x5e1ec7ULL, c);
                    start_index = pick_bootstrap(cdf, n, pcg32_double(&pick) * sum);
                }
                long long length = mutations / chains + (c < mutations % chains ? 1 : 0);
                run_chain(o, c, start_index, length, &film, &stats, &mine, &bar);
            }
#pragma omp critical(mlt_counters)
            {
                counters_add(&total, &mine);
                proposed += stats.proposed;
                accepted += stats.accepted;
                out_of_memory |= stats.out_of_memory;
            }
        }
        progress_end(&bar);
        result->proposed = proposed;
        result->accepted = accepted;
    }
    /* Each mutation is one sample of f / b; a pixel's value is b times the
     * (radiance / f) it received, per mutation per pixel. */
    splat_film_resolve(&film, o->mutations_per_pixel > 0 ? b / o->mutations_per_pixel : 0.0, out);
    splat_film_free(&film);
    free(f);
    free(cdf);
    result->counters = total;
    result->seconds = timer_seconds() - start;
    return !out_of_memory;
}

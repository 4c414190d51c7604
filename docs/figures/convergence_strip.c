/* convergence_strip.c -- the book's pictures of an estimator converging: one
 * scene rendered several times side by side, each panel labelled with what
 * changed, so that the noise can be seen falling (or growing).
 *
 *   --kind spp         chapter 09's Cornell box by the lecture's shade() at
 *                      each sample count of --counts (default 1,4,16,64,256)
 *   --kind roulette    the same box at --spp samples per pixel, with each
 *                      P_RR of --counts (default 0.2,0.5,0.8,1): the noise
 *                      Russian roulette adds, and the rays it saves
 *   --kind estimators  chapter 07's floor under its tilted square light, the
 *                      irradiance E = integral of L cos(theta) d omega at
 *                      each floor point estimated by chapter 08's estimator
 *                      with N = --counts samples (one row per strategy and
 *                      point set), and Lambert's closed form in the last column
 *
 * --width and --height are one panel's size. The labels are drawn with a
 * small bitmap font, so the picture says what it shows on any Git host.
 * Not a chapter program: it exists to draw the book's figures
 * (docs/figures.txt), through the chapters' own headers.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "07-radiometry/radiometry.h"
#include "08-monte-carlo/estimators.h"
#include "09-path-tracing/path_tracer.h"
#include "cli.h"
#include "image_file.h"
#include "memory.h"
#include "program.h"
#include "run_record.h"
#include "timer.h"

#define PROGRAM "convergence_strip"

enum { MAX_PANELS = 8, MAX_ROWS = 4, LABEL_SIZE = 48 };

/* ---- labels: a 5 x 7 bitmap font --------------------------------------------- */

/* Each glyph is seven rows, top first; bit 4 of a row is its leftmost pixel. */
typedef struct {
    char c;
    unsigned char rows[7];
} glyph;

static const glyph FONT[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}}, {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'/', {0x01, 0x01, 0x02, 0x04, 0x08, 0x10, 0x10}}, {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},
};

/* Pixels of one glyph cell (5 wide and a column of space), times the scale. */
enum { GLYPH_W = 5, GLYPH_H = 7, GLYPH_ADVANCE = 6, LINE_ADVANCE = 10 };

static const glyph *glyph_for(char c)
{
    c = (char)toupper((unsigned char)c);
    for (size_t i = 0; i < sizeof FONT / sizeof FONT[0]; i++)
        if (FONT[i].c == c)
            return &FONT[i];
    return NULL; /* drawn as a blank */
}

/* The widest line of `text` (lines split at '\n') and its number of lines. */
static void text_size(const char *text, int scale, int *width, int *height)
{
    int lines = 1, longest = 0, run = 0;
    for (const char *s = text; *s; s++) {
        if (*s == '\n') {
            lines++;
            run = 0;
        } else if (++run > longest) {
            longest = run;
        }
    }
    *width = longest > 0 ? scale * (GLYPH_ADVANCE * longest - 1) : 0;
    *height = scale * (LINE_ADVANCE * (lines - 1) + GLYPH_H);
}

/* Draws `text` with its first line's top at y; each line centred on
 * centre_x. Pixels outside the image are skipped. */
static void draw_text(image *img, const char *text, int centre_x, int y, int scale, vec3 colour)
{
    while (*text) {
        size_t n = strcspn(text, "\n");
        int left = centre_x - scale * (GLYPH_ADVANCE * (int)n - 1) / 2;
        for (size_t k = 0; k < n; k++) {
            const glyph *g = glyph_for(text[k]);
            for (int row = 0; g != NULL && row < GLYPH_H; row++)
                for (int col = 0; col < GLYPH_W; col++) {
                    if (!(g->rows[row] & (0x10 >> col)))
                        continue;
                    for (int dy = 0; dy < scale; dy++)
                        for (int dx = 0; dx < scale; dx++) {
                            int px = left + scale * (GLYPH_ADVANCE * (int)k + col) + dx, py = y + scale * row + dy;
                            if (px >= 0 && py >= 0 && px < img->width && py < img->height)
                                image_set(img, px, py, colour);
                        }
                }
        }
        text += n;
        if (*text == '\n')
            text++;
        y += scale * LINE_ADVANCE;
    }
}

/* ---- the strip: panels in a grid, labels under the columns and left of the rows */

typedef struct {
    int rows, columns;
    image panels[MAX_ROWS][MAX_PANELS];
    char column_labels[MAX_PANELS][LABEL_SIZE];
    char row_labels[MAX_ROWS][LABEL_SIZE]; /* empty: no margin for them */
} strip;

/* Space between panels, and around the labels; the font's scale. */
enum { GAP = 4, LABEL_PAD = 6, LABEL_SCALE = 2 };

static void strip_free(strip *s)
{
    for (int r = 0; r < s->rows; r++)
        for (int c = 0; c < s->columns; c++)
            image_free(&s->panels[r][c]);
}

/* One image: the panels on white, each column's label under the last row,
 * each row's label in a margin on the left. */
static image strip_compose(const strip *s)
{
    int pw = s->panels[0][0].width, ph = s->panels[0][0].height;
    int margin = 0, label_h = 0, w, h;
    for (int r = 0; r < s->rows; r++) {
        text_size(s->row_labels[r], LABEL_SCALE, &w, &h);
        margin = w > 0 && w + 2 * LABEL_PAD > margin ? w + 2 * LABEL_PAD : margin;
    }
    for (int c = 0; c < s->columns; c++) {
        text_size(s->column_labels[c], LABEL_SCALE, &w, &h);
        label_h = h + 2 * LABEL_PAD > label_h ? h + 2 * LABEL_PAD : label_h;
    }
    image out = image_make(margin + s->columns * (pw + GAP) + GAP, s->rows * (ph + GAP) + GAP + label_h);
    if (out.rgb == NULL)
        return out;
    for (int y = 0; y < out.height; y++)
        for (int x = 0; x < out.width; x++)
            image_set(&out, x, y, vec3_splat(1.0f));
    const vec3 ink = vec3_splat(0.0f);
    for (int r = 0; r < s->rows; r++) {
        int top = GAP + r * (ph + GAP);
        for (int c = 0; c < s->columns; c++) {
            int left = margin + GAP + c * (pw + GAP);
            for (int y = 0; y < ph; y++)
                for (int x = 0; x < pw; x++)
                    image_set(&out, left + x, top + y, image_get(&s->panels[r][c], x, y));
        }
        text_size(s->row_labels[r], LABEL_SCALE, &w, &h);
        draw_text(&out, s->row_labels[r], margin / 2, top + (ph - h) / 2, LABEL_SCALE, ink);
    }
    for (int c = 0; c < s->columns; c++)
        draw_text(&out, s->column_labels[c], margin + GAP + c * (pw + GAP) + pw / 2,
                  s->rows * (ph + GAP) + LABEL_PAD, LABEL_SCALE, ink);
    return out;
}

/* ---- chapter 09: the Cornell box at several spp, or several P_RR ------------------- */

/* One render of the box by pt at spp samples per pixel into *panel;
 * its counters are added to *counters. */
static bool render_box(const path_tracer *pt, const cli_options *opts, int spp, uint64_t seed, image *panel,
                       ray_counters *counters)
{
    camera cam = pt_scene_camera(pt->scene, opts->width, opts->height);
    *panel = image_make(opts->width, opts->height);
    if (panel->rgb == NULL)
        return false;
    render_job job = {.cam = &cam, .spp = spp, .seed = seed, .threads = opts->threads, .quiet = true,
                      .label = PROGRAM, .radiance = path_trace_radiance, .scene = pt, .jitter = true,
                      .sample = path_tracer_sample_fn(pt)};
    render_stats stats;
    render_image(&job, panel, &stats);
    counters_add(counters, &stats.counters);
    return true;
}

/* The lecture's rung at each sample count, each panel what
 * `09-path-tracing --spp N` renders at this size: the same seed for all, so
 * a pixel's first paths are the same in every panel, as when a render is
 * run again with more samples. */
static bool strip_spp(strip *s, const path_tracer *pt, const cli_options *opts, const double *counts, int n,
                      ray_counters *counters)
{
    s->rows = 1;
    s->columns = n;
    for (int c = 0; c < n; c++) {
        int spp = (int)counts[c];
        snprintf(s->column_labels[c], LABEL_SIZE, "%d SPP", spp);
        if (!render_box(pt, opts, spp, opts->seed, &s->panels[0][c], counters))
            return false;
        if (!opts->quiet)
            printf("%s: %d spp\n", PROGRAM, spp);
    }
    return true;
}

/* Each P_RR at opts->spp; each label also gives the rays the render traced
 * per camera sample (shadow rays included): what the roulette saves. */
static bool strip_roulette(strip *s, const path_tracer *lecture, const cli_options *opts, const double *counts,
                           int n, ray_counters *counters)
{
    s->rows = 1;
    s->columns = n;
    for (int c = 0; c < n; c++) {
        path_tracer pt = *lecture;
        pt.russian_roulette = RR_FIXED;
        pt.rr_probability = (float)counts[c];
        ray_counters mine = {0};
        if (!render_box(&pt, opts, opts->spp, opts->seed, &s->panels[0][c], &mine))
            return false;
        double rays = (double)counters_total_rays(&mine) / (double)mine.camera_rays;
        snprintf(s->column_labels[c], LABEL_SIZE, "P_RR=%g\n%.1f RAYS", counts[c], rays);
        counters_add(counters, &mine);
        if (!opts->quiet)
            printf("%s: P_RR %g, %d spp: %.2f rays per camera sample\n", PROGRAM, counts[c], opts->spp, rays);
    }
    return true;
}

/* ---- chapter 08: the irradiance on chapter 07's floor, by Monte Carlo -------------- */

/* Chapter 07's picture: a unit square light of radiance 1, at height 0.75,
 * tilted 30 degrees about the x axis; the floor z = 0 seen from straight
 * above, FLOOR_SIDE units across. */
static const double LIGHT_TILT_DEGREES = 30.0, LIGHT_HEIGHT = 0.75, FLOOR_SIDE = 4.0;

typedef struct {
    dvec3 corners[4];
    dvec3 centre, edge_u, edge_v, normal; /* centre + a edge_u + b edge_v, |a|, |b| <= 1/2 */
} square_light;

static square_light floor_light(void)
{
    double tilt = LIGHT_TILT_DEGREES * PI / 180.0;
    square_light l;
    l.centre = dvec3_make(0.0, 0.0, LIGHT_HEIGHT);
    l.edge_u = dvec3_make(1.0, 0.0, 0.0);
    l.edge_v = dvec3_make(0.0, cos(tilt), sin(tilt));
    l.normal = dvec3_cross(l.edge_u, l.edge_v);
    const double ab[4][2] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
    for (int i = 0; i < 4; i++)
        l.corners[i] = dvec3_add(l.centre, dvec3_add(dvec3_scale(l.edge_u, ab[i][0]), dvec3_scale(l.edge_v, ab[i][1])));
    return l;
}

/* L(p, w): 1 if the ray from p along w meets the light (from either face,
 * as chapter 07's lights emit), else 0. */
static double incident_radiance(const square_light *l, dvec3 p, dvec3 w)
{
    double facing = dvec3_dot(w, l->normal);
    if (facing == 0.0)
        return 0.0;
    double t = dvec3_dot(dvec3_sub(l->centre, p), l->normal) / facing;
    if (!(t > 0.0))
        return 0.0;
    dvec3 q = dvec3_sub(dvec3_add(p, dvec3_scale(w, t)), l->centre);
    return fabs(dvec3_dot(q, l->edge_u)) <= 0.5 && fabs(dvec3_dot(q, l->edge_v)) <= 0.5 ? 1.0 : 0.0;
}

/* One row of the estimator strip: a strategy of chapter 08 (the warp from
 * [0,1)^2 to a direction, with its pdf) on a point set. */
typedef struct {
    const char *label; /* in the picture */
    const char *name;  /* in the report */
    warp_fn warp;
    point_set points;
} estimator_row;

static const estimator_row ESTIMATOR_ROWS[MAX_ROWS] = {
    {"UNIFORM", "uniform hemisphere", warp_uniform_hemisphere, POINTS_INDEPENDENT},
    {"COSINE", "cosine-weighted", warp_cosine_hemisphere, POINTS_INDEPENDENT},
    {"COSINE\nJITTERED", "cosine, jittered", warp_cosine_hemisphere, POINTS_JITTERED},
    {"COSINE\nSOBOL", "cosine, Owen-Sobol", warp_cosine_hemisphere, POINTS_SOBOL_OWEN},
};

/* F_N = (1/N) sum f(X_i)/p(X_i) with f(w) = L(p, w) cos(theta): chapter
 * 08's estimator (monte_carlo_estimate), written out here because its
 * integrand depends on the floor point. u holds 2n numbers. */
static double irradiance_estimate(const square_light *l, dvec3 p, const estimator_row *row, const double *u, int n)
{
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        double w[3];
        double pdf = row->warp(NULL, &u[2 * i], w);
        if (pdf > 0.0) /* a sample the density cannot draw adds nothing (estimators.h) */
            sum += incident_radiance(l, p, dvec3_make(w[0], w[1], w[2])) * w[2] / pdf;
    }
    return sum / n;
}

static dvec3 floor_point(int x, int y, int w, int h)
{
    double scale = FLOOR_SIDE / (w > h ? w : h);
    return dvec3_make((x + 0.5 - 0.5 * w) * scale, (0.5 * h - y - 0.5) * scale, 0.0);
}

/* E at every pixel by `row` with n samples (or Lambert's closed form when
 * row is NULL), shown as grey E / E_max; the RMSE against the closed form
 * goes to *rmse. */
static bool floor_panel(const square_light *l, const estimator_row *row, int n, const cli_options *opts,
                        uint64_t stream, double E_max, image *panel, double *rmse)
{
    int w = opts->width, h = opts->height;
    *panel = image_make(w, h);
    if (panel->rgb == NULL)
        return false;
    dvec3 up = dvec3_make(0.0, 0.0, 1.0);
    double squared = 0.0;
#pragma omp parallel num_threads(opts->threads) reduction(+ : squared)
    {
        double *u = memory_allocate((size_t)2 * (size_t)n, sizeof *u);
#pragma omp for schedule(dynamic, 4)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                dvec3 p = floor_point(x, y, w, h);
                double exact = irradiance_polygon(1.0, l->corners, 4, p, up), E = exact;
                if (row != NULL) {
                    pcg32 rng = pcg32_for_pixel(opts->seed, stream * (uint64_t)w * (uint64_t)h + (uint64_t)(y * w + x));
                    points_generate(row->points, &rng, n, 2, u);
                    E = irradiance_estimate(l, p, row, u, n);
                }
                squared += (E - exact) * (E - exact);
                image_set(panel, x, y, vec3_splat((float)(E / E_max)));
            }
        free(u);
    }
    *rmse = sqrt(squared / ((double)w * h));
    return true;
}

/* Rows: the strategies; columns: N = counts, then the closed form. */
static bool strip_estimators(strip *s, const cli_options *opts, const double *counts, int n)
{
    square_light l = floor_light();
    double E_max = 0.0;
    dvec3 up = dvec3_make(0.0, 0.0, 1.0);
    for (int y = 0; y < opts->height; y++)
        for (int x = 0; x < opts->width; x++)
            E_max = fmax(E_max, irradiance_polygon(1.0, l.corners, 4, floor_point(x, y, opts->width, opts->height), up));
    s->rows = MAX_ROWS;
    s->columns = n + 1;
    for (int r = 0; r < s->rows; r++) {
        snprintf(s->row_labels[r], LABEL_SIZE, "%s", ESTIMATOR_ROWS[r].label);
        for (int c = 0; c <= n; c++) {
            bool exact = c == n;
            int samples = exact ? 0 : (int)counts[c];
            double rmse;
            if (!floor_panel(&l, exact ? NULL : &ESTIMATOR_ROWS[r], samples, opts, (uint64_t)(r * MAX_PANELS + c),
                             E_max, &s->panels[r][c], &rmse))
                return false;
            snprintf(s->column_labels[c], LABEL_SIZE, exact ? "EXACT" : "N=%d", samples);
            if (!opts->quiet && !exact)
                printf("%s: %-18s N = %4d: RMSE %.4f (E_max %.4f)\n", PROGRAM, ESTIMATOR_ROWS[r].name, samples, rmse,
                       E_max);
        }
    }
    return true;
}

/* ---- the program --------------------------------------------------------------- */

/* "1,4,16" into counts; false (with a message) unless 1 to MAX_PANELS
 * numbers in [min, max], whole when `whole`. */
static bool parse_counts(const char *text, double min, double max, bool whole, double *counts, int *n)
{
    const char *s = text;
    *n = 0;
    while (*n < MAX_PANELS) {
        char *end;
        double v = strtod(s, &end);
        if (end == s || !(v >= min && v <= max) || (whole && v != floor(v)))
            break;
        counts[(*n)++] = v;
        if (*end == '\0')
            return true;
        if (*end != ',')
            break;
        s = end + 1;
    }
    fprintf(stderr, "%s: --counts: expected 1 to %d comma-separated %s in [%g, %g], got '%s'\n", PROGRAM, MAX_PANELS,
            whole ? "whole numbers" : "numbers", min, max, text);
    return false;
}

static const char *const KIND_NAMES[] = {"spp", "roulette", "estimators", NULL};
static const char *const KIND_NOTES[] = {"chapter 09's Cornell box at each spp of --counts (default 1,4,16,64,256)",
                                         "the box at --spp with each P_RR of --counts (default 0.2,0.5,0.8,1)",
                                         "chapter 07's floor, E by chapter 08's estimators with N = --counts",
                                         NULL};
enum { KIND_SPP, KIND_ROULETTE, KIND_ESTIMATORS };

/* The strip of `kind`, composed and written with its record. */
static int run(const cli_options *opts, int kind, const double *counts, int n)
{
    static strip s; /* panels and labels: not on the stack */
    ray_counters counters = {0};
    double start = timer_seconds();
    bool ok;
    if (kind == KIND_ESTIMATORS) {
        ok = strip_estimators(&s, opts, counts, n);
    } else {
        pt_scene sc;
        pt_scene_build_builtin(&sc, "cornell");
        path_tracer pt = path_tracer_defaults(&sc);
        ok = kind == KIND_SPP ? strip_spp(&s, &pt, opts, counts, n, &counters)
                              : strip_roulette(&s, &pt, opts, counts, n, &counters);
        pt_scene_free(&sc);
    }
    image out = ok ? strip_compose(&s) : (image){0};
    char err[IMAGE_ERROR_SIZE] = "out of memory";
    ok = out.rgb != NULL && image_write(&out, opts->out, opts->exposure, err, sizeof err) &&
         program_write_record(opts, PROGRAM, &counters, timer_seconds() - start, err, sizeof err);
    if (!ok)
        fprintf(stderr, "%s: %s\n", PROGRAM, err);
    else if (!opts->quiet)
        printf("%s: wrote %s (%dx%d)\n", PROGRAM, opts->out, out.width, out.height);
    image_free(&out);
    strip_free(&s);
    return ok ? 0 : 1;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/convergence_strip.exr", 128, 128, 64);
    cli_choice kind = {KIND_NAMES, KIND_NOTES, KIND_SPP};
    const char *counts_text = NULL;
    cli_flag extras[] = {
        {"--kind", CLI_CHOICE, &kind, NULL, "which strip (default spp)", 0, 0},
        {"--counts", CLI_STRING, &counts_text, "A,B,..", "one panel per value: spp, P_RR or N (see --kind)", 0, 0},
    };
    cli_spec spec = {PROGRAM,
                     "Pictures of convergence for the book: one scene side by side at several sample counts\n"
                     "(chapter 09's Cornell box; chapter 07's floor by chapter 08's estimators) or several P_RR,\n"
                     "each panel labelled. --width and --height are one panel's size.",
                     extras, sizeof extras / sizeof extras[0], NULL};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if (opts.scene != NULL) { /* say so rather than ignore it */
        fprintf(stderr, "%s: --scene: the strips show the chapters' built-in scenes; render a scene file with\n"
                        "09-path-tracing --scene FILE --spp N for each N\n", PROGRAM);
        return 2;
    }
    const char *defaults[] = {"1,4,16,64,256", "0.2,0.5,0.8,1", "1,4,16,64,256"};
    double counts[MAX_PANELS];
    int n;
    bool roulette = kind.index == KIND_ROULETTE;
    if (counts_text == NULL)
        counts_text = defaults[kind.index];
    if (!parse_counts(counts_text, roulette ? 0.01 : 1, roulette ? 1 : 1 << 16, !roulette, counts, &n))
        return 2;
    /* the record's spp is --spp, which only the roulette strip uses: say what each panel had */
    run_record_note("strip", cli_choice_name(&kind));
    run_record_note(roulette ? "rr_probabilities" : "samples_per_panel", counts_text);
    return run(&opts, kind.index, counts, n);
}

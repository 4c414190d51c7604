#include "progress.h"

#include <stdio.h>
#include <unistd.h>

#include "timer.h"

/* Redraw at most this often: often enough to look alive, rarely enough that
 * printing never shows in the timings. */
static const double PROGRESS_REDRAW_SECONDS = 0.25;

void progress_begin(progress *p, const char *label, int64_t total, bool quiet)
{
    p->label = label;
    p->total = total;
    p->done = 0;
    p->start_seconds = timer_seconds();
    p->last_print_seconds = p->start_seconds;
    p->enabled = !quiet && isatty(fileno(stderr));
}

static void progress_draw(const progress *p, double now)
{
    double fraction = p->total > 0 ? (double)p->done / (double)p->total : 1.0;
    double elapsed = now - p->start_seconds;
    double remaining = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    fprintf(stderr, "\r%s: %5.1f%%  %.1fs elapsed, %.1fs left   ", p->label, 100.0 * fraction, elapsed, remaining);
    fflush(stderr);
}

void progress_advance(progress *p, int64_t amount)
{
    if (!p->enabled)
        return;
    int64_t done;
#pragma omp atomic capture
    done = p->done += amount;
    (void)done;
    double now = timer_seconds(), last;
#pragma omp atomic read
    last = p->last_print_seconds;
    if (now - last < PROGRESS_REDRAW_SECONDS)
        return;
#pragma omp critical(progress_draw)
    {
        if (now - p->last_print_seconds >= PROGRESS_REDRAW_SECONDS) {
#pragma omp atomic write
            p->last_print_seconds = now;
            progress_draw(p, now);
        }
    }
}

void progress_end(progress *p)
{
    if (!p->enabled)
        return;
    p->done = p->total;
    progress_draw(p, timer_seconds());
    fputc('\n', stderr);
}

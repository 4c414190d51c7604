/* timer.h -- a monotonic clock in seconds (never jumps with the wall clock). */
#ifndef TIMER_H
#define TIMER_H

double timer_seconds(void);

#endif

#include "explain.h"

#include <stdarg.h>

FILE *explain_stream = NULL;

void explain_begin(FILE *out) { explain_stream = out; }

void explain_end(void)
{
    if (explain_stream != NULL)
        fflush(explain_stream);
    explain_stream = NULL;
}

void explain_print_line(int depth, const char *format, ...)
{
    if (explain_stream == NULL)
        return;
    fprintf(explain_stream, "%*s", 2 * (depth < 0 ? 0 : depth > 40 ? 40 : depth), "");
    va_list args;
    va_start(args, format);
    vfprintf(explain_stream, format, args);
    va_end(args);
    fputc('\n', explain_stream);
}

const char *explain_vec3(char buffer[64], vec3 v)
{
    snprintf(buffer, 64, "(%.4g, %.4g, %.4g)", (double)v.x, (double)v.y, (double)v.z);
    return buffer;
}

void explain_ray(int depth, const char *label, ray r)
{
    char o[64], d[64];
    explain_line(depth, "%s: from %s towards %s", label, explain_vec3(o, r.origin), explain_vec3(d, r.direction));
}

/* run_record.c -- what a run was (see run_record.h). One record per
 * process, written by the main thread before and after rendering. */
#include "run_record.h"

#include <stdio.h>
#include <string.h>

enum { COMMAND_SIZE = 4096, NOTE_COUNT = 16, NOTE_SIZE = 256 };

static char command[COMMAND_SIZE];
static bool recorded;
static const cli_options *options; /* main()'s, alive for the whole run */
static int saved_argc;
static char **saved_argv; /* main()'s, alive for the whole run */
static char note_keys[NOTE_COUNT][64], note_values[NOTE_COUNT][NOTE_SIZE];
static int note_count;

/* The length of the well-formed UTF-8 sequence at s (RFC 3629: no
 * overlong forms, no surrogates, nothing past U+10FFFF), or 0. */
static size_t utf8_sequence(const unsigned char *s)
{
    unsigned char c = s[0];
    size_t n = c < 0x80 ? 1 : c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3 : c >= 0xf0 && c <= 0xf4 ? 4 : 0;
    for (size_t i = 1; i < n; i++)
        if ((s[i] & 0xc0) != 0x80)
            return 0; /* (the string's '\0' ends a sequence early here too) */
    if ((c == 0xe0 && s[1] < 0xa0) || (c == 0xed && s[1] > 0x9f) || (c == 0xf0 && s[1] < 0x90) ||
        (c == 0xf4 && s[1] > 0x8f))
        return 0;
    return n;
}

/* s as the body of a JSON string: quotes, backslashes and control bytes
 * escaped. JSON text is Unicode: a byte that is not part of well-formed
 * UTF-8 (a file name in Latin-1, say: a name on Linux is any bytes) is
 * written as U+FFFD, the replacement character, one for each such byte,
 * so the file stays valid JSON and says where a byte was not text.
 * Returns the characters written (less than size). */
static size_t json_escape(const char *s, char *out, size_t size)
{
    size_t n = 0;
    for (const unsigned char *p = (const unsigned char *)s; *p != '\0' && n + 7 < size;) {
        unsigned char c = *p;
        size_t length = utf8_sequence(p);
        if (c == '"' || c == '\\')
            n += (size_t)snprintf(out + n, size - n, "\\%c", c);
        else if (c < 0x20)
            n += (size_t)snprintf(out + n, size - n, "\\u%04x", c);
        else if (length == 0)
            n += (size_t)snprintf(out + n, size - n, "\\ufffd");
        else {
            memcpy(out + n, p, length);
            n += length;
        }
        p += length > 0 ? length : 1;
    }
    out[n] = '\0';
    return n;
}

void run_record_command(int argc, char **argv, const cli_options *opts)
{
    size_t n = 0;
    command[0] = '\0';
    for (int i = 0; i < argc && n + 2 < sizeof command; i++) {
        /* an argument with a space or a quote is shown in single quotes, so the line can be pasted back */
        bool quote = strpbrk(argv[i], " \t\"'\\") != NULL || argv[i][0] == '\0';
        n += (size_t)snprintf(command + n, sizeof command - n, "%s%s%s%s", i > 0 ? " " : "", quote ? "'" : "",
                              argv[i], quote ? "'" : "");
        if (n >= sizeof command)
            n = sizeof command - 1;
    }
    options = opts;
    saved_argc = argc;
    saved_argv = argv;
    recorded = true;
}

/* Flags that do not change the image (where it goes, how many threads,
 * how long to go on, what is printed), and those the checkpoint names
 * apart (size, samples, seed, scene: read from the options, which a scene
 * file may have set). The last two are switches, the rest take a value. */
static const char *const NOT_IMAGE_FLAGS[] = {
    "--out", "--threads", "--exposure", "--checkpoint", "--checkpoint-every", "--resume", "--max-input-mb",
    "--time-budget", "--target-error", "--width", "--height", "--spp", "--seed", "--scene", "--quiet", "-q", NULL};
enum { NOT_IMAGE_SWITCHES = 2 };

/* The index in NOT_IMAGE_FLAGS of arg ("--out" or "--out=x"), or -1. */
static int not_image_flag(const char *arg, bool *with_value)
{
    for (int k = 0; NOT_IMAGE_FLAGS[k] != NULL; k++) {
        size_t n = strlen(NOT_IMAGE_FLAGS[k]);
        if (strncmp(arg, NOT_IMAGE_FLAGS[k], n) == 0 && (arg[n] == '\0' || arg[n] == '=')) {
            *with_value = arg[n] == '=';
            return k;
        }
    }
    return -1;
}

void run_record_image_flags(char *out, size_t size)
{
    size_t n = 0;
    out[0] = '\0';
    int count = 0;
    while (NOT_IMAGE_FLAGS[count] != NULL)
        count++;
    for (int i = 1; i < saved_argc && n < size; i++) {
        bool with_value = false;
        int k = not_image_flag(saved_argv[i], &with_value);
        if (k >= 0) {
            if (!with_value && k < count - NOT_IMAGE_SWITCHES)
                i++; /* and its value */
            continue;
        }
        n += (size_t)snprintf(out + n, size - n, "%s%s", n > 0 ? " " : "", saved_argv[i]);
    }
}

void run_record_note(const char *key, const char *value)
{
    int k = 0;
    while (k < note_count && strcmp(note_keys[k], key) != 0)
        k++;
    if (k == NOTE_COUNT)
        return;
    snprintf(note_keys[k], sizeof note_keys[k], "%s", key);
    snprintf(note_values[k], sizeof note_values[k], "%s", value);
    if (k == note_count)
        note_count++;
}

bool run_record_json(char *out, size_t size)
{
    out[0] = '\0';
    if (!recorded)
        return true;
    char cmd[2 * COMMAND_SIZE], scene[2 * 1024];
    json_escape(command, cmd, sizeof cmd);
    if (options->scene != NULL)
        json_escape(options->scene, scene, sizeof scene);
    size_t n = (size_t)snprintf(out, size,
                                "\"command\": \"%s\",\n  \"version\": \"%s\",\n  \"seed\": %llu,\n  \"threads\": %d,\n"
                                "  \"width\": %d,\n  \"height\": %d,\n  \"spp\": %d,\n  \"scene\": %s%s%s",
                                cmd, PROJECT_VERSION, (unsigned long long)options->seed, options->threads,
                                options->width, options->height, options->spp, options->scene != NULL ? "\"" : "",
                                options->scene != NULL ? scene : "null", options->scene != NULL ? "\"" : "");
    for (int k = 0; k < note_count && n < size; k++) {
        char value[2 * NOTE_SIZE];
        json_escape(note_values[k], value, sizeof value);
        /* a note that is a JSON list (the effects) is written as it is */
        bool list = note_values[k][0] == '[';
        n += (size_t)snprintf(out + n, size - n, ",\n  \"%s\": %s%s%s", note_keys[k], list ? "" : "\"",
                              list ? note_values[k] : value, list ? "" : "\"");
    }
    return n < size;
}

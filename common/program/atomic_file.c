/* atomic_file.c -- temporary file, fsync, rename (see atomic_file.h). */
#include "atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Makes temporary names unique between threads of this process; the pid
 * separates processes, O_EXCL catches anything else. */
static atomic_uint temp_counter;

/* ---- a signal in the middle of a write ----------------------------------------
 * SIGINT, SIGTERM or SIGHUP while a file is being written (a long render's
 * checkpoint, stopped by Ctrl-C or by mpirun stopping the ranks) would
 * leave its temporary file beside the target. The handler removes every
 * temporary file in flight, then lets the signal end the process as it
 * would have. It is installed at the first write, for the signals whose
 * action is still the default (a program's own handler, or a signal that
 * is ignored, as SIGINT is for a background job, stays as it is). */
enum { IN_FLIGHT_SLOTS = 16 };
static char *_Atomic in_flight[IN_FLIGHT_SLOTS];
static atomic_flag handlers_installed = ATOMIC_FLAG_INIT;
static const int CLEANUP_SIGNALS[] = {SIGINT, SIGTERM, SIGHUP};

static void remove_in_flight(int sig)
{
    for (int k = 0; k < IN_FLIGHT_SLOTS; k++) {
        char *temp = atomic_load(&in_flight[k]);
        if (temp != NULL)
            unlink(temp); /* async-signal-safe */
    }
    signal(sig, SIG_DFL);
    raise(sig);
}

static void install_handlers(void)
{
    if (atomic_flag_test_and_set(&handlers_installed))
        return;
    for (size_t k = 0; k < sizeof CLEANUP_SIGNALS / sizeof CLEANUP_SIGNALS[0]; k++) {
        struct sigaction old, action;
        if (sigaction(CLEANUP_SIGNALS[k], NULL, &old) != 0 || old.sa_handler != SIG_DFL)
            continue;
        memset(&action, 0, sizeof action);
        action.sa_handler = remove_in_flight;
        sigemptyset(&action.sa_mask);
        sigaction(CLEANUP_SIGNALS[k], &action, NULL);
    }
}

/* While a temporary file exists its name is in a slot (if one is free). */
static void track(char *temp, bool on)
{
    for (int k = 0; k < IN_FLIGHT_SLOTS; k++) {
        char *expected = on ? NULL : temp;
        if (atomic_compare_exchange_strong(&in_flight[k], &expected, on ? temp : NULL))
            return;
    }
}

/* err may be NULL (or empty) for callers that do not want the message. */
static void set_error(char *err, size_t err_size, const char *path, int failure)
{
    if (err != NULL && err_size > 0)
        snprintf(err, err_size, "cannot write '%s': %s", path, failure > 0 ? strerror(failure) : "a write failed");
}

static void release(atomic_file *f)
{
    if (f->temp_path != NULL)
        track(f->temp_path, false);
    free(f->path);
    free(f->temp_path);
    f->path = f->temp_path = NULL;
    f->stream = NULL;
}

/* Creates the temporary file, its name tracked before the file exists: a
 * signal between the two would otherwise leave a file the handler does not
 * know (the handler may run on any thread, so blocking signals here would
 * not close the gap). Not mkstemp: it creates the file with mode 0600, and
 * the finished file should get the usual 0666 & ~umask like any other the
 * program writes. */
static int create_temp(atomic_file *f, size_t size)
{
    int fd = -1;
    for (int attempt = 0; attempt < 100 && fd < 0; attempt++) {
        unsigned n = atomic_fetch_add(&temp_counter, 1u);
        snprintf(f->temp_path, size, "%s.tmp.%ld.%u", f->path, (long)getpid(), n);
        track(f->temp_path, true);
        fd = open(f->temp_path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0)
            break;
        int failure = errno;
        track(f->temp_path, false);
        errno = failure;
        if (failure != EEXIST)
            break;
    }
    return fd;
}

bool atomic_file_open(atomic_file *f, const char *path, char *err, size_t err_size)
{
    size_t size = strlen(path) + 64;
    f->stream = NULL;
    f->path = strdup(path);
    f->temp_path = malloc(size);
    install_handlers();
    int fd = f->path != NULL && f->temp_path != NULL ? create_temp(f, size) : (errno = ENOMEM, -1);
    if (fd >= 0 && (f->stream = fdopen(fd, "w")) == NULL) {
        int failure = errno;
        close(fd);
        unlink(f->temp_path);
        errno = failure;
    }
    if (f->stream == NULL) {
        set_error(err, err_size, path, errno);
        release(f);
        return false;
    }
    return true;
}

bool atomic_file_open_in(atomic_file *f, const char *dir, const char *name, char *err, size_t err_size)
{
    size_t size = strlen(dir) + strlen(name) + 2;
    char *path = malloc(size);
    if (path == NULL) {
        set_error(err, err_size, name, ENOMEM);
        return false;
    }
    snprintf(path, size, "%s/%s", dir, name);
    bool ok = atomic_file_open(f, path, err, err_size);
    free(path);
    return ok;
}

/* fsync before rename: otherwise a crash soon after could leave the new
 * name on a file whose data never reached the disk. fclose is checked
 * because some filesystems report write errors only there. */
bool atomic_file_commit(atomic_file *f, char *err, size_t err_size)
{
    /* -1: an earlier write failed (the stream's error flag), and its errno
     * may be long gone. */
    int failure = 0;
    errno = 0;
    if (fflush(f->stream) != 0 || ferror(f->stream))
        failure = errno != 0 ? errno : -1;
    if (failure == 0 && fsync(fileno(f->stream)) != 0)
        failure = errno;
    if (fclose(f->stream) != 0 && failure == 0)
        failure = errno;
    if (failure == 0 && rename(f->temp_path, f->path) != 0)
        failure = errno;
    if (failure != 0) {
        set_error(err, err_size, f->path, failure);
        unlink(f->temp_path);
    }
    release(f);
    return failure == 0;
}

void atomic_file_abandon(atomic_file *f)
{
    if (f->stream != NULL)
        fclose(f->stream);
    unlink(f->temp_path);
    release(f);
}

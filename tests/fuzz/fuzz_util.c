/* SPDX-License-Identifier: MIT */
/* fuzz_util.c: the shared helpers of the fuzz targets (fuzz.h). */
#include "fuzz.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

double fz_clock_ms;

const char *fz_file(const char *tag, const uint8_t *data, size_t size)
{
    static char path[512];
    const char *d = getenv("TMPDIR");
    if (!d || !*d) /* tmpfs: a file per input on disk costs more than the parse */
        d = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    snprintf(path, sizeof path, "%s/cf-fuzz-%ld-%s", d, (long)getpid(), tag);
    FILE *f = fopen(path, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f)) {
        fprintf(stderr, "fuzz: cannot write %s\n", path);
        abort();
    }
    return path;
}

void fz_one_line(const char *msg)
{
    if (!msg || !*msg || strchr(msg, '\n')) {
        fprintf(stderr, "fuzz: error message is not one line: '%s'\n", msg ? msg : "(null)");
        abort();
    }
}

void fz_names(const char *msg, const char *what)
{
    if (!strstr(msg, what)) {
        fprintf(stderr, "fuzz: error message '%s' does not name '%s'\n", msg, what);
        abort();
    }
}

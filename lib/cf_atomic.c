/* SPDX-License-Identifier: MIT */
/* cf_atomic.c: write-to-temporary-then-rename (cf_atomic.h). */
#include "cf_atomic.h"
#include "cf_err.h"
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

int cf_atomic_open(cf_atomic_t *a, const char *path, char *msg, size_t ml)
{
    a->f = NULL;
    a->path = path;
    int n = snprintf(a->tmp, sizeof a->tmp, "%s.tmp.%ld", path, (long)getpid());
    if (n < 0 || (size_t)n >= sizeof a->tmp)
        return cf_fail(msg, ml, CF_EIO, "%s: path too long", path);
    a->f = fopen(a->tmp, "w+"); /* readable: a writer may patch what it wrote */
    if (!a->f)
        return cf_fail(msg, ml, CF_EIO, "%s: cannot create: %s", a->tmp, strerror(errno));
    return CF_OK;
}

int cf_atomic_commit(cf_atomic_t *a, int sync, char *msg, size_t ml)
{
    int err = 0;
    if (fflush(a->f) || ferror(a->f))
        err = errno ? errno : EIO;
    if (!err && sync && fsync(fileno(a->f)))
        err = errno;
    if (fclose(a->f) && !err)
        err = errno ? errno : EIO;
    a->f = NULL;
    if (!err && rename(a->tmp, a->path))
        err = errno;
    if (err) {
        remove(a->tmp);
        return cf_fail(msg, ml, CF_EIO, "%s: write failed: %s", a->path, strerror(err));
    }
    return CF_OK;
}

void cf_atomic_abort(cf_atomic_t *a)
{
    if (a->f)
        fclose(a->f);
    a->f = NULL;
    remove(a->tmp);
}

long long cf_atomic_stamp(void)
{
    const char *e = getenv("SOURCE_DATE_EPOCH");
    char *end;
    long long t = e && *e ? strtoll(e, &end, 10) : 0;
    if (!e || !*e || *end || t < 0)
        t = (long long)time(NULL);
    return t;
}

/* SPDX-License-Identifier: MIT */
/* cf_store_file.c: rig_store_t on a POSIX file (cf_store_file.h). */
#include "cf_store_file.h"
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int fail(cf_store_file_t *f, const char *what, int e)
{
    snprintf(f->err, sizeof f->err, "%s: %s", what, strerror(e));
    return (e == ENOSPC || e == EDQUOT || e == EFBIG) ? RIG_EFULL : RIG_EIO;
}

static int write_all(cf_store_file_t *f, const void *buf, size_t n)
{
    const char *p = buf;
    while (n > 0) {
        ssize_t w = write(f->fd, p, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0)
            return fail(f, "write", errno);
        if (w == 0)
            return fail(f, "write", ENOSPC);
        p += w;
        n -= (size_t)w;
    }
    return RIG_OK;
}

/* The gathered appends to the file. */
static int flush(cf_store_file_t *f)
{
    if (!f->wlen)
        return RIG_OK;
    size_t n = f->wlen;
    f->wlen = 0; /* written or failed: never written twice */
    /* A write cut short (a full disk) is cut back to the size before it:
     * the file then ends on a whole append, as it would one write each. */
    struct stat sb;
    off_t before = fstat(f->fd, &sb) ? -1 : sb.st_size;
    int rc = write_all(f, f->wbuf, n);
    if (rc && before >= 0 && ftruncate(f->fd, before) != 0)
        rc = fail(f, "truncate", errno);
    return rc;
}

static int f_append(void *ctx, const void *buf, size_t n)
{
    cf_store_file_t *f = ctx;
    if (f->mode == CF_STORE_READ)
        return RIG_ESTATE;
    if (!f->wbuf)
        return write_all(f, buf, n);
    if (f->wlen + n > f->wcap) {
        int rc = flush(f);
        if (rc)
            return rc;
    }
    if (n > f->wcap)
        return write_all(f, buf, n);
    memcpy(f->wbuf + f->wlen, buf, n);
    f->wlen += n;
    return RIG_OK;
}

static int f_sync(void *ctx)
{
    cf_store_file_t *f = ctx;
    int rc = flush(f);
    if (rc)
        return rc;
    if (fsync(f->fd))
        return fail(f, "fsync", errno);
    return RIG_OK;
}

static int f_read(void *ctx, uint64_t off, void *buf, size_t n, size_t *got)
{
    cf_store_file_t *f = ctx;
    char *p = buf;
    *got = 0;
    int rc = flush(f);
    if (rc)
        return rc;
    while (*got < n) {
        ssize_t r = pread(f->fd, p + *got, n - *got, (off_t)(off + *got));
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return fail(f, "read", errno);
        if (r == 0)
            break;
        *got += (size_t)r;
    }
    return RIG_OK;
}

static int f_size(void *ctx, uint64_t *bytes)
{
    cf_store_file_t *f = ctx;
    struct stat sb;
    int rc = flush(f);
    if (rc)
        return rc;
    if (fstat(f->fd, &sb))
        return fail(f, "stat", errno);
    *bytes = (uint64_t)sb.st_size;
    return RIG_OK;
}

static int f_truncate(void *ctx, uint64_t bytes)
{
    cf_store_file_t *f = ctx;
    if (f->mode == CF_STORE_READ)
        return RIG_ESTATE;
    struct stat sb;
    f->wlen = 0; /* a cut-back after a failure: what was gathered goes */
    if (f->wbuf && !fstat(f->fd, &sb) && (uint64_t)sb.st_size < bytes)
        bytes = (uint64_t)sb.st_size;
    if (ftruncate(f->fd, (off_t)bytes))
        return fail(f, "truncate", errno);
    return RIG_OK;
}

static const rig_store_ops_t file_ops = {RIG_OPS_VERSION, f_append, f_sync,
                                         f_read,          f_size,   f_truncate};

/* fsync the directory holding path: a new file's name is durable only then. */
static void sync_dir(const char *path)
{
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    int fd = open(dir, O_RDONLY | O_DIRECTORY);
    if (fd >= 0) {
        fsync(fd);
        close(fd);
    }
}

int cf_store_file_open(cf_store_file_t *f, const char *path, int mode, rig_store_t *st, char *msg,
                       size_t len)
{
    memset(f, 0, sizeof *f);
    f->fd = -1;
    int fl = mode == CF_STORE_READ    ? O_RDONLY
             : mode == CF_STORE_WRITE ? O_RDWR | O_APPEND
                                      : O_RDWR | O_APPEND | O_CREAT | O_EXCL;
    int fd = open(path, fl | O_CLOEXEC, 0644);
    if (fd < 0) {
        if (msg)
            snprintf(msg, len, "%s: %s", path, strerror(errno));
        return RIG_EOPEN;
    }
    if (mode == CF_STORE_CREATE)
        sync_dir(path);
    f->fd = fd;
    f->mode = mode;
    st->ops = &file_ops;
    st->ctx = f;
    return RIG_OK;
}

void cf_store_file_close(cf_store_file_t *f)
{
    if (f && f->fd >= 0) {
        (void)flush(f); /* unsynced, as without the buffer: a torn tail at worst */
        free(f->wbuf);
        f->wbuf = NULL;
        f->wlen = f->wcap = 0;
        close(f->fd);
        f->fd = -1;
    }
}

int cf_store_file_buffer(cf_store_file_t *f, size_t bytes)
{
    if (!f || f->fd < 0 || f->wbuf || !bytes)
        return RIG_EARG;
    if (!(f->wbuf = malloc(bytes)))
        return RIG_EIO;
    f->wcap = bytes;
    f->wlen = 0;
    return RIG_OK;
}

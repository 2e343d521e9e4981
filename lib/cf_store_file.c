/* SPDX-License-Identifier: MIT */
/* cf_store_file.c: rig_store_t on a POSIX file (cf_store_file.h). */
#include "cf_store_file.h"
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int fail(cf_store_file_t *f, const char *what, int e)
{
    snprintf(f->err, sizeof f->err, "%s: %s", what, strerror(e));
    return (e == ENOSPC || e == EDQUOT || e == EFBIG) ? RIG_EFULL : RIG_EIO;
}

static int f_append(void *ctx, const void *buf, size_t n)
{
    cf_store_file_t *f = ctx;
    const char *p = buf;
    if (f->mode == CF_STORE_READ)
        return RIG_ESTATE;
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

static int f_sync(void *ctx)
{
    cf_store_file_t *f = ctx;
    if (fsync(f->fd))
        return fail(f, "fsync", errno);
    return RIG_OK;
}

static int f_read(void *ctx, uint64_t off, void *buf, size_t n, size_t *got)
{
    cf_store_file_t *f = ctx;
    char *p = buf;
    *got = 0;
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
        close(f->fd);
        f->fd = -1;
    }
}

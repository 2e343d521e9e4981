/* SPDX-License-Identifier: MIT */
/* cf_portfile.c: serve's port file, claimed under a lock so a stale one is
 * replaced and a live one is never taken over (cf_portfile.h). */
#include "cf_portfile.h"
#include "cf_err.h"
#include "cf_log.h"
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* The old contents: port and PID, 0 when absent. */
static void read_old(int fd, long *port, long *pid)
{
    char buf[64];
    ssize_t n = pread(fd, buf, sizeof buf - 1, 0);
    *port = *pid = 0;
    if (n <= 0)
        return;
    buf[n] = 0;
    if (sscanf(buf, "%ld %ld", port, pid) < 1)
        *port = 0;
}

int cf_portfile_claim(cf_portfile_t *pf, const char *path, char *msg, size_t ml)
{
    pf->fd = -1;
    if (strlen(path) >= sizeof pf->path)
        return cf_fail(msg, ml, CF_EIO, "port file %s: name too long", path);
    snprintf(pf->path, sizeof pf->path, "%s", path);
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
        return cf_fail(msg, ml, CF_EIO, "port file %s: %s", path, strerror(errno));
    struct flock lk;
    memset(&lk, 0, sizeof lk);
    lk.l_type = F_WRLCK;
    lk.l_whence = SEEK_SET;
    long port, pid;
    if (fcntl(fd, F_SETLK, &lk)) {
        int e = errno;
        read_old(fd, &port, &pid);
        close(fd);
        if (e == EAGAIN || e == EACCES)
            return cf_fail(msg, ml, CF_EIO,
                           "port file %s is held by a running serve (pid %ld, port %ld): not "
                           "started",
                           path, pid, port);
        return cf_fail(msg, ml, CF_EIO, "port file %s: cannot lock: %s", path, strerror(e));
    }
    read_old(fd, &port, &pid);
    if (port || pid)
        cf_log(CF_LOG_WARN,
               "port file %s: stale (port %ld, serve pid %ld no longer holds it): replaced", path,
               port, pid);
    if (ftruncate(fd, 0)) {
        int e = errno;
        close(fd);
        return cf_fail(msg, ml, CF_EIO, "port file %s: %s", path, strerror(e));
    }
    pf->fd = fd;
    return 0;
}

int cf_portfile_write(cf_portfile_t *pf, int port)
{
    char buf[64];
    int n = snprintf(buf, sizeof buf, "%d\n%ld\n", port, (long)getpid());
    /* One write at offset 0 of an empty file: a reader sees all or nothing. */
    if (pf->fd < 0 || pwrite(pf->fd, buf, (size_t)n, 0) != n)
        return CF_EIO;
    return 0;
}

void cf_portfile_release(cf_portfile_t *pf, int remove_it)
{
    if (pf->fd < 0)
        return;
    if (remove_it)
        unlink(pf->path); /* while still locked: no other serve took it meanwhile */
    close(pf->fd);
    pf->fd = -1;
}

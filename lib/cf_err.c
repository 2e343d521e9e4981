/* SPDX-License-Identifier: MIT */
/* cf_err.c: strings for host error codes (and the firmware's). */
#include "cf_err.h"
#include "nf_err.h"
#include "rig_err.h"
#include <stdarg.h>
#include <stdio.h>

const char *cf_strerror(int err)
{
    switch (err) {
    case CF_EIO: return "input/output error";
    case CF_EPARSE: return "malformed input";
    case CF_ENOMEM: return "out of memory";
    case CF_ENOTFOUND: return "not found";
    case CF_EUNSUPPORTED: return "unsupported input";
    case CF_EARG: return "invalid argument (caller bug)";
    case CF_EEMPTY: return "no points in input";
    default: return err <= -200 ? rig_strerror(err) : nf_strerror(err);
    }
}

int cf_fail(char *msg, size_t len, int err, const char *fmt, ...)
{
    if (msg && len) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, len, fmt, ap);
        va_end(ap);
    }
    return err;
}

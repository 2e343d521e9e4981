/* SPDX-License-Identifier: MIT */
/* cf_err.h: error codes of the host tools (files, parsing, usage). Negative
 * values; 0 is success. Messages with file and line go into a caller's
 * buffer, the code says which kind of failure it was. */
#ifndef CF_ERR_H
#define CF_ERR_H

#include <stddef.h>

typedef enum cf_err {
    CF_OK = 0,
    CF_EIO = -101,          /* cannot open, read or write a file */
    CF_EPARSE = -102,       /* malformed input: says file and line/record */
    CF_ENOMEM = -103,       /* host allocation failed */
    CF_ENOTFOUND = -104,    /* requested entity/record not in the file */
    CF_EUNSUPPORTED = -105, /* valid input we do not handle (says what) */
    CF_EARG = -106,         /* caller bug */
    CF_EEMPTY = -107        /* file holds no points */
} cf_err_t;

/* A static string for every cf_err_t and every nf_err_t value. */
const char *cf_strerror(int err);

/* snprintf into a message buffer; buffer may be NULL. Returns err. */
int cf_fail(char *msg, size_t len, int err, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

#endif

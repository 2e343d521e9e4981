/* SPDX-License-Identifier: MIT */
/* cf_sha256.h: SHA-256 (FIPS 180-4, Section 6.2), for the checksums of the
 * result files recorded with each job (results.db, the plant database). */
#ifndef CF_SHA256_H
#define CF_SHA256_H

#include <stddef.h>
#include <stdint.h>

#define CF_SHA256_HEX 65 /* 64 hex digits and the NUL */

typedef struct cf_sha256 {
    uint32_t h[8];
    uint64_t len; /* bytes so far */
    uint8_t buf[64];
    size_t nbuf;
} cf_sha256_t;

void cf_sha256_init(cf_sha256_t *s);
void cf_sha256_update(cf_sha256_t *s, const void *data, size_t n);
void cf_sha256_final(cf_sha256_t *s, uint8_t out[32]);

/* The digest of n bytes as lower-case hex. */
void cf_sha256_hex(const void *data, size_t n, char out[CF_SHA256_HEX]);

/* The digest of a file as lower-case hex: CF_OK or CF_EIO. */
int cf_sha256_file(const char *path, char out[CF_SHA256_HEX]);

#endif

/* SPDX-License-Identifier: MIT */
/* cf_uuid.h: random (version 4) UUIDs, for job identities that stay unique
 * across cells, restarts and clock changes (RFC 9562, Section 5.4). */
#ifndef CF_UUID_H
#define CF_UUID_H

#define CF_UUID_LEN 37 /* 36 characters and the NUL */

/* A new UUID as "xxxxxxxx-xxxx-4xxx-yxxx-xxxxxxxxxxxx" (lower case) from
 * the kernel's random source. CF_OK, or CF_EIO when it cannot be read. */
int cf_uuid_new(char out[CF_UUID_LEN]);

/* 1 when s is a UUID in that form (any version), else 0. */
int cf_uuid_valid(const char *s);

#endif

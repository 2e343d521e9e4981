/* SPDX-License-Identifier: MIT */
/* bd_text.h: tiny text formatting for board reports. No printf: newlib's
 * printf family pulls in malloc and tens of KiB of flash. */
#ifndef BD_TEXT_H
#define BD_TEXT_H

#include <stddef.h>

typedef struct bd_text {
    char *buf;
    size_t cap; /* bytes of buf, the terminating NUL included */
    size_t len;
} bd_text_t;

/* Empty string in buf; appends below truncate silently at cap - 1. */
void bd_text_init(bd_text_t *t, char *buf, size_t cap);
void bd_text_str(bd_text_t *t, const char *s);
void bd_text_long(bd_text_t *t, long v);
/* Scientific notation with 7 significant digits, "-1.234568e-09", which
 * strtod and awk read back. */
void bd_text_sci(bd_text_t *t, double v);

#endif

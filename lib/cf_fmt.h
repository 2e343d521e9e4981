/* SPDX-License-Identifier: MIT */
/* cf_fmt.h: a double as the text printf's "%.17g" gives, fast. Seventeen
 * significant digits read back to the same double; glibc takes about 7,000
 * instructions a number for it (multi-precision), which made writing a
 * 10^5-point IGES net a third of a fit. */
#ifndef CF_FMT_H
#define CF_FMT_H

#include <stddef.h>

/* The bytes snprintf(b, bl, "%.17g", x) writes, and its return value.
 * Exact 128-bit integer arithmetic for 1e-16 <= |x| < 1e17 (rounding half
 * to even on the binary value, as glibc does); snprintf itself elsewhere
 * (zero, subnormal, huge, inf, NaN). bl >= 32. */
int cf_fmt17(double x, char *b, size_t bl);

#endif

/* SPDX-License-Identifier: MIT */
/* cf_fmt.h: a double as the text printf's "%.17g" gives, fast. Seventeen
 * significant digits read back to the same double; glibc takes about 7,000
 * instructions a number for it (multi-precision), which made writing a
 * 10^5-point IGES net a third of a fit. */
#ifndef CF_FMT_H
#define CF_FMT_H

#include <stddef.h>

/* The bytes snprintf(b, bl, "%.17g", x) writes, and its return value.
 * Exact integer arithmetic for zero and 1e-16 <= |x| < 1e17 (rounding half
 * to even on the binary value, as glibc does); snprintf itself elsewhere
 * (subnormal, huge, inf, NaN). bl >= 32. */
int cf_fmt17(double x, char *b, size_t bl);

/* The same text as IGES writes it (cf_iges_write.c): the 'e' of an
 * exponent as 'E', and ".0" added before the exponent or at the end when
 * there is no '.' ("1" -> "1.0", "1e-05" -> "1.0E-05"); its length.
 * bl >= 32. */
int cf_fmt17_iges(double x, char *b, size_t bl);

#endif

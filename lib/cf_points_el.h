/* SPDX-License-Identifier: MIT */
/* cf_points_el.h: Eisel-Lemire fast path of the point reader's number
 * parser: m * 10^q correctly rounded to a double from a 64-bit mantissa and
 * a 128-bit truncation of 5^q, when the truncation cannot change the
 * rounding; otherwise it says so and the caller takes the exact slow path.
 * The table of 5^q (q = CF_PEL_QMIN..CF_PEL_QMAX) is computed once, at the
 * first call, with exact multi-word integer arithmetic (no generated file).
 * Only normal results are decided: subnormals, overflow and zero go to the
 * caller's fallback. Needs unsigned __int128 (CF_PEL_HAVE); without it
 * cf_pel_decide always declines. */
#ifndef CF_POINTS_EL_H
#define CF_POINTS_EL_H

#include <stdint.h>

#define CF_PEL_QMIN (-342)
#define CF_PEL_QMAX 308

#if defined(__SIZEOF_INT128__)
#define CF_PEL_HAVE 1
#else
#define CF_PEL_HAVE 0
#endif

/* m * 10^q correctly rounded (round to nearest, ties to even) into *out when
 * the result is a normal double and the 128-bit product decides it: 1.
 * 0 (nothing written) when the caller must compute it exactly. m > 0. */
int cf_pel_decide(uint64_t m, long q, double *out);

/* The same for a value known only to lie in [m * 10^q, (m + 1) * 10^q]
 * (digits beyond the 19th dropped): decided when both ends round alike. */
int cf_pel_decide_range(uint64_t m, long q, double *out);

/* 1 when long double division has the x87's 64-bit significand here, so
 * that the readers' 80-bit check (cf_points.c, cf_iges_read.c) is exact: not
 * under valgrind (it keeps 80-bit values as doubles) or with the x87's
 * precision control lowered. Probed once, thread-safe. */
int cf_pel_ext_ok(void);

/* The table entry for 5^q: T = floor(5^q * 2^-s), 2^127 <= T < 2^128 (hi,
 * lo words), exact when 0 <= q <= 55. For the tests. */
void cf_pel_pow5(long q, uint64_t *hi, uint64_t *lo, int *s);

#endif

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

#include <float.h>
#include <stdint.h>
#include <string.h>

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

/* The shortcuts both text readers share (cf_points.c, cf_iges_read.c). */

/* x87 extended evaluation would round Clinger's operation twice. */
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD != 0
#define CF_PEL_FAST 0
#else
#define CF_PEL_FAST 1
#endif

/* With x87 80-bit long double, mantissas of up to 19 digits (%.17g text)
 * have an exact check too; see cf_pel_fast. */
#if CF_PEL_FAST && LDBL_MANT_DIG == 64 && (defined(__x86_64__) || defined(__i386__))
#define CF_PEL_EXT 1
#else
#define CF_PEL_EXT 0
#endif

/* Eight digits at a time (SWAR, as in fast_float) on little-endian hosts
 * with __builtin_ctzll; elsewhere one digit at a time. Either way the same
 * mantissa and digit counts, so the same value. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ && defined(__GNUC__)
#define CF_PEL_SWAR 1
#else
#define CF_PEL_SWAR 0
#endif

extern const double cf_pel_p10[23]; /* 10^0..10^22: exact doubles */
#if CF_PEL_EXT
extern const long double cf_pel_p10l[28]; /* 10^0..10^27: exact in 64 bits */
#endif
extern const uint64_t cf_pel_p10u[9]; /* 10^0..10^8 */

#if CF_PEL_SWAR
/* The run of up to 8 decimal digits at p (8 bytes are read: the caller's
 * buffer has room after its NUL): their count, and their value in *val.
 * Bytes below the first non-digit neither carry nor borrow, so its high
 * bit in t is exact; the bytes above it are shifted out. */
static inline __attribute__((always_inline)) int cf_pel_digits8(const char *p, uint64_t *val)
{
    uint64_t v;
    memcpy(&v, p, 8);
    const uint64_t t = ((v + UINT64_C(0x4646464646464646)) | (v - UINT64_C(0x3030303030303030))) &
                       UINT64_C(0x8080808080808080);
    const int n = t ? __builtin_ctzll(t) >> 3 : 8;
    if (!n)
        return 0;
    v -= UINT64_C(0x3030303030303030);
    if (n < 8)
        v <<= 8 * (8 - n); /* the digits to the high bytes, zeros (leading) below */
    v = v * 10 + (v >> 8);
    v = (((v & UINT64_C(0x000000FF000000FF)) * (100 + (UINT64_C(1000000) << 32))) +
         (((v >> 16) & UINT64_C(0x000000FF000000FF)) * (1 + (UINT64_C(10000) << 32)))) >>
        32;
    *val = v & 0xFFFFFFFFu;
    return n;
}
#endif

/* m * 10^e10 (m > 0; drop: digits after the 19th were dropped, the value
 * lies in [m, m + 1] * 10^e10) correctly rounded by the exact shortcuts in
 * turn: 1 with *out, or 0 when the caller must take strtod.
 * - Clinger: m and 10^|e10| exact doubles, one IEEE operation.
 * - x87: m < 2^64 and 10^|e10| <= 10^27 are exact in the 64-bit
 *   significand, so x is m 10^e10 rounded once to 64 bits; rounding x to 53
 *   bits is then exact unless x lies on a midpoint between two doubles (low
 *   11 bits 10000000000): a monotone rounding cannot move a value across a
 *   midpoint it can represent. Only where cf_pel_ext_ok (not under
 *   valgrind). Cheaper than Eisel-Lemire where it applies (4 against 7 ns a
 *   value on 17-digit mantissas).
 * - Eisel-Lemire (cf_pel_decide): nearly every other normal value, longer
 *   mantissas too when both ends of the dropped digits' interval round
 *   alike. */
static inline int cf_pel_fast(uint64_t m, long e10, int drop, double *out)
{
    if (CF_PEL_FAST && !drop && m <= (UINT64_C(1) << 53) && e10 >= -22 && e10 <= 22) {
        const double d = (double)m;
        *out = e10 < 0 ? d / cf_pel_p10[-e10] : d * cf_pel_p10[e10];
        return 1;
    }
#if CF_PEL_EXT
    if (!drop && e10 >= -27 && e10 <= 27 && cf_pel_ext_ok()) {
        long double x = (long double)m;
        uint64_t sig;
        x = e10 < 0 ? x / cf_pel_p10l[-e10] : x * cf_pel_p10l[e10];
        memcpy(&sig, &x, sizeof sig); /* x86 extended: bytes 0-7 hold the significand */
        if ((sig & 0x7FF) != 0x400) {
            *out = (double)x;
            return 1;
        }
    }
#endif
    return drop ? cf_pel_decide_range(m, e10, out) : cf_pel_decide(m, e10, out);
}

/* The table entry for 5^q: T = floor(5^q * 2^-s), 2^127 <= T < 2^128 (hi,
 * lo words), exact when 0 <= q <= 55. For the tests. */
void cf_pel_pow5(long q, uint64_t *hi, uint64_t *lo, int *s);

#endif

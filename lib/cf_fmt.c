/* SPDX-License-Identifier: MIT */
/* cf_fmt.c: "%.17g" by exact integer arithmetic (see cf_fmt.h): the 17
 * digits are round(|x| 10^k) for the k that makes them 17, from one
 * 128-bit product m 5^k shifted by the binary exponent; the digits leave
 * eight at a time (SWAR). About 90 instructions a value, 545 before. */
#include "cf_fmt.h"
#include <stdint.h>
#include <stdio.h>
#include <string.h>

typedef unsigned __int128 u128;

#define P8 100000000ULL           /* 10^8 */
#define P16 10000000000000000ULL  /* 10^16 */
#define P17 100000000000000000ULL /* 10^17 */
#define P5_27 7450580596923828125ULL

/* Eight digits to bytes at once where a uint64_t's bytes are in memory
 * order low to high; elsewhere one digit at a time. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ && defined(__GNUC__)
#define FM_SWAR 1
#else
#define FM_SWAR 0
#endif

/* Inlined into each caller: a call and its register saves were a tenth. */
#if defined(__GNUC__)
#define FM_INLINE static inline __attribute__((always_inline))
#else
#define FM_INLINE static inline
#endif

/* 5^k, k = 0..32 (5^32 < 2^75). */
static const u128 fm_p5[33] = {1ULL,
                               5ULL,
                               25ULL,
                               125ULL,
                               625ULL,
                               3125ULL,
                               15625ULL,
                               78125ULL,
                               390625ULL,
                               1953125ULL,
                               9765625ULL,
                               48828125ULL,
                               244140625ULL,
                               1220703125ULL,
                               6103515625ULL,
                               30517578125ULL,
                               152587890625ULL,
                               762939453125ULL,
                               3814697265625ULL,
                               19073486328125ULL,
                               95367431640625ULL,
                               476837158203125ULL,
                               2384185791015625ULL,
                               11920928955078125ULL,
                               59604644775390625ULL,
                               298023223876953125ULL,
                               1490116119384765625ULL,
                               P5_27,
                               (u128)P5_27 * 5u,
                               (u128)P5_27 * 25u,
                               (u128)P5_27 * 125u,
                               (u128)P5_27 * 625u,
                               (u128)P5_27 * 3125u};

/* 10^-16 .. 10^17 as doubles: a first guess of the decimal exponent only
 * (the digit count decides it, below). */
static const double fm_p10[34] = {1e-16, 1e-15, 1e-14, 1e-13, 1e-12, 1e-11, 1e-10, 1e-9, 1e-8,
                                  1e-7,  1e-6,  1e-5,  1e-4,  1e-3,  1e-2,  1e-1,  1e0,  1e1,
                                  1e2,   1e3,   1e4,   1e5,   1e6,   1e7,   1e8,   1e9,  1e10,
                                  1e11,  1e12,  1e13,  1e14,  1e15,  1e16,  1e17};

/* round(m 2^e2 10^k) to the nearest integer, ties to even, or 0 when it
 * leaves 64 bits (the caller falls back). 0 <= k <= 32, m < 2^53. The
 * shift right by r is done in 64-bit words (variable 128-bit shifts cost
 * three times as much): the quotient q, the remainder's leading 64 bits
 * left-aligned (top: 2^63 is half), and whether any bit below them is set. */
static inline uint64_t fm_scaled(uint64_t m, int e2, int k)
{
    const u128 n = (u128)m * fm_p5[k]; /* 2^k of 10^k joins the binary exponent */
    const uint64_t hi = (uint64_t)(n >> 64), lo = (uint64_t)n;
    const int s = e2 + k;
    if (s >= 0) {
        if (s > 63 || (n >> (64 - s)) != 0)
            return 0;
        return (uint64_t)(n << s);
    }
    const int r = -s;
    uint64_t q, top, below = 0;
    if (r < 64) {
        if (hi >> r)
            return 0;
        q = (hi << (64 - r)) | (lo >> r);
        top = lo << (64 - r);
    } else if (r == 64) {
        q = hi;
        top = lo;
    } else if (r < 128) {
        q = hi >> (r - 64);
        top = (hi << (128 - r)) | (lo >> (r - 64));
        below = lo << (128 - r);
    } else {
        return 0;
    }
    const uint64_t half = UINT64_C(1) << 63;
    if (top > half || (top == half && (below || (q & 1u))))
        q++; /* q < 2^64 - 1 here: n < 2^128 and r >= 1 */
    return q;
}

#if FM_SWAR
/* v < 10^8 as its eight decimal digits (values 0-9, not yet ASCII), the
 * first in the lowest byte: 4 + 4 digits in 32-bit lanes, each split by 100
 * into 16-bit lanes, each of those by 10 into bytes. The multiply-shifts
 * are exact divisions below 10^4 (by 100) and 100 (by 10). */
FM_INLINE uint64_t fm_enc8(uint32_t v)
{
    uint64_t x = (uint64_t)(v / 10000u) | ((uint64_t)(v % 10000u) << 32);
    const uint64_t h = ((x * 10486u) >> 20) & UINT64_C(0x0000007F0000007F);
    x = h | ((x - 100u * h) << 16);
    const uint64_t t = ((x * 103u) >> 10) & UINT64_C(0x000F000F000F000F);
    return t | ((x - 10u * t) << 8);
}
#endif

/* snprintf, with the IGES edits when iges is set. */
static int fm_slow(double x, char *b, size_t bl, int iges)
{
    int n = snprintf(b, bl, "%.17g", x);
    if (!iges || n < 0 || (size_t)n + 3 > bl)
        return n;
    char *e = memchr(b, 'e', (size_t)n);
    if (e)
        *e = 'E';
    if (!memchr(b, '.', (size_t)n)) {
        size_t at = e ? (size_t)(e - b) : (size_t)n;
        memmove(b + at + 2, b + at, (size_t)n - at + 1);
        b[at] = '.';
        b[at + 1] = '0';
        n += 2;
    }
    return n;
}

FM_INLINE int fm_fmt(double x, char *b, size_t bl, int iges)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    const int be = (int)(bits >> 52 & 0x7FF), neg = (int)(bits >> 63);
    if (bl < 32)
        return fm_slow(x, b, bl, iges);
    if ((bits << 1) == 0) { /* "0", "-0" */
        char *o = b;
        *o = '-';
        o += neg;
        memcpy(o, iges ? "0.0" : "0", iges ? 4 : 2);
        return (int)(o - b) + (iges ? 3 : 1);
    }
    const double ax = neg ? -x : x;
    if (!(ax >= 1e-16 && ax < 1e17)) /* NaN too */
        return fm_slow(x, b, bl, iges);
    const uint64_t m = (bits & ((1ULL << 52) - 1)) | (1ULL << 52);
    const int e2 = be - 1075; /* x = m 2^e2 */
    /* Decimal exponent: floor(log10 2^(be-1023)), one more when x is above
     * the double nearest 10^(E+1) (then above 10^(E+1) itself). Never too
     * big: the loop below mends a guess one too small (a 17-digit result
     * of 10^17 is the carry of 9.99...), not one too big (10^16 could be
     * a rounding up). */
    int E = (int)((double)(be - 1023) * 0.30102999566398120);
    E = be - 1023 < 0 ? E - 1 : E;
    if (E + 17 >= 0 && E + 17 < 34 && ax > fm_p10[E + 17])
        E++;
    uint64_t D = 0;
    for (int t = 0; t < 4; t++) {
        const int k = 16 - E;
        if (k < 0 || k > 32)
            return fm_slow(x, b, bl, iges);
        D = fm_scaled(m, e2, k);
        if (D == 0)
            return fm_slow(x, b, bl, iges);
        if (D >= P17) /* a carry to 10^17 gives 10^16 at k - 1: "1" */
            E++;
        else if (D < P16) /* not from the guess; kept as a guard */
            E--;
        else
            break;
    }
    if (D < P16 || D >= P17)
        return fm_slow(x, b, bl, iges);
    /* dg: the 17 digits, then '0's for the fixed-size copies below */
    char dg[40];
    int nd; /* %g drops trailing zeros */
#if FM_SWAR
    const uint64_t a = D / P16, r = D - a * P16, hi = r / P8;
    const uint64_t dh = fm_enc8((uint32_t)hi), dl = fm_enc8((uint32_t)(r - hi * P8));
    const uint64_t ch = dh + UINT64_C(0x3030303030303030), cl = dl + UINT64_C(0x3030303030303030);
    dg[0] = (char)('0' + a);
    memcpy(dg + 1, &ch, 8);
    memcpy(dg + 9, &cl, 8);
    nd = dl ? 17 - (__builtin_clzll(dl) >> 3) : dh ? 9 - (__builtin_clzll(dh) >> 3) : 1;
#else
    for (int i = 16; i >= 0; i--, D /= 10)
        dg[i] = (char)('0' + D % 10);
    nd = 17;
    while (nd > 1 && dg[nd - 1] == '0')
        nd--;
#endif
    memset(dg + 17, '0', sizeof dg - 17);
    /* Written whole words at a time: at most 36 bytes, so into b directly
     * when it has room for them. */
    char tmp[48], *s = bl >= sizeof tmp ? b : tmp, *o = s;
    *o = '-';
    o += neg;
    if (E >= 0) { /* %f style, E <= 16: the integer digits, then the rest */
        memcpy(o, dg, 17);
        o += E + 1;
        if (nd > E + 1) {
            *o = '.';
            memcpy(o + 1, dg + E + 1, 16);
            o += 1 + nd - (E + 1);
        } else if (iges) {
            memcpy(o, ".0", 2);
            o += 2;
        }
    } else if (E >= -4) { /* %f style: 0.000ddd */
        memcpy(o, "0.000000", 8);
        o += 1 - E;
        memcpy(o, dg, 17);
        o += nd;
    } else { /* %e style, -16 <= E <= -5: d.ddde-XX (d.0E-XX for IGES) */
        o[0] = dg[0];
        o[1] = '.';
        memcpy(o + 2, dg + 1, 16);
        o += nd > 1 ? nd + 1 : iges ? 3 : 1;
        o[0] = iges ? 'E' : 'e';
        o[1] = '-';
        o[2] = (char)('0' + -E / 10);
        o[3] = (char)('0' + -E % 10);
        o += 4;
    }
    *o = '\0';
    const int n = (int)(o - s);
    if (s != b)
        memcpy(b, s, (size_t)n + 1);
    return n;
}

int cf_fmt17(double x, char *b, size_t bl)
{
    return fm_fmt(x, b, bl, 0);
}

int cf_fmt17_iges(double x, char *b, size_t bl)
{
    return fm_fmt(x, b, bl, 1);
}

/* SPDX-License-Identifier: MIT */
/* cf_fmt.c: "%.17g" by exact integer arithmetic (see cf_fmt.h). */
#include "cf_fmt.h"
#include <stdint.h>
#include <stdio.h>
#include <string.h>

typedef unsigned __int128 u128;

#define P16 10000000000000000ULL  /* 10^16 */
#define P17 100000000000000000ULL /* 10^17 */

/* round(m 2^e2 10^k) to the nearest integer, ties to even, or 0 when the
 * product leaves 128 bits (the caller falls back). 0 <= k <= 32. */
static uint64_t scaled(uint64_t m, int e2, int k)
{
    u128 n = m;
    for (int i = 0; i < k; i++) /* 5^k: m < 2^53, 5^32 < 2^75 */
        n *= 5u;
    const int s = e2 + k; /* 2^k of 10^k joins the binary exponent */
    if (s >= 0) {
        if (s > 60 || (n >> (64 - s)) != 0)
            return 0;
        n <<= s;
        return n >> 64 ? 0 : (uint64_t)n;
    }
    if (-s >= 128)
        return 0;
    const int r = -s;
    const u128 q = n >> r, rem = n - (q << r), half = (u128)1 << (r - 1);
    u128 d = q;
    if (rem > half || (rem == half && (q & 1u)))
        d++;
    return d >> 64 ? 0 : (uint64_t)d;
}

int cf_fmt17(double x, char *b, size_t bl)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    const int be = (int)(bits >> 52 & 0x7FF);
    if (be == 0 || be == 0x7FF || bl < 32 || !(x < 1e17 && x > -1e17) || (x < 1e-16 && x > -1e-16))
        return snprintf(b, bl, "%.17g", x);
    const uint64_t m = (bits & ((1ULL << 52) - 1)) | (1ULL << 52);
    const int e2 = be - 1075; /* x = m 2^e2 */
    /* decimal exponent: log10(2) ~ 0.30103, off by at most one, fixed below */
    int E = (int)((double)(be - 1023) * 0.30102999566398120);
    E = be - 1023 < 0 ? E - 1 : E;
    uint64_t D = 0;
    for (int t = 0; t < 4; t++) {
        const int k = 16 - E;
        if (k < 0 || k > 32)
            return snprintf(b, bl, "%.17g", x);
        D = scaled(m, e2, k);
        if (D == 0)
            return snprintf(b, bl, "%.17g", x);
        if (D >= P17)
            E++;
        else if (D < P16)
            E--;
        else
            break;
    }
    if (D < P16 || D >= P17)
        return snprintf(b, bl, "%.17g", x);
    char dg[17];
    for (int i = 16; i >= 0; i--, D /= 10)
        dg[i] = (char)('0' + D % 10);
    int nd = 17; /* %g drops trailing zeros */
    while (nd > 1 && dg[nd - 1] == '0')
        nd--;
    char *o = b;
    if (x < 0)
        *o++ = '-';
    if (E >= -4 && E < 17) { /* %f style */
        if (E < 0) {
            *o++ = '0';
            *o++ = '.';
            for (int i = 0; i < -E - 1; i++)
                *o++ = '0';
            for (int i = 0; i < nd; i++)
                *o++ = dg[i];
        } else {
            for (int i = 0; i <= E; i++)
                *o++ = i < nd ? dg[i] : '0';
            if (nd > E + 1) {
                *o++ = '.';
                for (int i = E + 1; i < nd; i++)
                    *o++ = dg[i];
            }
        }
    } else { /* %e style: d.ddd, e, sign, at least two exponent digits */
        *o++ = dg[0];
        if (nd > 1) {
            *o++ = '.';
            for (int i = 1; i < nd; i++)
                *o++ = dg[i];
        }
        *o++ = 'e';
        *o++ = E < 0 ? '-' : '+';
        const int ae = E < 0 ? -E : E;
        if (ae >= 100)
            *o++ = (char)('0' + ae / 100);
        *o++ = (char)('0' + ae / 10 % 10);
        *o++ = (char)('0' + ae % 10);
    }
    *o = '\0';
    return (int)(o - b);
}

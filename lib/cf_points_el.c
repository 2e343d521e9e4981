/* SPDX-License-Identifier: MIT */
/* cf_points_el.c: Eisel-Lemire fast path for decimal to double (the method
 * of Lemire, "Number parsing at a gigabyte per second", 2021; our own code
 * and our own decision rule, below). The value m * 10^q is w * 2^-lz * 5^q *
 * 2^q with w = m normalised to bit 63; 5^q = F * 2^s with 2^127 <= F <
 * 2^128 and T = floor(F) in the table. The exact product X = w F lies in
 * [P, P + w) with P = w T (192 bits; X = P when T = F, i.e. 0 <= q <= 55),
 * X >= 2^190. Rounding X to 53 bits keeps the bits above L - 1 (L = 139 when
 * P >= 2^191, else 138), so it is decided when no multiple of 2^(L-1) falls
 * in (P, P + 2^64): then X's half bit and all bits above are P's, and X is
 * not a tie. When one does (for -27 <= q < 0 whenever 5^-q divides m: X is
 * then exactly that multiple), exact integer arithmetic says on which side
 * of it X lies, or that X is on it. */
#include "cf_points_el.h"
#include <float.h>
#include <pthread.h>
#include <string.h>

#if CF_PEL_HAVE
typedef unsigned __int128 pel_u128;

typedef struct pel_pow {
    uint64_t hi, lo;
    int s;
} pel_pow_t;

static pel_pow_t pel_tab[CF_PEL_QMAX - CF_PEL_QMIN + 1];
static pthread_once_t pel_once = PTHREAD_ONCE_INIT;

/* Multi-word integers for the table, 32-bit words, least significant first:
 * 2^PEL_K / 5^342 still has more than 128 bits (5^342 < 2^795). */
#define PEL_K 1024
#define PEL_W (PEL_K / 32 + 1)

static int pel_bits(const uint32_t *b)
{
    for (int i = PEL_W - 1; i >= 0; i--)
        if (b[i])
            return 32 * i + 32 - __builtin_clz(b[i]);
    return 0;
}

/* Bits i .. i + 63 of B (zero outside it), a word at a time: the table
 * is built at the first number read, inside every fit's clock (bit by bit
 * it cost 1.2 M instructions, a few percent of a fit of 4,000 points). */
static uint64_t pel_bits64(const uint32_t *b, int i)
{
    uint64_t r = 0;
    const int w0 = i >= 0 ? i / 32 : -((31 - i) / 32);
    for (int w = w0; w <= w0 + 2; w++) {
        if (w < 0 || w >= PEL_W)
            continue;
        const int off = 32 * w - i; /* where the word's bit 0 lands */
        if (off >= 0 && off < 64)
            r |= (uint64_t)b[w] << off;
        else if (off < 0 && off > -32)
            r |= (uint64_t)b[w] >> -off;
    }
    return r;
}

/* T = floor(B * 2^-s), s = bits(B) - 128: the top 128 bits, truncated (for
 * s < 0, B shifted left: exact). */
static void pel_top(const uint32_t *b, pel_pow_t *t, int extra)
{
    int s = pel_bits(b) - 128;
    t->lo = pel_bits64(b, s);
    t->hi = pel_bits64(b, s + 64);
    t->s = s - extra;
}

static void pel_build(void)
{
    uint32_t b[PEL_W];
    /* q >= 0: 5^q exactly, by repeated multiplication. */
    memset(b, 0, sizeof b);
    b[0] = 1;
    for (long q = 0; q <= CF_PEL_QMAX; q++) {
        pel_top(b, &pel_tab[q - CF_PEL_QMIN], 0);
        uint64_t c = 0;
        for (int i = 0; i < PEL_W; i++) {
            c += (uint64_t)b[i] * 5;
            b[i] = (uint32_t)c;
            c >>= 32;
        }
    }
    /* q < 0: floor(2^K / 5^n) by repeated division (floor(floor(x)/5) =
     * floor(x/5)), whose top 128 bits are floor(2^(K-j) / 5^n): s = j - K. */
    memset(b, 0, sizeof b);
    b[PEL_K / 32] = 1;
    for (long n = 1; n <= -CF_PEL_QMIN; n++) {
        uint64_t rem = 0;
        for (int i = PEL_W - 1; i >= 0; i--) {
            uint64_t cur = (rem << 32) | b[i];
            b[i] = (uint32_t)(cur / 5);
            rem = cur % 5;
        }
        pel_top(b, &pel_tab[-n - CF_PEL_QMIN], PEL_K);
    }
}

void cf_pel_pow5(long q, uint64_t *hi, uint64_t *lo, int *s)
{
    pthread_once(&pel_once, pel_build);
    const pel_pow_t *t = &pel_tab[q - CF_PEL_QMIN];
    *hi = t->hi;
    *lo = t->lo;
    *s = t->s;
}

/* m against K 5^n 2^E, exactly: -1, 0, 1 (n <= 27, K < 2^55: K 5^n <
 * 2^118). */
static int pel_side(uint64_t m, uint64_t K, int n, int E)
{
    pel_u128 a = K, b = m;
    for (int i = 0; i < n; i++)
        a *= 5;
    if (E >= 0) {
        if (a > b || E >= 64)
            return -1; /* a <= m < 2^64 below: a << E fits */
        a <<= E;
    } else if (-E <= 64) {
        b <<= -E;
    } else if (-E >= 118) {
        return 1;
    } else { /* m 2^64 against a / 2^(-E-64), the remainder breaking a tie */
        int sh = -E - 64;
        pel_u128 hi = a >> sh, lo = a & (((pel_u128)1 << sh) - 1);
        b <<= 64;
        return b > hi ? 1 : b < hi || lo ? -1 : 0;
    }
    return b > a ? 1 : b < a ? -1 : 0;
}

/* The bits of the double m * 10^q, or 0 when undecided (never a valid
 * answer here: results are normal, so nonzero). */
static uint64_t pel_one(uint64_t m, long q)
{
    const pel_pow_t *t = &pel_tab[q - CF_PEL_QMIN];
    int lz = __builtin_clzll(m);
    uint64_t w = m << lz;
    pel_u128 lo = (pel_u128)w * t->lo;
    pel_u128 mid = (pel_u128)w * t->hi + (uint64_t)(lo >> 64); /* < 2^128: no overflow */
    uint64_t p0 = (uint64_t)lo, p1 = (uint64_t)mid, p2 = (uint64_t)(mid >> 64);
    int top = (int)(p2 >> 63); /* P >= 2^191 */
    int sh = 9 + top;          /* L - 1 - 128 */
    uint64_t mask = (UINT64_C(1) << sh) - 1, rh = p2 & mask;
    uint64_t k = p2 >> sh; /* floor(P / 2^(L-1)): 53 bits and the half bit */
    uint64_t mant = k >> 1;
    int half = (int)(k & 1);
    if (q >= 0 && q <= 55) { /* X = P: round to nearest, ties to even */
        int sticky = rh || p1 || p0;
        mant += (uint64_t)(half && (sticky || (mant & 1)));
    } else {
        /* X in (P, P + w), w < 2^64: a multiple of 2^(L-1) can lie there
         * only when P mod 2^(L-1) > 2^(L-1) - 2^64. */
        if (rh == mask && p1 == UINT64_MAX && p0) {
            /* M0 = (k + 1) 2^(L-1) lies in (P, P + 2^64). For q < -27 or q
             * > 55, X is never a multiple of 2^(L-1) and this is rare
             * (about 2^-73): decline. For -27 <= q < 0 it is X exactly when
             * 5^-q divides m (X then just above P): compare m 10^q with M0
             * as integers, m against (k + 1) 5^-q 2^(L-1+s-lz). */
            if (q > 0 || q < -27)
                return 0;
            int c = pel_side(m, k + 1, (int)-q, 128 + sh + t->s - lz);
            if (c >= 0) { /* X in [M0, M0 + 2^64): k + 1's bits */
                k++;
                mant = k >> 1;
                half = (int)(k & 1);
                if (c == 0) /* X = M0: exact, or a tie (to even) */
                    half = half && (mant & 1);
            }
        }
        mant += (uint64_t)half; /* X strictly above or below the half way */
    }
    long e = 138 + top + 52 + t->s + q - lz; /* unbiased exponent of mant's bit 52 */
    if (e < -1022)
        return 0; /* subnormal (or below): the caller's exact path */
    if (mant >> 53) {
        mant >>= 1;
        e++;
    }
    if (e > 1023)
        return 0; /* overflow: the caller's path names it */
    return ((uint64_t)(e + 1023) << 52) | (mant & ((UINT64_C(1) << 52) - 1));
}

int cf_pel_decide(uint64_t m, long q, double *out)
{
    if (!m || q < CF_PEL_QMIN || q > CF_PEL_QMAX)
        return 0;
    pthread_once(&pel_once, pel_build);
    uint64_t b = pel_one(m, q);
    if (!b)
        return 0;
    memcpy(out, &b, sizeof *out);
    return 1;
}

int cf_pel_decide_range(uint64_t m, long q, double *out)
{
    if (!m || m == UINT64_MAX || q < CF_PEL_QMIN || q > CF_PEL_QMAX)
        return 0;
    pthread_once(&pel_once, pel_build);
    uint64_t a = pel_one(m, q), b = pel_one(m + 1, q);
    if (!a || a != b) /* rounding is monotone: equal ends decide all between */
        return 0;
    memcpy(out, &a, sizeof *out);
    return 1;
}

#else

int cf_pel_decide(uint64_t m, long q, double *out)
{
    (void)m, (void)q, (void)out;
    return 0;
}

int cf_pel_decide_range(uint64_t m, long q, double *out)
{
    (void)m, (void)q, (void)out;
    return 0;
}

void cf_pel_pow5(long q, uint64_t *hi, uint64_t *lo, int *s)
{
    (void)q;
    *hi = *lo = 0;
    *s = 0;
}

#endif

/* (2^64 - 1) / 3 = 0x5555555555555555 is exact in a 64-bit significand,
 * whose bytes then read 0xAAAAAAAAAAAAAAAA (normalised); the bytes are
 * looked at because under valgrind the quotient is a double that compares
 * equal to the right value anyway. */
static int pel_ext;
static pthread_once_t pel_ext_once = PTHREAD_ONCE_INIT;

static void pel_ext_probe(void)
{
#if LDBL_MANT_DIG == 64 && (defined(__x86_64__) || defined(__i386__))
    volatile uint64_t a = UINT64_MAX;
    volatile long double three = 3.0L;
    const long double q = (long double)a / three;
    uint64_t sig;
    memcpy(&sig, &q, sizeof sig);
    pel_ext = sig == UINT64_C(0xAAAAAAAAAAAAAAAA);
#else
    pel_ext = 0;
#endif
}

int cf_pel_ext_ok(void)
{
    pthread_once(&pel_ext_once, pel_ext_probe);
    return pel_ext;
}

const double cf_pel_p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                               1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                               1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
#if CF_PEL_EXT
const long double cf_pel_p10l[28] = {1e0L,  1e1L,  1e2L,  1e3L,  1e4L,  1e5L,  1e6L,
                                     1e7L,  1e8L,  1e9L,  1e10L, 1e11L, 1e12L, 1e13L,
                                     1e14L, 1e15L, 1e16L, 1e17L, 1e18L, 1e19L, 1e20L,
                                     1e21L, 1e22L, 1e23L, 1e24L, 1e25L, 1e26L, 1e27L};
#endif
const uint64_t cf_pel_p10u[9] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000};

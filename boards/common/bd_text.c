/* SPDX-License-Identifier: MIT */
/* bd_text.c: appending strings, integers and doubles to a fixed buffer. */
#include "bd_text.h"

void bd_text_init(bd_text_t *t, char *buf, size_t cap)
{
    t->buf = buf;
    t->cap = cap;
    t->len = 0;
    if (cap > 0)
        buf[0] = '\0';
}

static void put(bd_text_t *t, char c)
{
    if (t->len + 1 < t->cap) {
        t->buf[t->len++] = c;
        t->buf[t->len] = '\0';
    }
}

void bd_text_str(bd_text_t *t, const char *s)
{
    while (*s)
        put(t, *s++);
}

/* Digits of v, at least width of them (zero padded). */
static void put_digits(bd_text_t *t, unsigned long v, int width)
{
    char d[12];
    int n = 0;
    do {
        d[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v > 0 && n < (int)sizeof d);
    while (n < width--)
        put(t, '0');
    while (n > 0)
        put(t, d[--n]);
}

void bd_text_long(bd_text_t *t, long v)
{
    /* Negate in unsigned arithmetic: -LONG_MIN does not fit a long. */
    unsigned long u = (unsigned long)v;
    if (v < 0) {
        put(t, '-');
        u = 0ul - u;
    }
    put_digits(t, u, 1);
}

void bd_text_sci(bd_text_t *t, double v)
{
    if (v != v) {
        bd_text_str(t, "nan");
        return;
    }
    if (v < 0.0) {
        put(t, '-');
        v = -v;
    }
    if (v > 1.7976931348623157e308) {
        bd_text_str(t, "inf");
        return;
    }
    int e = 0;
    if (v > 0.0) {
        /* Big steps first keep the loop short; each division costs at most
         * an ulp, far below the 7 digits printed. */
        while (v >= 1e16) {
            v /= 1e16;
            e += 16;
        }
        while (v >= 10.0) {
            v /= 10.0;
            e++;
        }
        while (v < 1e-16) {
            v *= 1e16;
            e -= 16;
        }
        while (v < 1.0) {
            v *= 10.0;
            e--;
        }
    }
    unsigned long m = (unsigned long)(v * 1e6 + 0.5); /* 7 digits, rounded */
    if (m >= 10000000ul) {
        m /= 10;
        e++;
    }
    put_digits(t, m / 1000000ul, 1);
    put(t, '.');
    put_digits(t, m % 1000000ul, 6);
    put(t, 'e');
    put(t, e < 0 ? '-' : '+');
    put_digits(t, (unsigned long)(e < 0 ? -e : e), 2);
}

/* SPDX-License-Identifier: MIT */
/* cf_stats.c: streaming deviation statistics. Sums are compensated
 * (Neumaier) so mean and RMS stay exact to a few ulps over 10^9 points; the
 * percentile bins are log-spaced because the scale of the deviations is not
 * known while streaming, and a relative error is what a reader of
 * "p95 0.0312 mm" cares about at any scale. */
#include "cf_stats.h"
#include "cf_err.h"
#include "cf_json.h"
#include <math.h>
#include <string.h>

/* Bins per decade of |d|, and the histogram's bin index scale (2B + 1) / 2K:
 * |d| / tol times this, minus 1/2, rounded up, is the bin's distance from the
 * middle one. 15 / 6 = 2.5 is exact, so |d| = tol lands on its edge exactly. */
#define PBINS_PER_DECADE ((double)CF_STATS_PBINS / CF_STATS_PDECADES)
#define HIST_SCALE ((double)CF_STATS_HIST_BINS / (2.0 * CF_STATS_HIST_K))

int cf_stats_init(cf_stats_t *st, double tol)
{
    if (!st || !(tol > 0) || !isfinite(tol))
        return CF_EARG;
    memset(st, 0, sizeof *st);
    st->tol = tol;
    st->min = st->max = st->min_abs = st->max_abs = NAN;
    return CF_OK;
}

/* s + c += x, Neumaier's variant of Kahan summation. */
static void neumaier(double *s, double *c, double x)
{
    double t = *s + x;
    if (fabs(*s) >= fabs(x))
        *c += (*s - t) + x;
    else
        *c += (x - t) + *s;
    *s = t;
}

/* Bin i holds [10^(-9 + i / PBINS_PER_DECADE), ...): -9 is log10(CF_STATS_PLO). */
static int pbin(double a)
{
    int i = (int)floor((log10(a) + 9.0) * PBINS_PER_DECADE);
    return i < 0 ? 0 : i >= CF_STATS_PBINS ? CF_STATS_PBINS - 1 : i;
}

/* Geometric centre of percentile bin i, mm. */
static double pbin_mid(int i)
{
    return pow(10.0, -9.0 + (i + 0.5) / PBINS_PER_DECADE);
}

/* Histogram edge e in -B .. B + 1 (the lower edge of the bin e places right
 * of the middle one): (2e - 1) K / (2B + 1) tol, the ratio first so that the
 * edge at tol is tol exactly. Edges are symmetric: edge(1 - e) = -edge(e). */
static double hist_edge(double tol, int e)
{
    return tol * ((double)((2 * e - 1) * CF_STATS_HIST_K) / CF_STATS_HIST_BINS);
}

int cf_stats_add(cf_stats_t *st, double d)
{
    if (!isfinite(d))
        return CF_EARG;
    long long idx = st->n++;
    double a = fabs(d);
    neumaier(&st->sum, &st->sum_c, d);
    neumaier(&st->sq, &st->sq_c, d * d);
    double delta = d - st->wmean;
    st->wmean += delta / (double)st->n;
    st->m2 += delta * (d - st->wmean);
    if (idx == 0 || d < st->min) {
        st->min = d;
        st->imin = idx;
    }
    if (idx == 0 || d > st->max) {
        st->max = d;
        st->imax = idx;
    }
    if (idx == 0 || a < st->min_abs)
        st->min_abs = a;
    if (idx == 0 || a > st->max_abs) {
        st->max_abs = a;
        st->imaxabs = idx;
    }
    double u = a / st->tol;
    if (u <= 1.0)
        st->within++;
    /* Distance j of the bin from the middle one (B + 1: beyond +/- K tol):
     * the formula, then checked against the edges cf_stats_hist_bin reports,
     * so that a value on an edge is counted where the edges say. */
    double jf = ceil(u * HIST_SCALE - 0.5);
    int j = jf > CF_STATS_HIST_HALF ? CF_STATS_HIST_HALF + 1 : (int)jf;
    while (j > 0 && a <= hist_edge(st->tol, j))
        j--;
    while (j <= CF_STATS_HIST_HALF && a > hist_edge(st->tol, j + 1))
        j++;
    st->hist[1 + CF_STATS_HIST_HALF + (d > 0 ? j : -j)]++;
    if (a < CF_STATS_PLO)
        st->zero++;
    else if (a >= CF_STATS_PHI) {
        if (d > 0)
            st->pos_over++;
        else
            st->neg_over++;
    } else
        (d > 0 ? st->pos : st->neg)[pbin(a)]++;
    return CF_OK;
}

double cf_stats_mean(const cf_stats_t *st)
{
    return st->n ? (st->sum + st->sum_c) / (double)st->n : NAN;
}

double cf_stats_rms(const cf_stats_t *st)
{
    return st->n ? sqrt((st->sq + st->sq_c) / (double)st->n) : NAN;
}

double cf_stats_std(const cf_stats_t *st)
{
    return st->n > 1 ? sqrt(st->m2 / (double)(st->n - 1)) : NAN;
}

double cf_stats_within_pct(const cf_stats_t *st)
{
    return st->n ? 100.0 * (double)st->within / (double)st->n : NAN;
}

/* Nearest rank of percentile pct, 1..n; 0 for no answer. pct * n is exact
 * for integer pct (n < 2^46), so 95 % of 20 is rank 19, not 20. */
static long long rank(const cf_stats_t *st, double pct)
{
    if (!st->n || !(pct >= 0 && pct <= 100))
        return 0;
    double k = ceil(pct * (double)st->n / 100.0);
    return k < 1 ? 1 : k > (double)st->n ? st->n : (long long)k;
}

static double clamp(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

double cf_stats_percentile(const cf_stats_t *st, double pct)
{
    long long k = rank(st, pct);
    if (!k)
        return NAN;
    if (k == 1)
        return st->min;
    if (k == st->n)
        return st->max;
    /* Ascending d: the most negative bins first. */
    long long c = st->neg_over;
    if (c >= k)
        return st->min;
    for (int i = CF_STATS_PBINS - 1; i >= 0; i--)
        if ((c += st->neg[i]) >= k)
            return clamp(-pbin_mid(i), st->min, st->max);
    if ((c += st->zero) >= k)
        return clamp(0.0, st->min, st->max);
    for (int i = 0; i < CF_STATS_PBINS; i++)
        if ((c += st->pos[i]) >= k)
            return clamp(pbin_mid(i), st->min, st->max);
    return st->max;
}

double cf_stats_percentile_abs(const cf_stats_t *st, double pct)
{
    long long k = rank(st, pct);
    if (!k)
        return NAN;
    if (k == 1)
        return st->min_abs;
    if (k == st->n)
        return st->max_abs;
    long long c = st->zero;
    if (c >= k)
        return clamp(0.0, st->min_abs, st->max_abs);
    for (int i = 0; i < CF_STATS_PBINS; i++)
        if ((c += st->pos[i] + st->neg[i]) >= k)
            return clamp(pbin_mid(i), st->min_abs, st->max_abs);
    return st->max_abs;
}

void cf_stats_hist_bin(const cf_stats_t *st, int i, double *lo, double *hi, long long *count)
{
    int j = i - 1 - CF_STATS_HIST_HALF; /* bin offset from the middle */
    *lo = i <= 0 ? -INFINITY : hist_edge(st->tol, j);
    *hi = i > CF_STATS_HIST_BINS ? INFINITY : hist_edge(st->tol, j + 1);
    *count = i >= 0 && i <= CF_STATS_HIST_BINS + 1 ? st->hist[i] : 0;
}

int cf_stats_decimals(double tol)
{
    int d = (int)ceil(-log10(tol)) + 2;
    return d < 3 ? 3 : d > 12 ? 12 : d;
}

void cf_stats_json_fields(const cf_stats_t *st, cf_json_t *j)
{
    double none = NAN;
    int any = st->n > 0;
    cf_json_int(j, "points", (long)st->n);
    cf_json_num(j, "tol", st->tol);
    cf_json_num(j, "rms", cf_stats_rms(st));
    cf_json_num(j, "mean", cf_stats_mean(st));
    cf_json_num(j, "std", cf_stats_std(st));
    cf_json_num(j, "min", any ? st->min : none);
    cf_json_num(j, "max", any ? st->max : none);
    cf_json_num(j, "max_abs", any ? st->max_abs : none);
    cf_json_num(j, "min_index", any ? (double)st->imin : none);
    cf_json_num(j, "max_index", any ? (double)st->imax : none);
    cf_json_num(j, "max_abs_index", any ? (double)st->imaxabs : none);
    cf_json_int(j, "within_tol", (long)st->within);
    cf_json_num(j, "within_tol_pct", cf_stats_within_pct(st));
    static const double pcts[] = {5, 50, 95, 99};
    static const char *const names[] = {"p5", "p50", "p95", "p99"};
    static const char *const anames[] = {"p5_abs", "p50_abs", "p95_abs", "p99_abs"};
    for (int i = 0; i < 4; i++)
        cf_json_num(j, names[i], cf_stats_percentile(st, pcts[i]));
    for (int i = 0; i < 4; i++)
        cf_json_num(j, anames[i], cf_stats_percentile_abs(st, pcts[i]));
    cf_json_num(j, "pct_rel_err", CF_STATS_PCT_RELERR);
    cf_json_arr(j, "histogram");
    for (int i = 0; i <= CF_STATS_HIST_BINS + 1; i++) {
        double lo, hi;
        long long c;
        cf_stats_hist_bin(st, i, &lo, &hi, &c);
        cf_json_obj(j, NULL);
        cf_json_num(j, "lo", lo); /* null when open-ended */
        cf_json_num(j, "hi", hi);
        cf_json_int(j, "count", (long)c);
        cf_json_close(j);
    }
    cf_json_close(j);
}

void cf_stats_json(const cf_stats_t *st, FILE *f)
{
    cf_json_t j;
    cf_json_begin(&j, f);
    cf_stats_json_fields(st, &j);
    cf_json_end(&j);
}

/* A bar of up to width characters for count out of top. */
static void bar(FILE *f, long long count, long long top, int width)
{
    if (!count)
        return;
    int w = (int)((double)width * (double)count / (double)top + 0.5);
    if (w == 0)
        fputc('.', f); /* present but under half a character */
    for (int i = 0; i < w; i++)
        fputc('#', f);
}

void cf_stats_print(const cf_stats_t *st, FILE *f)
{
    int dp = cf_stats_decimals(st->tol);
    fprintf(f, "deviations d: signed normal distance to the surface, mm\n");
    fprintf(f, "  points            %lld\n", st->n);
    fprintf(f, "  tolerance         +/-%.*f\n", dp, st->tol);
    if (!st->n) {
        fprintf(f, "  (no points: nothing to report)\n");
        return;
    }
    fprintf(f, "  within tolerance  %lld (%.2f %%)\n", st->within, cf_stats_within_pct(st));
    fprintf(f, "  mean              %+.*f\n", dp, cf_stats_mean(st));
    if (st->n > 1)
        fprintf(f, "  std dev            %.*f\n", dp, cf_stats_std(st));
    fprintf(f, "  RMS                %.*f\n", dp, cf_stats_rms(st));
    fprintf(f, "  min               %+.*f  (point %lld)\n", dp, st->min, st->imin);
    fprintf(f, "  max               %+.*f  (point %lld)\n", dp, st->max, st->imax);
    static const double pcts[] = {5, 50, 95, 99};
    int cw = dp + 6; /* column width: sign, integer digits, point, decimals, gap */
    fprintf(f, "  percentile      ");
    for (int i = 0; i < 4; i++) {
        char h[16];
        snprintf(h, sizeof h, "p%g", pcts[i]);
        fprintf(f, "%*s", cw, h);
    }
    fprintf(f, "\n  d               ");
    for (int i = 0; i < 4; i++)
        fprintf(f, "%+*.*f", cw, dp, cf_stats_percentile(st, pcts[i]));
    fprintf(f, "\n  |d|             ");
    for (int i = 0; i < 4; i++)
        fprintf(f, "%*.*f", cw, dp, cf_stats_percentile_abs(st, pcts[i]));
    fprintf(f, "\n  (percentiles from log-spaced bins: within %.3g %% of the exact values)\n",
            100 * CF_STATS_PCT_RELERR);

    long long top = 1;
    for (int i = 0; i <= CF_STATS_HIST_BINS + 1; i++)
        top = st->hist[i] > top ? st->hist[i] : top;
    int lw = 2 * (dp + 3) + 4; /* width of "-0.1500 .. -0.1100" */
    fprintf(f, "\n%-*s  %10s  %6s\n", 2 + lw, "histogram of d, mm", "points", "%");
    for (int i = 0; i <= CF_STATS_HIST_BINS + 1; i++) {
        double lo, hi;
        long long c;
        char label[80];
        cf_stats_hist_bin(st, i, &lo, &hi, &c);
        /* The tolerance limits as lines across the chart, between the bins. */
        if (isfinite(lo) && fabs(lo + st->tol) < 1e-9 * st->tol)
            fprintf(f, "  %.*s lower tolerance %+.*f\n", lw, "--------------------------------", dp,
                    -st->tol);
        if (!isfinite(lo))
            snprintf(label, sizeof label, "below %+.*f", dp, hi);
        else if (!isfinite(hi))
            snprintf(label, sizeof label, "above %+.*f", dp, lo);
        else
            snprintf(label, sizeof label, "%+.*f .. %+.*f", dp, lo, dp, hi);
        fprintf(f, "  %*s  %10lld  %6.2f", lw, label, c, 100.0 * (double)c / (double)st->n);
        if (c)
            fputs("  ", f);
        bar(f, c, top, 40);
        fputc('\n', f);
        if (isfinite(hi) && fabs(hi - st->tol) < 1e-9 * st->tol)
            fprintf(f, "  %.*s upper tolerance %+.*f\n", lw, "--------------------------------", dp,
                    st->tol);
    }
}

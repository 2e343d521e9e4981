/* SPDX-License-Identifier: MIT */
/* cholmod_bench.c: CHOLMOD (SuiteSparse) on the normal equations cellfit
 * exports (`cellfit bench export --cp N --out FILE`): analyse + factorise,
 * then solve for the 3 right-hand sides (x y z), each timed; the relative
 * residual max_c ||b_c - A x_c|| / ||b_c|| (cellfit's definition) computed
 * here from the file's triplets. Prints one JSON line.
 *
 * File "CFNE0001": int64 n, int64 nnz, nnz x (int64 row, int64 col, double)
 * for the upper triangle (row <= col), then n x 3 doubles (x y z of row i).
 * Build: cc -std=c11 -O2 -I/usr/include/suitesparse cholmod_bench.c
 *        -lcholmod -lsuitesparseconfig -lm */
#include <cholmod.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct entry {
    int64_t row, col;
    double val;
} entry_t;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int fail(const char *what, const char *path)
{
    fprintf(stderr, "cholmod_bench: %s: %s\n", path, what);
    return 1;
}

/* max over the 3 columns of ||b - A x|| / ||b||, A from the upper triplets. */
static double rel_residual(int64_t n, int64_t nnz, const entry_t *e, const double *x,
                           const double *b)
{
    double *r = calloc((size_t)(3 * n), sizeof(double));
    if (!r)
        return NAN;
    for (int64_t k = 0; k < nnz; k++) {
        const int64_t i = e[k].row, j = e[k].col;
        for (int c = 0; c < 3; c++) {
            r[c * n + i] += e[k].val * x[c * n + j];
            if (i != j)
                r[c * n + j] += e[k].val * x[c * n + i];
        }
    }
    double worst = 0.0;
    for (int c = 0; c < 3; c++) {
        double rr = 0.0, bb = 0.0;
        for (int64_t i = 0; i < n; i++) {
            const double d = b[c * n + i] - r[c * n + i];
            rr += d * d;
            bb += b[c * n + i] * b[c * n + i];
        }
        const double rel = bb > 0.0 ? sqrt(rr / bb) : sqrt(rr);
        if (rel > worst || rel != rel)
            worst = rel;
    }
    free(r);
    return worst;
}

static const char *ordering_name(int o)
{
    switch (o) {
    case CHOLMOD_NATURAL: return "natural";
    case CHOLMOD_GIVEN: return "given";
    case CHOLMOD_AMD: return "amd";
    case CHOLMOD_METIS: return "metis";
    case CHOLMOD_NESDIS: return "nesdis";
    case CHOLMOD_COLAMD: return "colamd";
    case CHOLMOD_POSTORDERED: return "postordered";
    default: return "unknown";
    }
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: cholmod_bench SYSTEM.cfne\n");
        return 2;
    }
    const char *path = argv[1];
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return fail("cannot open", path);
    char magic[8];
    int64_t n = 0, nnz = 0;
    if (fread(magic, 1, 8, fp) != 8 || memcmp(magic, "CFNE0001", 8) ||
        fread(&n, sizeof n, 1, fp) != 1 || fread(&nnz, sizeof nnz, 1, fp) != 1 || n <= 0 ||
        nnz < n || nnz > n * n) {
        fclose(fp);
        return fail("not a CFNE0001 file", path);
    }
    entry_t *e = malloc((size_t)nnz * sizeof *e);
    double *brow = malloc((size_t)(3 * n) * sizeof(double));
    int bad = !e || !brow;
    for (int64_t k = 0; !bad && k < nnz; k++) {
        bad = fread(&e[k].row, sizeof(int64_t), 1, fp) != 1 ||
              fread(&e[k].col, sizeof(int64_t), 1, fp) != 1 ||
              fread(&e[k].val, sizeof(double), 1, fp) != 1;
        bad = bad || e[k].row < 0 || e[k].row > e[k].col || e[k].col >= n;
    }
    bad = bad || fread(brow, sizeof(double), (size_t)(3 * n), fp) != (size_t)(3 * n);
    fclose(fp);
    if (bad) {
        free(e);
        free(brow);
        return fail("truncated or malformed", path);
    }

    cholmod_common c;
    cholmod_l_start(&c);
    /* CSC, upper triangle (stype 1): column j holds rows i <= j. */
    cholmod_sparse *A =
        cholmod_l_allocate_sparse((size_t)n, (size_t)n, (size_t)nnz, 1, 1, 1, CHOLMOD_REAL, &c);
    cholmod_dense *B = cholmod_l_allocate_dense((size_t)n, 3, (size_t)n, CHOLMOD_REAL, &c);
    if (!A || !B) {
        free(e);
        free(brow);
        cholmod_l_finish(&c);
        return fail("out of memory", path);
    }
    SuiteSparse_long *Ap = A->p, *Ai = A->i;
    double *Ax = A->x, *Bx = B->x;
    for (int64_t j = 0; j <= n; j++)
        Ap[j] = 0;
    for (int64_t k = 0; k < nnz; k++)
        Ap[e[k].col + 1]++;
    for (int64_t j = 0; j < n; j++)
        Ap[j + 1] += Ap[j];
    SuiteSparse_long *next = malloc((size_t)n * sizeof *next);
    if (!next) {
        free(e);
        free(brow);
        cholmod_l_finish(&c);
        return fail("out of memory", path);
    }
    memcpy(next, Ap, (size_t)n * sizeof *next);
    int sorted = 1;
    for (int64_t k = 0; k < nnz; k++) {
        SuiteSparse_long at = next[e[k].col]++;
        sorted = sorted && (at == Ap[e[k].col] || Ai[at - 1] < e[k].row);
        Ai[at] = e[k].row;
        Ax[at] = e[k].val;
    }
    free(next);
    A->sorted = sorted;
    if (!sorted)
        cholmod_l_sort(A, &c);
    for (int64_t i = 0; i < n; i++) /* B is column-major: x, then y, then z */
        for (int col = 0; col < 3; col++)
            Bx[col * n + i] = brow[3 * i + col];

    const double t0 = now();
    cholmod_factor *L = cholmod_l_analyze(A, &c);
    const double t1 = now();
    int ok = L && cholmod_l_factorize(A, L, &c) && c.status == CHOLMOD_OK;
    const double t2 = now();
    cholmod_dense *X = ok ? cholmod_l_solve(CHOLMOD_A, L, B, &c) : NULL;
    const double t3 = now();
    if (!X) {
        fprintf(stderr, "cholmod_bench: %s: CHOLMOD failed, status %d\n", path, c.status);
        cholmod_l_free_factor(&L, &c);
        cholmod_l_free_sparse(&A, &c);
        cholmod_l_free_dense(&B, &c);
        cholmod_l_finish(&c);
        free(e);
        free(brow);
        return 1;
    }
    const double rel = rel_residual(n, nnz, e, X->x, Bx);
    printf("{\"bench\": \"cholmod\", \"control_points\": %lld, \"nnz_upper\": %lld, "
           "\"analyze_seconds\": %.6g, \"factor_seconds\": %.6g, "
           "\"analyze_factor_seconds\": %.6g, \"solve_seconds\": %.6g, \"seconds\": %.6g, "
           "\"rel_residual\": %.3e, \"supernodal\": %d, \"ordering\": \"%s\", "
           "\"nnz_L\": %.0f, \"flops\": %.4g, \"version\": \"%d.%d.%d\"}\n",
           (long long)n, (long long)nnz, t1 - t0, t2 - t1, t2 - t0, t3 - t2, t3 - t0, rel,
           L->is_super, ordering_name(L->ordering), c.lnz, c.fl, CHOLMOD_MAIN_VERSION,
           CHOLMOD_SUB_VERSION, CHOLMOD_SUBSUB_VERSION);
    cholmod_l_free_dense(&X, &c);
    cholmod_l_free_factor(&L, &c);
    cholmod_l_free_sparse(&A, &c);
    cholmod_l_free_dense(&B, &c);
    cholmod_l_finish(&c);
    free(e);
    free(brow);
    return rel == rel ? 0 : 1;
}

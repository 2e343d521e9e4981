/* SPDX-License-Identifier: MIT */
/* bd_budget.c: host helper printing a board's fitter budget from the byte
 * formula, compiled against that board's board_config.h (mk/cross.mk runs
 * it after every cross link; `make boards-budget` for all boards). A host
 * program, so 64-bit arithmetic and stdio are fine here.
 *   bd_budget              a human summary
 *   bd_budget --keys       max_square_gs=... max_square_chol=... max_square_pcg=...
 *   bd_budget --markdown   one row of the table in boards/README.md */
#include "nf_budget.h"
#include <stdio.h>
#include <string.h>

#define DEG NF_DESIGN_DEGREE

/* Largest N the arena alone holds with an iterative solver, whatever the
 * shape (their bytes depend on N only), ignoring NF_MAX_CP. */
static long arena_bound(nf_solver_t s)
{
    long lo = 0, hi = 1L << 40;
    while (hi - lo > 1) {
        const long mid = lo + (hi - lo) / 2;
        const long b = s == NF_SOLVER_GS ? NF_BYTES_GS(mid, DEG, DEG) : NF_BYTES_PCG(mid, DEG, DEG);
        if (b <= NF_ARENA_BYTES)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

static long side(long n)
{
    long s = 0;
    while ((s + 1) * (s + 1) <= n)
        s++;
    return s;
}

int main(int argc, char **argv)
{
    const nf_solver_t solvers[3] = {NF_SOLVER_GS, NF_SOLVER_CHOL, NF_SOLVER_PCG};
    long sq[3];
    for (int i = 0; i < 3; i++)
        sq[i] = nf_budget_max_square(NF_ARENA_BYTES, DEG, solvers[i]);

    if (argc > 1 && strcmp(argv[1], "--keys") == 0) {
        printf("max_square_gs=%ld max_square_chol=%ld max_square_pcg=%ld\n", sq[0], sq[1], sq[2]);
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--markdown") == 0) {
        printf(
            "| %s | %ld | %ld | %d | %ldx%ld (%ld) | %ldx%ld (%ld) | %ldx%ld (%ld) | %ld / %ld |\n",
            BOARD_NAME, (long)NF_ARENA_BYTES, (long)NF_MAX_CP, NF_MAX_DEGREE, side(sq[0]),
            side(sq[0]), sq[0], side(sq[1]), side(sq[1]), sq[1], side(sq[2]), side(sq[2]), sq[2],
            arena_bound(NF_SOLVER_GS), arena_bound(NF_SOLVER_PCG));
        return 0;
    }
    if (argc > 1) {
        fprintf(stderr, "usage: %s [--keys|--markdown]\n", argv[0]);
        return 2;
    }
    printf("budget %s: arena %ld bytes, NF_MAX_CP %ld, degree <= %d\n", BOARD_NAME,
           (long)NF_ARENA_BYTES, (long)NF_MAX_CP, NF_MAX_DEGREE);
    printf("  largest net at degree %d (nf_budget_max_square):", DEG);
    for (int i = 0; i < 3; i++)
        printf(" %s %ldx%ld = %ld%s", nf_solver_name(solvers[i]), side(sq[i]), side(sq[i]), sq[i],
               i < 2 ? "," : "\n");
    printf("  arena alone, any shape: gs %ld, pcg %ld control points\n", arena_bound(NF_SOLVER_GS),
           arena_bound(NF_SOLVER_PCG));
    return 0;
}

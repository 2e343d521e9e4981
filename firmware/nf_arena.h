/* SPDX-License-Identifier: MIT */
/* nf_arena.h: bump allocator over memory the caller owns (a static array on
 * a board, one host allocation of exactly the job's byte formula). Nothing
 * is freed piecemeal; a mark/release pair drops scratch storage. */
#ifndef NF_ARENA_H
#define NF_ARENA_H

#include <stddef.h>

#define NF_ARENA_ALIGN 64 /* cache line: stripes and vectors start aligned */

typedef struct nf_arena {
    unsigned char *base;
    size_t size; /* bytes usable after aligning the start */
    size_t skip; /* bytes lost aligning the start (the formula's slack covers them) */
    size_t used; /* bytes handed out */
    size_t high; /* high-water mark of used */
} nf_arena_t;

void nf_arena_init(nf_arena_t *a, void *mem, size_t size);
/* Zeroed, NF_ARENA_ALIGN-aligned block of n doubles, or NULL when exhausted. */
double *nf_arena_doubles(nf_arena_t *a, size_t n);
/* Bytes still free counting the start alignment, to hold against the byte
 * formula (which includes slack for it). */
size_t nf_arena_room(const nf_arena_t *a);
size_t nf_arena_mark(const nf_arena_t *a);
void nf_arena_release(nf_arena_t *a, size_t mark);

#endif

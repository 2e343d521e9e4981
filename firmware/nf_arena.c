/* SPDX-License-Identifier: MIT */
/* nf_arena.c: bump allocation from a caller-owned block (no heap). */
#include "nf_arena.h"
#include <stdint.h>
#include <string.h>

void nf_arena_init(nf_arena_t *a, void *mem, size_t size)
{
    /* Align the start so every block is aligned regardless of the caller. */
    uintptr_t p = (uintptr_t)mem;
    size_t skip = (NF_ARENA_ALIGN - (p % NF_ARENA_ALIGN)) % NF_ARENA_ALIGN;
    a->base = (unsigned char *)mem + (skip <= size ? skip : size);
    a->size = skip <= size ? size - skip : 0;
    a->skip = skip <= size ? skip : size;
    a->used = 0;
    a->high = 0;
}

size_t nf_arena_room(const nf_arena_t *a)
{
    return a->size - a->used + a->skip;
}

double *nf_arena_doubles(nf_arena_t *a, size_t n)
{
    if (n > (SIZE_MAX - NF_ARENA_ALIGN) / sizeof(double))
        return NULL;
    size_t bytes = (n * sizeof(double) + NF_ARENA_ALIGN - 1) / NF_ARENA_ALIGN * NF_ARENA_ALIGN;
    if (bytes > a->size - a->used)
        return NULL;
    double *d = (double *)(void *)(a->base + a->used);
    a->used += bytes;
    if (a->used > a->high)
        a->high = a->used;
    memset(d, 0, n * sizeof(double));
    return d;
}

size_t nf_arena_mark(const nf_arena_t *a)
{
    return a->used;
}

void nf_arena_release(nf_arena_t *a, size_t mark)
{
    if (mark <= a->used)
        a->used = mark;
}

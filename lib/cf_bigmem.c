/* SPDX-License-Identifier: MIT */
/* cf_bigmem.c: large buffers on transparent huge pages (cf_bigmem.h). A
 * 64-byte header before the caller's bytes says how they were made. */
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS, madvise */
#include "cf_bigmem.h"
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#define HDR 64 /* keeps the caller's bytes 64-byte aligned */
#define HUGE ((size_t)2 << 20)
#define MAGIC_MALLOC UINT64_C(0x63666267006d616c) /* "cfbg" "mal" */
#define MAGIC_MAP UINT64_C(0x63666267006d6170)    /* "cfbg" "map" */

typedef struct hdr {
    uint64_t magic;
    size_t len; /* the block's length, header included */
} hdr_t;
_Static_assert(sizeof(hdr_t) <= HDR, "the header fits its room");

#if defined(__linux__) && defined(MADV_HUGEPAGE)
/* A mapping that starts on a huge-page boundary (the kernel only backs
 * aligned 2 MiB ranges with huge pages), trimmed of the slack it took to
 * get there; NULL if mmap fails. */
static void *map_aligned(size_t len)
{
    size_t want = len + HUGE;
    char *m = mmap(NULL, want, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED)
        return NULL;
    uintptr_t a = ((uintptr_t)m + HUGE - 1) & ~(uintptr_t)(HUGE - 1);
    size_t head = a - (uintptr_t)m, tail = want - head - len;
    if (head)
        munmap(m, head);
    if (tail)
        munmap((char *)a + len, tail);
    /* Advice only: without huge pages the mapping still works. */
    (void)madvise((void *)a, len, MADV_HUGEPAGE);
    return (void *)a;
}
#endif

void *cf_bigmem_alloc(size_t n)
{
    if (n > SIZE_MAX - HDR - HUGE)
        return NULL;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (n >= CF_BIGMEM_MIN) {
        /* Whole huge pages: a tail of 4 KiB ones costs a fault each. */
        size_t len = (n + HDR + HUGE - 1) & ~(HUGE - 1);
        char *m = map_aligned(len);
        if (m) {
            hdr_t h = {MAGIC_MAP, len};
            memcpy(m, &h, sizeof h);
            return m + HDR;
        }
    }
#endif
    size_t len = (n + HDR + HDR - 1) & ~(size_t)(HDR - 1); /* aligned_alloc wants a multiple */
    char *b = aligned_alloc(HDR, len);
    if (!b)
        return NULL;
    hdr_t h = {MAGIC_MALLOC, len};
    memcpy(b, &h, sizeof h);
    return b + HDR;
}

static hdr_t header(const void *p)
{
    hdr_t h;
    memcpy(&h, (const char *)p - HDR, sizeof h);
    return h;
}

void cf_bigmem_free(void *p)
{
    if (!p)
        return;
    hdr_t h = header(p);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (h.magic == MAGIC_MAP) {
        munmap((char *)p - HDR, h.len);
        return;
    }
#endif
    free((char *)p - HDR);
}

int cf_bigmem_huge(const void *p)
{
    return p && header(p).magic == MAGIC_MAP;
}

/* SPDX-License-Identifier: MIT */
/* cf_bigmem.h: large host buffers (the fit job's arena, its batch buffers)
 * on transparent huge pages where the kernel offers them. A first touch of
 * a 2 MiB page replaces 512 faults of 4 KiB; in this project's VMs a fault
 * costs several microseconds (docs/performance.md, issue 20). Small sizes
 * and kernels without huge pages get ordinary memory; either way the
 * contents start undefined, as with malloc. */
#ifndef CF_BIGMEM_H
#define CF_BIGMEM_H

#include <stddef.h>

/* Sizes from which a separate huge-page mapping is made, in whole huge
 * pages: from half of one (a 1 MiB reader buffer costs 256 faults of 4 KiB
 * against one of 2 MiB; its resident size doubles). */
#define CF_BIGMEM_MIN ((size_t)1 << 20)

/* n bytes, 64-byte aligned; NULL when out of memory. */
void *cf_bigmem_alloc(size_t n);

/* Give back what cf_bigmem_alloc returned (NULL: nothing). */
void cf_bigmem_free(void *p);

/* 1 if p's memory is a huge-page-advised mapping (tests, reports). */
int cf_bigmem_huge(const void *p);

#endif

/* SPDX-License-Identifier: MIT */
/* ref_memstore.h: a rig_store_t in RAM for the journal tests, with the
 * faults SQLite's crash-test VFS models: the disk fills after `limit` bytes
 * (a partial write is kept, then RIG_EFULL), and a power cut keeps what was
 * synced and an arbitrary mangling of what was not. Counts syncs. */
#ifndef REF_MEMSTORE_H
#define REF_MEMSTORE_H

#include "rig.h"
#include <stddef.h>
#include <stdint.h>

#define REF_MEMSTORE_CAP (256u * 1024u)

typedef struct ref_memstore {
    uint8_t data[REF_MEMSTORE_CAP];
    size_t size;    /* bytes stored */
    size_t durable; /* bytes at the last sync */
    size_t limit;   /* appends beyond this many bytes fail with RIG_EFULL */
    long syncs;     /* sync calls */
    long appends;   /* append calls */
    int fail_sync;  /* sync returns RIG_EIO when set */
} ref_memstore_t;

/* Empty store, no limit; *st uses m. */
void ref_memstore_init(ref_memstore_t *m, rig_store_t *st);

/* A power cut: bytes after the last sync are cut at a random length and a
 * random part of what stays is overwritten with random bytes (seeded). */
void ref_memstore_crash(ref_memstore_t *m, uint64_t *seed);

#endif

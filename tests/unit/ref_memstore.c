/* SPDX-License-Identifier: MIT */
/* ref_memstore.c: the fault-injecting RAM store of the journal tests. */
#include "ref_memstore.h"
#include <string.h>

static int m_append(void *ctx, const void *buf, size_t n)
{
    ref_memstore_t *m = ctx;
    m->appends++;
    size_t room = (m->limit < REF_MEMSTORE_CAP ? m->limit : REF_MEMSTORE_CAP) - m->size;
    size_t k = n < room ? n : room;
    memcpy(m->data + m->size, buf, k); /* what fits is written, as write(2) would */
    m->size += k;
    return k == n ? RIG_OK : RIG_EFULL;
}

static int m_sync(void *ctx)
{
    ref_memstore_t *m = ctx;
    m->syncs++;
    if (m->fail_sync)
        return RIG_EIO;
    m->durable = m->size;
    return RIG_OK;
}

static int m_read(void *ctx, uint64_t off, void *buf, size_t n, size_t *got)
{
    ref_memstore_t *m = ctx;
    size_t k = off >= m->size ? 0 : (m->size - (size_t)off < n ? m->size - (size_t)off : n);
    if (k)
        memcpy(buf, m->data + off, k);
    *got = k;
    return RIG_OK;
}

static int m_size(void *ctx, uint64_t *bytes)
{
    *bytes = ((ref_memstore_t *)ctx)->size;
    return RIG_OK;
}

static int m_truncate(void *ctx, uint64_t bytes)
{
    ref_memstore_t *m = ctx;
    if (bytes > m->size)
        return RIG_EARG;
    m->size = (size_t)bytes;
    if (m->durable > m->size)
        m->durable = m->size;
    return RIG_OK;
}

static const rig_store_ops_t mem_ops = {RIG_OPS_VERSION, m_append, m_sync,
                                        m_read,          m_size,   m_truncate};

void ref_memstore_init(ref_memstore_t *m, rig_store_t *st)
{
    memset(m, 0, sizeof *m);
    m->limit = REF_MEMSTORE_CAP;
    st->ops = &mem_ops;
    st->ctx = m;
}

static uint64_t rnd(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

void ref_memstore_crash(ref_memstore_t *m, uint64_t *seed)
{
    size_t extra = m->size - m->durable;
    size_t keep = extra ? (size_t)(rnd(seed) % (extra + 1)) : 0;
    m->size = m->durable + keep;
    if (keep && rnd(seed) % 2) { /* garble a random stretch of the unsynced part */
        size_t a = (size_t)(rnd(seed) % keep), b = a + (size_t)(rnd(seed) % (keep - a)) + 1;
        for (size_t i = a; i < b; i++)
            m->data[m->durable + i] = (uint8_t)rnd(seed);
    }
}

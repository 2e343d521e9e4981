/* SPDX-License-Identifier: MIT */
/* fuzz_jnl.c: libFuzzer target for journal recovery and reading (jnl.c)
 * over a RAM store holding the input. The first byte may ask for a valid
 * header (bit 0), valid CRCs on every record (bit 1) and sequence numbers
 * in order (bit 2), so that the fuzzer reaches past the checks. Then:
 * jnl_scan; the reader must return exactly the records the scan counted;
 * jnl_open cuts any torn tail, after which a scan finds none and an append
 * and end record (when not ended) read back. */
#include "fuzz.h"
#include "jnl.h"
#include "ref_memstore.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static ref_memstore_t mem; /* 256 KiB: static, not on the stack */

static void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

static void fail(const char *why)
{
    fprintf(stderr, "fuzz_jnl: %s\n", why);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    unsigned mode = data[0];
    data++;
    size--;
    rig_store_t st;
    ref_memstore_init(&mem, &st);
    if (size > REF_MEMSTORE_CAP)
        size = REF_MEMSTORE_CAP;
    memcpy(mem.data, data, size);
    mem.size = mem.durable = size;
    if ((mode & 1) && size >= JNL_HDR_BYTES) {
        put32(mem.data, JNL_MAGIC);
        mem.data[4] = JNL_VERSION, mem.data[5] = 0;
        mem.data[6] = JNL_HDR_BYTES, mem.data[7] = 0;
        mem.data[8] = JNL_REC_BYTES, mem.data[9] = 0;
        if (!mem.data[12] && !mem.data[13] && !mem.data[14] && !mem.data[15])
            mem.data[12] = 1;
        put32(mem.data + 124, jnl_crc32(0, mem.data, 124));
    }
    for (size_t off = JNL_HDR_BYTES, i = 0; (mode & 6) && off + JNL_REC_BYTES <= size;
         off += JNL_REC_BYTES, i++) {
        if (mode & 4)
            put32(mem.data + off, (uint32_t)i);
        if (mode & 2)
            put32(mem.data + off + 76, jnl_crc32(0, mem.data + off, 76));
    }

    jnl_header_t h;
    jnl_info_t info;
    int rc = jnl_scan(st, &h, &info);
    if (rc != RIG_OK && rc != RIG_ECORRUPT)
        fail("jnl_scan: unexpected error");
    if (rc == RIG_OK) {
        if (info.records * JNL_REC_BYTES + info.tail_bytes + JNL_HDR_BYTES != size)
            fail("records and tail do not add up to the store size");
        jnl_reader_t rd;
        jnl_header_t h2;
        jnl_info_t i2;
        if (jnl_reader_open(&rd, st, &h2, &i2))
            fail("reader refuses what jnl_scan accepted");
        jnl_rec_t r;
        uint64_t n = 0;
        while ((rc = jnl_reader_next(&rd, &r)) == 1)
            if (r.seq != n++)
                fail("reader: records out of sequence");
        if (rc != 0 || n != info.records)
            fail("reader and scan disagree on the records");
    }
    jnl_t j;
    rc = jnl_open(&j, st, &info);
    if (rc == RIG_OK) {
        jnl_header_t h3;
        jnl_info_t i3;
        if (jnl_scan(st, &h3, &i3) || i3.tail_bytes || i3.records != info.records)
            fail("after jnl_open the journal is not clean");
        if (!info.ended && size + 2 * JNL_REC_BYTES <= REF_MEMSTORE_CAP) {
            jnl_rec_t r;
            memset(&r, 0, sizeof r);
            r.type = JNL_T_POINT;
            if (jnl_append(&j, &r) || jnl_end(&j, 0, 1.0))
                fail("append after recovery failed");
            if (jnl_scan(st, &h3, &i3) || i3.records != info.records + 2 || !i3.ended)
                fail("appended records do not read back");
        }
    }
    return 0;
}

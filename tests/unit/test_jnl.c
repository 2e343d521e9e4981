/* SPDX-License-Identifier: MIT */
/* test_jnl.c: the journal of measured points: CRC-32 against published check
 * values and a bitwise reference, round trips, torn tails at every byte,
 * damage before the tail, power cuts (SQLite's crash-test idea), a full
 * disk and the sync policy, over a RAM store with faults (ref_memstore) and
 * over the real file store. */
#include "cf_store_file.h"
#include "cf_test.h"
#include "jnl.h"
#include "ref_memstore.h"
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static ref_memstore_t ms; /* 256 KiB: static, not on the stack */
static rig_store_t st;

/* Bit-at-a-time CRC-32 straight from the definition (reflected 0xEDB88320). */
static uint32_t crc_bitwise(const uint8_t *p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

static void test_crc(void **state)
{
    (void)state;
    /* Check values: the CRC catalogue's "123456789", zlib's crc32 of "a"
     * and of the pangram. */
    assert_int_equal(jnl_crc32(0, "123456789", 9), 0xCBF43926u);
    assert_int_equal(jnl_crc32(0, "", 0), 0u);
    assert_int_equal(jnl_crc32(0, "a", 1), 0xE8B7BE43u);
    const char *fox = "The quick brown fox jumps over the lazy dog";
    assert_int_equal(jnl_crc32(0, fox, strlen(fox)), 0x414FA339u);
    /* Chaining over pieces equals one call; random buffers match the
     * bitwise definition. */
    assert_int_equal(jnl_crc32(jnl_crc32(0, "12345", 5), "6789", 4), 0xCBF43926u);
    uint8_t b[300];
    uint64_t s = 12345;
    for (int t = 0; t < 200; t++) {
        /* Lengths 0 .. 199 from every start modulo 8 (the slicing-by-8 path
         * reads eight bytes a step, then the tail a byte at a time). */
        size_t n = (size_t)(t % 290), at = (size_t)(t % 8);
        for (size_t i = 0; i < n; i++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            b[at + i] = (uint8_t)(s >> 56);
        }
        assert_int_equal(jnl_crc32(0, b + at, n), crc_bitwise(b + at, n));
        size_t cut = n / 3; /* chained at a cut that is not a multiple of 8 */
        assert_int_equal(jnl_crc32(jnl_crc32(0, b + at, cut), b + at + cut, n - cut),
                         crc_bitwise(b + at, n));
    }
}

static jnl_header_t hdr(uint32_t k)
{
    jnl_header_t h;
    memset(&h, 0, sizeof h);
    h.sync_every = k;
    h.job_id = 0x1122334455667788ULL;
    h.nominal_hash = 0xCAFEF00DDEADBEEFULL;
    snprintf(h.nominal_name, sizeof h.nominal_name, "nominal.igs");
    h.z0 = 100.0;
    h.cal[0] = 0.25;
    h.cal[1] = -0.5;
    h.cal[2] = 1.0 / 3.0;
    h.t_start = 12.5;
    h.planned = 1000;
    return h;
}

/* The i-th test point: every field distinct, some without a reading. */
static jnl_rec_t point(uint32_t i)
{
    jnl_rec_t r;
    memset(&r, 0, sizeof r);
    r.type = JNL_T_POINT;
    r.stage[0] = 0.1 * i;
    r.stage[1] = -0.7 * i + 1e-13;
    if (i % 7 == 3) {
        r.flags = JNL_F_NOSURF;
        r.code = RIG_ENOSURF;
        r.dist = r.xyz[0] = r.xyz[1] = r.xyz[2] = NAN;
    } else {
        r.dist = 10.0 + 1.0 / (i + 1);
        r.xyz[0] = r.stage[0] + 0.25;
        r.xyz[1] = r.stage[1] - 0.5;
        r.xyz[2] = 100.0 - r.dist + 1.0 / 3.0;
    }
    if (i % 10 == 9)
        r.flags |= JNL_F_ROWEND;
    r.t = 12.5 + 0.01 * i;
    return r;
}

/* Fields equal bit for bit (NaNs included). */
static void assert_rec_equal(const jnl_rec_t *a, const jnl_rec_t *b)
{
    assert_int_equal(a->seq, b->seq);
    assert_int_equal(a->type, b->type);
    assert_int_equal(a->flags, b->flags);
    assert_int_equal(a->code, b->code);
    assert_memory_equal(a->stage, b->stage, sizeof a->stage);
    assert_memory_equal(&a->dist, &b->dist, sizeof a->dist);
    assert_memory_equal(a->xyz, b->xyz, sizeof a->xyz);
    assert_memory_equal(&a->t, &b->t, sizeof a->t);
}

/* A journal of n points in the RAM store, synced every k. */
static void write_points(uint32_t n, uint32_t k)
{
    ref_memstore_init(&ms, &st);
    jnl_t j;
    jnl_header_t h = hdr(k);
    assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
    for (uint32_t i = 0; i < n; i++) {
        jnl_rec_t r = point(i);
        assert_int_equal(jnl_append(&j, &r), RIG_OK);
        assert_int_equal(r.seq, i);
    }
    assert_int_equal(jnl_sync(&j), RIG_OK);
}

/* Reads back every record and checks it against point(i); returns the count. */
static uint64_t read_back(void)
{
    jnl_reader_t rd;
    jnl_header_t h;
    jnl_info_t in;
    assert_int_equal(jnl_reader_open(&rd, st, &h, &in), RIG_OK);
    jnl_rec_t r;
    uint64_t n = 0;
    int rc;
    while ((rc = jnl_reader_next(&rd, &r)) == 1) {
        jnl_rec_t want = point((uint32_t)n);
        want.seq = (uint32_t)n;
        assert_rec_equal(&r, &want);
        n++;
    }
    assert_int_equal(rc, 0);
    assert_int_equal(n, in.records);
    return n;
}

static void test_roundtrip(void **state)
{
    (void)state;
    write_points(1000, 16);
    assert_int_equal(ms.size, JNL_HDR_BYTES + 1000 * JNL_REC_BYTES);
    jnl_t j;
    jnl_info_t in;
    assert_int_equal(jnl_open(&j, st, &in), RIG_OK);
    jnl_header_t want = hdr(16);
    want.version = JNL_VERSION;
    assert_memory_equal(&j.h, &want, sizeof want);
    assert_int_equal(in.records, 1000);
    assert_int_equal(in.tail_bytes, 0);
    long flagged = 0;
    for (int i = 0; i < 1000; i++)
        flagged += i % 7 == 3;
    assert_int_equal(in.flagged, flagged);
    assert_int_equal(in.points, 1000 - flagged);
    assert_near(in.t_first, 12.5, 0);
    assert_near(in.t_last, 12.5 + 0.01 * 999, 0);
    assert_int_equal(in.ended, 0);
    assert_int_equal(read_back(), 1000);
    /* Appending after recovery continues the sequence; the end record closes it. */
    jnl_rec_t r = point(1000);
    assert_int_equal(jnl_append(&j, &r), RIG_OK);
    assert_int_equal(r.seq, 1000);
    assert_int_equal(jnl_end(&j, RIG_EABORTED, 99.0), RIG_OK);
    assert_int_equal(jnl_append(&j, &r), RIG_ESTATE);
    assert_int_equal(jnl_open(&j, st, &in), RIG_OK);
    assert_int_equal(in.records, 1002);
    assert_int_equal(in.ended, 1);
    assert_int_equal(in.end_code, RIG_EABORTED);
    assert_int_equal(jnl_append(&j, &r), RIG_ESTATE);
    /* A store that is not empty is never overwritten. */
    jnl_header_t h = hdr(4);
    assert_int_equal(jnl_create(&j, st, &h), RIG_ESTATE);
}

static uint64_t le64_at(const uint8_t *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--)
        v = (v << 8) | p[i];
    return v;
}

/* Version 2 (issue 19): the part's ID in a meta record and gaps at their
 * numbers, each field at its byte offset of docs/journal.md (read from the
 * store's bytes, not through the decoder); counted by jnl_scan, skipped as
 * points; a version 1 journal (the header's version patched, its CRC
 * recomputed bitwise) still reads. */
static void test_gap_meta(void **state)
{
    (void)state;
    ref_memstore_init(&ms, &st);
    jnl_t j;
    jnl_header_t h = hdr(1000);
    assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
    assert_int_equal(ms.data[4] | ms.data[5] << 8, 2);
    const char *id = "SN-0042/A: a part ID longer than the forty-seven characters kept";
    assert_int_equal(jnl_meta(&j, JNL_META_PART_ID, id, 12.5), RIG_OK);
    jnl_rec_t r = point(0);
    assert_int_equal(jnl_append(&j, &r), RIG_OK);
    const double at[2] = {1.5, -2.25};
    assert_int_equal(jnl_gap(&j, JNL_GAP_NO_READING, 3, 17, 1, at, 13.0), RIG_OK);
    assert_int_equal(jnl_gap(&j, JNL_GAP_BOTH, 3, 40, 5, NULL, 13.5), RIG_OK);
    assert_int_equal(jnl_gap(&j, JNL_GAP_PROFILE, -1, 1u << 20, 16, NULL, 14.0), RIG_OK);
    assert_int_equal(jnl_gap(&j, JNL_GAP_NO_TRIGGER, 4, 2, 1, NULL, 14.5), RIG_OK);
    assert_int_equal(jnl_gap(&j, 0, 0, 0, 1, NULL, 0), RIG_EARG);
    assert_int_equal(jnl_gap(&j, JNL_GAP_KINDS, 0, 0, 1, NULL, 0), RIG_EARG);
    assert_int_equal(jnl_gap(&j, JNL_GAP_BOTH, 0, 0, 0, NULL, 0), RIG_EARG);
    assert_int_equal(jnl_meta(&j, 99, "x", 0), RIG_EARG);
    assert_int_equal(jnl_end(&j, 0, 15.0), RIG_OK);
    /* Record 0 (meta): type 4, key 1, text at 16, NUL at 63. */
    const uint8_t *m = ms.data + JNL_HDR_BYTES;
    assert_int_equal(m[8], JNL_T_META);
    assert_int_equal(m[12], JNL_META_PART_ID);
    assert_memory_equal(m + 16, id, 47);
    assert_int_equal(m[63], 0);
    /* Record 2 (the first gap): kind, stage, num at 32, row at 40, count at 48. */
    const uint8_t *g = ms.data + JNL_HDR_BYTES + 2 * JNL_REC_BYTES;
    assert_int_equal(g[8], JNL_T_GAP);
    assert_int_equal(g[12], JNL_GAP_NO_READING);
    double x;
    memcpy(&x, (uint64_t[]){le64_at(g + 16)}, sizeof x);
    assert_true(x == 1.5);
    assert_int_equal(le64_at(g + 32), 17);
    assert_int_equal(le64_at(g + 40), 3);
    assert_int_equal(le64_at(g + 48), 1);
    jnl_header_t h2;
    jnl_info_t in;
    assert_int_equal(jnl_scan(st, &h2, &in), RIG_OK);
    assert_int_equal(h2.version, 2);
    assert_int_equal(in.records, 7);
    assert_int_equal(in.points, 1);
    assert_int_equal(in.gaps, 4);
    assert_int_equal(in.lost[JNL_GAP_NO_READING], 1);
    assert_int_equal(in.lost[JNL_GAP_NO_TRIGGER], 1);
    assert_int_equal(in.lost[JNL_GAP_BOTH], 5);
    assert_int_equal(in.lost[JNL_GAP_PROFILE], 16);
    assert_int_equal(strlen(in.part_id), 47);
    assert_memory_equal(in.part_id, id, 47);
    jnl_reader_t rd;
    assert_int_equal(jnl_reader_open(&rd, st, &h2, &in), RIG_OK);
    int kinds[8], n = 0, rc;
    while ((rc = jnl_reader_next(&rd, &r)) == 1 && n < 8)
        kinds[n++] = r.type == JNL_T_GAP ? 100 + r.code : r.type;
    assert_int_equal(n, 7);
    assert_int_equal(kinds[0], JNL_T_META);
    assert_int_equal(kinds[1], JNL_T_POINT);
    assert_int_equal(kinds[3], 100 + JNL_GAP_BOTH);
    assert_string_equal(jnl_gap_name(JNL_GAP_PROFILE), "profile");
    /* Version 1: points only, the header saying 1. */
    write_points(10, 4);
    ms.data[4] = 1;
    uint32_t c = crc_bitwise(ms.data, 124);
    for (int i = 0; i < 4; i++)
        ms.data[124 + i] = (uint8_t)(c >> (8 * i));
    assert_int_equal(jnl_scan(st, &h2, &in), RIG_OK);
    assert_int_equal(h2.version, 1);
    assert_int_equal(in.points + in.flagged, 10);
    assert_int_equal(read_back(), 10);
    /* Version 3 is not ours: refused. */
    ms.data[4] = 3;
    c = crc_bitwise(ms.data, 124);
    for (int i = 0; i < 4; i++)
        ms.data[124 + i] = (uint8_t)(c >> (8 * i));
    assert_int_equal(jnl_scan(st, &h2, &in), RIG_ECORRUPT);
}

/* A write cut at every byte of the last record, and a last record complete
 * in length but garbled: dropped, every earlier record intact. */
static void test_torn_tail(void **state)
{
    (void)state;
    const uint32_t n = 40;
    write_points(n, 8);
    static uint8_t image[JNL_HDR_BYTES + 40 * JNL_REC_BYTES];
    memcpy(image, ms.data, sizeof image);
    size_t last = JNL_HDR_BYTES + (n - 1) * JNL_REC_BYTES;
    for (size_t cut = last; cut <= sizeof image; cut++) {
        for (int garble = 0; garble < 2; garble++) {
            if (garble && cut == sizeof image)
                continue;
            ref_memstore_init(&ms, &st);
            memcpy(ms.data, image, sizeof image);
            ms.size = garble ? sizeof image : cut;
            if (garble && cut < sizeof image)
                ms.data[cut] ^= 0x5A; /* one damaged byte anywhere in the record */
            int whole = cut == sizeof image && !garble;
            jnl_t j;
            jnl_info_t in;
            assert_int_equal(jnl_open(&j, st, &in), RIG_OK);
            assert_int_equal(in.records, whole ? n : n - 1);
            assert_int_equal(in.tail_bytes, whole ? 0 : (garble ? JNL_REC_BYTES : cut - last));
            assert_int_equal(ms.size, whole ? sizeof image : last); /* cut away */
            assert_int_equal(read_back(), whole ? n : n - 1);
            jnl_rec_t r = point(in.records); /* and the journal goes on */
            assert_int_equal(jnl_append(&j, &r), RIG_OK);
            assert_int_equal(r.seq, in.records);
        }
    }
}

/* A flipped bit in a record that a later record proves synced (records are
 * synced every 8 here, so record k says floor(k / 8) * 8 were durable) is
 * corruption, named, and the journal is left as it was; in the last
 * unsynced stretch it is a torn tail. The header too is checked. */
static void test_corrupt_middle(void **state)
{
    (void)state;
    const uint32_t n = 100;
    write_points(n, 8);
    static uint8_t image[JNL_HDR_BYTES + 100 * JNL_REC_BYTES];
    memcpy(image, ms.data, sizeof image);
    for (uint32_t bad = 0; bad < n; bad += 3) {
        int proven = bad < (n - 1) / 8 * 8; /* some later record has synced > bad */
        for (int bit = 0; bit < JNL_REC_BYTES * 8; bit += 37) {
            size_t at = JNL_HDR_BYTES + bad * JNL_REC_BYTES + (size_t)bit / 8;
            ms.data[at] ^= (uint8_t)(1u << (bit % 8));
            jnl_t j;
            jnl_info_t in;
            jnl_header_t h;
            if (proven) {
                assert_int_equal(jnl_scan(st, &h, &in), RIG_ECORRUPT);
                assert_int_equal(in.bad_record, bad);
                assert_int_equal(jnl_open(&j, st, &in), RIG_ECORRUPT);
                assert_int_equal(in.bad_record, bad);
                assert_int_equal(ms.size, sizeof image);
            } else {
                assert_int_equal(jnl_open(&j, st, &in), RIG_OK);
                assert_int_equal(in.records, bad);
                assert_int_equal(ms.size, JNL_HDR_BYTES + bad * JNL_REC_BYTES);
                ms.size = sizeof image;
                memcpy(ms.data, image, sizeof image);
            }
            ms.data[at] = image[at];
        }
    }
    for (int at = 0; at < JNL_HDR_BYTES; at += 5) {
        ms.data[at] ^= 4;
        jnl_t j;
        jnl_info_t in;
        assert_int_equal(jnl_open(&j, st, &in), RIG_ECORRUPT);
        assert_int_equal(in.bad_record, -1);
        ms.data[at] ^= 4;
    }
    ms.size = JNL_HDR_BYTES - 1; /* header torn while being created */
    jnl_t j;
    jnl_info_t in;
    assert_int_equal(jnl_open(&j, st, &in), RIG_ECORRUPT);
    assert_int_equal(in.bad_record, -1);
}

/* jnl_scan reads records in chunks (512 a read on the host boards, 16 on
 * the others): damage at and beside a chunk's first and last record is
 * found at the same record as anywhere else, and a journal of 3,000 points
 * scans to the same counts as read back one record at a time. */
static void test_corrupt_chunks(void **state)
{
    (void)state;
    const uint32_t n = 3000;
    write_points(n, 8);
    jnl_header_t h;
    jnl_info_t in;
    assert_int_equal(jnl_scan(st, &h, &in), RIG_OK);
    assert_int_equal(in.records, n);
    assert_int_equal(in.points + in.flagged, n);
    assert_int_equal(in.flagged, (n + 3) / 7); /* point(i) flags i % 7 == 3 */
    assert_int_equal(read_back(), n);
    static const uint32_t bads[] = {15, 16, 17, 511, 512, 513, 1023, 1024, 2559, 2560, 2999};
    for (size_t b = 0; b < sizeof bads / sizeof bads[0]; b++) {
        uint32_t bad = bads[b];
        int proven = bad < (n - 1) / 8 * 8;
        size_t at = JNL_HDR_BYTES + (size_t)bad * JNL_REC_BYTES + 40;
        ms.data[at] ^= 0x10;
        jnl_info_t s2;
        int rc = jnl_scan(st, &h, &s2);
        if (proven) {
            assert_int_equal(rc, RIG_ECORRUPT);
            assert_int_equal(s2.bad_record, bad);
        } else {
            assert_int_equal(rc, RIG_OK);
            assert_int_equal(s2.records, bad);
            assert_int_equal(s2.tail_bytes, (uint64_t)(n - bad) * JNL_REC_BYTES);
        }
        ms.data[at] ^= 0x10;
    }
}

/* Power cuts at random moments: what was synced survives, the unsynced
 * tail (cut and garbled at random) goes, and recovery never calls that
 * corruption. */
static void test_power_cut(void **state)
{
    (void)state;
    uint64_t seed = 0x9E3779B97F4A7C15ULL;
    for (int run = 0; run < 500; run++) {
        ref_memstore_init(&ms, &st);
        jnl_t j;
        jnl_header_t h = hdr(1 + (uint32_t)(run % 13));
        assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
        seed ^= seed << 13, seed ^= seed >> 7, seed ^= seed << 17;
        uint32_t n = (uint32_t)(seed % 300);
        for (uint32_t i = 0; i < n; i++) {
            jnl_rec_t r = point(i);
            assert_int_equal(jnl_append(&j, &r), RIG_OK);
            if (r.flags & JNL_F_ROWEND)
                assert_int_equal(jnl_sync(&j), RIG_OK);
        }
        uint64_t acked = jnl_acked(&j);
        ref_memstore_crash(&ms, &seed);
        jnl_info_t in;
        assert_int_equal(jnl_open(&j, st, &in), RIG_OK);
        assert_true(in.records >= acked);
        assert_true(in.records <= n);
        assert_int_equal(read_back(), in.records);
    }
}

/* The disk fills after every possible byte count: the append fails with
 * RIG_EFULL, the journal holds every record appended before, whole. */
static void test_disk_full(void **state)
{
    (void)state;
    for (size_t limit = JNL_HDR_BYTES; limit < JNL_HDR_BYTES + 6 * JNL_REC_BYTES; limit++) {
        ref_memstore_init(&ms, &st);
        ms.limit = limit;
        jnl_t j;
        jnl_header_t h = hdr(4);
        assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
        uint32_t ok = 0;
        int rc;
        for (;;) {
            jnl_rec_t r = point(ok);
            if ((rc = jnl_append(&j, &r)) != RIG_OK)
                break;
            ok++;
        }
        assert_int_equal(rc, RIG_EFULL);
        assert_int_equal(ok, (limit - JNL_HDR_BYTES) / JNL_REC_BYTES);
        assert_int_equal(ms.size, JNL_HDR_BYTES + ok * JNL_REC_BYTES);
        jnl_rec_t r = point(ok);
        assert_int_equal(jnl_append(&j, &r), RIG_ESTATE); /* failed journals stay failed */
        jnl_info_t in;
        assert_int_equal(jnl_open(&j, st, &in), RIG_OK);
        assert_int_equal(in.records, ok);
        assert_int_equal(in.tail_bytes, 0);
        assert_int_equal(read_back(), ok);
    }
    /* A header that does not fit leaves an empty store. */
    ref_memstore_init(&ms, &st);
    ms.limit = JNL_HDR_BYTES - 1;
    jnl_t j;
    jnl_header_t h = hdr(4);
    assert_int_equal(jnl_create(&j, st, &h), RIG_EFULL);
    assert_int_equal(ms.size, 0);
}

/* Syncs: the header at once, every K records, at each explicit sync with
 * something pending (none otherwise), and at the end record. */
static void test_sync_policy(void **state)
{
    (void)state;
    ref_memstore_init(&ms, &st);
    jnl_t j;
    jnl_header_t h = hdr(8);
    assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
    assert_int_equal(ms.syncs, 1);
    long want = 1;
    uint32_t since = 0;
    for (uint32_t i = 0; i < 100; i++) {
        jnl_rec_t r = point(i);
        assert_int_equal(jnl_append(&j, &r), RIG_OK);
        if (++since == 8)
            want++, since = 0;
        assert_int_equal(ms.syncs, want);
        assert_int_equal(jnl_acked(&j), i + 1 - since);
        assert_int_equal(ms.durable, JNL_HDR_BYTES + (i + 1 - since) * JNL_REC_BYTES);
        if (i % 10 == 9) { /* a row end */
            assert_int_equal(jnl_sync(&j), RIG_OK);
            if (since)
                want++, since = 0;
            assert_int_equal(ms.syncs, want);
            assert_int_equal(jnl_acked(&j), i + 1);
        }
    }
    assert_int_equal(jnl_sync(&j), RIG_OK); /* nothing pending: no store call */
    assert_int_equal(ms.syncs, want);
    assert_int_equal(jnl_end(&j, RIG_OK, 1.0), RIG_OK);
    assert_int_equal(ms.syncs, want + 1);
    assert_int_equal(ms.durable, ms.size);
    assert_int_equal(jnl_acked(&j), 101);
    /* A failing sync fails the journal: nothing more is acknowledged. */
    ref_memstore_init(&ms, &st);
    assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
    ms.fail_sync = 1;
    for (uint32_t i = 0; i < 7; i++) {
        jnl_rec_t r = point(i);
        assert_int_equal(jnl_append(&j, &r), RIG_OK);
    }
    jnl_rec_t r = point(7);
    assert_int_equal(jnl_append(&j, &r), RIG_EIO);
    assert_int_equal(jnl_acked(&j), 0);
    assert_int_equal(jnl_append(&j, &r), RIG_ESTATE);
}

static char tmpdir[512];

static void tmp_path(char *buf, size_t n, const char *name)
{
    const char *d = getenv("CF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", d && *d ? d : "/tmp");
    mkdir(tmpdir, 0777);
    snprintf(buf, n, "%s/test_jnl_%ld_%s", tmpdir, (long)getpid(), name);
}

/* The same journal through the real file store: round trip, recovery of a
 * torn tail written into the file, never overwriting an existing file. */
static void test_file_store(void **state)
{
    (void)state;
    char path[600], msg[512];
    tmp_path(path, sizeof path, "file.jnl");
    unlink(path);
    cf_store_file_t f;
    rig_store_t fs;
    assert_int_equal(cf_store_file_open(&f, path, CF_STORE_CREATE, &fs, msg, sizeof msg), RIG_OK);
    jnl_t j;
    jnl_header_t h = hdr(5);
    assert_int_equal(jnl_create(&j, fs, &h), RIG_OK);
    for (uint32_t i = 0; i < 123; i++) {
        jnl_rec_t r = point(i);
        assert_int_equal(jnl_append(&j, &r), RIG_OK);
    }
    assert_int_equal(jnl_sync(&j), RIG_OK);
    assert_int_equal(fs.ops->append(fs.ctx, "torn", 4), RIG_OK);
    cf_store_file_close(&f);
    cf_store_file_t f2;
    assert_int_equal(cf_store_file_open(&f2, path, CF_STORE_CREATE, &fs, msg, sizeof msg),
                     RIG_EOPEN);
    assert_int_equal(cf_store_file_open(&f2, path, CF_STORE_WRITE, &fs, msg, sizeof msg), RIG_OK);
    jnl_info_t in;
    assert_int_equal(jnl_open(&j, fs, &in), RIG_OK);
    assert_int_equal(in.records, 123);
    assert_int_equal(in.tail_bytes, 4);
    struct stat sb;
    assert_int_equal(stat(path, &sb), 0);
    assert_int_equal(sb.st_size, JNL_HDR_BYTES + 123 * JNL_REC_BYTES);
    st = fs;
    assert_int_equal(read_back(), 123);
    cf_store_file_close(&f2);
    unlink(path);
}

/* A real full disk: the file size limit (RLIMIT_FSIZE, EFBIG) in a child
 * process; the journal it leaves holds every record it appended. */
static void test_file_full(void **state)
{
    (void)state;
    char path[600], msg[512];
    tmp_path(path, sizeof path, "full.jnl");
    for (long limit = JNL_HDR_BYTES + 3 * JNL_REC_BYTES - 3; limit < JNL_HDR_BYTES + 5 * 80;
         limit += 41) {
        unlink(path);
        pid_t pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            signal(SIGXFSZ, SIG_IGN);
            struct rlimit rl = {(rlim_t)limit, (rlim_t)limit};
            cf_store_file_t f;
            rig_store_t fs;
            if (setrlimit(RLIMIT_FSIZE, &rl) ||
                cf_store_file_open(&f, path, CF_STORE_CREATE, &fs, msg, sizeof msg))
                _exit(100);
            jnl_t j;
            jnl_header_t h = hdr(2);
            if (jnl_create(&j, fs, &h))
                _exit(101);
            int ok = 0;
            for (;; ok++) {
                jnl_rec_t r = point((uint32_t)ok);
                int rc = jnl_append(&j, &r);
                if (rc)
                    _exit(rc == RIG_EFULL ? ok : 102);
            }
        }
        int ws;
        assert_int_equal(waitpid(pid, &ws, 0), pid);
        assert_true(WIFEXITED(ws));
        int ok = WEXITSTATUS(ws);
        assert_int_equal(ok, (limit - JNL_HDR_BYTES) / JNL_REC_BYTES);
        cf_store_file_t f;
        rig_store_t fs;
        assert_int_equal(cf_store_file_open(&f, path, CF_STORE_READ, &fs, msg, sizeof msg), RIG_OK);
        jnl_header_t h;
        jnl_info_t in;
        assert_int_equal(jnl_scan(fs, &h, &in), RIG_OK);
        assert_int_equal(in.records, ok);
        assert_int_equal(in.tail_bytes, 0);
        cf_store_file_close(&f);
    }
    unlink(path);
}

/* The file store gathering appends (cf_store_file_buffer, a fast scan's):
 * nothing reaches the file between syncs until the buffer is full, every
 * sync and read sees all, and a full disk met by a gathered write leaves
 * the file at the last whole write (records, not a torn piece), the
 * journal holding what was written before. */
static void test_file_buffered(void **state)
{
    (void)state;
    char path[600], msg[512];
    tmp_path(path, sizeof path, "buf.jnl");
    unlink(path);
    cf_store_file_t f;
    rig_store_t fs;
    struct stat sb;
    assert_int_equal(cf_store_file_open(&f, path, CF_STORE_CREATE, &fs, msg, sizeof msg), RIG_OK);
    assert_int_equal(cf_store_file_buffer(&f, 5 * JNL_REC_BYTES), RIG_OK);
    jnl_t j;
    jnl_header_t h = hdr(1000);
    assert_int_equal(jnl_create(&j, fs, &h), RIG_OK);
    assert_int_equal(stat(path, &sb), 0);
    assert_int_equal(sb.st_size, JNL_HDR_BYTES); /* the create's sync wrote it */
    for (uint32_t i = 0; i < 4; i++) {
        jnl_rec_t r = point(i);
        assert_int_equal(jnl_append(&j, &r), RIG_OK);
    }
    assert_int_equal(stat(path, &sb), 0);
    assert_int_equal(sb.st_size, JNL_HDR_BYTES); /* gathered */
    for (uint32_t i = 4; i < 12; i++) {
        jnl_rec_t r = point(i);
        assert_int_equal(jnl_append(&j, &r), RIG_OK);
    }
    assert_int_equal(stat(path, &sb), 0);
    assert_int_equal(sb.st_size, JNL_HDR_BYTES + 10 * JNL_REC_BYTES); /* two full buffers */
    st = fs;
    assert_int_equal(read_back(), 12); /* a read sees the buffer too */
    assert_int_equal(jnl_sync(&j), RIG_OK);
    assert_int_equal(stat(path, &sb), 0);
    assert_int_equal(sb.st_size, JNL_HDR_BYTES + 12 * JNL_REC_BYTES);
    cf_store_file_close(&f);
    unlink(path);
    /* A full disk: RLIMIT_FSIZE 20 bytes past 10 records, 5 records a write. */
    const long limit = JNL_HDR_BYTES + 10 * JNL_REC_BYTES + 20;
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit rl = {(rlim_t)limit, (rlim_t)limit};
        if (setrlimit(RLIMIT_FSIZE, &rl) ||
            cf_store_file_open(&f, path, CF_STORE_CREATE, &fs, msg, sizeof msg) ||
            cf_store_file_buffer(&f, 5 * JNL_REC_BYTES) || jnl_create(&j, fs, &h))
            _exit(100);
        for (int ok = 0;; ok++) {
            jnl_rec_t r = point((uint32_t)ok);
            int rc = jnl_append(&j, &r);
            if (rc)
                _exit(rc == RIG_EFULL ? ok : 102);
        }
    }
    int ws;
    assert_int_equal(waitpid(pid, &ws, 0), pid);
    assert_true(WIFEXITED(ws));
    assert_int_equal(WEXITSTATUS(ws), 15); /* the append that filled the third buffer */
    assert_int_equal(stat(path, &sb), 0);
    assert_int_equal(sb.st_size, JNL_HDR_BYTES + 10 * JNL_REC_BYTES);
    assert_int_equal(cf_store_file_open(&f, path, CF_STORE_READ, &fs, msg, sizeof msg), RIG_OK);
    jnl_info_t in;
    assert_int_equal(jnl_scan(fs, &h, &in), RIG_OK);
    assert_int_equal(in.records, 10);
    assert_int_equal(in.tail_bytes, 0);
    cf_store_file_close(&f);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc),
        cmocka_unit_test(test_roundtrip),
        cmocka_unit_test(test_torn_tail),
        cmocka_unit_test(test_corrupt_middle),
        cmocka_unit_test(test_corrupt_chunks),
        cmocka_unit_test(test_power_cut),
        cmocka_unit_test(test_disk_full),
        cmocka_unit_test(test_sync_policy),
        cmocka_unit_test(test_file_store),
        cmocka_unit_test(test_file_full),
        cmocka_unit_test(test_gap_meta),
        cmocka_unit_test(test_file_buffered),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* SPDX-License-Identifier: MIT */
/* jnl.h: the journal of measured points, append-only over a rig_store_t: a
 * header record (job, nominal, kinematic calibration), then fixed-size
 * records, each with its CRC-32, in little-endian byte order whatever the
 * CPU (docs/journal.md has the byte layout). A record is acknowledged only
 * once synced: sync every sync_every records, at every call of jnl_sync (the
 * scan calls it at each row end) and at jnl_end. Recovery (jnl_open)
 * verifies every record, cuts a torn tail away and refuses damage before it
 * with RIG_ECORRUPT naming the record. Fixed memory, no heap. */
#ifndef JNL_H
#define JNL_H

#include "rig.h"
#include <stddef.h>
#include <stdint.h>

#define JNL_MAGIC 0x314E4A43u /* "CJN1" in file byte order */
#define JNL_VERSION 2         /* written; 1 (no gap or meta records) is still read */
#define JNL_VERSION_MIN 1
#define JNL_HDR_BYTES 128 /* header record, CRC included */
#define JNL_REC_BYTES 80  /* one record, CRC included */
#define JNL_SYNC_EVERY_DEFAULT 64
#define JNL_READ_RECS 16 /* records the reader buffers (1280 bytes) */
#define JNL_NAME_LEN 32  /* nominal name field, NUL padded */
#define JNL_TEXT_LEN 48  /* a meta record's text, NUL padded (47 characters) */

/* CRC-32 (IEEE 802.3, reflected 0xEDB88320, as zlib's crc32): start with
 * crc = 0, chain calls over consecutive pieces. */
uint32_t jnl_crc32(uint32_t crc, const void *buf, size_t n);

/* Record types and point flags. Version 2 (issue 19) adds gaps (what a
 * fast scan lost, at its trigger or profile number) and meta records
 * (the part's ID); a version 1 journal holds neither. */
enum { JNL_T_POINT = 1, JNL_T_END = 2, JNL_T_GAP = 3, JNL_T_META = 4 };

/* A gap record's kind (its code field): what was lost, `count` numbers
 * from `num` on, in row `row`. */
enum {
    JNL_GAP_NO_READING = 1, /* on the fly: a trigger (position) whose reading never came */
    JNL_GAP_NO_TRIGGER = 2, /* on the fly: a reading whose position never came */
    JNL_GAP_BOTH = 3,       /* on the fly: numbers lost on both sides (a gap in both) */
    JNL_GAP_PROFILE = 4,    /* profiler: a profile that never came (its frame lost) */
    JNL_GAP_KINDS = 5
};

/* A meta record's key (its code field). */
enum { JNL_META_PART_ID = 1 /* the part's ID string (the PLC's PART_ID, --part-id) */ };
enum {
    JNL_F_NOSURF = 1u << 0, /* probe saw no surface: no point (code RIG_ENOSURF) */
    JNL_F_ROWEND = 1u << 1  /* last point of a stage row */
};

typedef struct jnl_header {
    uint32_t version;                /* JNL_VERSION */
    uint32_t sync_every;             /* K: records between forced syncs (>= 1) */
    uint64_t job_id;                 /* caller's job number */
    uint64_t nominal_hash;           /* identity of the nominal surface (e.g. FNV-1a of its file) */
    char nominal_name[JNL_NAME_LEN]; /* its name, NUL padded (for people) */
    double z0;                       /* kinematics (scan.h): probe height */
    double cal[3];                   /* calibration offset cx, cy, cz */
    double t_start;                  /* job start, clock seconds */
    uint64_t planned;                /* points planned */
    /* Wall-clock UTC of t_start (seconds since 1970) when the board has a
     * clock, so every record's t dates as utc_start + (t - t_start); 0 on a
     * board without one (a monotonic clock is no date). */
    double utc_start;
} jnl_header_t;

typedef struct jnl_rec {
    uint32_t seq;    /* 0, 1, 2 ... (set by jnl_append) */
    uint32_t synced; /* records durable when this one was appended (set by jnl_append) */
    uint16_t type;   /* JNL_T_POINT or JNL_T_END */
    uint16_t flags;  /* JNL_F_* */
    int32_t code;    /* point: the probe's result (0, RIG_ENOSURF); end: the job's result */
    double stage[2]; /* stage x, y (mm) */
    double dist;     /* probe distance (mm), NaN without a reading */
    double xyz[3];   /* the measured point (mm), NaN without a reading */
    double t;        /* clock seconds */
    /* A gap (JNL_T_GAP; code its kind, stage where known, else NaN): */
    uint64_t num;   /* the first number lost: trigger number in its row, profile number */
    uint64_t count; /* numbers lost from num on (>= 1) */
    int64_t row;    /* the row (on the fly), -1 */
    /* A meta record (JNL_T_META; code its key): */
    char text[JNL_TEXT_LEN];
} jnl_rec_t;

/* What a verification pass found (jnl_scan, jnl_open, jnl_reader_open). */
typedef struct jnl_info {
    uint64_t records;             /* valid records, end record included */
    uint64_t points;              /* valid point records with a reading */
    uint64_t flagged;             /* point records without a reading */
    uint64_t tail_bytes;          /* bytes after the valid records: a torn tail */
    int64_t bad_record;           /* RIG_ECORRUPT: the damaged record (-1: the header) */
    int ended;                    /* an end record closes the journal */
    int end_code;                 /* its code */
    double t_first, t_last;       /* time span of the valid records (NaN if none) */
    uint64_t gaps;                /* gap records */
    uint64_t lost[JNL_GAP_KINDS]; /* numbers lost, by kind (the gaps' counts summed) */
    char part_id[JNL_TEXT_LEN];   /* the first JNL_META_PART_ID record's text, "" */
} jnl_info_t;

typedef struct jnl {
    rig_store_t st;
    jnl_header_t h;
    uint64_t nrec;       /* records in the store */
    uint64_t synced;     /* records durable (acknowledged) */
    uint64_t syncs;      /* store syncs made (statistics, tests) */
    uint32_t since_sync; /* records appended since the last sync */
    int state;           /* JNL_S_* */
} jnl_t;

enum { JNL_S_CLOSED = 0, JNL_S_OPEN = 1, JNL_S_ENDED = 2, JNL_S_FAILED = 3 };

/* A new journal on an empty store: writes the header and syncs it.
 * RIG_ESTATE if the store is not empty, RIG_EARG for sync_every 0. */
int jnl_create(jnl_t *j, rig_store_t st, const jnl_header_t *h);

/* Verify a journal without changing it: header, then every record's CRC,
 * sequence and type. A damaged record is a torn tail (dropped, counted in
 * tail_bytes) unless a later valid record says it was synced (its synced
 * field is beyond it): then RIG_ECORRUPT with bad_record set. A header
 * shorter than JNL_HDR_BYTES or failing its checks: RIG_ECORRUPT, -1. */
int jnl_scan(rig_store_t st, jnl_header_t *h, jnl_info_t *info);

/* Recovery: jnl_scan, then cut the torn tail (truncate + sync) and get
 * ready to append after the last valid record (a journal with an end
 * record opens ended: appends are RIG_ESTATE). */
int jnl_open(jnl_t *j, rig_store_t st, jnl_info_t *info);

/* Append one record; r->seq and r->synced are set here. Syncs when
 * sync_every records are pending. On a store failure (RIG_EFULL, RIG_EIO)
 * the partial record is cut away and the journal refuses further appends
 * (what was synced stays valid). */
int jnl_append(jnl_t *j, jnl_rec_t *r);

/* Make every appended record durable (no store call if none is pending). */
int jnl_sync(jnl_t *j);

/* A gap record (kind JNL_GAP_*, count >= 1; stage NULL when unknown) and
 * a meta record (key JNL_META_*, text cut to JNL_TEXT_LEN - 1), appended
 * as jnl_append. RIG_EARG for a bad kind, key or count. */
int jnl_gap(jnl_t *j, int kind, int64_t row, uint64_t num, uint64_t count, const double stage[2],
            double t);
int jnl_meta(jnl_t *j, int key, const char *text, double t);
/* "no_reading", "no_trigger", "both", "profile"; "unknown". */
const char *jnl_gap_name(int kind);

/* Append the end record with the job's result code, and sync. */
int jnl_end(jnl_t *j, int code, double t);

/* Records acknowledged (durable). */
uint64_t jnl_acked(const jnl_t *j);

/* Streaming reader: one record at a time, JNL_READ_RECS buffered. */
typedef struct jnl_reader {
    rig_store_t st;
    uint64_t next, count; /* next record index, valid records */
    uint64_t buf_first;   /* index of buf's first record */
    unsigned nbuf;        /* records in buf */
    uint8_t buf[JNL_READ_RECS * JNL_REC_BYTES];
} jnl_reader_t;

/* Verify (jnl_scan) and position before the first record. */
int jnl_reader_open(jnl_reader_t *rd, rig_store_t st, jnl_header_t *h, jnl_info_t *info);
/* 1 and the record, 0 at the end of the valid records, or an error
 * (RIG_ECORRUPT if a record changed since the verification). */
int jnl_reader_next(jnl_reader_t *rd, jnl_rec_t *r);
void jnl_reader_rewind(jnl_reader_t *rd);

/* Record bytes <-> struct (exposed for tests and tools). */
void jnl_rec_encode(const jnl_rec_t *r, uint8_t out[JNL_REC_BYTES]);
/* RIG_ECORRUPT if the CRC fails. */
int jnl_rec_decode(const uint8_t in[JNL_REC_BYTES], jnl_rec_t *r);

#endif

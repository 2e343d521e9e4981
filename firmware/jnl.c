/* SPDX-License-Identifier: MIT */
/* jnl.c: the journal of measured points: encoding, append with the sync
 * policy, recovery and the streaming reader (jnl.h, docs/journal.md). */
#include "jnl.h"
#include "board_config.h"
#include <math.h>
#include <string.h>

/* Little-endian fields, whatever the CPU (the file moves between a board
 * and the cell controller). Doubles are IEEE 754 binary64 bit patterns. */
static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

static void put64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

static void putd(uint8_t *p, double d)
{
    uint64_t v;
    memcpy(&v, &d, sizeof v);
    put64(p, v);
}

static uint16_t get16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

static uint32_t get32(const uint8_t *p)
{
    uint32_t v = 0;
    for (int i = 3; i >= 0; i--)
        v = (v << 8) | p[i];
    return v;
}

static uint64_t get64(const uint8_t *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--)
        v = (v << 8) | p[i];
    return v;
}

static double getd(const uint8_t *p)
{
    uint64_t v = get64(p);
    double d;
    memcpy(&d, &v, sizeof d);
    return d;
}

/* Header: byte offsets of docs/journal.md. */
static void hdr_encode(const jnl_header_t *h, uint8_t b[JNL_HDR_BYTES])
{
    memset(b, 0, JNL_HDR_BYTES);
    put32(b + 0, JNL_MAGIC);
    put16(b + 4, (uint16_t)h->version);
    put16(b + 6, JNL_HDR_BYTES);
    put16(b + 8, JNL_REC_BYTES);
    put32(b + 12, h->sync_every);
    put64(b + 16, h->job_id);
    put64(b + 24, h->nominal_hash);
    memcpy(b + 32, h->nominal_name, JNL_NAME_LEN);
    b[32 + JNL_NAME_LEN - 1] = 0;
    putd(b + 64, h->z0);
    putd(b + 72, h->cal[0]);
    putd(b + 80, h->cal[1]);
    putd(b + 88, h->cal[2]);
    putd(b + 96, h->t_start);
    put64(b + 104, h->planned);
    putd(b + 112, h->utc_start); /* zero in journals from before it */
    put32(b + 124, jnl_crc32(0, b, 124));
}

static int hdr_decode(const uint8_t b[JNL_HDR_BYTES], jnl_header_t *h)
{
    if (get32(b) != JNL_MAGIC || get32(b + 124) != jnl_crc32(0, b, 124) ||
        get16(b + 4) < JNL_VERSION_MIN || get16(b + 4) > JNL_VERSION ||
        get16(b + 6) != JNL_HDR_BYTES || get16(b + 8) != JNL_REC_BYTES || get32(b + 12) == 0)
        return RIG_ECORRUPT;
    memset(h, 0, sizeof *h);
    h->version = get16(b + 4);
    h->sync_every = get32(b + 12);
    h->job_id = get64(b + 16);
    h->nominal_hash = get64(b + 24);
    memcpy(h->nominal_name, b + 32, JNL_NAME_LEN);
    h->nominal_name[JNL_NAME_LEN - 1] = 0;
    h->z0 = getd(b + 64);
    h->cal[0] = getd(b + 72);
    h->cal[1] = getd(b + 80);
    h->cal[2] = getd(b + 88);
    h->t_start = getd(b + 96);
    h->planned = get64(b + 104);
    h->utc_start = getd(b + 112);
    return RIG_OK;
}

void jnl_rec_encode(const jnl_rec_t *r, uint8_t b[JNL_REC_BYTES])
{
    put32(b + 0, r->seq);
    put32(b + 4, r->synced);
    put16(b + 8, r->type);
    put16(b + 10, r->flags);
    put32(b + 12, (uint32_t)r->code);
    if (r->type == JNL_T_META) { /* bytes 16..63: the text */
        memcpy(b + 16, r->text, JNL_TEXT_LEN);
        b[16 + JNL_TEXT_LEN - 1] = 0;
    } else if (r->type == JNL_T_GAP) { /* stage, then num, row, count */
        putd(b + 16, r->stage[0]);
        putd(b + 24, r->stage[1]);
        put64(b + 32, r->num);
        put64(b + 40, (uint64_t)r->row);
        put64(b + 48, r->count);
        put64(b + 56, 0);
    } else {
        putd(b + 16, r->stage[0]);
        putd(b + 24, r->stage[1]);
        putd(b + 32, r->dist);
        putd(b + 40, r->xyz[0]);
        putd(b + 48, r->xyz[1]);
        putd(b + 56, r->xyz[2]);
    }
    putd(b + 64, r->t);
    put32(b + 72, 0);
    put32(b + 76, jnl_crc32(0, b, 76));
}

int jnl_rec_decode(const uint8_t b[JNL_REC_BYTES], jnl_rec_t *r)
{
    if (get32(b + 76) != jnl_crc32(0, b, 76))
        return RIG_ECORRUPT;
    r->seq = get32(b + 0);
    r->synced = get32(b + 4);
    r->type = get16(b + 8);
    r->flags = get16(b + 10);
    r->code = (int32_t)get32(b + 12);
    r->num = r->count = 0;
    r->row = -1;
    r->text[0] = 0;
    r->stage[0] = r->stage[1] = r->dist = r->xyz[0] = r->xyz[1] = r->xyz[2] = NAN;
    if (r->type == JNL_T_META) {
        memcpy(r->text, b + 16, JNL_TEXT_LEN);
        r->text[JNL_TEXT_LEN - 1] = 0;
    } else if (r->type == JNL_T_GAP) {
        r->stage[0] = getd(b + 16);
        r->stage[1] = getd(b + 24);
        r->num = get64(b + 32);
        r->row = (int64_t)get64(b + 40);
        r->count = get64(b + 48);
    } else {
        r->stage[0] = getd(b + 16);
        r->stage[1] = getd(b + 24);
        r->dist = getd(b + 32);
        r->xyz[0] = getd(b + 40);
        r->xyz[1] = getd(b + 48);
        r->xyz[2] = getd(b + 56);
    }
    r->t = getd(b + 64);
    return RIG_OK;
}

static uint64_t rec_off(uint64_t i)
{
    return JNL_HDR_BYTES + i * JNL_REC_BYTES;
}

/* Read exactly n bytes at off; RIG_ECORRUPT if the store ends first. */
static int read_at(rig_store_t st, uint64_t off, void *buf, size_t n)
{
    size_t got = 0;
    int rc = st.ops->read(st.ctx, off, buf, n, &got);
    if (rc)
        return rc;
    return got == n ? RIG_OK : RIG_ECORRUPT;
}

int jnl_create(jnl_t *j, rig_store_t st, const jnl_header_t *h)
{
    if (!j || !h || !st.ops || h->sync_every == 0)
        return RIG_EARG;
    memset(j, 0, sizeof *j);
    uint64_t size;
    int rc = st.ops->size(st.ctx, &size);
    if (rc)
        return rc;
    if (size != 0)
        return RIG_ESTATE;
    j->st = st;
    j->h = *h;
    j->h.version = JNL_VERSION;
    uint8_t b[JNL_HDR_BYTES];
    hdr_encode(&j->h, b);
    rc = st.ops->append(st.ctx, b, sizeof b);
    if (!rc) {
        rc = st.ops->sync(st.ctx); /* no point is acknowledged before its header is */
        j->syncs++;
    }
    if (rc) {
        st.ops->truncate(st.ctx, 0);
        j->state = JNL_S_FAILED;
        return rc;
    }
    j->state = JNL_S_OPEN;
    return RIG_OK;
}

static int type_known(unsigned type)
{
    return type >= JNL_T_POINT && type <= JNL_T_META;
}

/* Record i is valid where it stands: CRC, sequence, a known type. */
static int rec_valid(const uint8_t *b, uint64_t i, jnl_rec_t *r)
{
    return jnl_rec_decode(b, r) == RIG_OK && r->seq == (uint32_t)i && type_known(r->type);
}

/* jnl_scan reads this many records a call (on the stack): one pread per
 * 80-byte record made a replay past 2^20 points slow on the cell. */
#ifdef BOARD_JNL_SCAN_RECS
#define JNL_SCAN_RECS BOARD_JNL_SCAN_RECS
#else
#define JNL_SCAN_RECS JNL_READ_RECS
#endif

/* Record i of a scan through chunks: *first and *n say what buf holds. */
static int scan_rec(rig_store_t st, uint64_t nfull, uint64_t i, uint8_t *buf, uint64_t *first,
                    uint64_t *n, const uint8_t **rec)
{
    if (i < *first || i >= *first + *n) {
        uint64_t left = nfull - i;
        uint64_t k = left < JNL_SCAN_RECS ? left : JNL_SCAN_RECS;
        int rc = read_at(st, rec_off(i), buf, (size_t)k * JNL_REC_BYTES);
        if (rc)
            return rc;
        *first = i;
        *n = k;
    }
    *rec = buf + (size_t)(i - *first) * JNL_REC_BYTES;
    return RIG_OK;
}

int jnl_scan(rig_store_t st, jnl_header_t *h, jnl_info_t *s)
{
    if (!h || !s || !st.ops)
        return RIG_EARG;
    memset(s, 0, sizeof *s);
    s->bad_record = -1;
    s->t_first = s->t_last = NAN;
    uint64_t size;
    int rc = st.ops->size(st.ctx, &size);
    if (rc)
        return rc;
    uint8_t b[JNL_SCAN_RECS * JNL_REC_BYTES > JNL_HDR_BYTES ? JNL_SCAN_RECS * JNL_REC_BYTES
                                                            : JNL_HDR_BYTES];
    if (size < JNL_HDR_BYTES)
        return RIG_ECORRUPT; /* torn while being created: nothing was acknowledged */
    if ((rc = read_at(st, 0, b, JNL_HDR_BYTES)) != RIG_OK)
        return rc;
    if (hdr_decode(b, h))
        return RIG_ECORRUPT;
    uint64_t nfull = (size - JNL_HDR_BYTES) / JNL_REC_BYTES;
    uint64_t i, first = 0, nbuf = 0;
    const uint8_t *p;
    jnl_rec_t r;
    for (i = 0; i < nfull; i++) {
        if ((rc = scan_rec(st, nfull, i, b, &first, &nbuf, &p)) != RIG_OK)
            return rc;
        if (s->ended || !rec_valid(p, i, &r))
            break;
        if (r.type == JNL_T_END) {
            s->ended = 1;
            s->end_code = r.code;
        } else if (r.type == JNL_T_GAP) {
            s->gaps++;
            if (r.code > 0 && r.code < JNL_GAP_KINDS)
                s->lost[r.code] += r.count;
        } else if (r.type == JNL_T_META) {
            if (r.code == JNL_META_PART_ID && !s->part_id[0])
                memcpy(s->part_id, r.text, JNL_TEXT_LEN);
        } else if (r.flags & JNL_F_NOSURF)
            s->flagged++;
        else
            s->points++;
        if (i == 0)
            s->t_first = r.t;
        s->t_last = r.t;
    }
    s->records = i;
    s->tail_bytes = size - rec_off(i);
    /* A damaged record followed by a valid one that was appended after it
     * had been synced is damage to acknowledged data, not a torn write. */
    for (uint64_t k = i + 1; k < nfull; k++) {
        if ((rc = scan_rec(st, nfull, k, b, &first, &nbuf, &p)) != RIG_OK)
            return rc;
        if (rec_valid(p, k, &r) && r.synced > i) {
            s->bad_record = (int64_t)i;
            return RIG_ECORRUPT;
        }
    }
    return RIG_OK;
}

int jnl_open(jnl_t *j, rig_store_t st, jnl_info_t *s)
{
    if (!j || !s)
        return RIG_EARG;
    memset(j, 0, sizeof *j);
    int rc = jnl_scan(st, &j->h, s);
    if (rc)
        return rc;
    j->st = st;
    if (s->tail_bytes) {
        rc = st.ops->truncate(st.ctx, rec_off(s->records));
        if (!rc)
            rc = st.ops->sync(st.ctx);
        j->syncs++;
        if (rc)
            return rc;
    }
    j->nrec = j->synced = s->records;
    j->state = s->ended ? JNL_S_ENDED : JNL_S_OPEN;
    return RIG_OK;
}

int jnl_sync(jnl_t *j)
{
    if (!j)
        return RIG_EARG;
    if (j->state == JNL_S_FAILED || j->state == JNL_S_CLOSED)
        return RIG_ESTATE;
    if (j->synced == j->nrec)
        return RIG_OK;
    int rc = j->st.ops->sync(j->st.ctx);
    j->syncs++;
    if (rc) {
        j->state = JNL_S_FAILED;
        return rc;
    }
    j->synced = j->nrec;
    j->since_sync = 0;
    return RIG_OK;
}

int jnl_append(jnl_t *j, jnl_rec_t *r)
{
    if (!j || !r || !type_known(r->type))
        return RIG_EARG;
    if (j->state != JNL_S_OPEN)
        return RIG_ESTATE;
    if (j->nrec >= UINT32_MAX)
        return RIG_EFULL; /* sequence numbers are 32-bit */
    r->seq = (uint32_t)j->nrec;
    r->synced = (uint32_t)j->synced;
    uint8_t b[JNL_REC_BYTES];
    jnl_rec_encode(r, b);
    int rc = j->st.ops->append(j->st.ctx, b, sizeof b);
    if (rc) {
        /* The store may hold part of the record: cut it so that the
         * journal ends on a whole record; recovery would drop it anyway. */
        j->st.ops->truncate(j->st.ctx, rec_off(j->nrec));
        j->state = JNL_S_FAILED;
        return rc;
    }
    j->nrec++;
    if (++j->since_sync >= j->h.sync_every)
        return jnl_sync(j);
    return RIG_OK;
}

int jnl_end(jnl_t *j, int code, double t)
{
    jnl_rec_t r;
    memset(&r, 0, sizeof r);
    r.type = JNL_T_END;
    r.code = code;
    r.dist = r.xyz[0] = r.xyz[1] = r.xyz[2] = r.stage[0] = r.stage[1] = NAN;
    r.t = t;
    int rc = jnl_append(j, &r);
    if (!rc)
        rc = jnl_sync(j);
    if (!rc)
        j->state = JNL_S_ENDED;
    return rc;
}

int jnl_gap(jnl_t *j, int kind, int64_t row, uint64_t num, uint64_t count, const double stage[2],
            double t)
{
    if (kind <= 0 || kind >= JNL_GAP_KINDS || count == 0)
        return RIG_EARG;
    jnl_rec_t r;
    memset(&r, 0, sizeof r);
    r.type = JNL_T_GAP;
    r.code = kind;
    r.stage[0] = stage ? stage[0] : NAN;
    r.stage[1] = stage ? stage[1] : NAN;
    r.dist = r.xyz[0] = r.xyz[1] = r.xyz[2] = NAN;
    r.num = num;
    r.count = count;
    r.row = row;
    r.t = t;
    return jnl_append(j, &r);
}

int jnl_meta(jnl_t *j, int key, const char *text, double t)
{
    if (key != JNL_META_PART_ID || !text)
        return RIG_EARG;
    jnl_rec_t r;
    memset(&r, 0, sizeof r);
    r.type = JNL_T_META;
    r.code = key;
    r.row = -1;
    r.stage[0] = r.stage[1] = r.dist = r.xyz[0] = r.xyz[1] = r.xyz[2] = NAN;
    size_t n = strlen(text);
    n = n < JNL_TEXT_LEN - 1 ? n : JNL_TEXT_LEN - 1;
    memcpy(r.text, text, n);
    r.t = t;
    return jnl_append(j, &r);
}

const char *jnl_gap_name(int kind)
{
    switch (kind) {
    case JNL_GAP_NO_READING: return "no_reading";
    case JNL_GAP_NO_TRIGGER: return "no_trigger";
    case JNL_GAP_BOTH: return "both";
    case JNL_GAP_PROFILE: return "profile";
    default: return "unknown";
    }
}

uint64_t jnl_acked(const jnl_t *j)
{
    return j ? j->synced : 0;
}

int jnl_reader_open(jnl_reader_t *rd, rig_store_t st, jnl_header_t *h, jnl_info_t *s)
{
    if (!rd)
        return RIG_EARG;
    memset(rd, 0, sizeof *rd);
    int rc = jnl_scan(st, h, s);
    if (rc)
        return rc;
    rd->st = st;
    rd->count = s->records;
    return RIG_OK;
}

int jnl_reader_next(jnl_reader_t *rd, jnl_rec_t *r)
{
    if (!rd || !r)
        return RIG_EARG;
    if (rd->next >= rd->count)
        return 0;
    if (rd->next < rd->buf_first || rd->next >= rd->buf_first + rd->nbuf) {
        uint64_t left = rd->count - rd->next;
        unsigned n = left < JNL_READ_RECS ? (unsigned)left : JNL_READ_RECS;
        int rc = read_at(rd->st, rec_off(rd->next), rd->buf, (size_t)n * JNL_REC_BYTES);
        if (rc)
            return rc;
        rd->buf_first = rd->next;
        rd->nbuf = n;
    }
    const uint8_t *b = rd->buf + (size_t)(rd->next - rd->buf_first) * JNL_REC_BYTES;
    if (!rec_valid(b, rd->next, r))
        return RIG_ECORRUPT; /* changed since jnl_scan verified it */
    rd->next++;
    return 1;
}

void jnl_reader_rewind(jnl_reader_t *rd)
{
    if (rd)
        rd->next = 0;
}

/* SPDX-License-Identifier: MIT */
/* test_resdb.c: cf_resdb against SQLite read directly (its own connection,
 * its own SQL): a version 1 database (the schema written here as the first
 * recorder wrote it) migrated on open with its rows kept; a newer schema
 * refused; a record and its outbox entries in one transaction; the outbox's
 * bound (oldest dropped and counted); due, retry and delivery; the queries'
 * filters; WAL on the file; figures a shell fit does not know (NaN,
 * verdict 0) stored as NULL and read back as NaN and 0; cf_resdb_check
 * telling ours from a text file, an empty one and another SQLite database
 * (each left byte for byte as it was). */
#include "cf_resdb.h"
#include "cf_test.h"
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static char path[512];

static int setup(void **state)
{
    (void)state;
    const char *dir = getenv("CF_TEST_TMP");
    if (dir)
        mkdir(dir, 0755);
    snprintf(path, sizeof path, "%s/resdb_%ld.db", dir ? dir : "/tmp", (long)getpid());
    const char *sfx[] = {"", "-wal", "-shm"};
    for (int i = 0; i < 3; i++) {
        char p[600];
        snprintf(p, sizeof p, "%s%s", path, sfx[i]);
        remove(p);
    }
    return 0;
}

/* One integer from sql on a connection of the test's own. */
static long long q1(const char *sql)
{
    sqlite3 *db;
    sqlite3_stmt *st;
    long long v = -999;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    assert_int_equal(sqlite3_prepare_v2(db, sql, -1, &st, NULL), SQLITE_OK);
    if (sqlite3_step(st) == SQLITE_ROW)
        v = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(db);
    return v;
}

static void exec_raw(const char *sql)
{
    sqlite3 *db;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    assert_int_equal(sqlite3_exec(db, sql, NULL, NULL, NULL), SQLITE_OK);
    sqlite3_close(db);
}

static void job(cf_resdb_job_t *j, int k, long part, const char *ended)
{
    memset(j, 0, sizeof *j);
    snprintf(j->job_uuid, sizeof j->job_uuid, "00000000-0000-4000-8000-%012d", k);
    snprintf(j->cell_id, sizeof j->cell_id, "cellT");
    j->part_number = part;
    j->program = 3;
    j->result_seq = k;
    snprintf(j->command, sizeof j->command, "fit");
    snprintf(j->started_at, sizeof j->started_at, "%s", ended);
    snprintf(j->ended_at, sizeof j->ended_at, "%s", ended);
    snprintf(j->state, sizeof j->state, "done");
    j->has_fit = 1;
    j->rms = 0.001f * (float)k; /* the floats the PLC reads */
    j->max_dev = 0.01f, j->min_dev = -0.02f, j->within_pct = 99.5f;
    j->verdict = 1, j->points = 1000 + k, j->control_points = 192;
}

static void test_migrate_v1(void **state)
{
    (void)state;
    /* A version 1 file: jobs without part_id, command, journal; no outbox. */
    exec_raw("CREATE TABLE jobs (job_uuid TEXT PRIMARY KEY NOT NULL, cell_id TEXT, part_number "
             "INTEGER, program INTEGER, result_seq INTEGER, started_at TEXT, ended_at TEXT, state "
             "TEXT, error_code INTEGER, fit_status INTEGER, rms REAL, max_dev REAL, min_dev REAL, "
             "within_pct REAL, verdict INTEGER, points INTEGER, control_points INTEGER, "
             "surface_path TEXT, surface_sha256 TEXT, report_path TEXT, report_sha256 TEXT);"
             "INSERT INTO jobs VALUES ('11111111-2222-4333-8444-555555555555', 'old', 42, 1, 9, "
             "'2026-01-01T00:00:00.000Z', '2026-01-01T00:00:01.000Z', 'done', 0, 0, 0.25, 0.5, "
             "-0.5, 97.5, 2, 500, 100, '/r/fitted.igs', 'ab', '/r/report.json', 'cd');"
             "PRAGMA user_version = 1;");
    cf_resdb_t *db;
    char msg[256];
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    assert_int_equal(cf_resdb_version(db), CF_RESDB_VERSION);
    cf_resdb_job_t j;
    assert_int_equal(cf_resdb_get(db, "11111111-2222-4333-8444-555555555555", &j), CF_RESDB_OK);
    assert_string_equal(j.cell_id, "old");
    assert_int_equal(j.part_number, 42);
    assert_int_equal(j.result_seq, 9);
    assert_true(j.has_fit);
    assert_true(j.rms == 0.25 && j.within_pct == 97.5 && j.points == 500);
    assert_string_equal(j.report_path, "/r/report.json");
    assert_string_equal(j.part_id, ""); /* the new columns: NULL */
    assert_string_equal(j.journal_path, "");
    /* The new tables work on the migrated file. */
    cf_resdb_job_t n;
    job(&n, 1, 7, "2026-02-01T00:00:00.000Z");
    assert_int_equal(cf_resdb_record(db, &n, CF_RESDB_PG | CF_RESDB_MQTT, 0), CF_RESDB_OK);
    cf_resdb_close(db);
    assert_int_equal(q1("PRAGMA user_version"), CF_RESDB_VERSION);
    assert_int_equal(q1("SELECT count(*) FROM jobs"), 2);
    assert_int_equal(q1("SELECT count(*) FROM outbox"), 2);
    assert_int_equal(q1("SELECT count(*) FROM pragma_table_info('jobs') WHERE name IN "
                        "('part_id', 'command', 'journal_path', 'journal_sha256')"),
                     4);
    /* Opening again migrates nothing and keeps everything. */
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    cf_resdb_close(db);
    assert_int_equal(q1("SELECT count(*) FROM jobs"), 2);
}

static void test_newer_refused(void **state)
{
    (void)state;
    exec_raw("CREATE TABLE jobs (x); PRAGMA user_version = 99;");
    cf_resdb_t *db;
    char msg[256];
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_ESCHEMA);
    assert_null(db);
    assert_non_null(strstr(msg, "99"));
    assert_int_equal(q1("PRAGMA user_version"), 99); /* untouched */
}

/* cf_resdb_check on what --db may be given: each file's bytes unchanged. */
static void check_file(const char *bytes, size_t n, int want, const char *why)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, n, f), n);
    fclose(f);
    char msg[256] = "", back[64];
    assert_int_equal(cf_resdb_check(path, msg, sizeof msg), want);
    assert_non_null(strstr(msg, why));
    f = fopen(path, "rb");
    assert_int_equal(fread(back, 1, sizeof back, f), n);
    fclose(f);
    assert_memory_equal(back, bytes, n);
    remove(path);
}

static void test_check(void **state)
{
    (void)state;
    char msg[256];
    check_file("x y z\n1 2 3\n", 12, CF_RESDB_ENOTDB, "not an SQLite database");
    check_file("", 0, CF_RESDB_ENOTDB, "an empty file");
    assert_int_equal(cf_resdb_check(path, msg, sizeof msg), CF_RESDB_EOPEN); /* none there */
    exec_raw("CREATE TABLE parts (id INTEGER); INSERT INTO parts VALUES (7);");
    assert_int_equal(cf_resdb_check(path, msg, sizeof msg), CF_RESDB_ENOTDB);
    assert_non_null(strstr(msg, "without a jobs table"));
    assert_int_equal(q1("SELECT count(*) FROM sqlite_master"), 1); /* parts alone, as it was */
    remove(path);
    exec_raw("CREATE TABLE jobs (x); PRAGMA user_version = 99;");
    assert_int_equal(cf_resdb_check(path, msg, sizeof msg), CF_RESDB_ESCHEMA);
    remove(path);
    cf_resdb_t *db; /* ours, current and (test_migrate_v1's) version 1 */
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    cf_resdb_close(db);
    assert_int_equal(cf_resdb_check(path, msg, sizeof msg), CF_RESDB_OK);
    remove(path);
    exec_raw("CREATE TABLE jobs (job_uuid TEXT); PRAGMA user_version = 1;");
    assert_int_equal(cf_resdb_check(path, msg, sizeof msg), CF_RESDB_OK);
}

static void test_record_wal(void **state)
{
    (void)state;
    cf_resdb_t *db;
    char msg[256];
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    cf_resdb_job_t j, g;
    job(&j, 5, 4711, "2026-03-01T10:00:00.000Z");
    snprintf(j.journal_path, sizeof j.journal_path, "/j/4711.jnl");
    assert_int_equal(cf_resdb_record(db, &j, CF_RESDB_MQTT, 0), CF_RESDB_OK);
    /* Another connection sees the row and its one entry at once. */
    assert_int_equal(q1("SELECT count(*) FROM jobs WHERE part_number = 4711"), 1);
    assert_int_equal(q1("SELECT count(*) FROM outbox WHERE target = 'mqtt'"), 1);
    assert_int_equal(q1("SELECT count(*) FROM outbox WHERE target = 'pg'"), 0);
    assert_int_equal(q1("SELECT count(*) FROM pragma_journal_mode WHERE journal_mode = 'wal'"), 1);
    assert_int_equal(cf_resdb_get(db, j.job_uuid, &g), CF_RESDB_OK);
    float rms5 = 0.001f * (float)5; /* as job() made it: stored and read back exactly */
    assert_true(g.rms == (double)rms5 && g.min_dev == (double)-0.02f);
    assert_string_equal(g.journal_path, "/j/4711.jnl");
    assert_int_equal(cf_resdb_get(db, "00000000-0000-4000-8000-999999999999", &g),
                     CF_RESDB_ENOTFOUND);
    /* A job without a fit: the figures are NULL. */
    job(&j, 6, 4711, "2026-03-01T11:00:00.000Z");
    j.has_fit = 0;
    snprintf(j.state, sizeof j.state, "error");
    j.error_code = 301;
    assert_int_equal(cf_resdb_record(db, &j, 0, 0), CF_RESDB_OK);
    assert_int_equal(q1("SELECT count(*) FROM jobs WHERE rms IS NULL AND error_code = 301"), 1);
    cf_resdb_close(db);
}

static void test_outbox_bound(void **state)
{
    (void)state;
    cf_resdb_t *db;
    char msg[256];
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    for (int k = 1; k <= 8; k++) {
        cf_resdb_job_t j;
        job(&j, k, 100 + k, "2026-04-01T00:00:00.000Z");
        assert_int_equal(cf_resdb_record(db, &j, CF_RESDB_PG | CF_RESDB_MQTT, 5), CF_RESDB_OK);
        assert_true(q1("SELECT count(*) FROM outbox") <= 5);
    }
    /* 16 entries into 5 places: 11 dropped, counted; every job kept. */
    assert_int_equal(q1("SELECT count(*) FROM outbox"), 5);
    assert_int_equal(q1("SELECT value FROM counters WHERE name = 'outbox_dropped'"), 11);
    assert_int_equal(q1("SELECT count(*) FROM jobs"), 8);
    /* The newest stay: jobs 6 (mqtt), 7 and 8 (both). */
    assert_int_equal(q1("SELECT min(j.result_seq) FROM outbox o JOIN jobs j USING (job_uuid)"), 6);
    cf_resdb_obstat_t st;
    assert_int_equal(cf_resdb_outbox_stat(db, &st), CF_RESDB_OK);
    assert_int_equal(st.pending_pg, 2);
    assert_int_equal(st.pending_mqtt, 3);
    assert_int_equal(st.dropped, 11);
    cf_resdb_close(db);
}

static void test_due_retry_delivered(void **state)
{
    (void)state;
    cf_resdb_t *db;
    char msg[256];
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    for (int k = 1; k <= 3; k++) {
        cf_resdb_job_t j;
        job(&j, k, 200 + k, "2026-05-01T00:00:00.000Z");
        assert_int_equal(cf_resdb_record(db, &j, CF_RESDB_PG, 0), CF_RESDB_OK);
    }
    double now = (double)time(NULL) + 1;
    cf_resdb_due_t e, e2;
    assert_int_equal(cf_resdb_due(db, CF_RESDB_MQTT, now, &e), 0);
    assert_int_equal(cf_resdb_due(db, CF_RESDB_PG, now, &e), 1);
    assert_string_equal(e.job_uuid, "00000000-0000-4000-8000-000000000001"); /* oldest first */
    assert_int_equal(cf_resdb_retry(db, e.id, now + 60, "connection refused"), CF_RESDB_OK);
    assert_int_equal(cf_resdb_due(db, CF_RESDB_PG, now, &e2), 1);
    assert_string_equal(e2.job_uuid, "00000000-0000-4000-8000-000000000002");
    assert_int_equal(cf_resdb_delivered(db, e2.id), CF_RESDB_OK);
    assert_int_equal(q1("SELECT attempts FROM outbox WHERE job_uuid LIKE '%0001'"), 1);
    assert_int_equal(q1("SELECT count(*) FROM outbox"), 2);
    cf_resdb_obstat_t st;
    assert_int_equal(cf_resdb_outbox_stat(db, &st), CF_RESDB_OK);
    assert_string_equal(st.last_error, "connection refused");
    /* After a reconnection everything is due again. */
    assert_int_equal(cf_resdb_due_now(db, CF_RESDB_PG), CF_RESDB_OK);
    assert_int_equal(cf_resdb_due(db, CF_RESDB_PG, now, &e), 1);
    assert_string_equal(e.job_uuid, "00000000-0000-4000-8000-000000000001");
    cf_resdb_close(db);
}

static int count_row(void *ctx, const cf_resdb_job_t *j)
{
    (void)j;
    ++*(int *)ctx;
    return 0;
}

static void test_query(void **state)
{
    (void)state;
    cf_resdb_t *db;
    char msg[256];
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    const char *ends[] = {"2026-06-01T08:00:00.000Z", "2026-06-02T08:00:00.000Z",
                          "2026-06-03T08:00:00.000Z", "2026-06-03T09:00:00.000Z"};
    for (int k = 0; k < 4; k++) {
        cf_resdb_job_t j;
        job(&j, k + 1, k % 2 ? 11 : 22, ends[k]);
        assert_int_equal(cf_resdb_record(db, &j, 0, 0), CF_RESDB_OK);
    }
    int n = 0;
    assert_int_equal(cf_resdb_query(db, -1, NULL, count_row, &n), 0);
    assert_int_equal(n, 4);
    n = 0;
    assert_int_equal(cf_resdb_query(db, 11, NULL, count_row, &n), 0);
    assert_int_equal(n, 2);
    n = 0;
    assert_int_equal(cf_resdb_query(db, -1, "2026-06-02", count_row, &n), 0);
    assert_int_equal(n, 3);
    n = 0;
    assert_int_equal(cf_resdb_query(db, 22, "2026-06-03", count_row, &n), 0);
    assert_int_equal(n, 1);
    cf_resdb_close(db);
}

/* A shell fit's row (cmd_record.h): no signed deviations, no share
 * within, no verdict. SQLite's own count of NULLs says what was stored. */
static void test_unknown_null(void **state)
{
    (void)state;
    cf_resdb_t *db;
    char msg[256];
    assert_int_equal(cf_resdb_open(path, &db, msg, sizeof msg), CF_RESDB_OK);
    cf_resdb_job_t j, g;
    job(&j, 5, 0, "2026-03-01T00:00:00.000Z");
    j.max_dev = j.min_dev = j.within_pct = NAN;
    j.verdict = 0;
    assert_int_equal(cf_resdb_record(db, &j, 0, 0), CF_RESDB_OK);
    assert_int_equal(cf_resdb_get(db, j.job_uuid, &g), CF_RESDB_OK);
    cf_resdb_close(db);
    assert_true(g.has_fit);
    assert_true(g.rms == j.rms && g.points == j.points);
    assert_true(isnan(g.max_dev) && isnan(g.min_dev) && isnan(g.within_pct));
    assert_int_equal(g.verdict, 0);
    assert_int_equal(q1("SELECT count(*) FROM jobs WHERE max_dev IS NULL AND min_dev IS NULL AND "
                        "within_pct IS NULL AND verdict IS NULL AND rms IS NOT NULL"),
                     1);
    assert_int_equal(q1("SELECT count(*) FROM outbox"), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_migrate_v1, setup),
        cmocka_unit_test_setup(test_newer_refused, setup),
        cmocka_unit_test_setup(test_check, setup),
        cmocka_unit_test_setup(test_record_wal, setup),
        cmocka_unit_test_setup(test_outbox_bound, setup),
        cmocka_unit_test_setup(test_due_retry_delivered, setup),
        cmocka_unit_test_setup(test_query, setup),
        cmocka_unit_test_setup(test_unknown_null, setup),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    setup(NULL);
    return rc;
}

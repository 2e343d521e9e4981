/* SPDX-License-Identifier: MIT */
/* cf_plant.h: serve's settings for results and the plant, and their start
 * and stop: the cell's results.db (cf_resdb.h), the recording runner table
 * (cf_record.h) and the forwarder (cf_forward.h). Keys (config file, or
 * options with '-' for '_'):
 *   results_db PATH     the cell's database (default RESULTS_DIR/results.db)
 *   record yes|no       record jobs at all (default yes)
 *   cell_id NAME        the cell's name in rows and topics (default host name)
 *   plant_db URL        postgresql://USER@HOST:PORT/DB[?sslmode=...]
 *   plant_db_password   (or PGPASSWORD, ~/.pgpass: libpq's own)
 *   mqtt URL            mqtt://HOST:PORT/PREFIX or mqtts://...
 *   mqtt_username, mqtt_password (or CELLFIT_MQTT_USERNAME/_PASSWORD)
 *   mqtt_cafile, mqtt_certfile, mqtt_keyfile   TLS
 *   outbox_max N        outbox entries kept at most (default 100000)
 *   forward_backoff_max S   longest wait between retries (default 30 s) */
#ifndef CF_PLANT_H
#define CF_PLANT_H

#include "cf_forward.h"
#include "cf_record.h"

#define CF_PLANT_MAX_STRS 16

typedef struct cf_plant {
    cf_forward_opts_t fo;
    const char *results_db;
    int record; /* 1 by default */
    long outbox_max;
    char db_path[4096];
    char host_id[64]; /* cell_id when the config names none: the host's name */
    cf_record_t rec;
    cf_forward_t *fwd;
    int started;
    char *strs[CF_PLANT_MAX_STRS];
    int nstrs;
} cf_plant_t;

void cf_plant_init(cf_plant_t *pl);

/* One setting: 0 taken, 1 not one of ours, <0 a bad value (msg). */
int cf_plant_apply(cf_plant_t *pl, const char *key, const char *val, char *msg, size_t ml);

/* Open results.db (in results_dir unless results_db is set; nothing when
 * neither is, or record is no), wrap the runner table inner (its context
 * rr) into out, start the forwarder. 0, or <0 with msg. */
int cf_plant_start(cf_plant_t *pl, cf_plcrun_t *rr, const char *results_dir,
                   const cf_runner_t *inner, cf_runner_t *out, char *msg, size_t ml);

/* After the server has stopped (no job runs): stop the forwarder, close. */
void cf_plant_stop(cf_plant_t *pl);

/* The option summary for serve's usage line. */
#define CF_PLANT_USAGE                                                                             \
    "[--results-db F] [--cell-id NAME] [--plant-db postgresql://USER@HOST:PORT/DB] "               \
    "[--mqtt mqtt://HOST:PORT/PREFIX] [--outbox-max N]"

#endif

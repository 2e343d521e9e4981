/* SPDX-License-Identifier: MIT */
/* cf_plant.c: serve's results and plant settings, start and stop
 * (cf_plant.h). */
#define _DEFAULT_SOURCE /* gethostname beside C11 */
#include "cf_plant.h"
#include "cf_log.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

void cf_plant_init(cf_plant_t *pl)
{
    memset(pl, 0, sizeof *pl);
    pl->record = 1;
    pl->outbox_max = 100000;
    pl->fo.backoff_max = 30;
}

static const char *keep(cf_plant_t *pl, const char *v)
{
    char *s = pl->nstrs < CF_PLANT_MAX_STRS ? strdup(v) : NULL;
    if (s)
        pl->strs[pl->nstrs++] = s;
    return s;
}

static int num(const char *v, double lo, double hi, double *out)
{
    char *e;
    double x = strtod(v, &e);
    if (e == v || *e || !(x >= lo && x <= hi))
        return -1;
    *out = x;
    return 0;
}

int cf_plant_apply(cf_plant_t *pl, const char *k, const char *v, char *msg, size_t ml)
{
    static const char *const strk[] = {"results_db",        "cell_id",     "plant_db",
                                       "plant_db_password", "mqtt",        "mqtt_username",
                                       "mqtt_password",     "mqtt_cafile", "mqtt_certfile",
                                       "mqtt_keyfile",      NULL};
    const char **dst[] = {&pl->results_db,       &pl->fo.cell_id,     &pl->fo.plant_db,
                          &pl->fo.pg_password,   &pl->fo.mqtt,        &pl->fo.mqtt_user,
                          &pl->fo.mqtt_password, &pl->fo.mqtt_cafile, &pl->fo.mqtt_certfile,
                          &pl->fo.mqtt_keyfile};
    double x;
    for (int i = 0; strk[i]; i++)
        if (!strcmp(k, strk[i])) {
            if (!(*dst[i] = keep(pl, v)))
                return snprintf(msg, ml, "%s: more than %d plant settings", k, CF_PLANT_MAX_STRS),
                       -1;
#if CF_NO_PLANT
            return 0; /* refused at start (cf_plant_start) */
#else
            cf_forward_opts_t probe = pl->fo;
            return cf_forward_check(&probe, msg, ml) ? -1 : 0;
#endif
        }
    if (!strcmp(k, "record")) {
        if (!strcmp(v, "yes") || !strcmp(v, "1") || !strcmp(v, "true"))
            pl->record = 1;
        else if (!strcmp(v, "no") || !strcmp(v, "0") || !strcmp(v, "false"))
            pl->record = 0;
        else
            return snprintf(msg, ml, "record '%s': yes or no", v), -1;
        return 0;
    }
    if (!strcmp(k, "outbox_max")) {
        if (num(v, 1, 1e9, &x))
            return snprintf(msg, ml, "outbox_max '%s': need 1 .. 1e9 entries", v), -1;
        pl->outbox_max = (long)x;
        return 0;
    }
    if (!strcmp(k, "forward_backoff_max")) {
        if (num(v, 0.1, 3600, &x))
            return snprintf(msg, ml, "forward_backoff_max '%s': need 0.1 .. 3600 (s)", v), -1;
        pl->fo.backoff_max = x;
        return 0;
    }
    return 1;
}

#if CF_NO_PLANT
/* A build without SQLite, libpq and libmosquitto (a cross build whose
 * target lacks them): jobs are not recorded, and asking for it is refused. */
int cf_plant_start(cf_plant_t *pl, cf_plcrun_t *rr, const char *results_dir,
                   const cf_runner_t *inner, cf_runner_t *out, char *msg, size_t ml)
{
    (void)rr;
    (void)results_dir;
    if (out != inner)
        *out = *inner;
    if (pl->fo.plant_db || pl->fo.mqtt || pl->results_db)
        return snprintf(msg, ml,
                        "this cellfit is built without SQLite, libpq and libmosquitto: "
                        "no results database or plant forwarding"),
               -1;
    cf_log(CF_LOG_INFO, "record: built without SQLite: jobs not recorded");
    return 0;
}

void cf_plant_stop(cf_plant_t *pl)
{
    for (int i = 0; i < pl->nstrs; i++)
        free(pl->strs[i]);
    pl->nstrs = 0;
}
#else
int cf_plant_start(cf_plant_t *pl, cf_plcrun_t *rr, const char *results_dir,
                   const cf_runner_t *inner, cf_runner_t *out, char *msg, size_t ml)
{
    int fwd = pl->fo.plant_db || pl->fo.mqtt;
    if (out != inner)
        *out = *inner;
    if (!pl->fo.cell_id) {
        /* One name for results.db's rows, the plant's rows and the MQTT
         * topics, as `fit --record` names the cell: the host's name. */
        if (gethostname(pl->host_id, sizeof pl->host_id - 1) || !pl->host_id[0])
            snprintf(pl->host_id, sizeof pl->host_id, "cell");
        pl->fo.cell_id = pl->host_id;
    }
    if (!pl->record) {
        if (fwd)
            return snprintf(msg, ml, "plant_db and mqtt need record = yes"), -1;
        return 0;
    }
    if (pl->results_db)
        snprintf(pl->db_path, sizeof pl->db_path, "%s", pl->results_db);
    else if (!results_dir || cf_record_default_path(results_dir, pl->db_path, sizeof pl->db_path)) {
        if (fwd)
            return snprintf(msg, ml, "plant_db and mqtt need a results folder or results_db"), -1;
        cf_log(CF_LOG_INFO, "record: no results folder and no results_db: jobs not recorded");
        return 0;
    }
    cf_record_t *r = &pl->rec;
    memset(r, 0, sizeof *r);
    /* An existing file that is not a results database is refused, never
     * migrated (as `cellfit results` and `fit --record` refuse it). */
    struct stat sb;
    if (!stat(pl->db_path, &sb) && cf_resdb_check(pl->db_path, msg, ml))
        return -1;
    int rc = cf_resdb_open(pl->db_path, &r->db, msg, ml);
    if (rc)
        return -1;
    pl->fo.db_path = pl->db_path;
    if (fwd && cf_forward_start(&pl->fo, &pl->fwd, msg, ml)) {
        cf_resdb_close(r->db);
        r->db = NULL;
        return -1;
    }
    r->inner = *inner;
    r->rr = rr;
    r->fwd = pl->fwd;
    r->cell_id = pl->fo.cell_id;
    r->targets = cf_forward_targets(&pl->fo);
    r->outbox_max = pl->outbox_max;
    cf_record_wrap(r, out);
    pl->started = 1;
    char m1[512] = "", m2[512] = "";
    if (pl->fo.plant_db)
        cf_forward_mask(pl->fo.plant_db, m1, sizeof m1);
    if (pl->fo.mqtt)
        cf_forward_mask(pl->fo.mqtt, m2, sizeof m2);
    cf_log(CF_LOG_INFO, "record: jobs into %s%s%s%s%s", pl->db_path, *m1 ? ", plant database " : "",
           m1, *m2 ? ", broker " : "", m2);
    return 0;
}

void cf_plant_stop(cf_plant_t *pl)
{
    if (pl->started) {
        cf_forward_stop(pl->fwd);
        pl->fwd = NULL;
        cf_log(CF_LOG_INFO, "record: %ld jobs recorded, %ld lost to database errors",
               pl->rec.recorded, pl->rec.failed);
        cf_resdb_close(pl->rec.db);
        pl->rec.db = NULL;
        pl->started = 0;
    }
    for (int i = 0; i < pl->nstrs; i++)
        free(pl->strs[i]);
    pl->nstrs = 0;
}
#endif

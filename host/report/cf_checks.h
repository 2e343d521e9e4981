/* SPDX-License-Identifier: MIT */
/* cf_checks.h: named check points and zones (docs/formats.md, "Check
 * points"): a file of `NAME X Y Z [RADIUS]` lines, and per check the signed
 * normal deviation there, accumulated point by point as a report streams
 * its points: without RADIUS the deviation of the measured point nearest
 * (X,Y,Z) (the first one on a tie), with it the mean deviation of the
 * points within RADIUS (a zone; none: no value). Memory: the checks', never
 * a function of the number of points. */
#ifndef CF_CHECKS_H
#define CF_CHECKS_H

#include "cf_json.h"
#include <stddef.h>
#include <stdio.h>

#define CF_CHECKS_MAX 9994 /* K0100 counts at most 9999, the five figures included */
#define CF_CHECKS_NAME 80  /* K2002 holds at most 80 characters */

typedef struct cf_check {
    char name[CF_CHECKS_NAME + 1];
    double p[3];   /* X Y Z, mm */
    double radius; /* mm; NaN: the nearest point */
    long points;   /* zone: points within radius; nearest: points seen */
    double sum;    /* zone: their deviations' sum */
    double best2;  /* nearest: squared distance of the nearest so far */
    double best;   /* nearest: its deviation */
} cf_check_t;

typedef struct cf_checks {
    cf_check_t *c;
    int n;
} cf_checks_t;

/* Read the checks of path into cs (zeroed first; cf_checks_free it).
 * CF_OK, CF_EIO, CF_EPARSE (file and line), CF_ENOMEM with msg. */
int cf_checks_read(cf_checks_t *cs, const char *path, char *msg, size_t ml);

/* Forget what cf_checks_add gathered (another pass over the points). */
void cf_checks_reset(cf_checks_t *cs);

/* One measured point Q and its signed normal deviation dev. */
void cf_checks_add(cf_checks_t *cs, const double Q[3], double dev);

/* Check i's deviation: NaN when it has no point (a zone with none inside). */
double cf_checks_value(const cf_checks_t *cs, int i);

/* Why check i has no value, into buf ("check NAME: no point within R mm
 * of (X, Y, Z): no value"); NULL when it has one. */
const char *cf_checks_missing(const cf_checks_t *cs, int i, char *buf, size_t n);

/* One warning line on f per check without a value (cf_checks_missing),
 * each naming who; the number of such checks. */
int cf_checks_warn(const cf_checks_t *cs, FILE *f, const char *who);

/* The array "checks" into j: name, x, y, z, radius (null: nearest point),
 * points (a zone's count; 1 for a nearest point), deviation (null: no
 * value). */
void cf_checks_json(const cf_checks_t *cs, cf_json_t *j);

void cf_checks_free(cf_checks_t *cs);

#endif

/* SPDX-License-Identifier: MIT */
/* cf_ptsout.c: per-point deviation files (cf_ptsout.h). */
#include "cf_ptsout.h"
#include "cf_err.h"
#include "cf_fmt.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define PLY_COUNT_DIGITS 15 /* room for any count, patched at close */

int cf_ptsout_open(cf_ptsout_t *o, const char *csv, const char *ply, double tol, int weights,
                   cf_ptsout_rgb_fn rgb, void *rgb_ctx, char *msg, size_t ml)
{
    memset(o, 0, sizeof *o);
    o->tol = tol;
    o->weights = weights;
    o->rgb = rgb;
    o->rgb_ctx = rgb_ctx;
    o->late_rgb = ply && !rgb;
    int rc;
    if (csv) {
        if ((rc = cf_atomic_open(&o->csv, csv, msg, ml)))
            return rc;
        o->has_csv = 1;
        fprintf(o->csv.f, "x,y,z,u,v,deviation,in_tolerance%s\n", weights ? ",weight" : "");
    }
    if (ply) {
        if ((rc = cf_atomic_open(&o->ply, ply, msg, ml))) {
            cf_ptsout_abort(o);
            return rc;
        }
        o->has_ply = 1;
        FILE *f = o->ply.f;
        fputs("ply\nformat binary_little_endian 1.0\n"
              "comment cellfit: measured points coloured by signed normal deviation (mm)\n"
              "element vertex ",
              f);
        o->count_at = ftell(f);
        fprintf(f, "%0*d\n", PLY_COUNT_DIGITS, 0);
        fputs("property double x\nproperty double y\nproperty double z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\n"
              "property double scalar_deviation\nend_header\n",
              f);
        o->data_at = ftell(f);
    }
    return CF_OK;
}

static void put_le64(FILE *f, double d)
{
    uint64_t b;
    memcpy(&b, &d, 8);
    unsigned char c[8];
    for (int i = 0; i < 8; i++)
        c[i] = (unsigned char)(b >> (8 * i));
    fwrite(c, 1, 8, f);
}

void cf_ptsout_add(cf_ptsout_t *o, const cf_ptsout_pt_t *p)
{
    o->n++;
    if (o->has_csv) {
        char b[7][40];
        const double v[6] = {p->x, p->y, p->z, p->u, p->v, p->dev};
        for (int i = 0; i < 6; i++)
            cf_fmt17(v[i], b[i], sizeof b[i]);
        fprintf(o->csv.f, "%s,%s,%s,%s,%s,%s,%d", b[0], b[1], b[2], b[3], b[4], b[5],
                fabs(p->dev) <= o->tol);
        if (o->weights) {
            cf_fmt17(p->weight, b[6], sizeof b[6]);
            fprintf(o->csv.f, ",%s", b[6]);
        }
        fputc('\n', o->csv.f);
    }
    if (o->has_ply) {
        unsigned char rgb[3] = {0, 0, 0}; /* late colours: patched at close */
        if (!o->late_rgb)
            o->rgb(p->dev, o->rgb_ctx, rgb);
        put_le64(o->ply.f, p->x);
        put_le64(o->ply.f, p->y);
        put_le64(o->ply.f, p->z);
        fwrite(rgb, 1, 3, o->ply.f);
        put_le64(o->ply.f, p->dev);
    }
}

void cf_ptsout_set_rgb(cf_ptsout_t *o, cf_ptsout_rgb_fn rgb, void *rgb_ctx)
{
    o->rgb = rgb;
    o->rgb_ctx = rgb_ctx;
}

static double get_le64(const unsigned char *c)
{
    uint64_t b = 0;
    for (int i = 0; i < 8; i++)
        b |= (uint64_t)c[i] << (8 * i);
    double d;
    memcpy(&d, &b, 8);
    return d;
}

/* The late colours: each vertex's from the deviation written in it, a block
 * at a time (relative seeks: a long offset may not reach 2 GB). 0 or -1. */
static int recolour(cf_ptsout_t *o)
{
    enum { REC = 35, DEV = 27, RGB = 24, BLOCK = 256 }; /* x y z, r g b, deviation */
    unsigned char buf[REC * BLOCK];
    FILE *f = o->ply.f;
    if (fflush(f) || fseek(f, o->data_at, SEEK_SET))
        return -1;
    for (long long left = o->n; left > 0;) {
        size_t k = left < BLOCK ? (size_t)left : BLOCK;
        if (fread(buf, REC, k, f) != k)
            return -1;
        for (size_t i = 0; i < k; i++)
            o->rgb(get_le64(buf + REC * i + DEV), o->rgb_ctx, buf + REC * i + RGB);
        if (fseek(f, -(long)(REC * k), SEEK_CUR) || fwrite(buf, REC, k, f) != k ||
            fseek(f, 0, SEEK_CUR)) /* a seek between a write and the next read */
            return -1;
        left -= (long long)k;
    }
    return 0;
}

int cf_ptsout_close(cf_ptsout_t *o, char *msg, size_t ml)
{
    int rc = CF_OK;
    if (o->has_ply) {
        FILE *f = o->ply.f;
        if (o->late_rgb && !o->rgb)
            rc = cf_fail(msg, ml, CF_EARG, "cf_ptsout_close: the PLY has no colour scale");
        else if (o->late_rgb && recolour(o))
            rc = cf_fail(msg, ml, CF_EIO, "%s: cannot write the colours", o->ply.path);
        else if (fseek(f, o->count_at, SEEK_SET) ||
                 fprintf(f, "%0*lld", PLY_COUNT_DIGITS, o->n) < 0)
            rc = cf_fail(msg, ml, CF_EIO, "%s: cannot patch the vertex count", o->ply.path);
        if (rc)
            cf_atomic_abort(&o->ply);
        else
            rc = cf_atomic_commit(&o->ply, 1, msg, ml);
        o->has_ply = 0;
    }
    if (o->has_csv) {
        if (rc)
            cf_atomic_abort(&o->csv);
        else
            rc = cf_atomic_commit(&o->csv, 1, msg, ml);
        o->has_csv = 0;
    }
    return rc;
}

void cf_ptsout_abort(cf_ptsout_t *o)
{
    if (o->has_csv)
        cf_atomic_abort(&o->csv);
    if (o->has_ply)
        cf_atomic_abort(&o->ply);
    o->has_csv = o->has_ply = 0;
}

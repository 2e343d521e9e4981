/* SPDX-License-Identifier: MIT */
/* sim_fault.c: faults on demand: KIND[@WIRE]:WHEN[:MS] specs, each with
 * its own event counter, firing at the K-th event, every K-th, or with a
 * seeded probability. */
#include "sim.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const names[SIM_F_NKINDS] = {"crc",        "garble",    "drop", "slow",
                                                "disconnect", "silent",    "busy", "nosurf",
                                                "proberr",    "stagefault"};

const char *sim_fault_name(sim_fkind_t k)
{
    return (unsigned)k < SIM_F_NKINDS ? names[k] : "?";
}

int sim_fault_class(sim_fkind_t k)
{
    if (k == SIM_F_NOSURF || k == SIM_F_PROBEERR)
        return 1;
    if (k == SIM_F_STAGEFAULT)
        return 2;
    return 0;
}

static int fail(char *msg, size_t len, const char *spec, const char *why)
{
    snprintf(msg, len, "--fault '%s': %s", spec, why);
    return -1;
}

int sim_fault_parse(const char *spec, sim_fault_t *f, char *msg, size_t len)
{
    memset(f, 0, sizeof *f);
    char buf[128];
    if (strlen(spec) >= sizeof buf)
        return fail(msg, len, spec, "too long");
    strcpy(buf, spec);
    char *when = strchr(buf, ':');
    if (!when)
        return fail(msg, len, spec, "want KIND[@WIRE]:WHEN[:MS]");
    *when++ = '\0';
    char *ms = strchr(when, ':');
    if (ms)
        *ms++ = '\0';
    char *wire = strchr(buf, '@');
    if (wire) {
        *wire++ = '\0';
        if (!strcmp(wire, "tcp"))
            f->wires = SIM_W_TCP;
        else if (!strcmp(wire, "rtu"))
            f->wires = SIM_W_RTU;
        else if (!strcmp(wire, "ascii"))
            f->wires = SIM_W_ASCII;
        else
            return fail(msg, len, spec, "wire not tcp, rtu or ascii");
    }
    int k;
    for (k = 0; k < SIM_F_NKINDS; k++)
        if (!strcmp(buf, names[k]))
            break;
    if (k == SIM_F_NKINDS)
        return fail(msg, len, spec,
                    "kind not crc, garble, drop, slow, disconnect, silent, busy, nosurf, proberr "
                    "or stagefault");
    f->kind = (sim_fkind_t)k;
    char *end;
    f->mode = when[0];
    if (f->mode == 'n' || f->mode == 'e') {
        f->k = strtol(when + 1, &end, 10);
        if (end == when + 1 || *end || f->k < 1)
            return fail(msg, len, spec, "WHEN: nK or eK with K >= 1");
    } else if (f->mode == 'p') {
        f->p = strtod(when + 1, &end);
        if (end == when + 1 || *end || !(f->p >= 0 && f->p <= 1))
            return fail(msg, len, spec, "WHEN: pP with 0 <= P <= 1");
    } else if (f->mode == 's') {
        f->k = strtol(when + 1, &end, 10);
        if (end == when + 1 || *end || f->k < 0 || f->k > 65535)
            return fail(msg, len, spec, "WHEN: sK with 0 <= K <= 65535");
        if (f->kind != SIM_F_CRC && f->kind != SIM_F_GARBLE && f->kind != SIM_F_DROP &&
            f->kind != SIM_F_SLOW && f->kind != SIM_F_SILENT)
            return fail(msg, len, spec, "sK (a stream entry): crc, garble, drop, slow or silent");
    } else
        return fail(msg, len, spec,
                    "WHEN not nK (K-th), eK (every K-th), pP (probability) or sK (the reply with "
                    "stream entry K)");
    int needs_ms = f->kind == SIM_F_SLOW || f->kind == SIM_F_DISCONNECT;
    if (needs_ms) {
        if (!ms)
            return fail(msg, len, spec, "slow and disconnect need :MS");
        f->ms = strtod(ms, &end);
        if (end == ms || *end || !(f->ms > 0 && f->ms < 3.6e6))
            return fail(msg, len, spec, "MS not a positive number of milliseconds");
    } else if (ms)
        return fail(msg, len, spec, "only slow and disconnect take :MS");
    return 0;
}

unsigned sim_faults_event(sim_faults_t *fs, int cls, int wire, double *ms)
{
    unsigned fired = 0;
    *ms = 0;
    for (int i = 0; i < fs->n; i++) {
        sim_fault_t *f = &fs->f[i];
        if (sim_fault_class(f->kind) != cls || (f->wires && wire && !(f->wires & wire)) ||
            f->mode == 's')
            continue;
        f->count++;
        int fire = f->mode == 'n'   ? f->count == f->k
                   : f->mode == 'e' ? f->count % f->k == 0
                                    : sim_urand(&fs->rng) < f->p;
        if (!fire)
            continue;
        fired |= 1u << f->kind;
        if (f->ms > *ms)
            *ms = f->ms;
        if (fs->verbose)
            fprintf(stderr, "cellsim: fault %s at event %ld\n", names[f->kind], f->count);
    }
    return fired;
}

unsigned sim_faults_stream(sim_faults_t *fs, int wire, uint16_t lo, int n, double *ms)
{
    unsigned fired = 0;
    *ms = 0;
    for (int i = 0; i < fs->n && n > 0; i++) {
        sim_fault_t *f = &fs->f[i];
        if (f->mode != 's' || (f->wires && wire && !(f->wires & wire)) ||
            (uint16_t)((uint16_t)f->k - lo) >= (unsigned)n)
            continue;
        f->count++;
        fired |= 1u << f->kind;
        if (f->ms > *ms)
            *ms = f->ms;
        if (fs->verbose)
            fprintf(stderr, "cellsim: fault %s at stream entry %ld\n", names[f->kind], f->k);
    }
    return fired;
}

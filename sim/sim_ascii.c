/* SPDX-License-Identifier: MIT */
/* sim_ascii.c: the ASCII protocol of the simulated laser probe, as common
 * laser displacement sensors speak it: "M0" -> "M0,+45.123" (mm),
 * out of range "M0,FFFFFFF", "RG" -> "RG,+30.000,+60.000" (measuring
 * range), errors "ER,<cmd>,nn"; every line ends in CR LF. Streaming
 * (docs/rig-devices.md): "TP,<us>" sets the trigger period, "MS" starts one
 * reading per trigger, each sent as "SQ,<n>,<mm>,<x um>,<y um>", and "MQ"
 * stops them, answered after the last by "MQ,<triggers>,<dropped>". */
#include "hal_regmap.h"
#include "sim.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Arm or stop the streaming FIFO as its Modbus registers would. */
static int stream_set(sim_probe_t *pr, double now, uint32_t period)
{
    uint16_t r[2] = {(uint16_t)(period >> 16), (uint16_t)(period & 0xFFFFu)};
    return sim_stream_write(pr, now, PRB_H_PERIOD, 2, r);
}

size_t sim_ascii_stream_lines(sim_probe_t *pr, double now, char *out, size_t cap)
{
    sim_stream_t *s = &pr->stream;
    size_t n = 0;
    if (!s->ascii)
        return 0;
    sim_stream_catch_up(pr, now);
    for (;;) {
        uint16_t r[2 + PRB_FIFO_ENTRY];
        char line[96];
        int len;
        if (cap - n < sizeof line)
            break;
        if (!s->count) {
            if (s->ascii == 2) { /* stopped and drained: the end line */
                len = snprintf(line, sizeof line, "MQ,%05u,%05u\r\n", (unsigned)(s->k & 0xFFFF),
                               (unsigned)s->overrun);
                memcpy(out + n, line, (size_t)len);
                n += (size_t)len;
                s->ascii = 0;
            }
            break;
        }
        sim_stream_read_fifo(pr, PRB_FIFO_COUNT, 2 + PRB_FIFO_ENTRY, r);
        const uint16_t *e = r + 2;
        int32_t v[3];
        for (int j = 0; j < 3; j++)
            v[j] = (int32_t)(((uint32_t)e[PRB_FE_DIST + 2 * j] << 16) | e[PRB_FE_DIST + 2 * j + 1]);
        char val[16];
        if (e[PRB_FE_STATUS] & PRB_ST_ERROR)
            snprintf(val, sizeof val, "ER01");
        else if (!(e[PRB_FE_STATUS] & PRB_ST_VALID))
            snprintf(val, sizeof val, "FFFFFFF");
        else
            snprintf(val, sizeof val, "%+07.3f", v[0] * 1e-3);
        len = snprintf(line, sizeof line, "SQ,%05u,%s,%+ld,%+ld\r\n", (unsigned)e[PRB_FE_SEQ], val,
                       (long)v[1], (long)v[2]);
        memcpy(out + n, line, (size_t)len);
        n += (size_t)len;
    }
    return n;
}

size_t sim_ascii_answer(sim_probe_t *pr, double now, const char *line, char *out, size_t cap)
{
    int n;
    if (!strcmp(line, "M0")) {
        double d = 0;
        int m = sim_probe_measure(pr, now, SIM_W_ASCII, &d);
        if (m == 2)
            n = snprintf(out, cap, "ER,M0,01\r\n"); /* sensor head not ready */
        else if (m == 1)
            n = snprintf(out, cap, "M0,FFFFFFF\r\n");
        else
            n = snprintf(out, cap, "M0,%+07.3f\r\n", d);
    } else if (!strncmp(line, "TP,", 3)) {
        char *end;
        unsigned long p = strtoul(line + 3, &end, 10);
        if (*end || end == line + 3 || p < PRB_MIN_PERIOD_US || p > PRB_MAX_PERIOD_US)
            n = snprintf(out, cap, "ER,TP,02\r\n"); /* value out of range */
        else {
            pr->stream.ascii_period = (uint32_t)p;
            n = snprintf(out, cap, "TP,%07lu\r\n", p);
        }
    } else if (!strcmp(line, "MS")) {
        uint32_t p = pr->stream.ascii_period ? pr->stream.ascii_period : 100;
        if (pr->stream.ascii || stream_set(pr, now, p))
            n = snprintf(out, cap, "ER,MS,03\r\n"); /* already streaming, or no memory */
        else {
            pr->stream.ascii = 1;
            pr->stream.ascii_new = 1;
            n = snprintf(out, cap, "MS\r\n");
        }
    } else if (!strcmp(line, "MQ")) {
        if (pr->stream.ascii == 1) {
            sim_stream_catch_up(pr, now);
            stream_set(pr, now, 0);
            pr->stream.ascii = 2; /* the end line follows the queue */
            n = 0;
        } else
            n = snprintf(out, cap, "ER,MQ,03\r\n"); /* not streaming */
    } else if (!strcmp(line, "RG"))
        n = snprintf(out, cap, "RG,%+07.3f,%+07.3f\r\n", pr->lo, pr->hi);
    else if (!strcmp(line, "ID"))
        n = snprintf(out, cap, "ID,CELLSIM-LDS,1\r\n");
    else {
        char cmd[3] = {line[0] ? line[0] : '?', line[0] && line[1] ? line[1] : '?', 0};
        n = snprintf(out, cap, "ER,%s,00\r\n", cmd); /* unknown command */
    }
    return n < 0 ? 0 : (size_t)n < cap ? (size_t)n : cap - 1;
}

/* SPDX-License-Identifier: MIT */
/* hal_uri.c: strict parsing of device URIs (rtu:, tcp:, serial:, tty:, usb:, gev:)
 * into hal_uri_t; every refusal gives a one-line reason naming the field. */
#include "hal.h"
#include <arpa/inet.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define URI_MAX_FIELDS 8

static int bad(char *msg, size_t len, const char *uri, const char *why, const char *field)
{
    if (msg && len)
        snprintf(msg, len, "device URI '%s': %s%s%s%s", uri, why, field ? " '" : "",
                 field ? field : "", field ? "'" : "");
    return RIG_EARG;
}

/* A decimal integer in [lo, hi], the whole field, no sign or spaces. */
static int dec(const char *f, long lo, long hi, long *out)
{
    if (!*f || strlen(f) > 9)
        return -1;
    for (const char *c = f; *c; c++)
        if (*c < '0' || *c > '9')
            return -1;
    long v = strtol(f, NULL, 10);
    if (v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

/* Exactly four hexadecimal digits (USB vendor and product ids). */
static int hex4(const char *f, uint16_t *out)
{
    if (strlen(f) != 4)
        return -1;
    unsigned v = 0;
    for (const char *c = f; *c; c++) {
        int d = (*c >= '0' && *c <= '9')   ? *c - '0'
                : (*c >= 'a' && *c <= 'f') ? *c - 'a' + 10
                : (*c >= 'A' && *c <= 'F') ? *c - 'A' + 10
                                           : -1;
        if (d < 0)
            return -1;
        v = v * 16 + (unsigned)d;
    }
    *out = (uint16_t)v;
    return 0;
}

/* The rates termios and libmodbus know by name; anything else is a typo. */
static int std_baud(long b)
{
    static const long rates[] = {300,    600,     1200,    2400,    4800,    9600,    19200,
                                 38400,  57600,   115200,  230400,  460800,  500000,  576000,
                                 921600, 1000000, 1152000, 1500000, 2000000, 3000000, 4000000};
    for (size_t i = 0; i < sizeof rates / sizeof rates[0]; i++)
        if (rates[i] == b)
            return 1;
    return 0;
}

/* "8N1": data bits 7 or 8, parity N/E/O, stop bits 1 or 2. */
static int frame(const char *f, hal_uri_t *u)
{
    if (strlen(f) != 3 || (f[0] != '7' && f[0] != '8') || !strchr("NEO", f[1]) ||
        (f[2] != '1' && f[2] != '2'))
        return -1;
    u->data_bits = f[0] - '0';
    u->parity = f[1];
    u->stop_bits = f[2] - '0';
    return 0;
}

/* A path or host: non-empty, printable, no spaces. */
static int word(const char *f)
{
    if (!*f)
        return -1;
    for (const char *c = f; *c; c++)
        if (*c <= ' ' || *c > '~')
            return -1;
    return 0;
}

int hal_uri_parse(const char *s, hal_uri_t *u, char *msg, size_t msglen)
{
    if (!s || !u)
        return bad(msg, msglen, s ? s : "(null)", "null argument", NULL);
    memset(u, 0, sizeof *u);
    char buf[512];
    if (strlen(s) >= sizeof buf)
        return bad(msg, msglen, "...", "longer than 511 characters", NULL);
    strcpy(buf, s);
    char *fld[URI_MAX_FIELDS];
    int nf = 0;
    for (char *p = buf;;) {
        if (nf == URI_MAX_FIELDS)
            return bad(msg, msglen, s, "too many ':' fields", NULL);
        fld[nf++] = p;
        char *c = strchr(p, ':');
        if (!c)
            break;
        *c = '\0';
        p = c + 1;
    }
    const char *k = fld[0];
    long v;
    u->data_bits = 8;
    u->parity = 'N';
    u->stop_bits = 1;
    if (!strcmp(k, "rtu") || !strcmp(k, "serial") || !strcmp(k, "tty")) {
        int rtu = !strcmp(k, "rtu");
        u->kind = rtu ? HAL_RTU : !strcmp(k, "serial") ? HAL_SERIAL : HAL_TTY;
        if (rtu && nf != 5)
            return bad(msg, msglen, s, "want rtu:PATH:BAUD:8N1:SLAVE", NULL);
        if (!rtu && nf != 3 && nf != 4)
            return bad(msg, msglen, s,
                       u->kind == HAL_TTY ? "want tty:PATH:BAUD[:8N1]"
                                          : "want serial:PATH:BAUD[:8N1]",
                       NULL);
        if (word(fld[1]) || strlen(fld[1]) >= sizeof u->path)
            return bad(msg, msglen, s, "bad device path", fld[1]);
        strcpy(u->path, fld[1]);
        if (dec(fld[2], 1, 4000000, &v) || !std_baud(v))
            return bad(msg, msglen, s, "baud rate not a standard rate (300..4000000)", fld[2]);
        u->baud = (int)v;
        if (nf >= 4 && frame(fld[3], u))
            return bad(msg, msglen, s, "frame not data bits 7|8, parity N|E|O, stop 1|2", fld[3]);
        if (rtu) {
            if (dec(fld[4], 1, 247, &v))
                return bad(msg, msglen, s, "slave address not 1..247", fld[4]);
            u->unit = (int)v;
        }
        return RIG_OK;
    }
    if (!strcmp(k, "tcp")) {
        u->kind = HAL_TCP;
        if (nf != 3 && nf != 4)
            return bad(msg, msglen, s, "want tcp:HOST:PORT[:UNIT]", NULL);
        if (word(fld[1]) || strlen(fld[1]) >= sizeof u->path)
            return bad(msg, msglen, s, "bad host", fld[1]);
        strcpy(u->path, fld[1]);
        if (dec(fld[2], 1, 65535, &v))
            return bad(msg, msglen, s, "port not 1..65535", fld[2]);
        u->port = (int)v;
        u->unit = 1;
        if (nf == 4) {
            if (dec(fld[3], 0, 255, &v))
                return bad(msg, msglen, s, "unit id not 0..255", fld[3]);
            u->unit = (int)v;
        }
        return RIG_OK;
    }
    if (!strcmp(k, "usb")) {
        u->kind = HAL_USB;
        if (nf != 3 && nf != 4)
            return bad(msg, msglen, s, "want usb:VID:PID[:SERIAL]", NULL);
        if (hex4(fld[1], &u->vid))
            return bad(msg, msglen, s, "vendor id not 4 hex digits", fld[1]);
        if (hex4(fld[2], &u->pid))
            return bad(msg, msglen, s, "product id not 4 hex digits", fld[2]);
        if (nf == 4) {
            if (word(fld[3]) || strlen(fld[3]) >= sizeof u->serial)
                return bad(msg, msglen, s, "bad serial number", fld[3]);
            strcpy(u->serial, fld[3]);
        }
        return RIG_OK;
    }
    if (!strcmp(k, "gev")) {
        /* GigE Vision: opened by address (no discovery: loopback has no
         * broadcast), so a dotted IPv4 address, never a name. */
        u->kind = HAL_GEV;
        struct in_addr a;
        if (nf != 2 && nf != 3)
            return bad(msg, msglen, s, "want gev:ADDRESS[:SERIAL]", NULL);
        if (strlen(fld[1]) >= sizeof u->path || inet_pton(AF_INET, fld[1], &a) != 1)
            return bad(msg, msglen, s, "address not a dotted IPv4 address", fld[1]);
        strcpy(u->path, fld[1]);
        if (nf == 3) {
            if (word(fld[2]) || strlen(fld[2]) >= sizeof u->serial)
                return bad(msg, msglen, s, "bad serial number", fld[2]);
            strcpy(u->serial, fld[2]);
        }
        return RIG_OK;
    }
    return bad(msg, msglen, s, "unknown scheme (rtu, tcp, serial, tty, usb, gev)", k);
}

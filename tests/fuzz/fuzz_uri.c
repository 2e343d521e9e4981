/* SPDX-License-Identifier: MIT */
/* fuzz_uri.c: libFuzzer target for device URIs (hal_uri.c): the input as
 * a string. An accepted URI has its fields in range; a refusal is one line
 * naming the URI. */
#include "fuzz.h"
#include "hal.h"
#include <arpa/inet.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char s[1024], msg[1200];
    size_t n = size < sizeof s - 1 ? size : sizeof s - 1;
    memcpy(s, data, n);
    s[n] = '\0';
    hal_uri_t u;
    if (hal_uri_parse(s, &u, msg, sizeof msg)) {
        if (!strchr(s, '\n')) /* the message quotes the URI */
            fz_one_line(msg);
        return 0;
    }
    int ok = 1;
    switch (u.kind) {
    case HAL_RTU: ok = u.unit >= 1 && u.unit <= 247 && u.baud > 0; break;
    case HAL_SERIAL:
    case HAL_TTY: ok = u.baud > 0 && (u.data_bits == 7 || u.data_bits == 8); break;
    case HAL_TCP: ok = u.port >= 1 && u.port <= 65535 && u.unit >= 0 && u.unit <= 255; break;
    case HAL_USB: ok = 1; break;
    case HAL_GEV: { /* a profiler: a dotted IPv4 address, never a name */
        struct in_addr a;
        ok = inet_pton(AF_INET, u.path, &a) == 1;
        break;
    }
    default: ok = 0;
    }
    if (!ok || !u.path[0] == (u.kind != HAL_USB) || strchr(u.path, ':'))
        abort();
    return 0;
}

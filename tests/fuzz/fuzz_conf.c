/* SPDX-License-Identifier: MIT */
/* fuzz_conf.c: libFuzzer target for the cell's configuration file
 * (cf_conf.c) and the settings `cellfit serve` takes from it
 * (cmd_serve.c, run with --print-map so it never starts serving). Keys
 * and values reach the callback trimmed, one line each; a refusal is one
 * line naming the file. */
#include "cf_cli.h"
#include "cf_conf.h"
#include "cmd.h"
#include "fuzz.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    if (!freopen("/dev/null", "w", stdout)) /* the printed map */
        abort();
    return 0;
}

static int pair(void *ctx, const char *k, const char *v, char *msg, size_t ml)
{
    (void)ctx;
    size_t nk = strlen(k), nv = strlen(v);
    if (!nk || strchr(k, '=') || strchr(k, '\n') || strchr(v, '\n') || k[0] == ' ' ||
        k[nk - 1] == ' ' || (nv && (v[0] == ' ' || v[nv - 1] == ' ')))
        abort();
    if (!strcmp(k, "stop")) { /* a callback's refusal */
        snprintf(msg, ml, "stop here");
        return -2;
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fz_file("serve.conf", data, size);
    char msg[1024];
    if (cf_conf_read(path, pair, NULL, msg, sizeof msg)) {
        fz_one_line(msg);
        fz_names(msg, path);
    }
    char *argv[] = {"serve", "--config", (char *)path, "--print-map", NULL};
    int rc = cmd_serve(4, argv);
    if (rc != 0 && rc != 2)
        abort();
    return 0;
}

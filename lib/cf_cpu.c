/* SPDX-License-Identifier: MIT */
/* cf_cpu.c: CELLFIT_CPU picks the hot kernels' path (cf_cpu.h). */
#include "cf_cpu.h"
#include "cf_err.h"
#include "nf_isa.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cf_cpu_apply(const char *value, char *msg, size_t len)
{
    nf_isa_t isa;
    if (!value || !*value || !strcmp(value, "auto"))
        isa = NF_ISA_AUTO;
    else if (!strcmp(value, "baseline"))
        isa = NF_ISA_BASE;
    else if (!strcmp(value, "x86-64-v3") || !strcmp(value, "v3"))
        isa = NF_ISA_V3;
    else
        return cf_fail(msg, len, CF_EARG, "unknown path (baseline, x86-64-v3 or auto)");
    if (nf_isa_select(isa) != 0)
        return cf_fail(msg, len, CF_EARG, "this CPU (or build) lacks AVX2/FMA; baseline runs");
    return CF_OK;
}

int cf_cpu_from_env(void)
{
    const char *v = getenv("CELLFIT_CPU");
    char msg[160];
    int rc = cf_cpu_apply(v, msg, sizeof msg);
    if (rc)
        fprintf(stderr, "cellfit: CELLFIT_CPU=%s: %s\n", v, msg);
    return rc;
}

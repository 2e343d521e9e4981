/* SPDX-License-Identifier: MIT */
/* nf_chol_v3.c: nf_chol.c compiled again for x86-64-v3 (AVX2, FMA; flags from
 * mk/arch.mk), its entry point named nf_chol_solve_v3 and chosen at run time
 * (nf_isa.h). Without dispatch this file is empty. */
#include "nf_isa.h"

#if NF_ISA_DISPATCH
#define NF_ISA_V3_PASS 1
#include "nf_chol.c"
#else
typedef int nf_chol_v3_unused_t; /* ISO C: no empty translation unit */
#endif

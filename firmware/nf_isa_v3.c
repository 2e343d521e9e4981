/* SPDX-License-Identifier: MIT */
/* nf_isa_v3.c: the v3 copy's own probe (nf_isa.h), compiled with the v3
 * copy's flags (mk/arch.mk: -mavx2 -mfma and the board's -ffp-contract). */
#include "nf_isa_pass.h"

#if NF_ISA_DISPATCH
#if !defined(__AVX2__) || !defined(__FMA__)
#error "nf_isa_v3.c needs -mavx2 -mfma (mk/arch.mk)"
#endif
double nf_isa_v3_fma_probe(double a, double b, double c)
{
    return a * b + c; /* one fused multiply-add where the compiler contracts */
}
#else
typedef int nf_isa_v3_unused_t; /* ISO C: no empty translation unit */
#endif

/* SPDX-License-Identifier: MIT */
/* nf_isa.h: run-time choice of the instruction set of the hot kernels.
 * The default x86-64 build runs on every x86-64 CPU (baseline: SSE2). The
 * modules whose loops dominate a fit (nf_accum.c, nf_fit.c's point paths,
 * nf_pcg.c, nf_quad.c, nf_stripe.c, nf_surf.c) are compiled a second time for
 * x86-64-v3's vector part, AVX2 and FMA (nf_*_v3.c), and every hot entry
 * point forwards to one of the two copies: the v3 copy when the CPU and the
 * OS support AVX2 and FMA, chosen once (nf_isa_active), unless a caller
 * chose (nf_isa_select: tests, CELLFIT_CPU). Inside one copy the modules
 * call each other directly, so a fit runs wholly on the path chosen.
 *
 * NF_ISA_DISPATCH is 1 only where the build says so (mk/arch.mk: native
 * x86-64 builds, which also compile nf_*_v3.c with -mavx2 -mfma); cross
 * boards, other CPUs and builds that do not know about it get one plain
 * copy, no renaming, no CPU test. Firmware memory and freestanding rules
 * are unchanged: no heap, no libc beyond the compiler's CPU test. */
#ifndef NF_ISA_H
#define NF_ISA_H

#ifndef NF_ISA_DISPATCH
#define NF_ISA_DISPATCH 0
#endif
#if NF_ISA_DISPATCH && !(defined(__x86_64__) && defined(__GNUC__))
#error "NF_ISA_DISPATCH needs an x86-64 GCC or clang"
#endif

typedef enum nf_isa {
    NF_ISA_AUTO = -1, /* the best path this CPU runs */
    NF_ISA_BASE = 0,  /* baseline x86-64 (or the only path without dispatch) */
    NF_ISA_V3 = 1     /* x86-64-v3's AVX2 and FMA */
} nf_isa_t;

/* 1 when this build has the v3 copy and this CPU (and OS) runs it. */
int nf_isa_has_v3(void);

/* The path the hot entry points take now; the first call settles AUTO. */
nf_isa_t nf_isa_active(void);

/* Take path isa from now on (NF_ISA_AUTO: the best one). NF_EARG when this
 * build or CPU lacks it (the path stays as it was). Call it before fits
 * start, not while one runs on another thread. */
int nf_isa_select(nf_isa_t isa);

/* "baseline", "x86-64-v3" or "auto". */
const char *nf_isa_name(nf_isa_t isa);

/* Tests: a * b + c as the v3 copy computes it (0.0 without one). Shows
 * whether that copy's compiler fused multiply-adds (-ffp-contract), the
 * one thing that lets the two paths round differently. */
double nf_isa_v3_fma_probe(double a, double b, double c);

#endif

/* SPDX-License-Identifier: MIT */
/* cf_cpu.h: CELLFIT_CPU, the environment's say on the hot kernels' path
 * (firmware/nf_isa.h): "baseline" (any x86-64 CPU), "x86-64-v3" (AVX2 and
 * FMA; refused on a CPU without them) or "auto"/unset (the best the CPU
 * runs). For A/B measurements and for ruling the fast path out on a cell
 * controller; results agree to rounding either way. */
#ifndef CF_CPU_H
#define CF_CPU_H

#include <stddef.h>

/* Apply value (NULL or "" leaves the choice automatic). CF_OK, or CF_EARG
 * with a one-line reason in msg (the path stays automatic). */
int cf_cpu_apply(const char *value, char *msg, size_t len);

/* cf_cpu_apply(getenv("CELLFIT_CPU")), a refusal printed to stderr as
 * "cellfit: CELLFIT_CPU=...: reason". Called first in cellfit's and
 * cellsim's main() (a constructor would be dropped from a static archive). */
int cf_cpu_from_env(void);

#endif

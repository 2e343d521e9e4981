/* SPDX-License-Identifier: MIT */
/* nf_config.h: compile-time configuration of the fitter. The board header
 * (boards/<board>/board_config.h, found on the include path) comes first;
 * this file fills what it leaves out and proves the budget is coherent. */
#ifndef NF_CONFIG_H
#define NF_CONFIG_H

#include "board_config.h"

#ifndef BOARD_NAME
#define BOARD_NAME "unnamed"
#endif
#ifndef NF_MAX_DEGREE
#define NF_MAX_DEGREE 5
#endif
#ifndef NF_MAX_CP
#define NF_MAX_CP 10000L
#endif
#ifndef NF_DESIGN_DEGREE
#define NF_DESIGN_DEGREE 3
#endif
#ifndef NF_ARENA_BYTES
#define NF_ARENA_BYTES (8L * 1024L * 1024L)
#endif

#if NF_MAX_DEGREE < 1 || NF_MAX_DEGREE > 9
#error "NF_MAX_DEGREE must be within 1..9"
#endif
#if NF_DESIGN_DEGREE > NF_MAX_DEGREE
#error "NF_DESIGN_DEGREE above NF_MAX_DEGREE"
#endif

/* Non-zero basis functions per direction and per point at the maximum degree. */
#define NF_MAX_ORDER (NF_MAX_DEGREE + 1)
#define NF_MAX_LOCAL (NF_MAX_ORDER * NF_MAX_ORDER)

#endif

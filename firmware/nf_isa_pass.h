/* SPDX-License-Identifier: MIT */
/* nf_isa_pass.h: included first by each module that has a v3 copy (see
 * nf_isa.h). With dispatch, it renames the hot entry points of all those
 * modules for this pass: name_base in nf_X.c, name_v3 in nf_X_v3.c (which
 * defines NF_ISA_V3_PASS and includes nf_X.c), so calls between the modules
 * stay on one path; nf_isa.c defines the plain names, which forward. The
 * list here and NF_ISA_LIST in nf_isa.c name the same functions (a name
 * missing from either fails to link). NF_ISA_COLD is 1 in the pass that
 * compiles a module's other functions (once, under their own names): a new
 * external function of these modules goes into both lists (hot) or inside
 * #if NF_ISA_COLD (cold); elsewhere it is defined twice and the link fails. */
#ifndef NF_ISA_PASS_H
#define NF_ISA_PASS_H

#include "nf_isa.h"

#if NF_ISA_DISPATCH
#ifdef NF_ISA_V3_PASS
#if !defined(__AVX2__) || !defined(__FMA__)
#error "the v3 copy needs -mavx2 -mfma (mk/arch.mk)"
#endif
#define NF_ISA_SFX(f) f##_v3
#define NF_ISA_COLD 0
#else
#define NF_ISA_SFX(f) f##_base
#define NF_ISA_COLD 1
#endif
/* nf_accum.c */
#define nf_accum_point NF_ISA_SFX(nf_accum_point)
#define nf_accum_point_at NF_ISA_SFX(nf_accum_point_at)
#define nf_accum_lone33 NF_ISA_SFX(nf_accum_lone33)
#define nf_accum_rows33 NF_ISA_SFX(nf_accum_rows33)
#define nf_accum_flush NF_ISA_SFX(nf_accum_flush)
/* nf_chol.c */
#define nf_chol_solve NF_ISA_SFX(nf_chol_solve)
/* nf_fit.c */
#define nf_fit_add NF_ISA_SFX(nf_fit_add)
#define nf_fit_add_rows NF_ISA_SFX(nf_fit_add_rows)
#define nf_fit_shard_merge NF_ISA_SFX(nf_fit_shard_merge)
#define nf_fit_finish NF_ISA_SFX(nf_fit_finish)
#define nf_fit_solve NF_ISA_SFX(nf_fit_solve)
/* nf_pcg.c */
#define nf_pcg_solve NF_ISA_SFX(nf_pcg_solve)
#define nf_pcg_apply NF_ISA_SFX(nf_pcg_apply)
/* nf_stripe.c */
#define nf_stripe_add_outer NF_ISA_SFX(nf_stripe_add_outer)
#define nf_stripe_matvec NF_ISA_SFX(nf_stripe_matvec)
/* nf_quad.c */
#define nf_quad_init NF_ISA_SFX(nf_quad_init)
#define nf_quad_start NF_ISA_SFX(nf_quad_start)
#define nf_quad_newton NF_ISA_SFX(nf_quad_newton)
#define nf_quad_project NF_ISA_SFX(nf_quad_project)
/* nf_surf.c */
#define nf_surf_eval NF_ISA_SFX(nf_surf_eval)
#define nf_surf_rbasis NF_ISA_SFX(nf_surf_rbasis)
#define nf_surf_derivs NF_ISA_SFX(nf_surf_derivs)
#else
#define NF_ISA_COLD 1
#endif

#endif

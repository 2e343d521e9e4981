/* SPDX-License-Identifier: MIT */
/* nf_err.c: one string for each fitter error code. */
#include "nf_err.h"

const char *nf_strerror(int err)
{
    switch (err) {
    case NF_OK: return "success";
    case NF_EARG: return "invalid argument (caller bug)";
    case NF_EBUDGET: return "job exceeds the board's memory budget";
    case NF_EARENA: return "arena too small for the job";
    case NF_EDEGREE: return "degree out of range for this board";
    case NF_EKNOTS: return "invalid knot vector";
    case NF_EWEIGHT: return "weights must be finite and positive";
    case NF_EDOMAIN: return "parameter outside the knot domain";
    case NF_ENONFINITE: return "non-finite coordinate";
    case NF_ENODATA: return "control point has no data under it and alpha = beta = 0";
    case NF_ESINGULAR: return "normal equations are numerically rank deficient";
    case NF_ENOCONV: return "iterative solver did not converge";
    case NF_ESOLVER: return "solver not available for this job";
    case NF_ESTATE: return "call out of order";
    case NF_ESIZE: return "control net size invalid for the degree";
    default: return "unknown error";
    }
}

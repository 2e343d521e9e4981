/* SPDX-License-Identifier: MIT */
/* plc_err.c: one string per PLC error code. */
#include "plc_err.h"

const char *plc_strerror(int code)
{
    switch ((plc_err_t)code) {
    case PLC_E_NONE: return "no error";
    case PLC_E_UNKNOWN_CMD: return "unknown command code";
    case PLC_E_BUSY: return "busy: a job is running (only abort is accepted)";
    case PLC_E_IN_ERROR: return "cell in error: reset first";
    case PLC_E_RESULTS_LATCHED: return "results not acknowledged: acknowledge them first";
    case PLC_E_NO_RESULTS: return "no valid results to export or acknowledge";
    case PLC_E_NO_RIG: return "rig not configured (no stage and probe)";
    case PLC_E_NOT_HOMED: return "stage not homed: home first";
    case PLC_E_BAD_PARAM: return "job parameter not usable by this job";
    case PLC_E_NO_ERROR: return "no error to reset";
    case PLC_E_TOO_BIG: return "control net exceeds the board's budget";
    case PLC_E_NO_JOB_FILES: return "fit not configured (nominal and points files)";
    case PLC_E_SEQ_ZERO: return "sequence 0 is not a command: count from 1";
    case PLC_E_SEQ_REUSED: return "sequence already used by another command: take a new one";
    case PLC_E_NO_RECIPE: return "recipe not configured (no such nominal)";
    case PLC_E_WATCHDOG: return "watchdog: PLC heartbeat stopped";
    case PLC_E_RIG_LINK: return "rig line failed (stage or probe not answering)";
    case PLC_E_RIG_GONE: return "rig process ended";
    case PLC_E_NOMINAL: return "cannot read the nominal surface";
    case PLC_E_POINTS: return "cannot read the measured points";
    case PLC_E_NO_POINTS: return "no points";
    case PLC_E_FIT: return "fit failed";
    case PLC_E_EXPORT: return "cannot write the results folder";
    case PLC_E_MEMORY: return "out of memory";
    case PLC_E_STAGE: return "stage fault";
    case PLC_E_PROBE: return "probe fault";
    case PLC_E_RIG: return "rig failure";
    case PLC_E_INTERNAL: return "internal error";
    case PLC_E_ESTOP: return "emergency stop";
    }
    return "unknown error code";
}

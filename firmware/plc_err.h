/* SPDX-License-Identifier: MIT */
/* plc_err.h: the error codes the cell shows a PLC (register ERROR_CODE and
 * CMD_RESULT), in ranges as on industrial vision sensors: 1xx a command
 * refused (the cell's state is unchanged), 2xx communication, 3xx the
 * measurement or fitting job. They are register values, so positive; 0 is
 * "no error". One string each (plc_strerror); docs/plc-register-map.md
 * gives causes and remedies. */
#ifndef PLC_ERR_H
#define PLC_ERR_H

typedef enum plc_err {
    PLC_E_NONE = 0,
    /* 1xx: command refused; nothing was started or changed */
    PLC_E_UNKNOWN_CMD = 101,     /* command code not defined */
    PLC_E_BUSY = 102,            /* a job is running: only ABORT is accepted */
    PLC_E_IN_ERROR = 103,        /* cell in ERROR: RESET first */
    PLC_E_RESULTS_LATCHED = 104, /* previous results not acknowledged */
    PLC_E_NO_RESULTS = 105,      /* export / acknowledge without valid results */
    PLC_E_NO_RIG = 106,          /* home / scan without a stage and probe configured */
    PLC_E_NOT_HOMED = 107,       /* scan before home */
    PLC_E_BAD_PARAM = 108,       /* a job parameter the job cannot use */
    PLC_E_NO_ERROR = 109,        /* reset with no error to reset */
    PLC_E_TOO_BIG = 110,         /* control net beyond the board's budget */
    PLC_E_NO_JOB_FILES = 111,    /* fit: no nominal / points configured */
    PLC_E_SEQ_ZERO = 112,        /* sequence 0: never a command */
    PLC_E_SEQ_REUSED = 113,      /* the sequence of the last command with another code */
    PLC_E_NO_RECIPE = 114,       /* RECIPE names no configured nominal */
    /* 2xx: communication */
    PLC_E_WATCHDOG = 201, /* PLC heartbeat unchanged for WATCHDOG_MS */
    PLC_E_RIG_LINK = 202, /* the line to the stage or probe failed (timeout, lost) */
    PLC_E_RIG_GONE = 203, /* the rig's process (the simulator) ended */
    /* 3xx: measurement and job */
    PLC_E_NOMINAL = 301,   /* cannot read the nominal surface */
    PLC_E_POINTS = 302,    /* cannot read the points */
    PLC_E_NO_POINTS = 303, /* no points measured / in the file */
    PLC_E_FIT = 304,       /* the fit failed (singular, no convergence) */
    PLC_E_EXPORT = 305,    /* cannot write the results folder */
    PLC_E_MEMORY = 306,    /* out of memory */
    PLC_E_STAGE = 307,     /* stage fault, limit or emergency stop */
    PLC_E_PROBE = 308,     /* probe or its line failed */
    PLC_E_RIG = 309,       /* other rig failure (journal, storage) */
    PLC_E_INTERNAL = 310,  /* a bug: please report */
    PLC_E_ESTOP = 311      /* emergency stop pressed during the job */
} plc_err_t;

/* A static string for every value above; "unknown error code" otherwise. */
const char *plc_strerror(int code);

#endif

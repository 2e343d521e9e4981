/* SPDX-License-Identifier: MIT */
/* rig_err.h: error codes of the rig interfaces (rig.h) and of the scan and
 * journal that use them; 0 is success, negatives errors, disjoint from
 * nf_err_t (-1..-99) and cf_err_t (-101..). One string each (rig_strerror).
 * Device and line faults come first, storage next, job control last. */
#ifndef RIG_ERR_H
#define RIG_ERR_H

typedef enum rig_err {
    RIG_OK = 0,
    RIG_EARG = -201,         /* caller bug: null pointer, bad value */
    RIG_ETIMEOUT = -202,     /* device did not answer in time */
    RIG_ECRC = -203,         /* frame failed its checksum */
    RIG_EPROTO = -204,       /* reply malformed or not the one asked for */
    RIG_EEXCEPTION = -205,   /* device refused the request (Modbus exception) */
    RIG_EDISCONNECT = -206,  /* line or connection lost (reconnect was tried) */
    RIG_EOPEN = -207,        /* cannot open the device or address */
    RIG_ENOSURF = -208,      /* probe: no surface within the measuring range */
    RIG_EFAULT = -209,       /* stage: drive fault latched */
    RIG_EESTOP = -210,       /* stage: emergency stop active */
    RIG_ELIMIT = -211,       /* stage: target outside the soft limits */
    RIG_ENOTHOMED = -212,    /* stage: move asked before homing */
    RIG_EUNSUPPORTED = -213, /* backend or operation not in this build */
    RIG_EIO = -214,          /* storage read or write failed */
    RIG_EFULL = -215,        /* storage full */
    RIG_ECORRUPT = -216,     /* journal record damaged before its tail */
    RIG_EABORTED = -217,     /* job stopped on request (abort, watchdog) */
    RIG_ESTATE = -218,       /* call out of order */
    RIG_ELOST = -219 /* the rig is gone for good (its process ended): a job stopped for it */
} rig_err_t;

/* A static string for every value above; "unknown error" otherwise. */
const char *rig_strerror(int err);

#endif

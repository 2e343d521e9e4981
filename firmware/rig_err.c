/* SPDX-License-Identifier: MIT */
/* rig_err.c: one string for each rig error code. */
#include "rig_err.h"

const char *rig_strerror(int err)
{
    switch (err) {
    case RIG_OK: return "success";
    case RIG_EARG: return "invalid argument (caller bug)";
    case RIG_ETIMEOUT: return "device did not answer in time";
    case RIG_ECRC: return "frame failed its checksum";
    case RIG_EPROTO: return "malformed or unexpected reply";
    case RIG_EEXCEPTION: return "device refused the request";
    case RIG_EDISCONNECT: return "line or connection lost";
    case RIG_EOPEN: return "cannot open the device";
    case RIG_ENOSURF: return "probe sees no surface within its range";
    case RIG_EFAULT: return "stage drive fault";
    case RIG_EESTOP: return "emergency stop active";
    case RIG_ELIMIT: return "target outside the soft limits";
    case RIG_ENOTHOMED: return "stage not homed";
    case RIG_EUNSUPPORTED: return "not supported by this build or device";
    case RIG_EIO: return "storage input/output error";
    case RIG_EFULL: return "storage full";
    case RIG_ECORRUPT: return "journal record damaged";
    case RIG_EABORTED: return "job stopped on request";
    case RIG_ESTATE: return "call out of order";
    case RIG_ELOST: return "rig lost (its process ended)";
    default: return "unknown error";
    }
}

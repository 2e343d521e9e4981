/* SPDX-License-Identifier: MIT */
/* cf_version.c: version strings (cf_version.h); the build writes cf_rev.h. */
#include "cf_version.h"
#include "cf_rev.h"

const char *cf_version(void)
{
    return CF_VERSION;
}

const char *cf_revision(void)
{
    return CF_REV;
}

const char *cf_version_string(void)
{
    return "cellfit " CF_VERSION " (" CF_REV ")";
}

/* SPDX-License-Identifier: MIT */
/* cf_version.h: the release and the git revision this build came from, for
 * `--version`, IGES headers, report.json and the journal header. */
#ifndef CF_VERSION_H
#define CF_VERSION_H

const char *cf_version(void);  /* "0.13.0" */
const char *cf_revision(void); /* git describe of the build, or "unknown" */
/* "cellfit 0.13.0 (abc123def456)" */
const char *cf_version_string(void);

#endif

/* SPDX-License-Identifier: MIT */
/* cf_store_file.h: the journal's storage (rig_store_t) on a file of the
 * cell controller: appends with O_APPEND, sync is fsync, reads are pread,
 * truncate is ftruncate. A full disk (ENOSPC, EDQUOT, EFBIG) is RIG_EFULL,
 * other failures RIG_EIO with the errno text in the store's err. */
#ifndef CF_STORE_FILE_H
#define CF_STORE_FILE_H

#include "rig.h"
#include <stddef.h>

enum {
    CF_STORE_READ = 0,  /* existing file, read only */
    CF_STORE_WRITE = 1, /* existing file, read and append (recovery) */
    CF_STORE_CREATE = 2 /* new file; fails if it exists (never overwrite a journal) */
};

typedef struct cf_store_file {
    int fd;
    int mode;
    char err[256]; /* detail of the last failure */
    /* Appends gathered (cf_store_file_buffer): written when full and before
     * every sync, read, size and close. */
    unsigned char *wbuf;
    size_t wlen, wcap;
} cf_store_file_t;

/* Open path in mode; *st then uses f (which must outlive it). CREATE also
 * fsyncs the directory so that the new name survives a power cut. RIG_EOPEN
 * with "path: reason" in msg. */
int cf_store_file_open(cf_store_file_t *f, const char *path, int mode, rig_store_t *st, char *msg,
                       size_t len);
void cf_store_file_close(cf_store_file_t *f);

/* Gather appends in bytes of memory (a fast scan's records: one write per
 * bytes instead of one per record; issue 19). Nothing changes for the
 * journal's durability, which is its syncs': the buffer is written before
 * each. A write that fails is reported by the append that filled the
 * buffer or by the sync; a truncate (the journal cutting a failed append
 * back) drops what the buffer held and never lengthens the file. 0, or
 * RIG_EIO without memory (the store then writes each append). */
int cf_store_file_buffer(cf_store_file_t *f, size_t bytes);

#endif

/* SPDX-License-Identifier: MIT */
/* fuzz.h: what the libFuzzer targets share: the entry point's prototype, a
 * temporary file per process for the parsers that read a path, a checked
 * one-line error message, and a fake hal/ transport that plays a device
 * whose replies are the fuzz input, on a virtual clock (hal_now_ms and
 * hal_sleep_ms are wrapped at link time, so no target ever sleeps). */
#ifndef FUZZ_H
#define FUZZ_H

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Write data to this process's temporary file; returns its path. */
const char *fz_file(const char *tag, const uint8_t *data, size_t size);

/* abort() unless msg is one non-empty line (the CLI prints it as is). */
void fz_one_line(const char *msg);

/* abort() unless msg contains what. */
void fz_names(const char *msg, const char *what);

/* The virtual clock the hal targets run on (milliseconds). */
extern double fz_clock_ms;

#endif

/* SPDX-License-Identifier: MIT */
/* bench_project.h: `cellfit bench project`, the projection benchmark. */
#ifndef BENCH_PROJECT_H
#define BENCH_PROJECT_H

/* argv[0] is "bench", argv[1] "project"; CLI exit codes. */
int bench_project(int argc, char **argv);

#endif

/* SPDX-License-Identifier: MIT */
/* cmd.h: the cellfit subcommands, one file each (host/cmd/cmd_*.c),
 * dispatched by main.c. */
#ifndef CMD_H
#define CMD_H

int cmd_fit(int argc, char **argv);
int cmd_eval(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_gen(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_report(int argc, char **argv);
int cmd_project(int argc, char **argv);
int cmd_base(int argc, char **argv);
int cmd_journal(int argc, char **argv);
int cmd_scan(int argc, char **argv);
int cmd_rig(int argc, char **argv);
int cmd_ports(int argc, char **argv);
int cmd_thin(int argc, char **argv);
int cmd_serve(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_results(int argc, char **argv);

#endif

/* SPDX-License-Identifier: MIT */
/* main.c: the cellfit command-line tool: one table of subcommands, each
 * with its own option table (cf_opt.h) behind `cellfit CMD --help`. */
#include "cf_cli.h"
#include "cf_cpu.h"
#include "cf_version.h"
#include "cmd.h"
#include "nf_config.h"
#include <string.h>

typedef struct cmd_entry {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} cmd_entry_t;

static const cmd_entry_t cmds[] = {
    {"fit", cmd_fit, "fit a surface's control net to measured points (Eq. 7), to a tolerance"},
    {"base", cmd_base, "a base surface for scattered points (plane, Coons, tensor fit)"},
    {"report", cmd_report, "deviations of points from a surface: statistics, histogram, map"},
    {"project", cmd_project, "u v and distance of each point projected onto a surface"},
    {"thin", cmd_thin, "keep the nearest point per vertex of a quadrilateral blanket"},
    {"convert", cmd_convert, "a surface from IGES to STEP AP242 or back, by extension"},
    {"eval", cmd_eval, "x y z of a surface at given u v"},
    {"info", cmd_info, "degrees, net, knots, weights and the bytes a fit needs"},
    {"gen", cmd_gen, "write a synthetic part: nominal, points, check grid"},
    {"scan", cmd_scan, "measure a part on the rig into a journal, and fit it"},
    {"journal", cmd_journal, "the journal of measured points: export, info, recover, fit"},
    {"rig", cmd_rig, "the stage and probe by hand: status, home, move, probe, reset, stop"},
    {"ports", cmd_ports, "serial ports, the laser probe, the USB trigger box"},
    {"serve", cmd_serve, "the cell headless, driven by a PLC over Modbus TCP"},
    {"results", cmd_results, "the jobs in the cell's results database, and its outbox"},
    {"bench", cmd_bench, "benchmarks on generated data"},
};
#define NCMDS (sizeof cmds / sizeof cmds[0])

static int usage(FILE *f, int code)
{
    fprintf(f, "usage: cellfit COMMAND [options] [arguments]\n"
               "       cellfit COMMAND --help    the command's options and their defaults\n"
               "       cellfit --version\n\ncommands:\n");
    for (size_t i = 0; i < NCMDS; i++)
        fprintf(f, "  %-8s %s\n", cmds[i].name, cmds[i].summary);
    fprintf(f,
            "\nboard %s: at most %ld control points, degree %d, arena %ld bytes\n"
            "exit status: 0 success, 1 the work failed, 2 bad usage or input\n",
            BOARD_NAME, (long)NF_MAX_CP, NF_MAX_DEGREE, (long)NF_ARENA_BYTES);
    return code;
}

int main(int argc, char **argv)
{
    cf_cpu_from_env();
    if (argc < 2)
        return usage(stderr, CLI_USAGE);
    const char *c = argv[1];
    for (size_t i = 0; i < NCMDS; i++)
        if (!strcmp(c, cmds[i].name))
            return cmds[i].run(argc - 1, argv + 1);
    if (!strcmp(c, "-h") || !strcmp(c, "--help"))
        return usage(stdout, CLI_OK);
    if (!strcmp(c, "help")) {
        if (argc < 3)
            return usage(stdout, CLI_OK);
        for (size_t i = 0; i < NCMDS; i++)
            if (!strcmp(argv[2], cmds[i].name)) {
                char *av[] = {argv[2], "--help", NULL};
                return cmds[i].run(2, av);
            }
        fprintf(stderr, "cellfit help: unknown command '%s' (cellfit --help lists them)\n",
                argv[2]);
        return CLI_USAGE;
    }
    if (!strcmp(c, "--version") || !strcmp(c, "-V")) {
        printf("%s\nboard %s\n", cf_version_string(), BOARD_NAME);
        return CLI_OK;
    }
    if (!strcmp(c, "--commands")) { /* for completion and the man page */
        for (size_t i = 0; i < NCMDS; i++)
            printf("%s\n", cmds[i].name);
        return CLI_OK;
    }
    fprintf(stderr, "cellfit: unknown command '%s' (cellfit --help lists them)\n", c);
    return CLI_USAGE;
}

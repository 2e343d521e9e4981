/* main.c: the cellfit command-line tool: dispatch to subcommands. */
#include "cf_cli.h"
#include "cmd.h"
#include "nf_config.h"
#include <string.h>

static int usage(FILE *f, int code)
{
    fprintf(f,
            "usage: cellfit <command> [options]\n"
            "commands:\n"
            "  fit   --base BASE.igs --points FILE [--uv | --reparam K] [--alpha A]\n"
            "        [--beta B] [--solver auto|gs|chol|pcg] [--entity N] --out OUT.igs [--json]\n"
            "        (x y z points are projected onto BASE; --uv takes u v x y z)\n"
            "        [--tol T [--within PCT] [--refine residual|uniform] [--max-cp N]\n"
            "        [--max-rounds R]]  insert knots until PCT %% of the points are within T\n"
            "        [--robust [--robust-iters K]]  Tukey reweighting against outliers\n"
            "        [--far MM [--drop-far]]  flag (drop) projected points farther than MM\n"
            "  eval  SURF.igs UVFILE [--entity N]   print x y z for each u v line\n"
            "  project SURF.igs XYZFILE [--entity N]  print u v distance for each point\n"
            "  report SURF.igs POINTS --tol T [--png MAP.png] [--json]\n"
            "        signed normal deviations, statistics, histogram, colour deviation map\n"
            "  thin  SURF.igs POINTS --tol T [--radius R] --out FILE [--json]\n"
            "        keep the nearest point per vertex of a T-relative quadrilateral blanket\n"
            "  info  SURF.igs [--entity N] [--json] degrees, net, knots, weights, bytes\n"
            "  base  --points FILE [--curves CURVES.igs [--de a,b,c,d]]\n"
            "        [--method plane|bilinear|bicubic|tensor] [--subset PCT] [--seed S]\n"
            "        [--nu N --nv N --degree P] --out BASE.igs [--json]   base surface for fit\n"
            "        (--extract SURF.igs --out CURVES.igs: its four boundary curves, IGES 126)\n"
            "  gen   --dir DIR [--nu N --nv N --degree P --points M --noise SIGMA --seed S]\n"
            "        [--bump H,X,Y,R] [--ridge H,X,W] [--outliers FRAC [--spike MM]]\n"
            "        write a synthetic part: nominal.igs, points.uvxyz, check grid\n"
            "  serve --plc tcp:ADDR:PORT [--config FILE] [--word-order lo-hi|hi-lo]\n"
            "        [--watchdog-ms T] [--port-file F] [--syslog]   the cell headless, driven\n"
            "        by a PLC over Modbus TCP (docs/plc-register-map.md)\n"
            "  scan  --stage URI --probe URI --nominal N.igs --journal FILE [--fit OUT.igs]\n"
            "        [--step MM] [--region x0:x1:y0:y1] [--z0 Z --cal cx:cy:cz] [--alpha A]\n"
            "        [--beta B] [--report REPORT.json] [--json]   measure on the rig\n"
            "  journal export JOURNAL [--out FILE] | info JOURNAL [--json] | recover JOURNAL\n"
            "        | fit JOURNAL --nominal N.igs --out OUT.igs [--reparam K]   the journal of "
            "points\n"
            "  rig   status|home|move X Y|probe|reset|stop --stage URI --probe URI [--count N]\n"
            "        [--timeout MS] [--retries N] [--json]   the stage and probe by hand (hal.h)\n"
            "  ports [--json]   serial ports with their USB VID:PID\n"
            "  ports --probe PORT [--n N] [--baud B] [--retries R] [--timeout MS] [--json]\n"
            "        read the laser probe (M0) on a serial port\n"
            "  ports --trig VID:PID[:SERIAL] [--n N] [--period US] [--json]\n"
            "        identity and encoder packets of the USB trigger box (1209:cf01)\n"
            "  bench accumulate|solve|fit|export|project [--points M] [--cp N]\n"
            "        [--order raster|random] [--solver S] [--json]   benchmarks on generated data\n"
            "board %s: at most %ld control points, degree %d, arena %ld bytes\n"
            "exit status: 0 success, 1 the work failed, 2 bad usage or input\n",
            BOARD_NAME, (long)NF_MAX_CP, NF_MAX_DEGREE, (long)NF_ARENA_BYTES);
    return code;
}

int main(int argc, char **argv)
{
    if (argc < 2)
        return usage(stderr, CLI_USAGE);
    const char *c = argv[1];
    if (!strcmp(c, "fit"))
        return cmd_fit(argc - 1, argv + 1);
    if (!strcmp(c, "eval"))
        return cmd_eval(argc - 1, argv + 1);
    if (!strcmp(c, "info"))
        return cmd_info(argc - 1, argv + 1);
    if (!strcmp(c, "gen"))
        return cmd_gen(argc - 1, argv + 1);
    if (!strcmp(c, "bench"))
        return cmd_bench(argc - 1, argv + 1);
    if (!strcmp(c, "report"))
        return cmd_report(argc - 1, argv + 1);
    if (!strcmp(c, "project"))
        return cmd_project(argc - 1, argv + 1);
    if (!strcmp(c, "base"))
        return cmd_base(argc - 1, argv + 1);
    if (!strcmp(c, "journal"))
        return cmd_journal(argc - 1, argv + 1);
    if (!strcmp(c, "scan"))
        return cmd_scan(argc - 1, argv + 1);
    if (!strcmp(c, "rig"))
        return cmd_rig(argc - 1, argv + 1);
    if (!strcmp(c, "ports"))
        return cmd_ports(argc - 1, argv + 1);
    if (!strcmp(c, "thin"))
        return cmd_thin(argc - 1, argv + 1);
    if (!strcmp(c, "serve"))
        return cmd_serve(argc - 1, argv + 1);
    if (!strcmp(c, "-h") || !strcmp(c, "--help") || !strcmp(c, "help"))
        return usage(stdout, CLI_OK);
    fprintf(stderr, "cellfit: unknown command '%s'\n", c);
    return usage(stderr, CLI_USAGE);
}

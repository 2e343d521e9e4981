/* sim_ascii.c: the ASCII protocol of the simulated laser probe, as common
 * laser displacement sensors speak it: "M0" -> "M0,+45.123" (mm),
 * out of range "M0,FFFFFFF", "RG" -> "RG,+30.000,+60.000" (measuring
 * range), errors "ER,<cmd>,nn"; every line ends in CR LF. */
#include "sim.h"
#include <stdio.h>
#include <string.h>

size_t sim_ascii_answer(sim_probe_t *pr, double now, const char *line, char *out, size_t cap)
{
    int n;
    if (!strcmp(line, "M0")) {
        double d = 0;
        int m = sim_probe_measure(pr, now, SIM_W_ASCII, &d);
        if (m == 2)
            n = snprintf(out, cap, "ER,M0,01\r\n"); /* sensor head not ready */
        else if (m == 1)
            n = snprintf(out, cap, "M0,FFFFFFF\r\n");
        else
            n = snprintf(out, cap, "M0,%+07.3f\r\n", d);
    } else if (!strcmp(line, "RG"))
        n = snprintf(out, cap, "RG,%+07.3f,%+07.3f\r\n", pr->lo, pr->hi);
    else if (!strcmp(line, "ID"))
        n = snprintf(out, cap, "ID,CELLSIM-LDS,1\r\n");
    else {
        char cmd[3] = {line[0] ? line[0] : '?', line[0] && line[1] ? line[1] : '?', 0};
        n = snprintf(out, cap, "ER,%s,00\r\n", cmd); /* unknown command */
    }
    return n < 0 ? 0 : (size_t)n < cap ? (size_t)n : cap - 1;
}

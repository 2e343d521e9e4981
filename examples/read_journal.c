/* SPDX-License-Identifier: MIT */
/* read_journal.c: libcellfit from a program: read the measured points of a
 * cell's journal (every record's checksum verified) and print their count
 * and bounding box; with a nominal IGES surface as the second argument, fit
 * it to the points and write the result.
 * Usage: read_journal JOURNAL [NOMINAL.igs OUT.igs]
 * Build: cc read_journal.c $(pkg-config --cflags --libs cellfit) */
#include <cellfit.h>
#include <math.h>
#include <stdio.h>

int main(int argc, char **argv)
{
    if (argc != 2 && argc != 4) {
        fprintf(stderr, "usage: read_journal JOURNAL [NOMINAL.igs OUT.igs]\n");
        return 2;
    }
    char msg[512];
    cellfit_journal_t *j;
    int rc = cellfit_journal_open(&j, argv[1], msg, sizeof msg);
    if (rc) {
        fprintf(stderr, "%s\n", msg);
        return 2;
    }
    cellfit_fit_t *fit = NULL;
    if (argc == 4 && (rc = cellfit_fit_open_file(&fit, argv[2], NULL, msg, sizeof msg))) {
        fprintf(stderr, "%s\n", msg);
        cellfit_journal_close(j);
        return 2;
    }
    cellfit_point_t pt;
    long valid = 0, flagged = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    while ((rc = cellfit_journal_next(j, &pt)) == 1) {
        if (!pt.valid) {
            flagged++;
            continue;
        }
        double q[3] = {pt.x, pt.y, pt.z};
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], q[k]);
            hi[k] = fmax(hi[k], q[k]);
        }
        valid++;
        if (fit && (rc = cellfit_fit_add_xyz(fit, q, 1)) < 0)
            break;
    }
    if (rc < 0) {
        fprintf(stderr, "%s: %s\n", argv[1], cellfit_strerror(rc));
        cellfit_journal_close(j);
        cellfit_fit_close(fit);
        return 1;
    }
    printf("points %ld\nflagged %ld\nrecords %ld\n", valid, flagged, cellfit_journal_count(j));
    if (valid)
        printf("box %.6g %.6g %.6g  %.6g %.6g %.6g\n", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    cellfit_journal_close(j);
    if (fit) {
        rc = cellfit_fit_solve(fit);
        if (!rc)
            rc = cellfit_fit_write(fit, argv[3]);
        if (rc)
            fprintf(stderr, "fit: %s: %s\n", cellfit_strerror(rc), cellfit_fit_message(fit));
        else
            printf("fitted %s\n", argv[3]);
        cellfit_fit_close(fit);
    }
    return rc ? 1 : 0;
}

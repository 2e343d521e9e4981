#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/man.sh: the man pages, generated from the programs' own option
# tables (`CMD --help-man`, the same tables `--help` prints), so they never
# drift from the code. Usage: scripts/man.sh CELLFIT CELLSIM OUTDIR
# Writes OUTDIR/cellfit.1, cellsim.1 and cellfit.conf.5.
set -eu
cf=$1 cs=$2 out=$3
mkdir -p "$out"
ver=$("$cf" --version | head -1 | sed 's/^cellfit //; s/ (.*//')
# The date of the revision built (reproducible), not of the build.
date=$(git log -1 --format=%cs 2>/dev/null || date -u +%Y-%m-%d)

{
    printf '.TH CELLFIT 1 "%s" "cellfit %s" "cellfit manual"\n' "$date" "$ver"
    cat <<'T'
.SH NAME
cellfit \- measurement\-based NURBS surface fitting for inspection cells
.SH SYNOPSIS
.B cellfit
.I command
.RI [ options ]
.RI [ arguments ]
.br
.B cellfit
.I command
.B \-\-help
.br
.B cellfit \-\-version
.SH DESCRIPTION
.B cellfit
fits the control net of a nominal NURBS surface to measured points
(Brujic, Ainsworth and Ristic 2010, Eq. 7: least squares with a Greville
term \fIalpha\fR and a stay\-near\-nominal term \fIbeta\fR), streamed one
row of the observation matrix at a time into storage that depends on the
control net alone. It parameterises scattered points by projection onto a
base surface, refines knots until a tolerance holds, reports deviations,
drives a measuring rig (stage and probe over Modbus and serial, a USB
trigger box) and serves a PLC over Modbus TCP
.RB ( "cellfit serve" ).
Surfaces are IGES entity 128; points are ASCII
.I "x y z"
or
.I "u v x y z"
lines, or PLY.
.PP
Options take their value as the next argument or after an equals sign
.RB ( \-\-tol=0.05 ).
Every command answers
.BR \-\-help .
.SH COMMANDS
T
    for c in $("$cf" --commands); do
        "$cf" "$c" --help-man
        for s in $("$cf" "$c" --subcommands 2>/dev/null || true); do
            "$cf" "$c" "$s" --help-man
        done
    done
    cat <<'T'
.SH EXIT STATUS
0 success; 1 the work failed (a tolerance not met, a device fault); 2 bad
usage or input (a file that cannot be read, a job over the board's memory
budget, points that do not determine the surface), with one line on
standard error naming the cause.
.SH FILES
.TP
.I /etc/cellfit/cellfit.conf
the cell's configuration, see
.BR cellfit.conf (5).
.TP
.I /var/lib/cellfit
results and journals of the service.
.SH SEE ALSO
.BR cellsim (1),
.BR cellfit.conf (5);
the register map for PLC programmers, plc\-register\-map.md, and the other
documents in the package's documentation folder.
T
} >"$out/cellfit.1"

{
    printf '.TH CELLSIM 1 "%s" "cellfit %s" "cellfit manual"\n' "$date" "$ver"
    cat <<'T'
.SH NAME
cellsim \- the simulated measuring rig of cellfit: stage, probe and part
.SH DESCRIPTION
.B cellsim
plays a motion stage (Modbus RTU or TCP) and a laser displacement probe
(ASCII serial or Modbus) over pseudo\-terminals and loopback TCP, with a
known part under the probe and faults on demand, so that
.BR cellfit (1)
and a PLC can be tested without hardware.
.SH OPTIONS
T
    "$cs" --help-man | sed '1,/^\.br$/d' | sed '1d'
    cat <<'T'
.SH SEE ALSO
.BR cellfit (1)
T
} >"$out/cellsim.1"

# cellfit.conf(5): every option of `cellfit serve` is a key of the file,
# its name with underscores for dashes.
{
    printf '.TH CELLFIT.CONF 5 "%s" "cellfit %s" "cellfit manual"\n' "$date" "$ver"
    cat <<'T'
.SH NAME
cellfit.conf \- configuration of the cellfit cell service
.SH SYNOPSIS
.I /etc/cellfit/cellfit.conf
.SH DESCRIPTION
The file read by
.B cellfit serve \-\-config
.IR FILE :
one
.I "key = value"
a line; blank lines and lines starting with
.B #
are ignored. Every option of
.B cellfit serve
is a key, with underscores for its dashes
.RB ( \-\-watchdog\-ms " is " watchdog_ms );
options given on the command line override the file. A key the service does
not know stops it with the file and line named.
.SH KEYS
T
    "$cf" serve --help-man | sed '1,/^\.br$/d' | sed '1d' | awk '
        # One option a block (.TP, .B --name ARG, its text); skip those that
        # are not settings, turn --name into the key.
        /^\.TP$/ { skip = 0; tp = 1; next }
        tp && /^\.B \\-\\-/ {
            tp = 0; k = $2; sub(/^\\-\\-/, "", k)
            if (k ~ /^(config|help|print\\-map)$/) { skip = 1; next }
            gsub(/\\-/, "_", k); $1 = ".B"; $2 = k " ="; print ".TP"; print; next
        }
        !skip { print }'
    cat <<'T'
.SH EXAMPLE
An example configuration is installed with the documentation
(examples/cellfit.conf).
.SH SEE ALSO
.BR cellfit (1)
T
} >"$out/cellfit.conf.5"
echo "man: $out/cellfit.1 $out/cellsim.1 $out/cellfit.conf.5"

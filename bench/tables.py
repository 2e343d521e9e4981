# SPDX-License-Identifier: MIT
"""bench/tables.py: Markdown tables of bench/run.sh's JSON lines, beside the
paper's figures (Brujic, Ainsworth & Ristic 2010, Tables 2-4: Xeon 3.2 GHz).

Usage: python3 bench/tables.py OUTDIR SECTION
SECTION: machine stream accumulate solve cholmod fitpack e2e targets.
Each cell is the fastest of the runs recorded for it ("seconds", or
"wall_seconds" end to end); failed runs are listed under their table.
"""

import json
import os
import sys

# Paper, milliseconds, keyed by (M, N); None where it prints "-".
T2_MS = {(10**4, 10**2): 46, (10**4, 10**3): 63, (10**4, 10**4): 93, (10**4, 10**5): None,
         (10**5, 10**2): 422, (10**5, 10**3): 502, (10**5, 10**4): 875, (10**5, 10**5): 1159,
         (10**6, 10**2): 4172, (10**6, 10**3): 4813, (10**6, 10**4): 8797,
         (10**6, 10**5): 11468}
T2_KB = {10**2: "42.6", 10**3: "425", 10**4: "4,253", 10**5: "42,534"}
T3_MS = {10**2: (15, 31, 32), 10**3: (140, 156, 171), 10**4: (1125, 2007, 1797),
         10**5: (None, 13672, 21285)}
T4_MS = {10**2: (11, 10, 12), 10**3: (93, 94, 94), 10**4: (7344, 7235, 7328),
         10**5: (None, 1967339, 1926738)}
DECADES = (10**2, 10**3, 10**4, 10**5, 10**6)


def load(out, name):
    """(good lines, failed lines) of OUT/name.jsonl."""
    path = os.path.join(out, name + ".jsonl")
    good, bad = [], []
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                line = line.strip()
                if not line:
                    continue
                try:
                    d = json.loads(line)
                except ValueError:
                    bad.append({"command": "?", "message": "unparsable: " + line[:200]})
                    continue
                (bad if d.get("bench") == "error" else good).append(d)
    return good, bad


def best(lines, key, field="seconds"):
    """The fastest line of each key(line), with the number of runs."""
    out = {}
    for d in lines:
        k = key(d)
        runs = out[k][1] + 1 if k in out else 1
        if k not in out or d.get(field, 1e300) < out[k][0].get(field, 1e300):
            out[k] = (d, runs)
        else:
            out[k] = (out[k][0], runs)
    return out


def decade(n):
    """The paper's N for one of our square nets (1024 -> 10^3, 99856 -> 10^5)."""
    return min(DECADES, key=lambda d: abs(d - n) / d)


def ms(s):
    return "-" if s is None else ("%.3g" % (1e3 * s) if s < 1 else "{:,.0f}".format(1e3 * s))


def paper_ms(v):
    return "-" if v is None else "{:,}".format(v)


def sec(s):
    return "-" if s is None else "%.3g" % s


def mps(p):
    return "-" if p is None else "%.2f" % (p / 1e6)


def table(head, rows):
    print("| " + " | ".join(head) + " |")
    print("|" + "|".join("---" for _ in head) + "|")
    for r in rows:
        print("| " + " | ".join(str(c) for c in r) + " |")
    print()


def failures(bad):
    for b in bad:
        print("- FAILED: `%s`: %s" % (b.get("command", "?"), b.get("message", "").strip()))
    if bad:
        print()


def machine(out):
    good, _ = load(out, "machine")
    if not good:
        return
    m = good[0]
    print("## Machine\n")
    print("- command: `%s` (`make bench`)" % m["command"])
    print("- date: %s" % m["date"])
    print("- CPU: %s, nproc %d, %.1f GB RAM, Linux %s"
          % (m["cpu"], m["nproc"], m["mem_total_kb"] / 2**20, m["kernel"]))
    print("- compiler: %s; cellfit built with `%s` (one core unless a table says two)"
          % (m["compiler"], m["cellfit_cflags"]))
    print("- cellfit revision: %s" % m["cellfit_rev"])
    print("- CHOLMOD's BLAS: %s; %s, scipy %s" % (m["blas"], m["python"], m["scipy"]))
    print("- repetitions: each cell is the fastest of %d run%s, a single run where one takes "
          "%s s or more (wall)\n" % (m["reps"], "s" if m["reps"] > 1 else "",
                                      m["repeat_below_s"]))


def stream(out):
    good, bad = load(out, "stream")
    print("## Memory bandwidth, one core (bench/stream.c)\n")
    if good:
        s = good[0]
        for d in good:
            if d["triad_GBps"] > s["triad_GBps"]:
                s = d
        table(["triad GB/s", "read GB/s",
               "random 4 x 800 B read-modify-write, M points/s: N = 10^4", "10^5", "10^6",
               "dependent FMA ns", "peak GFLOP/s (AVX2 FMA)"],
              [["%.1f" % s["triad_GBps"], "%.1f" % s["read_GBps"],
                mps(s["scatter_1e4_points_per_s"]), mps(s["scatter_1e5_points_per_s"]),
                mps(s["scatter_1e6_points_per_s"]), "%.2f" % s["fma_latency_ns"],
                "%.0f" % s["fma_peak_gflops"]]])
    failures(bad)


def accumulate(out):
    good, bad = load(out, "accumulate")
    two = [d for d in good if d.get("threads", 1) == 2]
    good = [d for d in good if d.get("threads", 1) == 1]
    b = best(good, lambda d: (d["points"], d["control_points"], d["order"]))
    print("## Accumulation (preparation phase, paper Table 2)\n")
    print("Time to stream M points into the stripes (R^T R and R^T Q), point generation"
          " excluded; paper: Xeon 3.2 GHz, 2010, order unstated.\n")
    cells = sorted({(m, n) for (m, n, _) in b})
    rows = []
    for m, n in cells:
        r = b.get((m, n, "raster"), ({}, 0))[0]
        q = b.get((m, n, "random"), ({}, 0))[0]
        pm = T2_MS.get((m, decade(n)))
        rs = r.get("accumulate_seconds")
        speed = "%.0fx" % (pm / 1e3 / rs) if pm and rs else "-"
        store = (r or q).get("store_bytes")
        rss = max(r.get("peak_rss_bytes", 0), q.get("peak_rss_bytes", 0))
        rows.append(["{:,}".format(m), "{:,}".format(n), paper_ms(pm), ms(rs),
                     mps(r.get("points_per_s")), ms(q.get("accumulate_seconds")),
                     mps(q.get("points_per_s")), speed,
                     "{:,.0f}".format(store / 1e3) if store else "-",
                     T2_KB.get(decade(n), "-"), "%.0f" % (rss / 2**20) if rss else "-"])
    table(["M", "N", "paper ms", "raster ms", "raster M pts/s", "random ms", "random M pts/s",
           "paper / raster", "stripes kB", "paper kB", "peak RSS MiB"], rows)
    if two:
        b2 = best(two, lambda d: (d["points"], d["control_points"], d["order"]))
        print("One core and two (`--threads 2`: the job and a shard, each on its own stripes,"
              " half of every chunk each, merged at the end; merge included), M = 10^6:\n")
        rows = []
        for m, n, o in sorted(b2):
            d2 = b2[(m, n, o)][0]
            d1 = b.get((m, n, o), ({}, 0))[0]
            p1, p2 = d1.get("points_per_s"), d2.get("points_per_s")
            rows.append(["{:,}".format(n), o, mps(p1), mps(p2),
                         "%.2f" % (p2 / p1) if p1 and p2 else "-",
                         ms(d2.get("merge_seconds")),
                         "{:,.0f}".format(d2["arena_bytes"] / 1e3)])
        table(["N", "order", "1 core M pts/s", "2 cores M pts/s", "speed-up", "merge ms",
               "arena kB, 2 cores"], rows)
    failures(bad)


def solve(out):
    good, bad = load(out, "solve")
    b = best([d for d in good if not d.get("skipped")],
             lambda d: (d["control_points"], d["solver"]), "solve_seconds")
    skipped = {(d["control_points"], d["solver"]): d for d in good if d.get("skipped")}
    print("## Solve to relative residual 1e-10 (paper Tables 3: Gauss-Seidel, 4: banded "
          "Cholesky)\n")
    print("Ours: M = 10 N random points, Eq. 7 with alpha 0.1, beta 0.001, start at the "
          "nominal net; time of the solve alone. The paper's Gauss-Seidel stopped when every "
          "control point moved less than 1e-4 (relative); its times barely depend on M.\n")
    keys = sorted(set(b) | set(skipped), key=lambda k: (k[0], ["gs", "pcg", "chol"].index(k[1])
                                                       if k[1] in ("gs", "pcg", "chol") else 9))
    rows = []
    for k in keys:
        n, s = k
        paper = {"gs": T3_MS, "chol": T4_MS}.get(s, {}).get(decade(n))
        pap = " / ".join(paper_ms(v) for v in paper) if paper else "(not in the paper)"
        if k in skipped:
            rows.append(["{:,}".format(n), s,
                         "- (est. %s s)" % sec(skipped[k]["estimate_seconds"]), "-", "-", "-",
                         "-", pap])
            continue
        d = b[k][0]
        rows.append(["{:,}".format(n), s, ms(d["solve_seconds"]), d["iterations"],
                     "%.1e" % d["rel_residual"], "%.1f" % (d["arena_bytes"] / 2**20),
                     "%.0f" % (d["arena_bytes"] / n), pap])
    table(["N", "solver", "ms", "iterations", "rel. residual", "arena MiB", "arena B/cp",
           "paper ms, M = 10^4 / 10^5 / 10^6"], rows)
    failures(bad)


def cholmod(out):
    good, bad = load(out, "cholmod")
    sol, _ = load(out, "solve")
    ours = best([d for d in sol if not d.get("skipped")],
                lambda d: (d["control_points"], d["solver"]), "solve_seconds")
    b = best(good, lambda d: d["control_points"])
    print("## CHOLMOD (SuiteSparse) on the same normal equations\n")
    print("`cellfit bench export` writes the assembled Eq. 7 of the solve benchmark; "
          "bench/cholmod_bench.c: cholmod_analyze + cholmod_factorize, then cholmod_solve "
          "for x, y, z. Ratios: our solve time over CHOLMOD's analyse + factor + solve, same "
          "run.\n")
    rows = []
    for n in sorted(b):
        d = b[n][0]
        row = ["{:,}".format(n), sec(d["analyze_seconds"]), sec(d["factor_seconds"]),
               sec(d["solve_seconds"]), sec(d["seconds"]), "%.1e" % d["rel_residual"],
               "{:,.0f}".format(d["nnz_L"]), d["ordering"]]
        for s in ("pcg", "chol", "gs"):
            o = ours.get((n, s))
            row.append("%s (%.2f)" % (sec(o[0]["solve_seconds"]),
                                      o[0]["solve_seconds"] / d["seconds"]) if o else "-")
        rows.append(row)
    table(["N", "analyse s", "factor s", "solve s", "CHOLMOD total s", "rel. residual",
           "nnz(L)", "ordering", "our pcg s (ratio)", "our chol s (ratio)", "our gs s (ratio)"],
          rows)
    failures(bad)


def fitpack(out):
    fp, bad = load(out, "fitpack")
    us, bad2 = load(out, "fit")
    f = best(fp, lambda d: (d["points"], d["control_points"]))
    o = best(us, lambda d: (d["points"], d["control_points"]))
    print("## FITPACK (scipy LSQBivariateSpline, surfit) on the same points\n")
    print("Same random points and height field, bicubic, same uniform knots. FITPACK fits z "
          "only; cellfit fits x, y and z (3 right-hand sides) with Eq. 7's regularisation. "
          "FITPACK: the LSQBivariateSpline call (Givens QR of the observation matrix, no "
          "normal equations); cellfit: `bench fit` accumulate + solve (the fit job, whose "
          "check pass over the points is not timed). N = 1,024 = 2^10: "
          "FITPACK runs several times slower there than at N = 961 (and about 30 s at "
          "N = 4,096), presumably cache-set conflicts from a power-of-two stride in its band "
          "array; both are shown.\n")
    rows, notes = [], []
    for k in sorted(set(f) | set(o)):
        d = f.get(k, ({}, 0))[0]
        e = o.get(k, ({}, 0))[0]
        st = d.get("status", "-")
        if d.get("message"):
            notes.append("- M = {:,}, N = {:,}: FITPACK {}: {}".format(k[0], k[1], st,
                                                                        d["message"]))
        ratio = "%.3f" % (e["seconds"] / d["seconds"]) if d.get("seconds") and e else "-"
        rows.append(["{:,}".format(k[0]), "{:,}".format(k[1]), sec(d.get("seconds")), st,
                     "%.2g" % d["rms"] if "rms" in d else "-", sec(e.get("seconds")),
                     e.get("solver", "-"), ratio])
    table(["M", "N", "FITPACK s (z)", "FITPACK status", "FITPACK rms", "cellfit s (x, y, z)",
           "cellfit solver", "cellfit / FITPACK"], rows)
    for n in notes:
        print(n)
    if notes:
        print()
    failures(bad + bad2)


def e2e(out):
    good, bad = load(out, "e2e")
    peers, pbad = load(out, "e2e_peers")
    print("## End to end: `cellfit fit --uv`, 10^6 points, beside scipy CG and CHOLMOD\n")
    print("Wall time of the whole command (IGES in, two passes over the file: accumulate, "
          "then the residual pass for RMS and max; IGES out), the file in the page cache "
          "(`cellfit gen` and bench/genbin wrote it, not timed): ASCII (`%.9f %.9f %.6f "
          "%.6f %.6f` lines, 54 MB) and raw float64 (`.uvxyz.bin`, 40 MB). Peers "
          "(bench/peers_e2e.py) on the same points and net, in-process, file I/O excluded: "
          "scipy sparse normal equations (R^T R + tiny ridge) with Jacobi CG to 1e-10, and "
          "the same assembly followed by CHOLMOD (bench/cholmod_bench: analyse + factor + "
          "solve); their MB is the Python process's peak RSS. Ratio: the better peer's "
          "seconds over cellfit's.\n")
    b = best([d for d in good if d.get("points", 0) <= 10**6],
             lambda d: (d["control_points"], d.get("input", "ascii")), "wall_seconds")
    cg = {d["control_points"]: d for d in peers if d.get("peer") == "scipy_cg"}
    asm = {d["control_points"]: d for d in peers if d.get("peer") == "cholmod_assembly"}
    ch = {d["control_points"]: d for d in peers if d.get("e2e") and d.get("bench") == "cholmod"}
    rows = []
    for n in sorted({k[0] for k in b}):
        def cf(inp):
            d = b.get((n, inp))
            return d[0] if d else None
        a, bn = cf("ascii"), cf("bin")
        peer = []
        if n in cg:
            peer.append(cg[n]["seconds"])
        if n in asm and n in ch:
            peer.append(asm[n]["assembly_seconds"] + ch[n]["seconds"])
        better = min(peer) if peer else None

        def fmt(d):
            return "-" if not d else "%s / %.0f" % (sec(d["wall_seconds"]),
                                                     d["peak_rss_bytes"] / 2**20)

        def ratio(d):
            return "-" if not d or better is None else "%.1fx" % (better / d["wall_seconds"])
        rows.append(["{:,}".format(n), fmt(a), fmt(bn),
                     "-" if not a else "%s / %s / %s" % (sec(a["accumulate_seconds"]),
                                                        sec(a["solve_seconds"]),
                                                        sec(a["seconds"] - a["accumulate_seconds"]
                                                            - a["solve_seconds"])),
                     "-" if not bn else "%s / %s / %s" % (sec(bn["accumulate_seconds"]),
                                                         sec(bn["solve_seconds"]),
                                                         sec(bn["seconds"]
                                                             - bn["accumulate_seconds"]
                                                             - bn["solve_seconds"])),
                     "-" if n not in cg else "%s / %.0f" % (sec(cg[n]["seconds"]),
                                                            cg[n]["peak_rss_mib"]),
                     "-" if not (n in asm and n in ch) else "%s / %.0f" % (
                         sec(asm[n]["assembly_seconds"] + ch[n]["seconds"]),
                         asm[n]["peak_rss_mib"]),
                     ratio(a), ratio(bn)])
    table(["N", "cellfit ASCII s / MiB", "cellfit binary s / MiB",
           "ASCII: read + accumulate / solve / other s", "binary: same",
           "scipy CG s / MiB", "CHOLMOD s / MiB", "ratio ASCII", "ratio binary"], rows)
    long = [d for d in good if d.get("points", 0) > 10**6]
    if long:
        print("\nLong runs: 10^8 points = the 10^6-point raster above "
              "written 100 times into one `.uvxyz.bin` (4 GB, streamed, deleted after), "
              "onto N = 10^4 (and with `BENCH_LONG=1` onto N = 10^5, and N = 10^6 from 10^7 "
              "points of `cellfit gen`). One run each.\n")
        one = {k: v[0] for k, v in b.items()}
        lrows = []
        for d in sorted(long, key=lambda x: (x["points"], x["control_points"])):
            ref = one.get((d["control_points"], d.get("input")))
            lrows.append(["{:,}".format(d["points"]), "{:,}".format(d["control_points"]),
                          d.get("input", "ascii"), sec(d["wall_seconds"]),
                          sec(d["accumulate_seconds"]), sec(d["solve_seconds"]),
                          "%.2f" % (d["points"] / d["wall_seconds"] / 1e6),
                          "%.0f" % (d["peak_rss_bytes"] / 2**20),
                          "-" if not ref else "%.2f" % (d["peak_rss_bytes"]
                                                        / ref["peak_rss_bytes"]),
                          "-" if not ref else "%.1f" % (d["wall_seconds"]
                                                        / ref["wall_seconds"])])
        table(["M", "N", "input", "wall s", "read + accumulate s", "solve s", "M points/s",
               "peak RSS MiB", "RSS / 10^6 run", "time / 10^6 run"], lrows)
    failures(bad + pbad)


def project(out):
    good, bad = load(out, "project")
    print("## Projection: closest points on the surface (`cellfit bench project`)\n")
    print("200,000 points Q = S(u, v) + d n(u, v), |d| <= 1 mm, around a curved bicubic "
          "100 x 100 mm part whose true (u, v) are known; quadrilateral decomposition, grid "
          "search, Newton to 1e-9 of the domain (Piegl & Tiller 2001; firmware/nf_quad.c). "
          "Time per core (CPU seconds), generation excluded; parameter error against the "
          "truth, relative to the domain. Issue 6's target: 1 M points/s at 1e-9.\n")
    b = best(good, lambda d: (d["control_points"], d["order"]))
    rows = []
    for (n, o), d in sorted(b.items()):
        d = d[0]
        rows.append(["{:,}".format(n), o, mps(d["points_per_s"]), "%.1e" % d["max_param_error"],
                     "%.2f" % d["mean_newton_iters"], d["quads"], d["not_converged"],
                     "%.2f" % (d["init_seconds"] * 1e3), "%.0f" % (d["quad_bytes"] / 1024)])
    table(["N", "order", "M points/s", "max param. error", "Newton steps", "quads",
           "not converged", "set-up ms", "quad store kB (reserved)"], rows)
    failures(bad)


def targets(out):
    acc, _ = load(out, "accumulate")
    acc2 = [d for d in acc if d.get("threads", 1) == 2]
    acc = [d for d in acc if d.get("threads", 1) == 1]
    sol, _ = load(out, "solve")
    e2, _ = load(out, "e2e")
    a = best(acc, lambda d: (d["points"], d["control_points"], d["order"]))
    s = best([d for d in sol if not d.get("skipped")],
             lambda d: (d["control_points"], d["solver"]), "solve_seconds")
    print("## Targets (issue 6)\n")
    rows = []

    def verdict(ok):
        return "-" if ok is None else ("met" if ok else "not met")

    ras = [(d[0]["points_per_s"], n) for (m, n, o), d in a.items()
           if m == 10**6 and o == "raster" and n <= 100000]
    if ras:
        lo = min(ras)
        rows.append(["accumulation, raster, N <= 10^5, one core", ">= 20 M points/s",
                     "%s M/s (lowest, N = %s; M = 10^6)" % (mps(lo[0]), "{:,}".format(lo[1])),
                     verdict(lo[0] >= 20e6)])
    rnd = [d[0]["points_per_s"] for (m, n, o), d in a.items()
           if m == 10**6 and o == "random" and decade(n) == 10**5]
    if rnd:
        rows.append(["accumulation, random, N = 10^5", ">= 5 M points/s",
                     "%s M/s (M = 10^6)" % mps(rnd[0]), verdict(rnd[0] >= 5e6)])
    a2 = best(acc2, lambda d: (d["points"], d["control_points"], d["order"]))
    for o in ("raster", "random"):
        c = [(d[0]["points_per_s"], n) for (m, n, oo), d in a2.items()
             if m == 10**6 and oo == o and n <= 100000]
        if c:
            lo = min(c)
            rows.append(["accumulation, %s, N <= 10^5, two cores" % o, "(where it pays)",
                         "%s M/s (lowest, N = %s)" % (mps(lo[0]), "{:,}".format(lo[1])), "-"])
    for dec, lim in ((10**5, 0.3), (10**6, 5.0)):
        c = [(d[0]["solve_seconds"], sv, d[0]["rel_residual"]) for (n, sv), d in s.items()
             if decade(n) == dec and d[0]["rel_residual"] <= 1e-10]
        if c:
            t, sv, _ = min(c)
            rows.append(["solve to 1e-10, N = 10^%d" % (5 if dec == 10**5 else 6),
                         "<= %g s" % lim, "%s s (%s)" % (sec(t), sv), verdict(t <= lim)])
    e2 = [d for d in e2 if d.get("control_points") == 99856 and d.get("input", "ascii") == "ascii"
          and d.get("points") == 10**6]
    if e2:
        w = min(d["wall_seconds"] for d in e2)
        rows.append(["end to end, 10^6 ASCII points onto 10^5 control points", "<= 2 s",
                     "%s s wall" % sec(w), verdict(w <= 2.0)])
    pr, _ = load(out, "project")
    pb = best(pr, lambda d: (d["control_points"], d["order"]))
    if pb:
        lo = min(pb.values(), key=lambda d: d[0]["points_per_s"])[0]
        err = max(d[0]["max_param_error"] for d in pb.values())
        ok = lo["points_per_s"] >= 1e6 and err <= 1e-9
        rows.append(["projection (closest point on the surface), to 1e-9", ">= 1 M points/s",
                     "%s M/s (lowest, N = %s, %s), max error %.1e" %
                     (mps(lo["points_per_s"]), "{:,}".format(lo["control_points"]), lo["order"],
                      err), verdict(ok)])
    table(["target", "goal", "measured", ""], rows)
    e2e_targets(out, verdict)


def e2e_targets(out, verdict):
    """Issue 20's targets from the e2e section: the best wall time of each
    (N, input) at 10^6 points, the ratio to the better peer, the 10^8 run."""
    peers, _ = load(out, "e2e_peers")
    allrun, _ = load(out, "e2e")
    one = best([d for d in allrun if d.get("points") == 10**6],
               lambda d: (d["control_points"], d.get("input", "ascii")), "wall_seconds")
    if not one:
        return
    w = {k: v[0]["wall_seconds"] for k, v in one.items()}
    cg = {d["control_points"]: d["seconds"] for d in peers if d.get("peer") == "scipy_cg"}
    asm = {d["control_points"]: d["assembly_seconds"] for d in peers
           if d.get("peer") == "cholmod_assembly"}
    ch = {d["control_points"]: d["seconds"] for d in peers
          if d.get("e2e") and d.get("bench") == "cholmod"}
    rows = []
    for inp, small, lim in (("ascii", 0.2, 0.5), ("bin", 0.08, None)):
        c = [(t, n) for (n, i), t in w.items() if i == inp and n <= 10**4]
        if c:
            t, n = max(c)
            rows.append(["%s, 10^6 points, N <= 10^4" % inp, "<= %g s" % small,
                         "%s s (slowest, N = %s)" % (sec(t), "{:,}".format(n)),
                         verdict(t <= small)])
        c = [t for (n, i), t in w.items() if i == inp and decade(n) == 10**5]
        if c and lim:
            rows.append(["%s, 10^6 points, N = 10^5" % inp, "<= %g s" % lim,
                         "%s s" % sec(c[0]), verdict(c[0] <= lim)])
        rat = []
        for (n, i), t in w.items():
            pe = [cg[n]] if n in cg else []
            if n in asm and n in ch:
                pe.append(asm[n] + ch[n])
            if i == inp and pe:
                rat.append((min(pe) / t, n))
        if rat:
            r, n = min(rat)
            rows.append(["%s: >= 10x the better of scipy CG and CHOLMOD, every N" % inp, ">= 10x",
                         "%.1fx (lowest, N = %s)" % (r, "{:,}".format(n)), verdict(r >= 10)])
    big = [d for d in allrun if d.get("points") == 10**8 and d.get("input") == "bin"
           and decade(d["control_points"]) == 10**4]
    ref = one.get((10000, "bin"))
    if big:
        d = big[0]
        rss = d["peak_rss_bytes"] / ref[0]["peak_rss_bytes"] if ref else None
        rows.append(["10^8 binary points onto N = 10^4", "<= 8 s, peak RSS within 10 % of 10^6",
                     "%s s, RSS %.0f MiB (%s of the 10^6 run)" % (
                         sec(d["wall_seconds"]), d["peak_rss_bytes"] / 2**20,
                         "-" if rss is None else "%.2fx" % rss),
                     verdict(d["wall_seconds"] <= 8 and rss is not None and rss <= 1.10)])
    print("\n## Targets (issue 20)\n")
    table(["target", "goal", "measured", ""], rows)


def main():
    if len(sys.argv) != 3:
        print("usage: tables.py OUTDIR SECTION", file=sys.stderr)
        return 2
    sections = {"machine": machine, "stream": stream, "accumulate": accumulate, "solve": solve,
                "cholmod": cholmod, "fitpack": fitpack, "e2e": e2e, "project": project,
                "targets": targets}
    if sys.argv[2] not in sections:
        print("tables.py: unknown section %s" % sys.argv[2], file=sys.stderr)
        return 2
    sections[sys.argv[2]](sys.argv[1])
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())

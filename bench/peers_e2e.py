#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# bench/peers_e2e.py: the end-to-end peers of `cellfit fit --uv` (issue 20):
# the same points (the .uvxyz.bin file, read by numpy: file I/O NOT timed),
# the same bicubic net (uniform clamped knots on [0,1]^2, nu x nv control
# points), scipy's sparse normal equations R^T R P = R^T Q with a small ridge
# (1e-9 of the mean diagonal: cellfit's Eq. 7 smoothing has no scipy
# counterpart; the ridge only keeps empty cells solvable). Timed in-process:
#   scipy_cg:  assembly + Jacobi-preconditioned CG for x, y, z (rtol 1e-10);
#   cholmod:   assembly here, then the system is written as CFNE0001 (not
#              timed) for bench/cholmod_bench.c, whose analyse + factor +
#              solve run.sh adds to "assembly_seconds".
# Prints one JSON line per peer; peak RSS of this process (ru_maxrss).
import argparse
import json
import resource
import struct
import time

import numpy as np
import scipy
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.interpolate import BSpline


def knots(n, p=3):
    inner = np.linspace(0.0, 1.0, n - p + 1)
    return np.concatenate([np.zeros(p), inner, np.ones(p)])


def assemble(pts, nu, nv):
    u, v, Q = pts[:, 0], pts[:, 1], pts[:, 2:5]
    Bu = BSpline.design_matrix(np.clip(u, 0, 1), knots(nu), 3).tocsr()
    Bv = BSpline.design_matrix(np.clip(v, 0, 1), knots(nv), 3).tocsr()
    m = len(u)
    iu, iv = Bu.indices.reshape(m, 4), Bv.indices.reshape(m, 4)
    bu, bv = Bu.data.reshape(m, 4), Bv.data.reshape(m, 4)
    cols = (iv[:, :, None] * nu + iu[:, None, :]).reshape(m, 16)
    vals = (bv[:, :, None] * bu[:, None, :]).reshape(m, 16)
    R = sp.csr_matrix((vals.ravel(), cols.ravel(), np.arange(0, 16 * m + 1, 16)),
                      shape=(m, nu * nv))
    A = (R.T @ R).tocsr()
    b = R.T @ Q
    ridge = 1e-9 * A.diagonal().mean()
    A = A + ridge * sp.identity(nu * nv, format="csr")
    return A, b


def rss_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", required=True, help="u v x y z as little-endian float64")
    ap.add_argument("--nu", type=int, required=True)
    ap.add_argument("--nv", type=int, required=True)
    ap.add_argument("--cfne", help="write the system here for bench/cholmod_bench")
    a = ap.parse_args()
    pts = np.fromfile(a.points, dtype="<f8").reshape(-1, 5)
    n = a.nu * a.nv
    t0 = time.perf_counter()
    A, b = assemble(pts, a.nu, a.nv)
    t_asm = time.perf_counter() - t0
    d = A.diagonal()
    M = spla.LinearOperator(A.shape, matvec=lambda x: x / d)
    P = np.zeros((n, 3))
    its = [0]

    def count(_):
        its[0] += 1

    for c in range(3):
        kw = {"tol": 1e-10} if tuple(map(int, scipy.__version__.split(".")[:2])) < (1, 12) \
            else {"rtol": 1e-10}
        P[:, c], info = spla.cg(A, b[:, c], M=M, maxiter=20000, callback=count, atol=0.0, **kw)
    t_cg = time.perf_counter() - t0
    rel = max(np.linalg.norm(b[:, c] - A @ P[:, c]) / np.linalg.norm(b[:, c]) for c in range(3))
    base = {"points": len(pts), "control_points": n, "nu": a.nu, "nv": a.nv}
    print(json.dumps(dict(base, bench="e2e_peer", peer="scipy_cg", seconds=t_cg,
                          assembly_seconds=t_asm, iterations=its[0], rel_residual=rel,
                          peak_rss_mib=rss_mib())))
    if a.cfne:
        U = sp.triu(A).tocoo()
        with open(a.cfne, "wb") as f:
            f.write(b"CFNE0001" + struct.pack("<qq", n, U.nnz))
            rec = np.empty(U.nnz, dtype=[("r", "<i8"), ("c", "<i8"), ("v", "<f8")])
            rec["r"], rec["c"], rec["v"] = U.row, U.col, U.data
            rec.tofile(f)
            np.ascontiguousarray(b, dtype="<f8").tofile(f)
        print(json.dumps(dict(base, bench="e2e_peer", peer="cholmod_assembly",
                              assembly_seconds=t_asm, peak_rss_mib=rss_mib())))


if __name__ == "__main__":
    main()

# SPDX-License-Identifier: MIT
# tests/cli/fpcount.py: the data footprint counted independently of cellfit
# (tests/cli/report_footprint.sh): `python3 fpcount.py INFO UVFILE` reads
# the knots from `cellfit info` output and the points' parameters, splits
# every non-empty knot span pair into 2 x 2 cells, and prints
# "cells filled empty outline" (outline: cells with points beside a cell
# without, 4-neighbours). `python3 fpcount.py --png MAP.png` prints the
# count of pixels of the hatch (0x5A5A5A) and of black (0x000000: the
# outline, and the title, scale bar and tolerance lines of every map).
import struct
import sys
import zlib

SUB = 2


def knots(info, name):
    for line in open(info):
        if line.startswith(name + " knots"):
            return [float(x) for x in line.split(":", 1)[1].split()]
    raise SystemExit("no %s knots in %s" % (name, info))


def cells_of(K):
    """The cells along one direction: (lo, hi) of each, in order."""
    out = []
    for a, b in zip(K, K[1:]):
        if b > a:
            for s in range(SUB):
                out.append((a + (b - a) * s / SUB, a + (b - a) * (s + 1) / SUB))
    return out


def index(cs, x):
    for i, (a, b) in enumerate(cs):
        if a <= x < b or (i == len(cs) - 1 and x == b):
            return i
    return None


def count(info, uvfile):
    cu, cv = cells_of(knots(info, "u")), cells_of(knots(info, "v"))
    n = {}
    for line in open(uvfile):
        u, v = (float(x) for x in line.split()[:2])
        i, j = index(cu, u), index(cv, v)
        if i is not None and j is not None:
            n[(i, j)] = n.get((i, j), 0) + 1
    filled = len(n)
    cells = len(cu) * len(cv)
    outline = 0
    for (i, j) in n:
        for a, b in ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)):
            if 0 <= a < len(cu) and 0 <= b < len(cv) and (a, b) not in n:
                outline += 1
                break
    print(cells, filled, cells - filled, outline)


def png_pixels(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, w, h = 8, b"", 0, 0
    while pos < len(data):
        ln, typ = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + ln]
        if typ == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype == 2, "RGB 8-bit expected"
        elif typ == b"IDAT":
            idat += body
        pos += 12 + ln
    raw, rows, prev, stride = zlib.decompress(idat), [], bytearray(w * 3), w * 3
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b = prev[x]
            c = prev[x - 3] if x >= 3 else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, rows


def png_count(path):
    w, h, rows = png_pixels(path)
    hatch = outline = 0
    for y in range(h):
        line = rows[y]
        for x in range(w):
            rgb = tuple(line[3 * x:3 * x + 3])
            if rgb == (0x5A, 0x5A, 0x5A):
                hatch += 1
            elif rgb == (0, 0, 0):
                outline += 1
    print(hatch, outline)


if __name__ == "__main__":
    if sys.argv[1] == "--png":
        png_count(sys.argv[2])
    else:
        count(sys.argv[1], sys.argv[2])

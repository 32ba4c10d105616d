#!/usr/bin/env python3
"""Read a large binary 58b file (written by lamdyn) with lamdyn and with pyuff, side by side.

Usage: python3 tools/uff/bench_vs_pyuff.py [N_FRF LINES REPEATS]   (default 400 16384 3: 105 MB)
Needs `cargo build --release -p lamdyn-uff --example uff_bench` and `pip install pyuff`.
Prints a markdown table (docs/uff.md); times are the median of REPEATS runs of a full read in a
fresh process each (lamdyn: its own timer around read_path; pyuff: UFF(path).read_sets()).
"""
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import pyuff

N, LINES, REPEATS = (int(a) for a in (sys.argv[1:4] if len(sys.argv) >= 4 else ("400", "16384", "3")))
BIN = "target/release/examples/uff_bench"

with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "big.uff")
    subprocess.run([BIN, "write", path, str(N), str(LINES)], check=True, capture_output=True)
    size = os.path.getsize(path)
    lam, py = [], []
    checksum_l = checksum_p = None
    for _ in range(REPEATS):
        out = subprocess.run([BIN, "read", path], check=True, capture_output=True, text=True).stdout.split()
        lam.append(float(out[0]))
        checksum_l = float(out[2])
        t = time.perf_counter()
        sets = pyuff.UFF(path).read_sets()
        py.append(time.perf_counter() - t)
        checksum_p = float(sum(np.sum(np.real(s["data"])) for s in sets))
    tl, tp = statistics.median(lam), statistics.median(py)
    cores = os.cpu_count()
    print(f"file: {size / 1e6:.1f} MB, {N} FRFs x {LINES} lines, complex double, binary 58b; {cores} cores; pyuff {pyuff.__version__}")
    print(f"checksums (sum of real parts): lamdyn {checksum_l:.9e}, pyuff {checksum_p:.9e}, rel diff {abs(checksum_l - checksum_p) / abs(checksum_p):.1e}")
    print()
    print("| reader | median of %d | throughput | ratio |" % REPEATS)
    print("|---|---|---|---|")
    print(f"| lamdyn | {tl:.3f} s | {size / 1e6 / tl:.0f} MB/s | 1 |")
    print(f"| pyuff | {tp:.3f} s | {size / 1e6 / tp:.0f} MB/s | {tp / tl:.1f}x slower |")

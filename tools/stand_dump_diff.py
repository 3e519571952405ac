#!/usr/bin/env python3
"""Compares two leaf-cluster dumps of the stand bench (benches/stand.rs, SYLVA_STAND_DUMP=FILE:
little-endian f32 rows of tree index, centre x, y, z (m), light i, light in the analysis i_l0,
radius (m)) cluster by cluster, in order, and prints what a change moved (BENCHMARKS.md, round
40): |delta light| mean, 99th percentile and largest, the share of clusters whose light is equal
bit for bit and that differ by more than 1e-3, the clusters whose centre moved more than 1 mm and
1 cm, the largest move, and the mean light of both. Clusters are matched by their place in the
dump, so two runs with different cluster counts per tree (branches pruned in one run only) are
compared tree by tree up to the shorter list. Usage: stand_dump_diff.py BEFORE AFTER"""
import sys
import numpy as np

def load(p):
    a = np.fromfile(p, dtype='<f4')
    return a.reshape(-1, 7)

a, b = load(sys.argv[1]), load(sys.argv[2])
if len(a) != len(b) or not np.array_equal(a[:, 0], b[:, 0]):
    # match tree by tree up to the shorter list of each tree
    ia, ib = [], []
    for t in np.unique(a[:, 0]):
        xa, xb = np.nonzero(a[:, 0] == t)[0], np.nonzero(b[:, 0] == t)[0]
        n = min(len(xa), len(xb))
        ia.extend(xa[:n]); ib.extend(xb[:n])
    print(f"cluster counts differ ({len(a)} / {len(b)}): {len(ia)} matched by tree and order")
    a, b = a[ia], b[ib]
dl = np.abs(a[:, 4].astype(np.float64) - b[:, 4])
mv = np.linalg.norm(a[:, 1:4].astype(np.float64) - b[:, 1:4], axis=1)
print(f"clusters {len(a)}; |dlight| mean {dl.mean():.3e}, p99 {np.percentile(dl, 99):.3e}, max {dl.max():.3f}; "
      f"equal {np.mean(a[:, 4] == b[:, 4]) * 100:.1f} %, > 1e-3 {np.mean(dl > 1e-3) * 100:.1f} %, > 0.05 {np.mean(dl > 0.05) * 100:.2f} %; "
      f"moved > 1 mm {np.mean(mv > 1e-3) * 100:.1f} %, > 1 cm {np.mean(mv > 1e-2) * 100:.1f} %, max {mv.max():.2f} m; "
      f"mean light {a[:, 4].mean():.5f} -> {b[:, 4].mean():.5f}; dark (0) {np.mean(a[:, 4] == 0) * 100:.2f} % -> {np.mean(b[:, 4] == 0) * 100:.2f} %")

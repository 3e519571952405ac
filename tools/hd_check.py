#!/usr/bin/env python3
"""Slenderness (H/D, m/m: 100 * height_m / dbh_cm) of the living trees of an inventory with a
DBH (>= 1.3 m tall): share above 100 and 150, percentiles, maximum and the slenderest trees;
per species the median and the share above 100.

    python3 tools/hd_check.py OUT_DIR/inventory/year_0150.parquet   (a file or a partitioned folder)

Reads with pyarrow. Prints Markdown."""
import sys
import pyarrow.parquet as pq
import pyarrow.compute as pc

t = pq.read_table(sys.argv[1])
cols = t.column_names
h = t.column("height_m").to_pylist()
d = t.column("dbh_cm").to_pylist()
sp = t.column("species").to_pylist() if "species" in cols else ["?"] * len(h)
st = t.column("status").to_pylist() if "status" in cols else ["alive"] * len(h)
rows = [(100.0 * hh / dd, hh, dd, s) for hh, dd, s, x in zip(h, d, sp, st) if dd and dd > 0 and hh >= 1.3 and str(x) in ("alive", "0", "None", "live")]
if not rows:
    sys.exit(f"no living trees with a DBH in {sys.argv[1]} (status values: {sorted(set(map(str, st)))[:5]})")
hd = sorted(r[0] for r in rows)
n = len(hd)
q = lambda p: hd[min(n - 1, int(p * n))]
print(f"trees with a DBH: {n}; H/D > 100: {sum(x > 100 for x in hd) / n * 100:.1f} %; > 150: {sum(x > 150 for x in hd) / n * 100:.2f} %; "
      f"median {q(0.5):.0f}, p90 {q(0.9):.0f}, p99 {q(0.99):.0f}, max {hd[-1]:.0f}")
print("slenderest: " + "; ".join(f"{s} {hh:.2f} m on {dd:.2f} cm (H/D {x:.0f})" for x, hh, dd, s in sorted(rows, reverse=True)[:3]))
print()
print("| species | trees | median H/D | H/D > 100 | H/D > 150 |")
print("|---|---|---|---|---|")
by = {}
for x, _, _, s in rows:
    by.setdefault(s, []).append(x)
for s, v in sorted(by.items(), key=lambda kv: -len(kv[1])):
    v.sort()
    print(f"| {s} | {len(v)} | {v[len(v) // 2]:.0f} | {sum(x > 100 for x in v) / len(v) * 100:.1f} % | {sum(x > 150 for x in v) / len(v) * 100:.2f} % |")

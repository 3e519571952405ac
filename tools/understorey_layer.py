#!/usr/bin/env python3
"""Which layer the suppressed old trees stand in (issue 35, round 40): of the living trees aged >= 50
and under 10 m, the share under 2/3 of the local top height (the tallest crown over their 5 m
light cell, stamped as the light phase stamps crowns: the equal-area square of the crown, here
the inventory's outline radius, so an estimate).

Usage: python3 tools/understorey_layer.py RUN/inventory/year_0150.parquet  (needs pyarrow, pandas, numpy)
"""
import sys, numpy as np, pyarrow.parquet as pq
t = pq.read_table(sys.argv[1], columns=["species","age_yr","height_m","x_m","y_m","crown_radius_m","status"]).to_pandas()
t = t[t.status == "alive"]
cell = 5.0
x, y, h, r = t.x_m.values, t.y_m.values, t.height_m.values, t.crown_radius_m.values
x0, y0 = x.min(), y.min()
nc, nr = int((x.max()-x0)/cell)+2, int((y.max()-y0)/cell)+2
top = np.zeros((nr, nc), np.float32)
s = np.maximum(r, 0.05) * 0.8862269
c0 = np.floor((x - s - x0)/cell).astype(int); c1 = np.floor((x + s - x0)/cell).astype(int)
r0 = np.floor((y - s - y0)/cell).astype(int); r1 = np.floor((y + s - y0)/cell).astype(int)
span = int(max((c1-c0).max(), (r1-r0).max()))
for dc in range(span+1):
    for dr in range(span+1):
        m = (c0+dc <= c1) & (r0+dr <= r1)
        cc = np.clip(c0[m]+dc, 0, nc-1); rr = np.clip(r0[m]+dr, 0, nr-1)
        np.maximum.at(top, (rr, cc), h[m])
own = top[np.floor((y-y0)/cell).astype(int), np.floor((x-x0)/cell).astype(int)]
t["rel"] = h / np.maximum(own, 1e-3)
for sp in ["sessile_oak", "scots_pine", "beech"]:
    d = t[(t.species == sp) & (t.age_yr >= 50) & (t.height_m < 10)]
    if len(d):
        print(f"{sp}: aged>=50 under 10 m: {len(d)}, share below 2/3 of the local top (outline crowns, 5 m cells): {(d.rel < 2/3).mean():.3f}; median local top {np.median(own[d.index.map(t.index.get_loc)]):.1f} m")

#!/usr/bin/env python3
"""Tree balance of a run's stand table (round 46, trial 46 D6): checks stems(t) = stems(t-1) +
regen_recruited(t) - sum of deaths_*(t) in every year (exact in a run without plantings) and
reports the worst miss of the rounded stems_ha x area_ha. Usage: stand_balance.py RUN/stand_table.csv"""
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
dc = [k for k in rows[0] if k.startswith("deaths_") and not k.endswith("_ha")]
bad = 0; worst_old = 0.0
for a, b in zip(rows, rows[1:]):
    d = sum(int(b[k]) for k in dc)
    want = int(a["stems"]) + int(b["regen_recruited"]) - d
    bad += int(b["stems"]) != want
    area = float(b["area_ha"])
    old = float(a["stems_ha"]) * area + int(b["regen_recruited"]) - d - float(b["stems_ha"]) * area
    worst_old = max(worst_old, abs(old))
print(f"{sys.argv[1]}: {len(rows)-1} years, deaths columns {dc}; balance misses in {bad} years with `stems`; with rounded stems_ha x area the worst miss is {worst_old:.1} trees")

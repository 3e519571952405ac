#!/usr/bin/env python3
"""Suppressed understorey of a run's tree inventory (issue 35, round 39; trial 38's figure).

Usage: python3 tools/understorey_check.py RUN/inventory/year_0150.parquet

For each species of the default pool: the trees aged >= 50 years, and the share of them under
10 m tall with their median age and DBH (light-demanders persisting suppressed under a closed
canopy). Needs pyarrow and pandas.
"""
import sys

import pyarrow.parquet as pq

t = pq.read_table(sys.argv[1], columns=["species", "age_yr", "height_m", "dbh_cm"]).to_pandas()
print("trees", len(t))
for sp in ["sessile_oak", "scots_pine", "silver_birch", "norway_spruce", "norway_maple", "beech"]:
    d = t[(t.species == sp) & (t.age_yr >= 50)]
    if len(d) == 0:
        print(sp, 0)
        continue
    s = d[d.height_m < 10]
    age = s.age_yr.median() if len(s) else 0
    dbh = s.dbh_cm.median() if len(s) else 0
    print(f"{sp}: aged>=50 {len(d)}, under 10 m {len(s) / len(d):.3f} (median age {age:.0f}, DBH {dbh:.1f} cm)")

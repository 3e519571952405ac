#!/usr/bin/env python3
"""Where a pure stand's main-stand Dq change comes from, period by period (issue 35, round 39:
why the young thinned beech's Dq grows slowly at ages 35-45).

    python3 tools/dq_components.py [--species beech|spruce] OUT_DIR [PLANT_AGE] [FROM_AGE] [TO_AGE]

OUT_DIR holds a run's inventory/year_YYYY.csv of every year (`snapshot_every = 1`,
`--inventory csv`; age = PLANT_AGE + year, default 3). Periods of 5 years from FROM_AGE
(default 25) to TO_AGE (default 100). The main stand is counted as tools/stem_loss.py counts it
(stems >= 7 cm at least a third of the top height tall). For each period a0 -> a1, with M0, M1
the main stands and S the stems of M0 still living at a1 (cm/yr, the period's change / 5):

- growth: Dq of S at a1 less Dq of S at a0 (the kept stems' own diameter growth);
- removal: Dq of S at a0 less Dq of M0 (the stems that died or were thinned: positive when
  they were the smaller ones, the thinning's shift);
- ingrowth: Dq of M1 less Dq of S at a1 (stems that joined the main stand by passing 7 cm or a
  third of top height: negative when they are small);
- their sum, the main stand's Dq change, beside the table's; and the kept stems' median DBH
  increment (cm/yr) of the period, with the stand's stems joining and leaving.

Reads files only. Prints Markdown."""
import math, sys
from pathlib import Path

from wiedemann import class_one, inventory, print_table, run_area_ha, species_args, top_height

species, args = species_args(sys.argv[1:])
out = Path(args[0])
plant = float(args[1]) if len(args) > 1 else 3.0
a_from = int(args[2]) if len(args) > 2 else 25
a_to = int(args[3]) if len(args) > 3 else 100
table = {int(float(r["age"])): float(r["d_q_cm"]) for r in class_one(species)}


area = run_area_ha(out)


def main_stand(year):
    """({id: dbh} of the main stand, {id: dbh} of every living stem with a DBH) of `year`, or
    (None, None) without its inventory: the main stand as tools/stem_loss.py counts it (top
    height over the upper layer, as sim::stats::top_height)."""
    inv = inventory(out, year)
    if inv is None:
        return None, None
    alive = {i: float(r["dbh_cm"]) for i, r in inv[0].items()}
    hts = {i: float(r["height_m"]) for i, r in inv[0].items()}
    trees = [(d, hts[i]) for i, d in alive.items() if d >= 7.0 and hts[i] >= 1.3]
    h = top_height(trees, area)
    return {i: d for i, d in alive.items() if d >= 7.0 and hts[i] >= h / 3.0}, alive


def dq(ds):
    return math.sqrt(sum(d * d for d in ds) / len(ds)) if ds else float("nan")


rows = []
for a0 in range(a_from, a_to, 5):
    a1 = a0 + 5
    m0, _alive0 = main_stand(int(round(a0 - plant)))
    m1, alive1 = main_stand(int(round(a1 - plant)))
    if m0 is None or m1 is None or not m0:
        continue
    s = [i for i in m0 if i in alive1]
    dq_m0, dq_m1 = dq(m0.values()), dq(m1.values())
    dq_s0, dq_s1 = dq([m0[i] for i in s]), dq([alive1[i] for i in s])
    inc = sorted(alive1[i] - m0[i] for i in s)
    med = inc[len(inc) // 2] if inc else float("nan")
    joined = len([i for i in m1 if i not in m0])
    t = (table[a1] - table[a0]) / 5 if a0 in table and a1 in table else float("nan")
    rows.append("| " + " | ".join([f"{a0}-{a1}", f"{len(m0)} -> {len(m1)}", f"{len(m0) - len(s)}", f"{joined}", f"{(dq_s1 - dq_s0) / 5:.2f}", f"{(dq_s0 - dq_m0) / 5:+.2f}", f"{(dq_m1 - dq_s1) / 5:+.2f}", f"{(dq_m1 - dq_m0) / 5:.2f}", f"{t:.2f}", f"{med / 5:.2f}"]) + " |")
print_table("| ages | main stand (trees) | left | joined | growth cm/yr | removal | ingrowth | Dq change | table | median kept ΔDBH cm/yr |", rows)

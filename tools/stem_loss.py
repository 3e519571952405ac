#!/usr/bin/env python3
"""Where a thinned pure stand's stems go, period by period from planting, beside a Wiedemann
yield table, class I (issue 35, round 34: why the thinned beech ends with a third of the table's
stems).

    python3 tools/stem_loss.py [--species beech|spruce] OUT_DIR [PLANT_AGE] [TO_AGE]

OUT_DIR holds a run's stand_table.csv and inventory/year_YYYY.csv of every year
(`snapshot_every = 1`, `--inventory csv`; age = PLANT_AGE + year, default 3). Periods of 5
years end at the ages 10, 15, ..., TO_AGE (default 100); the first starts at the planting.

Table 1, the stems: living stems with a DBH at the period's end (N) and the main stand (N7:
stems >= 7 cm at least a third of top height tall, as the thinnings and tests/yield_thinned.rs
count it); the stems lost in the period by cause, from the inventories' dead rows
(harvest = thinnings; stress = crowding / suppression; background; age; wind); the share of
the stems at the period's start that were lost (all causes, and without the thinnings); the
table's N and its loss N(a - 5) - N(a) as a share (the table gives no removed stand, only the
remaining one: tests/data/stands/README.md), and the ratio N7 / table N.

Table 2, the diameter distribution and the thinnings: at each period's start, the coefficient
of variation (sd / mean) of the DBH of the stems >= 7 cm and of all stems with a DBH, and the
dominant diameter D100 (quadratic mean of the 100 thickest stems per ha) over its Dq; for each thinning year, the main stand's Dq (last year's inventory) before and
after removing the stems that thinning took, their ratio (the thinning's shift of Dq) and the
removed stems' quadratic mean DBH over the Dq before.

Table 3, the gap to the table at its ages: ln(N7 / N_table) = ln(RD / RD_table)
- s ln(Dq7 / Dq_table), where RD = N (Dq / 25)^s / SDI_max is the relative density on the
species' line (life.density: s = -reineke_slope); the two terms, and the share of the gap that
the Dq term makes.

Reads files only. Prints Markdown."""
import math, sys
from pathlib import Path

from wiedemann import class_one, print_table, run_area_ha, species_args, species_number, top_height
from wiedemann import inventory as read_inventory

species, args = species_args(sys.argv[1:])
out = Path(args[0])
plant = float(args[1]) if len(args) > 1 else 3.0
a_to = int(args[2]) if len(args) > 2 else 100
step = 5
table = {int(float(r["age"])): (float(r["n_ha"]), float(r["d_q_cm"])) for r in class_one(species)}
sdi_max, s = species_number(species, "sdi_max"), -species_number(species, "reineke_slope")
area = run_area_ha(out)
CAUSES = ("harvest", "stress", "background", "age", "wind")
_cache = {}


def inventory(year):
    """({id: dbh} of the living stems with a DBH, [(cause, id, dbh)] of the year's dead,
    {id: dbh} of the main stand: stems >= 7 cm at least a third of the top height of the stems
    >= 7 cm tall, as the thinnings (sim::phases::management::MAIN_STAND_SHARE) and
    tests/yield_thinned.rs count it; the yield tables leave a lower layer of ingrowth out)."""
    if year in _cache:
        return _cache[year]
    inv = read_inventory(out, year)
    if inv is not None:
        alive = {i: float(r["dbh_cm"]) for i, r in inv[0].items()}
        hts = {i: float(r["height_m"]) for i, r in inv[0].items()}
        dead = [(c, r["id"], float(r["dbh_cm"])) for c, r in inv[1]]
        stock = [(d, hts[i]) for i, d in alive.items() if d >= 7.0 and hts[i] >= 1.3]
        low = top_height(stock, area) / 3.0
        main = {i: d for i, d in alive.items() if d >= 7.0 and hts[i] >= low}
    else:
        alive, dead, main = None, [], None
    _cache[year] = (alive, dead, main)
    return alive, dead, main


def dq(ds):
    return math.sqrt(sum(d * d for d in ds) / len(ds)) if ds else 0.0


def cv(ds):
    if len(ds) < 2:
        return 0.0
    mu = sum(ds) / len(ds)
    return math.sqrt(sum((d - mu) ** 2 for d in ds) / (len(ds) - 1)) / mu


def d100(ds):
    k = max(1, int(round(100 * area)))
    return dq(sorted(ds, reverse=True)[:k])


t1, t2, t3 = [], [], []
ages = [plant] + list(range(10, a_to + 1, step))
for a0, a1 in zip(ages, ages[1:]):
    y0, y1 = int(round(a0 - plant)), int(round(a1 - plant))
    start, _d, start_main = inventory(y0) if y0 > 0 else (None, None, None)
    end, _d, end_main = inventory(y1)
    if end is None:
        continue
    lost = {c: 0 for c in CAUSES}
    for y in range(y0 + 1, y1 + 1):
        alive_prev = inventory(y - 1)[2] if y > 1 else None
        _al, dead, _m = inventory(y)
        harvested = [i for c, i, _d in dead if c == "harvest"]
        for c, _i, _d in dead:
            lost[c] = lost.get(c, 0) + 1
        if harvested and alive_prev:
            before = list(alive_prev.values())
            hs = set(harvested)
            after = [d for i, d in alive_prev.items() if i not in hs]
            rem = [alive_prev[i] for i in harvested if i in alive_prev]
            t2.append(f"| thinning, age {plant + y:.0f} | | | | {len(before) / area:.0f} → {len(after) / area:.0f} | {dq(before):.1f} → {dq(after):.1f} (× {dq(after) / dq(before):.3f}) | {dq(rem) / dq(before):.2f} |")
    n0 = len(start) / area if start else None
    n = len(end) / area
    n7 = len(end_main) / area
    tot = sum(lost.values()) / area
    nat = tot - lost["harvest"] / area
    share = lambda x: f"{100 * x / n0:.0f} %" if n0 else "—"
    t = table.get(int(a1))
    tb = table.get(int(a0))
    if t and tb:
        tab = f"{t[0]:.0f} | {tb[0] - t[0]:.0f} ({100 * (tb[0] - t[0]) / tb[0]:.0f} %) | {n7 / t[0]:.2f}"
    elif t:
        tab = f"{t[0]:.0f} | — | {n7 / t[0]:.2f}"
    else:
        tab = "— | — | —"
    t1.append(f"| {a0:.0f}–{a1:.0f} | {n:.0f} / {n7:.0f} | " + " / ".join(f"{lost.get(c, 0) / area:.0f}" for c in CAUSES) + f" | {share(tot)}, {share(nat)} | {tab} |")
    if start:
        st7 = list(start_main.values())
        sall = list(start.values())
        t2.append(f"| start of {a0:.0f}–{a1:.0f} | {cv(st7):.3f} | {cv(sall):.3f} | {d100(st7) / dq(st7) if st7 else 0:.2f} | {len(st7) / area:.0f} | {dq(st7):.1f} | |")
    if t:
        d7 = list(end_main.values())
        q7 = dq(d7)
        rd = n7 * (q7 / 25) ** s / sdi_max
        rdt = t[0] * (t[1] / 25) ** s / sdi_max
        gap = math.log(n7 / t[0])
        a_rd, a_dq = math.log(rd / rdt), -s * math.log(q7 / t[1])
        t3.append(f"| {a1:.0f} | {n7:.0f} / {t[0]:.0f} ({100 * (n7 / t[0] - 1):+.0f} %) | {q7:.1f} / {t[1]:.1f} ({100 * (q7 / t[1] - 1):+.0f} %) | {rd:.2f} / {rdt:.2f} | {gap:+.3f} | {a_rd:+.3f} | {a_dq:+.3f} | {100 * a_dq / gap:.0f} % |")

print_table("| period (age) | N / N7 at its end | lost: " + " / ".join(CAUSES) + " (stems/ha) | lost of the start's N: all, without thinnings | table N | table lost (share) | N7 / table N |", t1)
print()
print_table("| when | CV of DBH, main stand | CV, all stems | D100 / Dq7 | N7 (before → after) | Dq7 cm (before → after, shift) | removed Dq / Dq before |", t2)
print()
print_table("| age | N7 / table N | Dq7 / table Dq (cm) | RD / table RD | ln(N7 / N_t) | RD term | Dq term | Dq term's share |", t3)

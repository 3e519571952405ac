#!/usr/bin/env python3
"""Issue 35 round 43: the thinned beech run's main stand, age by age, beside Wiedemann's
moderate-thinning table, class I (where the run departs from it).

    python3 tools/experiments/r43_trajectory.py OUT_DIR [PLANT_AGE]

OUT_DIR is a `sylva simulate` run of scenarios/thinning_beech.toml with `snapshot_every = 1`
and `--inventory csv` (age = PLANT_AGE + year, default 3); the table starts at age 30 (nan before). Ages 20-60 every 5 years, then
70-100 every 10. Main stand as tests/yield_thinned.rs counts it: living stems >= 7 cm DBH at
least a third (MAIN_STAND_SHARE) of the stand's top height (sim::stats::top_height) tall.
N, Dq, BA of the main stand; h_q the mean height of its stems whose DBH is within 10 % of Dq
(the height of the tree of mean basal area, as the table gives it); H/D the mean of 100 h/d
over the main stand's stems and h_q/Dq; N<7 the living stems with a DBH under 7 cm (they count
in the thinning's relative density but are not in the main stand). Prints Markdown."""
import math, sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from wiedemann import class_one, inventory, run_area_ha, top_height

out = Path(sys.argv[1])
plant = float(sys.argv[2]) if len(sys.argv) > 2 else 3.0
table = {float(r["age"]): r for r in class_one("beech")}
area = run_area_ha(out)
print("| age | N sim / table | Dq cm sim / table | BA m²/ha sim / table | h_q m sim / table | H/D mean; h_q/Dq sim / table h_q/Dq | N<7 cm |")
print("|---|---|---|---|---|---|---|")
for age in list(range(20, 61, 5)) + list(range(70, 101, 10)):
    inv = inventory(out, int(age - plant))
    if inv is None:
        continue
    living = inv[0]
    trees = [(float(r["dbh_cm"]), float(r["height_m"])) for r in living.values()]
    top = top_height([t for t in trees if t[1] >= 1.3], area)
    main = [t for t in trees if t[0] >= 7.0 and t[1] >= top / 3.0]
    small = sum(1 for t in trees if t[0] < 7.0) / area
    t = table.get(float(age))
    tn, tdq, tba, thq = (float(t["n_ha"]), float(t["d_q_cm"]), float(t["ba_m2_ha"]), float(t["h_q_m"])) if t else (math.nan,) * 4
    if not main:
        print(f"| {age} | 0 / {tn:.0f} | | | | | {small:.0f} |")
        continue
    n = len(main) / area
    dq = math.sqrt(sum(d * d for d, _ in main) / len(main))
    ba = math.pi / 4 * n * dq * dq / 1e4
    near = [h for d, h in main if abs(d - dq) <= 0.1 * dq] or [h for _d, h in main]
    hq = sum(near) / len(near)
    hd = sum(100 * h / d for d, h in main) / len(main)
    pc = lambda s, x: f"{(s - x) / x * 100:+.0f} %"
    print(f"| {age} | {n:.0f} / {tn:.0f} ({pc(n, tn)}) | {dq:.1f} / {tdq:.1f} ({pc(dq, tdq)}) | {ba:.1f} / {tba:.1f} | {hq:.1f} / {thq:.2f} | {hd:.0f}; {100 * hq / dq:.0f} / {100 * thq / tdq:.0f} | {small:.0f} |")

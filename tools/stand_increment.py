#!/usr/bin/env python3
"""Where a thinned pure stand's growth and stems go, period by period, beside a Wiedemann yield
table (class I) (issue 35, round 31: the thinned beech stand against the moderate-thinning table).

    python3 tools/stand_increment.py [--species beech|spruce] OUT_DIR [PLANT_AGE] [STEP] [FROM_AGE] [TO_AGE]

OUT_DIR holds a run's stand_table.csv (age = PLANT_AGE + year, default 3) and its inventories
inventory/year_YYYY.csv of every year (`snapshot_every = 1`, `--inventory csv`): the living
trees and the trees that died that year with their cause (`dead:harvest` = thinnings,
`dead:stress` = crowding/suppression, `dead:background`). For each STEP-year period (default 5)
ending at an age from FROM_AGE to TO_AGE (default 25 to 100):

Table 1, the stand (all stems with a DBH; the stand table's stems >= 7 cm as N7 / Dq7):
- N, Dq, basal area G at the period's end; N7, Dq7;
- gross basal-area increment per ha and year: the change of the living stand's G plus the G (at
  their last DBH) of the trees that died or were removed in the period, over STEP years;
- gross volume increment per ha and year from the stand table (V = f g h of stems >= 7 cm, the
  model's form factor): the change of `volume_m3_ha` plus `harvest_volume_m3_ha` of the period,
  over STEP years; beside the table's `pai_m3_ha_yr` (mean of the period's two ends);
- stems removed in the period by thinning (harvest), crowding (stress) and background
  mortality, with the quadratic mean DBH of the removed stems, and the table's loss of stems
  `N(a - STEP) - N(a)` and its thinning volume `red_pre_yield_m3_ha_10yr · STEP / 10`
  (merchantable volume, under bark, the table's "reduced" volume).

Table 2, the trees alive at both ends of the period, by their size at its start relative to the
stand's Dq then (suppressed < 0.8 Dq, mean 0.8-1.2, dominant >= 1.2): their number per ha and
mean basal-area increment per tree and year (cm²/yr), and the table's mean-tree increment
`(G(a) - G(a - STEP) + removed G) / N(a) / STEP`, with the removed G taken as the removed volume
(its `red_pre_yield` converted to total volume by the table's V / red_V) over the stand's form
height V / G at the period's start (an approximation: removed trees, being smaller, have a
lower form height, so the table's figure is a lower bound).

Prints Markdown. Reads files only; no model code."""
import csv, math, sys
from pathlib import Path

from wiedemann import class_one, print_table, run_area_ha, species_args, species_number
from wiedemann import inventory as read_inventory

species, args = species_args(sys.argv[1:])
out = Path(args[0])
plant = float(args[1]) if len(args) > 1 else 3.0
step = int(args[2]) if len(args) > 2 else 5
a_from = int(args[3]) if len(args) > 3 else 25
a_to = int(args[4]) if len(args) > 4 else 100
table = {}
for r in class_one(species):
    num = lambda k: float(r[k]) if r[k] not in ("", "NA") else float("nan")
    table[float(r["age"])] = {k: num(k) for k in ("n_ha", "ba_m2_ha", "d_q_cm", "v_m3_ha", "pai_m3_ha_yr", "red_v_m3_ha", "red_pre_yield_m3_ha_10yr")}
crown_c0, crown_c1 = (species_number(species, k) for k in ("crown_c0", "crown_c1"))
rows = {}
with open(out / "stand_table.csv") as f:
    for r in csv.DictReader(f):
        rows[int(r["year"])] = r

g_of = lambda d: math.pi / 4 * d * d / 1e4  # m² of a DBH in cm


def inventory(year):
    """(living {id: dbh}, dead [(cause, dbh)], living {id: (dbh, height, crown base)}) of the
    inventory of `year`, or None."""
    inv = read_inventory(out, year)
    if inv is None:
        return None
    living, died = inv
    alive = {i: float(r["dbh_cm"]) for i, r in living.items()}
    full = {i: (float(r["dbh_cm"]), float(r["height_m"]), float(r["crown_base_m"])) for i, r in living.items()}
    dead = [(c, float(r["dbh_cm"])) for c, r in died if float(r["dbh_cm"]) > 0]
    return alive, dead, full


# PROGNAUS basal-area increment (Monserud & Sterba 1996, For. Ecol. Manage. 80:57-80, Eq. 3;
# coefficients Hasenauer 2000, Die simultanen Eigenschaften von Waldwachstumsmodellen, as
# transcribed in github:SonjaVospernik/Prognaus @ dc7892988f29960b62b59b0a27d23ec7d77d80ff BAI.R,
# BART 10 Buche, BART 1 Fichte): ln(BAI, cm² per 5 yr) = a0 + b1 ln D + b2 D² + b3 ln CR + c1 BAL
# + c2 CCF + site terms. The site terms are those of that function's default arguments (humus F 3
# cm, H 2 cm, soil depth 50 cm, moist, middle slope, soil type 9, vegetation type 1, growth
# district 13) with the scenario's flat ground (slope 0) at 200 m a.s.l.: they sum to `site`.
PROGNAUS = {
    # a0, b1, b2, b3, c1 (per m²/ha of BAL), c2 (per % of CCF), site
    "beech": (-0.644436, 1.589274, -0.000189, 0.630734, -0.016353, -0.000175,
              -0.00308 * 2.0 ** 2 - 0.031316 * 3 + 0.021224 * 2 + 0.458712 + 0.179966),
    "spruce": (0.07, 1.396876, -0.000165, 0.634179, -0.017369, -0.000497,
               -0.003824 * (2.0 - 6) ** 2 - 0.018425 * 3 - 0.009333 * 2 + 0.122647 + 0.410682 + 0.187571),
}


def prognaus_bai(d, cr, bal, ccf_pct):
    """PROGNAUS basal-area increment (cm²/yr) of a tree of DBH d (cm), crown ratio cr (0-1),
    basal area of larger trees bal (m²/ha) in a stand of crown competition factor ccf_pct (%)."""
    a0, b1, b2, b3, c1, c2, site = PROGNAUS[species]
    return math.exp(a0 + b1 * math.log(d) + b2 * d * d + b3 * math.log(max(cr, 0.01)) + c1 * bal + c2 * ccf_pct + site) / 5


area_ha = run_area_ha(out)

stand, trees = [], []
for age in range(a_from, a_to + 1, step):
    y, yb = int(round(age - plant)), int(round(age - step - plant))
    now, before = inventory(y), inventory(yb)
    if now is None or before is None or y not in rows:
        continue
    alive, _, _ = now
    alive_b, _, full_b = before
    dead = {}
    for k in range(yb + 1, y + 1):
        inv = inventory(k)
        for cause, d in inv[1] if inv else []:
            dead.setdefault(cause, []).append(d)
    n = len(alive) / area_ha
    dq = math.sqrt(sum(d * d for d in alive.values()) / len(alive)) if alive else 0.0
    g = sum(g_of(d) for d in alive.values()) / area_ha
    g_b = sum(g_of(d) for d in alive_b.values()) / area_ha
    g_dead = sum(g_of(d) for ds in dead.values() for d in ds) / area_ha
    ig = (g - g_b + g_dead) / step
    r, rb = rows[y], rows[yb]
    harv_v = sum(float(rows[k]["harvest_volume_m3_ha"]) for k in range(yb + 1, y + 1))
    iv = (float(r["volume_m3_ha"]) - float(rb["volume_m3_ha"]) + harv_v) / step
    cnt = lambda c: len(dead.get(c, [])) / area_ha
    qd = lambda c: math.sqrt(sum(d * d for d in dead[c]) / len(dead[c])) if dead.get(c) else 0.0
    t, tb = table.get(float(age)), table.get(float(age - step))
    tab, tab_inc = "— | — | — | —", "—"
    if t and tb:
        pai = (t["pai_m3_ha_yr"] + tb["pai_m3_ha_yr"]) / 2
        red_thin = t["red_pre_yield_m3_ha_10yr"] * step / 10
        thin_v = red_thin * tb["v_m3_ha"] / tb["red_v_m3_ha"]
        g_removed = thin_v / (tb["v_m3_ha"] / tb["ba_m2_ha"])
        ig_t = (t["ba_m2_ha"] - tb["ba_m2_ha"] + g_removed) / step
        tab = f"{t['n_ha']:.0f} / {t['d_q_cm']:.1f} / {t['ba_m2_ha']:.1f} | {ig_t:.2f} | {pai:.1f} | {tb['n_ha'] - t['n_ha']:.0f}, {red_thin:.0f} m³"
        tab_inc = f"{ig_t * 1e4 / t['n_ha']:.1f}"
    elif t:
        tab = f"{t['n_ha']:.0f} / {t['d_q_cm']:.1f} / {t['ba_m2_ha']:.1f} | — | {t['pai_m3_ha_yr']:.1f} | —"
    stand.append(f"| {age - step}–{age} | {n:.0f} / {dq:.1f} / {g:.1f} | {float(r['stems_7cm_ha']):.0f} / {float(r['qmd_7cm_cm']):.1f} | {ig:.2f} | {iv:.1f} | {cnt('harvest'):.0f} ({qd('harvest'):.1f} cm), {cnt('stress'):.0f}, {cnt('background'):.0f} | {tab} |")
    # PROGNAUS's BAI for the period's survivors, from their state at its start: BAL of the
    # larger trees (m²/ha, over the whole site), the stand's CCF (%) from the species'
    # open-grown crown radius c0 + c1 D (Krajicek et al. 1961), crown ratio (h - crown base) / h
    order = sorted(full_b.items(), key=lambda kv: -kv[1][0])
    bal, acc = {}, 0.0
    k = 0
    while k < len(order):
        j = k
        while j < len(order) and order[j][1][0] == order[k][1][0]:
            j += 1
        for i, _v in order[k:j]:
            bal[i] = acc / area_ha
        acc += sum(g_of(v[0]) for _i, v in order[k:j])
        k = j
    ccf_pct = 100 * sum(math.pi * (crown_c0 + crown_c1 * v[0]) ** 2 for v in full_b.values()) / (area_ha * 1e4)
    # survivors by relative size at the start
    dq_b = math.sqrt(sum(d * d for d in alive_b.values()) / len(alive_b)) if alive_b else 0.0
    cls = {"sup": [], "mean": [], "dom": []}
    for i, d1 in alive.items():
        d0 = alive_b.get(i)
        if d0 is None:
            continue
        s = d0 / dq_b
        c = "sup" if s < 0.8 else ("mean" if s < 1.2 else "dom")
        d0_, h0, cb0 = full_b[i]
        cls[c].append(((g_of(d1) - g_of(d0)) * 1e4 / step, prognaus_bai(d0, (h0 - cb0) / h0 if h0 > 0 else 1.0, bal[i], ccf_pct)))
    cell = lambda c: f"{len(cls[c]) / area_ha:.0f}, {sum(v[0] for v in cls[c]) / len(cls[c]):.1f} ({sum(v[1] for v in cls[c]) / len(cls[c]):.1f})" if cls[c] else "0, —"
    allb = [v for c in cls.values() for v in c]
    trees.append(f"| {age - step}–{age} | {dq_b:.1f}, {ccf_pct:.0f} % | {cell('sup')} | {cell('mean')} | {cell('dom')} | {sum(v[0] for v in allb) / len(allb):.1f} ({sum(v[1] for v in allb) / len(allb):.1f}) | {tab_inc} |")

print_table("| period (age) | N / Dq (cm) / G (m²/ha), all stems | N7 / Dq7 | gross BA incr. (m²/ha/yr) | gross V incr. (m³/ha/yr) | removed: thinning (their Dq), stress, background (stems/ha) | table N / Dq / G | table gross BA incr. | table pai (m³/ha/yr) | table: stems lost, thinning volume |", stand)
print()
print_table("| period (age) | Dq (cm), CCF at start | suppressed < 0.8 Dq: stems/ha, BAI (cm²/yr per tree) (PROGNAUS) | mean 0.8–1.2 | dominant ≥ 1.2 | all survivors' BAI (PROGNAUS) | table mean tree's gross BAI |", trees)

#!/usr/bin/env python3
"""A young beech planting's diameter increment split into potential and competition response,
beside PROGNAUS's for the same trees (issue 35, round 33, branch r33h2).

    python3 tools/young_stand_prognaus.py OUT_DIR [PLANT_AGE] [FROM_YEAR] [TO_YEAR] [STEP]

OUT_DIR holds a run of a pure beech stand with inventories of every year (`snapshot_every = 1`,
`--inventory csv`). PLANT_AGE (default 3) turns years into ages. For each year y from FROM_YEAR
(default 4) to TO_YEAR (default 26) in steps of STEP (default 2), over the trees with a DBH
alive in years y and y + 1, prints one Markdown row of means:

- the stand at year y: Dq (cm, trees with a DBH), CCF (%: the open-grown crown areas
  pi (c0 + c1 D)^2 of species/beech.toml's crown allometry over the ground, Krajicek et al.
  1961) and RD (N over the maximum-density line 900 (Dq / 25)^-1.789, beech's `life.density`);
- Sylva: the DBH increment dD (cm/yr) and its potential dd_open = D_open(h + dH) - D_open(h)
  (the open-grown height-DBH curve of the species file's allometry, dH the Chapman-Richards
  height increment at the height's effective age, as `growth::grow` before light, crowding
  and the tree's growth factor), and their ratio (the share the light response, the crowding
  or PROGNAUS modifier and the growth factor leave);
- PROGNAUS (Monserud & Sterba 1996, For. Ecol. Manage. 80:57-80, Eq. 3; Hasenauer 2000's
  beech coefficients as in tools/stand_increment.py, same site terms): the dD of an open tree
  of the same DBH (CR 1, BAL 0, CCF 0), the dD with the tree's crown ratio (h - crown base) / h,
  its basal area of larger trees in the whole plot (m2/ha) and the plot's CCF, and their ratio
  (PROGNAUS's competition response); exp(c2 CCF), the CCF term alone.

BAI (cm2/yr) becomes dD by sqrt(D^2 + 4 BAI / pi) - D. PROGNAUS was fitted to trees of the
Austrian forest inventory, whose threshold is 5 cm DBH: below it the figures are extrapolated.
Reads files only; no model code. The plot's area is read from its scenario.toml (uniform
terrain: width x height cells of cell_m)."""
import csv, math, re, sys
from pathlib import Path

args = sys.argv[1:]
out = Path(args[0])
plant = float(args[1]) if len(args) > 1 else 3.0
y_from = int(args[2]) if len(args) > 2 else 4
y_to = int(args[3]) if len(args) > 3 else 26
step = int(args[4]) if len(args) > 4 else 2
root = Path(__file__).resolve().parent.parent
sp = (root / "species" / "beech.toml").read_text()
num = lambda k: float(re.search(rf"\b{k}\s*=\s*(-?[0-9.]+)", sp).group(1))
h_max, hd_a, hd_b, c0, c1cr = num("max_height_m"), num("hd_a"), num("hd_b"), num("crown_c0"), num("crown_c1")
gk, gp = (float(x) for x in re.search(r"growth = \{ k = ([0-9.]+), p = ([0-9.]+) \}", sp).groups())
text = (out / "scenario.toml").read_text()
m = re.search(r"width\s*=\s*(\d+)\D+height\s*=\s*(\d+)\D+cell_m\s*=\s*([0-9.]+)", text)
area_ha = int(m.group(1)) * int(m.group(2)) * float(m.group(3)) ** 2 / 1e4

# PROGNAUS, beech (BART 10): a0, b1, b2, b3, c1, c2 and the site terms of tools/stand_increment.py
A0, B1, B2, B3, C1, C2 = -0.644436, 1.589274, -0.000189, 0.630734, -0.016353, -0.000175
SITE = -0.00308 * 2.0 ** 2 - 0.031316 * 3 + 0.021224 * 2 + 0.458712 + 0.179966


def prognaus_dd(d, cr, bal, ccf_pct):
    bai = math.exp(A0 + B1 * math.log(d) + B2 * d * d + B3 * math.log(max(cr, 0.01)) + C1 * bal + C2 * ccf_pct + SITE) / 5
    return math.sqrt(d * d + 4 * bai / math.pi) - d


def d_open(h):
    if h <= 1.3:
        return 0.0
    q = min(max((h - 1.3) / (h_max - 1.3), 0.0), 0.999) ** (1 / hd_b)
    return -math.log(1 - q) / hd_a


def h_of(t):
    return h_max * (1 - math.exp(-gk * t)) ** gp


def dd_potential(h):
    t = -math.log(1 - min(h / h_max, 0.999) ** (1 / gp)) / gk  # effective age of the height
    hp = min(h + h_of(t + 1) - h_of(t), h_max * 0.999)
    return max(d_open(hp) - d_open(min(h, hp)), 0.05 if h > 1.3 else 0.0)


def inventory(y):
    with open(out / "inventory" / f"year_{y:04d}.csv") as f:
        return {r["id"]: (float(r["dbh_cm"]), float(r["height_m"]), float(r["crown_base_m"])) for r in csv.DictReader(f) if r["status"] == "alive" and float(r["dbh_cm"]) > 0}


mean = lambda xs: sum(xs) / len(xs)
print("| age | Dq cm | CCF % | RD | Sylva dD cm/yr | Sylva potential | share | PROGNAUS open tree dD | PROGNAUS dD | share | exp(c2 CCF) | Sylva / PROGNAUS |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for y in range(y_from, y_to + 1, step):
    a, b = inventory(y), inventory(y + 1)
    ds = sorted((v[0] for v in a.values()), reverse=True)
    dq = math.sqrt(mean([d * d for d in ds]))
    ccf = sum(math.pi * (c0 + c1cr * d) ** 2 for d in ds) / (area_ha * 1e4) * 100
    rd = len(ds) / area_ha / (900 * (dq / 25) ** -1.789)
    bal, cum = {}, 0.0
    for d in ds:
        bal.setdefault(d, cum)
        cum += math.pi / 4 * d * d / 1e4 / area_ha
    s, pot, po, pc = [], [], [], []
    for k, (d, h, cb) in a.items():
        if k in b:
            s.append(b[k][0] - d)
            pot.append(dd_potential(h))
            po.append(prognaus_dd(d, 1.0, 0.0, 0.0))
            pc.append(prognaus_dd(d, (h - cb) / h, bal[d], ccf))
    print(f"| {y + plant:.0f}–{y + plant + 1:.0f} | {dq:.1f} | {ccf:.0f} | {rd:.2f} | {mean(s):.3f} | {mean(pot):.3f} | {mean(s) / mean(pot):.2f} | {mean(po):.3f} | {mean(pc):.3f} | {mean(pc) / mean(po):.2f} | {math.exp(C2 * ccf):.3f} | {mean(s) / mean(pc):.1f} |")

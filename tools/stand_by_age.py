#!/usr/bin/env python3
"""A run of a planted pure stand, age by age, beside a Wiedemann yield table (class I): how the
stand gets to its figures (issue 35: why the thinned beech stand loses its stems and doubles its
Dq before age 50).

    python3 tools/stand_by_age.py [--species beech|spruce] OUT_DIR [PLANT_AGE] [STEP]

OUT_DIR holds a run's stand_table.csv (age = PLANT_AGE + year, default 3) and, where the run wrote
them (`inventory_every = 1`), its inventories inventory/*YYYY.csv. Per age that is a multiple of
STEP (default 5; the tables' ages), from PLANT_AGE + STEP on:

- from the stand table: stems >= 1.3 m (N) and their Dq, mean height, top height H100, stems
  >= 7 cm (N7) and their Dq (Dq7), basal area of N7 (BA7), relative density of N7 on the species'
  line (RD7: N7 (Dq7 / 25)^-slope / SDI_max, the thinnings' figure), and the deaths of the
  STEP years before by cause (stress = crowding/suppression, background, harvest = thinnings);
- from the inventories: the crown competition factor CCF (open-grown crown areas, r = c0 + c1 D,
  over the ground; Krajicek et al. 1961), the relative density with the small stems' additive
  shares (RD, as the growth phase's crowding sums it: stems >= 7 cm by their Dq plus
  (D / 25)^-slope / SDI_max for each thinner stem), and for the trees alive at both ends of the
  STEP years their mean height and DBH increments and the H/D of the increments
  (100 sum dH / sum dD, m/m) and of the trees (median 100 h / d);
- the table's N, Dq, h_q and the H/D of its mean tree's increment over the same years
  (100 dh_q / dDq; dDq includes the thinnings' shift of Dq).

Prints a Markdown table. The species' constants are those of species/<id>.toml (life.density,
life.allometry crown_c0 / crown_c1), read here as numbers, not parsed."""
import csv, glob, math, re, sys
from pathlib import Path

from wiedemann import class_one, species_args, species_number

species, args = species_args(sys.argv[1:])
out = Path(args[0])
plant = float(args[1]) if len(args) > 1 else 3.0
step = int(args[2]) if len(args) > 2 else 5
# species' maximum-density line and open-grown crown radius (species/beech.toml, norway_spruce.toml)
sdi_max, slope, c0, c1 = (species_number(species, k) for k in ("sdi_max", "reineke_slope", "crown_c0", "crown_c1"))

table = {float(r["age"]): (float(r["n_ha"]), float(r["d_q_cm"]), float(r["h_q_m"])) for r in class_one(species)}
rows = {}
with open(out / "stand_table.csv") as f:
    for r in csv.DictReader(f):
        rows[int(r["year"])] = r


def inventory(year):
    """Living trees of the inventory of `year`: {id: (height m, dbh cm)}, or None."""
    files = [p for p in glob.glob(str(out / "inventory" / "*.csv")) if re.search(rf"(^|[^0-9])0*{year}\.csv$", Path(p).name)]
    if not files:
        return None
    trees = {}
    with open(files[0]) as f:
        for r in csv.DictReader(f):
            if r["status"] not in ("", "alive", "live", "living"):
                continue
            trees[r["id"]] = (float(r["height_m"]), float(r["dbh_cm"]))
    return trees


area_ha = None
head = "| age | N | Dq | mean h | H100 | N7 | Dq7 | BA7 | RD7 | RD | CCF | dead: stress / backgr. / harvest | dH, dD (cm) | H/D incr. | H/D median | table N / Dq / h_q | table H/D incr. |"
print(head)
print("|" + "|".join(["---"] * (head.count("|") - 1)) + "|")
years = sorted(rows)
for age in range(int(math.ceil((plant + step) / step)) * step, int(plant + years[-1]) + 1, step):
    y = int(round(age - plant))
    if y not in rows:
        continue
    r = rows[y]
    n7, dq7 = float(r["stems_7cm_ha"]), float(r["qmd_7cm_cm"])
    ba7 = math.pi / 4 * n7 * dq7 * dq7 / 1e4
    rd7 = n7 * (dq7 / 25.0) ** (-slope) / sdi_max if dq7 > 0 else 0.0
    dead = [sum(int(rows[k][f"deaths_{c}"]) for k in range(y - step + 1, y + 1) if k in rows) for c in ("stress", "background", "harvest")]
    now, before = inventory(y), inventory(y - step)
    rd = ccf = incr = hd_inc = hd_med = ""
    if now is not None:
        if area_ha is None:
            # stems/ha of the stand table over the inventory's count of trees >= 1.3 m
            n_inv = sum(1 for h, d in now.values() if h >= 1.3)
            area_ha = n_inv / float(r["stems_ha"]) if float(r["stems_ha"]) > 0 else 1.0
        big = [d for h, d in now.values() if d >= 7.0]
        small = sum((d / 25.0) ** (-slope) for h, d in now.values() if 0 < d < 7.0) / sdi_max
        q = math.sqrt(sum(d * d for d in big) / len(big)) if big else 0.0
        rdv = (len(big) * (q / 25.0) ** (-slope) / sdi_max if big else 0.0) + small
        rd = f"{rdv / area_ha:.2f}"
        crown = sum(math.pi * (c0 + c1 * d) ** 2 for h, d in now.values() if h >= 1.3)
        ccf = f"{crown / (area_ha * 1e4):.2f}"
        hds = sorted(100 * h / d for h, d in now.values() if d > 0)
        hd_med = f"{hds[len(hds) // 2]:.0f}" if hds else ""
        if before is not None:
            both = [(now[i], before[i]) for i in now if i in before and before[i][1] > 0]
            if both:
                dh = sum(a[0] - b[0] for a, b in both) / len(both)
                dd = sum(a[1] - b[1] for a, b in both) / len(both)
                incr = f"{dh:.2f}, {dd:.2f}"
                hd_inc = f"{100 * dh / dd:.0f}" if dd > 0 else ""
    t = table.get(age)
    tp = table.get(age - step)
    tab = f"{t[0]:.0f} / {t[1]:.1f} / {t[2]:.1f}" if t else "—"
    tab_inc = f"{100 * (t[2] - tp[2]) / (t[1] - tp[1]):.0f}" if t and tp else "—"
    print(f"| {age:.0f} | {float(r['stems_ha']):.0f} | {float(r['qmd_cm']):.1f} | {float(r['mean_height_m']):.1f} | {float(r['top_height_m']):.1f} | {n7:.0f} | {dq7:.1f} | {ba7:.1f} | {rd7:.2f} | {rd} | {ccf} | {dead[0]} / {dead[1]} / {dead[2]} | {incr} | {hd_inc} | {hd_med} | {tab} | {tab_inc} |")

#!/usr/bin/env python3
"""A Wiedemann moderate-thinning yield table's own stand density and removals (issue 35): for
each age of yield class I, the remaining stand's N (stems/ha), Dq (cm), BA (m²/ha), its relative
density against the species' maximum-density line of the simulation (`life.density` of
species/<name>.toml: RD = N · (Dq / 25)^(−slope) / SDI_max, as `sim::density::stand_density`),
and what the stand loses in the next 5 years: stems (N(a) − N(a + 5)) and volume, the total
volume production's increase less the standing volume's (tvp(a + 5) − tvp(a) − (V(a + 5) − V(a)),
m³/ha: thinnings and mortality together).

    python3 tools/table_density.py [--species beech|spruce] [--scenario OUT.toml]

--scenario writes scenarios/thinning_<species>.toml with its [[management]] entries replaced by
one thinning from below per table age a ≥ 4 (year a − 3: planted at age 3) to the table's own RD
at that age. Prints a Markdown table."""
import csv, re, sys
from pathlib import Path

args = sys.argv[1:]
species, scenario = "beech", None
while args:
    if args[0] == "--species":
        species, args = args[1], args[2:]
    elif args[0] == "--scenario":
        scenario, args = args[1], args[2:]
    else:
        sys.exit(__doc__)
root = Path(__file__).resolve().parent.parent
table, sp_file, sc_file = {
    "beech": ("ForestElementsR_fe_ytable_beech_wiedemann_moderate_1931.csv", "beech", "thinning_beech"),
    "spruce": ("ForestElementsR_fe_ytable_spruce_wiedemann_moderate_1936_42.csv", "norway_spruce", "thinning_spruce"),
}[species]
m = re.search(r"^density = \{ sdi_max = ([0-9.]+), reineke_slope = (-?[0-9.]+) \}", (root / "species" / f"{sp_file}.toml").read_text(), re.M)
sdi_max, slope = float(m.group(1)), float(m.group(2))
with open(root / "tests/data/stands" / table) as f:
    rows = sorted((r for r in csv.DictReader(f) if float(r["site_index"]) == 1.0), key=lambda r: float(r["age"]))
print(f"{species}: {table}, class I; maximum-density line SDI_max {sdi_max:g}, slope {slope:g}\n")
print("| age | N | Dq (cm) | BA (m²/ha) | RD | next 5 years: stems lost | % of N | volume lost (m³/ha) | % of V |")
print("|---|---|---|---|---|---|---|---|---|")
rd_at = {}
for i, r in enumerate(rows):
    a, n, dq, ba, v, tvp = (float(r[k]) for k in ("age", "n_ha", "d_q_cm", "ba_m2_ha", "v_m3_ha", "tvp_m3_ha"))
    rd_at[a] = n * (dq / 25.0) ** (-slope) / sdi_max
    line = f"| {a:.0f} | {n:.0f} | {dq:.1f} | {ba:.1f} | {rd_at[a]:.2f} |"
    if i + 1 < len(rows):
        q = rows[i + 1]
        dn = n - float(q["n_ha"])
        dv = (float(q["tvp_m3_ha"]) - tvp) - (float(q["v_m3_ha"]) - v)
        line += f" {dn:.0f} | {100 * dn / n:.1f} | {dv:.1f} | {100 * dv / v:.1f} |"
    else:
        line += " | | | |"
    print(line)
if scenario:
    text = (root / "scenarios" / f"{sc_file}.toml").read_text()
    text = text[: text.index("[[management]]")]
    for a, rd in rd_at.items():
        if a - 3 >= 1:
            text += f'\n[[management]]\nkind = "thinning"\nmethod = "from_below"\ntarget_relative_density = {rd:.3f}\nyear = {a - 3:.0f}\n'
    Path(scenario).write_text(text)

#!/usr/bin/env python3
"""Crown radii of a run's inventory against the stand-grown crown-width functions of its species.

Usage: python3 tools/crown_check.py RUN_DIR YEAR [SPECIES_DIR]

Reads the inventory of YEAR in RUN_DIR: inventory/year_YYYY.csv, year_YYYY.parquet (needs
pyarrow), or the folder year_YYYY/ of a tiled run (`mpirun -np N sylva simulate`: one part per
rank, part-RRRRR.parquet or .csv, read as one table); and the
`life.stand_crown` coefficients of species/*.toml; canopy trees are the living trees of
DBH >= 10 cm whose height is at least 0.8 x the top height of their 50 m x 50 m cell (the mean
height of its 25 tallest trees, i.e. 100 per hectare). Prints, per species and 10 cm DBH class
with at least 20 canopy trees, the median crown radius of the simulation, the function's radius
at the class's trees, and their ratio (mean of per-tree ratios).

The inventories' crown radius is the crown's outline, at least the function's radius for a crown
in light (sim::rules::crown_outline_radius), so canopy ratios near 1 come largely by construction:
this checks what a run reports and draws, not an independent allometry. Ratios well below 1 mark
shaded crowns; above 1, crowns wider from open growth.
"""
import csv, math, sys, tomllib, glob, os
from collections import defaultdict

if len(sys.argv) < 3 or not sys.argv[2].isdigit():
    sys.exit(__doc__.strip().split("\n\n")[1] + "\n(YEAR: a snapshot year of the run, a whole number)")
run, year = sys.argv[1], int(sys.argv[2])
sp_dir = sys.argv[3] if len(sys.argv) > 3 else os.path.join(os.path.dirname(__file__), "..", "species")
inv = os.path.join(run, "inventory")
base = os.path.join(inv, f"year_{year:04d}")


def inventory_files():
    """The files of the inventory of YEAR: the single file (CSV before Parquet) or a tiled
    run's parts (Parquet before CSV, in rank order)."""
    for ext in ("csv", "parquet"):
        if os.path.isfile(f"{base}.{ext}"):
            return [f"{base}.{ext}"]
    if os.path.isdir(base):
        return sorted(glob.glob(os.path.join(base, "part-*.parquet"))) or sorted(glob.glob(os.path.join(base, "part-*.csv")))
    return []


def read_rows(paths):
    """The rows of the inventory files `paths` as dicts (column name -> value)."""
    for p in paths:
        if p.endswith(".parquet"):
            try:
                import pyarrow.parquet as pq
            except ImportError:
                sys.exit(f"{p}: reading Parquet needs pyarrow (pip install pyarrow); or simulate with `--inventory csv`")
            yield from pq.read_table(p).to_pylist()
        else:
            with open(p) as fh:
                yield from csv.DictReader(fh)


files = inventory_files()
if not files:
    years = sorted({int(n[5:9]) for n in (os.listdir(inv) if os.path.isdir(inv) else []) if n.startswith("year_") and n[5:9].isdigit() and (n.endswith((".csv", ".parquet")) or len(n) == 9)})
    sys.exit(f"{base}: no inventory for year {year} in {run} (.csv, .parquet or a folder of parts; years present: {', '.join(str(y) for y in years) or 'none'})")
coef = {}
for f in glob.glob(os.path.join(sp_dir, "*.toml")):
    with open(f, "rb") as fh:
        t = tomllib.load(fh)
    sc = t.get("life", {}).get("stand_crown")
    if sc:
        coef[t["identity"]["id"] if "id" in t.get("identity", {}) else os.path.basename(f)[:-5]] = sc

def ref(sp, d, h, cb):
    c = coef[sp]
    sat = 1.0 - math.exp(-((d / c["c"]) ** c["e"]))
    ln = 1.0 if c.get("g", 0.0) == 0.0 else max(h - cb, 0.1) ** c["g"]
    return 0.5 * (c["a"] + c["b"] * d ** c.get("p", 1.0)) * sat * ln

rows = []
for r in read_rows(files):
    if r["status"] != "alive":
        continue
    rows.append((r["species"], float(r["x_m"]), float(r["y_m"]), float(r["height_m"]), float(r["dbh_cm"]), float(r["crown_radius_m"]), float(r["crown_base_m"])))
cells = defaultdict(list)
for i, r in enumerate(rows):
    cells[(int(r[1] // 50), int(r[2] // 50))].append(r[3])
top = {k: sum(sorted(v)[-25:]) / min(25, len(v)) for k, v in cells.items()}
classes = defaultdict(list)
for sp, x, y, h, d, cr, cb in rows:
    if d < 10 or sp not in coef or h < 0.8 * top[(int(x // 50), int(y // 50))]:
        continue
    rr = ref(sp, d, h, cb)
    if rr > 0:
        classes[(sp, int(d // 10))].append((cr, rr))
print("| species | DBH class (cm) | canopy trees | crown radius sim, median (m) | function (m) | ratio (mean) |")
print("|---|---|---|---|---|---|")
worst = []
for (sp, k), v in sorted(classes.items()):
    if len(v) < 20:
        continue
    sims = sorted(a for a, _ in v)
    refs = sorted(b for _, b in v)
    ratio = sum(a / b for a, b in v) / len(v)
    worst.append(ratio)
    print(f"| {sp} | {k*10}-{k*10+10} | {len(v)} | {sims[len(v)//2]:.2f} | {refs[len(v)//2]:.2f} | {ratio:.2f} |")
if worst:
    print(f"\n{len(worst)} classes; ratios {min(worst):.2f}-{max(worst):.2f}; within +-20 %: {sum(0.8 <= w <= 1.2 for w in worst)}")
else:
    print("\n0 classes: no species and 10 cm DBH class holds 20 canopy trees (DBH >= 10 cm, >= 0.8 x the local top height) in this year")

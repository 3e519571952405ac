"""What the issue 35 tools share (tools/stem_loss.py, stand_increment.py, stand_by_age.py,
thinning_check.py): the `--species beech|spruce` argument, the Wiedemann moderate-thinning
yield table of the species (class I rows of tests/data/stands/, see its README.md), numbers of
the species file (species/<id>.toml, read as numbers, not parsed) and a run's area.

Import from a script in tools/: `from wiedemann import ...` (Python puts the script's folder
first on sys.path)."""
import csv, re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# the species' yield table (tests/data/stands/README.md) and species file
TABLES = {"beech": "ForestElementsR_fe_ytable_beech_wiedemann_moderate_1931.csv", "spruce": "ForestElementsR_fe_ytable_spruce_wiedemann_moderate_1936_42.csv"}
SPECIES_FILES = {"beech": "beech.toml", "spruce": "norway_spruce.toml"}


def species_args(argv):
    """(species, the other arguments) of a command line `[--species beech|spruce] ...`
    (default beech)."""
    if argv[:1] == ["--species"]:
        return argv[1], argv[2:]
    return "beech", argv


def class_one(species):
    """The class I rows (site_index 1) of the species' table, as csv.DictReader dicts (strings)."""
    with open(ROOT / "tests/data/stands" / TABLES[species]) as f:
        return [r for r in csv.DictReader(f) if float(r["site_index"]) == 1.0]


def species_number(species, key):
    """The first number given to `key` in the species file (e.g. sdi_max, reineke_slope,
    crown_c0): a float."""
    text = (ROOT / "species" / SPECIES_FILES[species]).read_text()
    return float(re.search(rf"\b{key}\s*=\s*(-?[0-9.]+)", text).group(1))


def run_area_ha(out):
    """Area (ha) of a run on a uniform terrain: width × height cells of cell_m, from the run
    directory's scenario.toml."""
    text = (Path(out) / "scenario.toml").read_text()
    m = re.search(r"width\s*=\s*(\d+)\D+height\s*=\s*(\d+)\D+cell_m\s*=\s*([0-9.]+)", text)
    return int(m.group(1)) * int(m.group(2)) * float(m.group(3)) ** 2 / 1e4


def inventory(out, year):
    """The inventory of `year` of a run (OUT/inventory/year_YYYY.csv, `--inventory csv`) as
    (living, dead): living {id: row} of the living trees with a DBH (dbh_cm > 0), dead
    [(cause, row)] of the trees that died that year (status `dead:<cause>`: harvest, stress,
    background, age, wind); rows as csv.DictReader dicts (strings). None where the file is
    missing."""
    p = Path(out) / "inventory" / f"year_{year:04d}.csv"
    if not p.exists():
        return None
    living, dead = {}, []
    with open(p) as f:
        for r in csv.DictReader(f):
            if r["status"] == "alive":
                if float(r["dbh_cm"]) > 0:
                    living[r["id"]] = r
            elif r["status"].startswith("dead:"):
                dead.append((r["status"][5:], r))
    return living, dead


def h100(trees, area_ha):
    """Assmann's h100: mean height of the 100 thickest stems per ha of [(dbh, height)] on
    `area_ha` hectares."""
    k = max(1, int(round(100 * area_ha)))
    top = sorted(trees, reverse=True)[:k]
    return sum(h for _d, h in top) / len(top) if top else 0.0


def top_height(trees, area_ha):
    """The stand's top height as sim::stats::top_height: h100 over the upper layer, the stems
    at least 2/3 of the last round's h100 tall (UPPER_LAYER_SHARE), up to 8 rounds."""
    h, layer = h100(trees, area_ha), len(trees)
    for _ in range(8):
        keep = [t for t in trees if t[1] >= 2.0 / 3.0 * h]
        if len(keep) == layer or not keep:
            break
        h, layer = h100(keep, area_ha), len(keep)
    return h


def print_table(head, rows):
    """Prints a Markdown table: the header line `head` ("| a | b |"), its separator and `rows`
    (lines)."""
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    print("\n".join(rows))

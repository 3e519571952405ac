//! The stand table over time as CSV.

use super::Result;
use crate::sim::stats::StandRow;
use crate::sim::trees::DeathCause;
use std::fmt::Write as _;
use std::path::Path;

/// CSV text: `year,stems_ha,seedlings_ha,regeneration_ha,basal_area_m2_ha,mean_height_m,
/// top_height_m,qmd_cm,stems_7cm_ha,qmd_7cm_cm,ba_share_<sp>…,stem_share_<sp>…,regen_germinated,
/// regen_recruited,regen_deaths_shade,regen_deaths_crowding,deaths_age,deaths_stress,deaths_wind,
/// deaths_background,deaths_harvest,volume_m3_ha,harvest_stems_ha,harvest_volume_m3_ha,
/// temperature_offset_k,precipitation_factor,drought_index` (regeneration-layer stems in the year, then tree
/// deaths in the year by [`DeathCause`], then standing and harvested stem volume (m³/ha),
/// harvested stems/ha and the year's climate: temperature offset (K), precipitation factor and
/// the site-mean drought index, [`StandRow::drought_index`])
/// (`species` = pool ids in pool order). `top_height_m` is H100 over the upper layer (stems at
/// least two thirds of the top height tall; [`StandRow::top_height_m`]), so a stand with fewer
/// than 100 overstorey trees per ha reports their height, not that of ingrowth among the 100
/// thickest.
pub fn stand_table_csv(rows: &[StandRow], species: &[&str]) -> String {
    let mut s = String::from("year,stems_ha,seedlings_ha,regeneration_ha,basal_area_m2_ha,mean_height_m,top_height_m,qmd_cm,stems_7cm_ha,qmd_7cm_cm");
    share_columns(&mut s, species);
    s.push_str(",regen_germinated,regen_recruited");
    for c in crate::sim::cohorts::RegenDeath::ALL {
        let _ = write!(s, ",regen_deaths_{}", c.name());
    }
    for c in DeathCause::ALL {
        let _ = write!(s, ",deaths_{}", c.name());
    }
    s.push_str(",volume_m3_ha,harvest_stems_ha,harvest_volume_m3_ha,temperature_offset_k,precipitation_factor,drought_index\n");
    for r in rows {
        let _ = write!(s, "{},{:.1},{:.1},{:.1},{:.3},{:.2},{:.2},{:.2},{:.1},{:.2}", r.year, r.stems_ha, r.seedlings_ha, r.regeneration_ha, r.basal_area_m2_ha, r.mean_height_m, r.top_height_m, r.qmd_cm, r.stems_7cm_ha, r.qmd_7cm_cm);
        for v in &r.share_ba {
            let _ = write!(s, ",{v:.4}");
        }
        for v in &r.share_stems {
            let _ = write!(s, ",{v:.4}");
        }
        let _ = write!(s, ",{},{}", r.regen_germinated, r.regen_recruited);
        for d in r.regen_deaths {
            let _ = write!(s, ",{d}");
        }
        for d in r.deaths {
            let _ = write!(s, ",{d}");
        }
        let _ = write!(s, ",{:.2},{:.1},{:.2},{:.3},{:.3},{:.4}", r.volume_m3_ha, r.harvest_stems_ha, r.harvest_volume_m3_ha, r.temperature_offset_k, r.precipitation_factor, r.drought_index);
        s.push('\n');
    }
    s
}

/// [`stand_table_csv`] with two last columns: `area_ha`, the site's unmasked area (ha) that the
/// per-hectare columns divide by, the same in every row, so the site totals (`regen_*`,
/// `deaths_*`) convert to rates per hectare (trial 36: the area was written nowhere); then
/// `deaths_volume_m3_ha`, the stem volume (m³/ha, DBH ≥ 7 cm) of the trees that died of
/// natural causes in the year (all but harvest: [`StandRow::deaths_volume_m3_ha`]; round 42,
/// trial 41 defect 2), so gross total production is `volume_m3_ha` plus the running sums of
/// `deaths_volume_m3_ha` and `harvest_volume_m3_ha`; last `stems`, the site's count of the
/// trees `stems_ha` counts (≥ 1.3 m: `stems_ha · area_ha`, exact, as `stems_ha` is that count
/// over the area), so that with the site totals `regen_recruited` and `deaths_*` the tree
/// balance `stems(t) = stems(t−1) + regen_recruited(t) − Σ deaths_*(t)` closes exactly in a run
/// without plantings (trial 46 D6: the rounded `stems_ha` missed it by up to 28 trees). With
/// plantings, planted trees enter without being recruits and count from 1.3 m on, and the
/// deaths count the planted trees below 1.3 m too: the balance then holds for
/// `stems + seedlings_ha · area_ha` with the plantings' `planted_ha · area_ha` of
/// `management_table.csv` added.
pub fn stand_table_csv_with_area(rows: &[StandRow], species: &[&str], area_ha: f64) -> String {
    let body = stand_table_csv(rows, species);
    let mut s = String::with_capacity(body.len() + 24 * (rows.len() + 1));
    for (k, line) in body.lines().enumerate() {
        s.push_str(line);
        if k == 0 {
            s.push_str(",area_ha,deaths_volume_m3_ha,stems\n");
        } else {
            let r = &rows[k - 1];
            let _ = writeln!(s, ",{area_ha:.4},{:.2},{}", r.deaths_volume_m3_ha, site_count(r.stems_ha, area_ha));
        }
    }
    s
}

/// CSV text of the per-species stand table (`stand_table_species.csv`; round 42, trial 41
/// defect 2): one row per year and pool species (`species` = pool ids in pool order; years
/// ascending, species in pool order), each per hectare of the site's unmasked area:
/// `year,species,stems_ha,basal_area_m2_ha,qmd_cm,top_height_m,top_height_own_area_m,
/// volume_m3_ha,deaths_stems_ha,deaths_volume_m3_ha,harvest_stems_ha,harvest_volume_m3_ha,
/// deaths_<cause>_stems_ha…,deaths_<cause>_volume_m3_ha…` — stems ≥ 1.3 m, their basal area
/// (m²/ha) and quadratic mean DBH (cm), the species' top height over the whole site (m: the
/// mean height of its 100 thickest stems per ha of the site,
/// [`crate::sim::stats::SpeciesRow::top_height_m`]) and over its own area (m: per hectare of
/// its share of the stand's basal area, [`crate::sim::stats::SpeciesRow::top_height_own_area_m`];
/// round 44, the one to read for a species growing in patches), the standing stem volume of its stems with
/// DBH ≥ 7 cm (m³/ha, [`crate::sim::stats::stem_volume_m3`], as the stand table's); then the
/// year's deaths of natural causes (every cause but harvest: stems ≥ 1.3 m per ha and their
/// volume, m³/ha), the year's harvest (the same for cause harvest), and the deaths by each cause
/// ([`DeathCause::ALL`], harvest included). Over the species of a year, stems, basal area and
/// volume add up to the stand table's `stems_ha`, `basal_area_m2_ha` and `volume_m3_ha`, and
/// the deaths' volumes to its `deaths_volume_m3_ha` and `harvest_volume_m3_ha` (each within
/// the printed rounding). Decimals as the stand table's. Rows without per-species figures are
/// left out.
pub fn stand_table_species_csv(rows: &[StandRow], species: &[&str]) -> String {
    let mut s = String::from("year,species,stems_ha,basal_area_m2_ha,qmd_cm,top_height_m,top_height_own_area_m,volume_m3_ha,deaths_stems_ha,deaths_volume_m3_ha,harvest_stems_ha,harvest_volume_m3_ha");
    for what in ["stems_ha", "volume_m3_ha"] {
        for c in DeathCause::ALL {
            let _ = write!(s, ",deaths_{}_{what}", c.name());
        }
    }
    s.push('\n');
    let h = DeathCause::Harvest.index();
    for r in rows {
        for (sp, v) in species.iter().zip(&r.species) {
            let natural = |a: &[f64]| a.iter().enumerate().filter(|(c, _)| *c != h).map(|(_, x)| x).sum::<f64>();
            let _ = write!(s, "{},{},{:.1},{:.3},{:.2},{:.2},{:.2},{:.2},{:.1},{:.2},{:.1},{:.2}", r.year, csv_field(sp), v.stems_ha, v.basal_area_m2_ha, v.qmd_cm, v.top_height_m, v.top_height_own_area_m, v.volume_m3_ha, natural(&v.deaths_stems_ha), natural(&v.deaths_volume_m3_ha), v.deaths_stems_ha[h], v.deaths_volume_m3_ha[h]);
            for x in v.deaths_stems_ha {
                let _ = write!(s, ",{x:.1}");
            }
            for x in v.deaths_volume_m3_ha {
                let _ = write!(s, ",{x:.2}");
            }
            s.push('\n');
        }
    }
    s
}

/// Writes the per-species stand table ([`stand_table_species_csv`]) atomically.
///
/// Errors: [`super::OutputError::Io`] naming `path`.
pub fn write_stand_table_species(path: &Path, rows: &[StandRow], species: &[&str]) -> Result<()> {
    crate::output::write_atomic(path, stand_table_species_csv(rows, species).as_bytes())
}

/// Writes the stand table CSV ([`stand_table_csv_with_area`]) atomically; `area_ha` is the
/// site's unmasked area (ha).
///
/// Errors: [`super::OutputError::Io`] naming `path`.
pub fn write_stand_table(path: &Path, rows: &[StandRow], species: &[&str], area_ha: f64) -> Result<()> {
    crate::output::write_atomic(path, stand_table_csv_with_area(rows, species, area_ha).as_bytes())
}

/// CSV text of the management table: one row per year and `[[management]]` entry
/// ([`crate::sim::stats::EntryRow`]), years ascending, entries in scenario order:
/// `year,entry,kind,method,area_ha,stems_ha,basal_area_m2_ha,volume_m3_ha,qmd_cm,top_height_m,
/// harvest_stems_ha,harvest_volume_m3_ha,name,harvest_basal_area_m2_ha,cut_saplings_ha,
/// ba_share_<sp>…,stem_share_<sp>…,capped` — the entry's index (0 the first) and kind, its area's
/// unmasked hectares, and over the trees standing in that area at the year's end the stand
/// table's figures per hectare of the area (stems ≥ 1.3 m, basal area, volume of stems ≥ 7 cm
/// DBH, quadratic mean DBH, top height: the area's, so entries on the same parcel show the same
/// standing figures), then what this entry removed in the year per hectare of its area (stems,
/// volume); after them (round 41, trial 40) the entry's name
/// ([`crate::sim::management::Management::display_name`]; quoted as RFC 4180 says where it holds
/// a comma or quote), the basal area it removed (m²/ha), the sapling stems it cut (`keep_open`,
/// per ha) and the species mix standing in the area: each pool species' share of the basal area
/// and of the stems (`species` = pool ids in pool order, as the stand table's); last (round 42,
/// trial 41 defect 1) `capped`, `true` where the entry's `max_removal_share` stopped its
/// thinning that year short of its target, else `false`; after it (round 46, trial 46 D5)
/// `planted_ha`, the trees the entry planted in the year per ha of its area (0 for the other
/// kinds and years), and `seedlings_ha`, the trees below 1.3 m standing in the area per ha of
/// it (planted ones: natural regeneration is in the cohorts; the stand table's `seedlings_ha`
/// over the area). Decimals as the stand table's. Just the header for rows without management.
pub fn management_table_csv(rows: &[StandRow], species: &[&str]) -> String {
    let mut s = String::from("year,entry,kind,method,area_ha,stems_ha,basal_area_m2_ha,volume_m3_ha,qmd_cm,top_height_m,harvest_stems_ha,harvest_volume_m3_ha,name,harvest_basal_area_m2_ha,cut_saplings_ha");
    share_columns(&mut s, species);
    s.push_str(",capped,planted_ha,seedlings_ha\n");
    for r in rows {
        for e in &r.management {
            let _ = write!(
                s,
                "{},{},{},{},{:.4},{:.1},{:.3},{:.2},{:.2},{:.2},{:.1},{:.2},{},{:.3},{:.1}",
                r.year,
                e.entry,
                e.kind,
                e.method,
                e.area_ha,
                e.stems_ha,
                e.basal_area_m2_ha,
                e.volume_m3_ha,
                e.qmd_cm,
                e.top_height_m,
                e.harvest_stems_ha,
                e.harvest_volume_m3_ha,
                csv_field(&e.name),
                e.harvest_basal_area_m2_ha,
                e.cut_saplings_ha
            );
            for k in 0..species.len() {
                let _ = write!(s, ",{:.4}", e.ba_share.get(k).copied().unwrap_or(0.0));
            }
            for k in 0..species.len() {
                let _ = write!(s, ",{:.4}", e.stem_share.get(k).copied().unwrap_or(0.0));
            }
            let _ = writeln!(s, ",{},{:.1},{:.1}", e.capped, e.planted_ha, e.seedlings_ha);
        }
    }
    s
}

/// The site's count behind a per-hectare figure `per_ha` of a site of `area_ha` unmasked
/// hectares: `per_ha` is `n / max(area_ha, 1e-9)` ([`crate::sim::stats::row_of`]), so
/// `per_ha · area` rounds back to `n` exactly for any count below 2⁵².
fn site_count(per_ha: f64, area_ha: f64) -> u64 {
    (per_ha * area_ha.max(1e-9)).round() as u64
}

/// Appends the species-share columns' names: `,ba_share_<sp>…,stem_share_<sp>…`.
fn share_columns(s: &mut String, species: &[&str]) {
    for kind in ["ba_share", "stem_share"] {
        for sp in species {
            let _ = write!(s, ",{kind}_{sp}");
        }
    }
}

/// A CSV field as RFC 4180 §2 writes it: as it is, or in double quotes (quotes doubled) where it
/// holds a comma, a double quote or a line break.
fn csv_field(v: &str) -> String {
    if v.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", v.replace('"', "\"\""))
    } else {
        v.to_string()
    }
}

/// Writes the management table ([`management_table_csv`]) atomically.
///
/// Errors: [`super::OutputError::Io`] naming `path`.
pub fn write_management_table(path: &Path, rows: &[StandRow], species: &[&str]) -> Result<()> {
    crate::output::write_atomic(path, management_table_csv(rows, species).as_bytes())
}

//! Forest management in scenarios (`[[management]]` entries): thinnings, harvests and plantings,
//! their areas (a rectangle, inline polygons or polygons of a GeoJSON or GeoPackage file) and
//! their timing, and clearings kept open (`kind = "keep_open"`: every tree and sapling cohort
//! taller than `max_height_m` in the area removed at each entry, so a designed clearing or a
//! path does not grow over).
//! [`Management`] is the entry as written; [`Operation`] the entry resolved against the site and
//! the species library (its region's polygons in world metres, its area, its species), which the
//! management phase ([`super::phases::management`]) carries out.
//!
//! Timing: an entry acts in the simulation years `Y` (the stand table's year: 1 = the first
//! simulated year) it lists (`year`, `years`) or from `from_year` every `every_years` (every
//! year when omitted) up to `until_year`, at the end of the year, after mortality and before
//! the year's stand-table row; a planting in year 0 is planted with the start. Thinnings may
//! carry triggers (`trigger_relative_density`, `trigger_top_height_m`): in a scheduled year they
//! act only when every trigger given holds over their area.

use super::light_grid::LightGrid;
use crate::conditions::SiteConditions;
use crate::error::{Error, Result};
use crate::species::{SpeciesId, SpeciesLibrary};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One `[[management]]` entry as written in the scenario (fields by `kind`; see the module
/// documentation for timing). Checked by [`Management::validate`].
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Management {
    /// `"thinning"`, `"harvest"`, `"planting"` or `"keep_open"`.
    pub kind: String,
    /// A name for the entry in `management_table.csv` (its `name` column; 1–64 characters, no
    /// line breaks, no two entries of a scenario alike). When omitted: the filter's value where an `area_file` filter picks the
    /// area (`filter = { property = "parcel", equals = "oak_park" }` → `oak_park`), else
    /// `KIND#INDEX` (`thinning#4`): [`Management::display_name`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Keep open: the height (m, 0–50) above which trees and the regeneration's sapling cohorts
    /// (by their mean height) in the area are removed at each entry; 0 (the default) removes
    /// every tree and cohort, a bare clearing; 1.5 keeps a low layer (a mown meadow's brush).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_height_m: Option<f64>,
    /// Thinning: `"from_below"` (smallest DBH first) or `"from_above"` (largest first).
    /// Harvest: `"clear_cut"` (every tree of the area) or `"patch"` (square patches).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// Thinning target: basal area (m²/ha, > 0) of the stems ≥ 1.3 m in the area.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_basal_area_m2_ha: Option<f64>,
    /// Thinning target: relative density (0–2) against the species' maximum-density lines
    /// ([`super::phases::management::stand_rd`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_relative_density: Option<f64>,
    /// Thinning target: stems/ha (≥ 1.3 m) left in the area.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_stems_ha: Option<f64>,
    /// Thinning trigger: act only when the area's relative density is at least this (0–2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trigger_relative_density: Option<f64>,
    /// Thinning trigger: act only when the area's top height H100 is at least this (m, 0–100).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trigger_top_height_m: Option<f64>,
    /// Thinning: the largest share (> 0, ≤ 1) of the basal area an entry removes, of the basal
    /// area it measures its target on before it starts (the area's main stand; for
    /// `crop_trees` every stem ≥ 1.3 m of the area); trees are taken in the method's order
    /// while the removed basal area stays within it, and where it stops the thinning short of
    /// its target the management table's `capped` says so and a note goes to the log. Basal
    /// area because the yield tables give the removals so (G of the removed stand) and it
    /// weighs a tree by its share of the growing space, not by count. None (the default): no
    /// cap. Moderate thinning in German practice removes about 15–25 % of the basal area per
    /// 5-year entry in middle-aged stands: the NW-FVA 2021 beech table (yield class I; Albert
    /// et al. 2021, shipped in `tests/data/stands/`) removes 24 % at age 40, 18 % at 50, 13 %
    /// at 70 and 9 % at 100 (`G_aus / (G + G_aus)`), so `max_removal_share = 0.2` is a typical
    /// cap (round 42, trial 41 defect 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_removal_share: Option<f64>,
    /// A single year (0–10000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub year: Option<u32>,
    /// Years (each 0–10000), ascending, each once.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub years: Option<Vec<u32>>,
    /// First year of a recurring entry (1–10000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from_year: Option<u32>,
    /// Interval (years, 1–1000) of a recurring entry; every year when omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_years: Option<u32>,
    /// Last year of a recurring entry (≥ `from_year`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub until_year: Option<u32>,
    /// Area as a rectangle `[x0, y0, x1, y1]` (m, world coordinates, origin SW corner, as the
    /// `[[start]]` areas).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area: Option<[f64; 4]>,
    /// Area as polygons, each a list of rings of `[x, y]` points (m, world coordinates): the
    /// first ring the outline, further rings holes (even-odd rule).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polygons: Option<Vec<Vec<Vec<[f64; 2]>>>>,
    /// Area as the (Multi)Polygons of a vector file in the DEM's CRS: a GeoPackage (`.gpkg`,
    /// [`read_gpkg_polygons`]) or else GeoJSON ([`read_geojson_polygons`]); relative paths are
    /// relative to the scenario file. On a site without georeferencing (uniform or generated
    /// terrain) the file is in the coordinates of the run's outputs (m): x 0 to W east, y −H
    /// (south edge) to 0 (north edge), origin the NW corner, as the inventories and GeoTIFFs
    /// are written (not the world metres of `area` and `polygons`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area_file: Option<PathBuf>,
    /// The feature layer (table) of a GeoPackage `area_file`; its first feature layer when
    /// omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer: Option<String>,
    /// Only the features of `area_file` whose property equals a value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub filter: Option<AreaFilter>,
    /// Patch cut: side of the square patches (m, 5–1000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patch_size_m: Option<f64>,
    /// Patch cut: share (0–1) of the area's patches cut at each entry (new patches each time).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub share: Option<f64>,
    /// Planting: species mix, species id → share (> 0; normalised to sum 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mix: Option<BTreeMap<String, f64>>,
    /// Planting: spacing of the square lattice (m, 0.5–50).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing_m: Option<f64>,
    /// Planting: age of the planted trees (years, 0–1000; default 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub age_yr: Option<f32>,
    /// Thinning `crop_trees`: crop trees per hectare (1–1000) selected in the area, the largest
    /// vigorous stems at least `crop_tree_distance_m` apart, whose strongest competitors are
    /// removed ([`crop_tree_distance`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crop_trees_ha: Option<f64>,
    /// Thinning `crop_trees`: least distance between two crop trees (m, 1–100); by default
    /// [`crop_tree_distance`] of `crop_trees_ha`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crop_tree_distance_m: Option<f64>,
    /// Harvest `shelterwood`: the stages (seed cut, removal cuts), each a year and the share of
    /// the overstorey's basal area it removes; they are the entry's timing (no `year`, `years`
    /// or `from_year`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stages: Option<Vec<Stage>>,
}

/// One stage of a shelterwood harvest: in simulation year `year` (1–10000) it removes `share`
/// (> 0, ≤ 1) of the basal area of the overstorey standing in the area then (trees at least
/// half the area's top height tall; [`SHELTER_OVERSTOREY`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stage {
    /// Simulation year (the stand table's year).
    pub year: u32,
    /// Share (> 0, ≤ 1) of the overstorey basal area removed; 1 is the final removal cut.
    pub share: f64,
}

/// Shelterwood: the overstorey a stage cuts are the trees at least this share of the area's top
/// height (H100) tall; shorter trees, the regeneration establishing under the shelter, are left.
pub const SHELTER_OVERSTOREY: f32 = 0.5;

/// Shelterwood: radius (m) of the neighbourhood whose basal area ranks the trees of a stage
/// (densest neighbourhood first, so the shelter is opened evenly); about a crown diameter of a
/// mature beech or spruce.
pub const SHELTER_RADIUS_M: f64 = 10.0;

/// The default least distance (m) between crop trees at `n_ha` crop trees per hectare:
/// `0.75 · 100 / √n`. `100 / √n` is the spacing of `n` trees per hectare on a square lattice,
/// the usual planning figure for crop trees (e.g. 100 beech crop trees/ha ≈ 10 m apart; Abetz &
/// Klädtke 2002, *Die Z-Baum-Kontrollmethode*, Forstw. Cbl. 121); a greedy selection among
/// irregularly placed trees packs at most about 0.7 trees per square of the exclusion distance
/// (random sequential adsorption of disks), so the distance is shortened by a quarter for the
/// selection to reach `n` in a stand that has enough candidates.
pub fn crop_tree_distance(n_ha: f64) -> f64 {
    0.75 * 100.0 / n_ha.sqrt()
}

/// An attribute filter on the features of an `area_file`: a feature is kept when its property
/// `property` equals `equals` (a text, or a number compared as a number).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaFilter {
    /// Property name.
    pub property: String,
    /// Value the property must have.
    pub equals: toml::Value,
}

/// Most trees all `planted` starts of a scenario may plant together, and one planting entry at
/// a time (each is an individual; 5 M is about 2,000 ha at 2 m spacing).
pub const MAX_PLANTED_TREES: u64 = 5_000_000;

const KINDS: &str = "\"thinning\", \"harvest\", \"planting\" or \"keep_open\"";

/// How far the shares of a planting's `mix` may sum from 1 (absolute): a sum within it (three
/// thirds written 0.33) is scaled to 1 without a word, a sum further off is an error (trial 46).
pub const MIX_SUM_TOLERANCE: f64 = 0.01;

fn invalid(ctx: &str, i: usize, field: &str, value: impl ToString, expected: &str) -> Error {
    Error::Invalid { context: ctx.to_string(), field: format!("management[{i}].{field}"), value: value.to_string(), expected: expected.to_string() }
}

impl Management {
    /// Checks entry `i` of a scenario (`ctx` names the file): the kind, its method and target,
    /// the fields the kind allows, ranges, timing and area.
    ///
    /// Errors: [`Error::Invalid`] naming `management[i].<field>`, the value and what was expected.
    pub fn validate(&self, i: usize, ctx: &str) -> Result<()> {
        let given = |o: bool| o;
        let bad = |field: &str, value: String, expected: &str| invalid(ctx, i, field, value, expected);
        // fields each kind may carry
        let thinning_only = [("target_basal_area_m2_ha", self.target_basal_area_m2_ha.is_some()), ("target_relative_density", self.target_relative_density.is_some()), ("target_stems_ha", self.target_stems_ha.is_some()), ("trigger_relative_density", self.trigger_relative_density.is_some()), ("trigger_top_height_m", self.trigger_top_height_m.is_some()), ("max_removal_share", self.max_removal_share.is_some())];
        let harvest_only = [("patch_size_m", self.patch_size_m.is_some()), ("share", self.share.is_some()), ("stages", self.stages.is_some())];
        let crop_only = [("crop_trees_ha", self.crop_trees_ha.is_some()), ("crop_tree_distance_m", self.crop_tree_distance_m.is_some())];
        let planting_only = [("mix", self.mix.is_some()), ("spacing_m", self.spacing_m.is_some()), ("age_yr", self.age_yr.is_some())];
        if let Some(n) = &self.name {
            if n.trim().is_empty() || n.chars().count() > 64 || n.contains(['\n', '\r']) {
                return Err(bad("name", format!("{n:?}"), "a name of 1–64 characters on one line (it names the entry's rows in management_table.csv)"));
            }
        }
        if self.kind != "keep_open" && self.max_height_m.is_some() {
            return Err(bad("max_height_m", "given".into(), &format!("not with kind = \"{}\" (only with kind = \"keep_open\")", self.kind)));
        }
        let refuse = |list: &[(&str, bool)], kind: &str| -> Result<()> {
            for (f, g) in list {
                if *g {
                    return Err(bad(f, "given".into(), &format!("not with kind = \"{}\" (only with {kind})", self.kind)));
                }
            }
            Ok(())
        };
        let method = self.method.as_deref();
        match self.kind.as_str() {
            "thinning" => {
                refuse(&harvest_only, "kind = \"harvest\"")?;
                refuse(&planting_only, "kind = \"planting\"")?;
                const METHODS: &str = "\"from_below\", \"from_above\" or \"crop_trees\"";
                match method {
                    Some("from_below" | "from_above") => refuse(&crop_only, "kind = \"thinning\", method = \"crop_trees\"")?,
                    Some("crop_trees") => {
                        let n = self.crop_trees_ha.ok_or_else(|| bad("crop_trees_ha", "(missing)".into(), "the crop trees per hectare, 1–1000"))?;
                        if !(n.is_finite() && (1.0..=1000.0).contains(&n)) {
                            return Err(bad("crop_trees_ha", n.to_string(), "1–1000 crop trees per hectare"));
                        }
                        if let Some(d) = self.crop_tree_distance_m {
                            if !(d.is_finite() && (1.0..=100.0).contains(&d)) {
                                return Err(bad("crop_tree_distance_m", d.to_string(), "1–100 m"));
                            }
                        }
                    }
                    Some(m) => return Err(bad("method", format!("{m:?}"), METHODS)),
                    None => return Err(bad("method", "(missing)".into(), METHODS)),
                }
                let n = thinning_only[..3].iter().filter(|t| t.1).count();
                if method == Some("crop_trees") && n > 1 {
                    return Err(bad("target_*", format!("{n} targets"), "at most one of target_basal_area_m2_ha, target_relative_density, target_stems_ha with method = \"crop_trees\" (none: every competitor whose crown touches a crop tree's goes)"));
                }
                if method != Some("crop_trees") && n != 1 {
                    return Err(bad("target_*", format!("{n} targets"), "exactly one of target_basal_area_m2_ha, target_relative_density, target_stems_ha"));
                }
                let ranges = [
                    ("target_basal_area_m2_ha", self.target_basal_area_m2_ha, 0.0, 200.0),
                    ("target_relative_density", self.target_relative_density, 0.0, 2.0),
                    ("target_stems_ha", self.target_stems_ha, 0.0, 1e6),
                    ("trigger_relative_density", self.trigger_relative_density, 0.0, 2.0),
                    ("trigger_top_height_m", self.trigger_top_height_m, 0.0, 100.0),
                ];
                if let Some(v) = self.max_removal_share {
                    if !(v.is_finite() && v > 0.0 && v <= 1.0) {
                        return Err(bad("max_removal_share", v.to_string(), "a share of the basal area > 0 and ≤ 1 (0.2: at most a fifth of the stand's basal area per entry)"));
                    }
                }
                for (f, v, lo, hi) in ranges {
                    if let Some(v) = v {
                        if !(v.is_finite() && v >= lo && v <= hi) {
                            return Err(bad(f, v.to_string(), &format!("a number {lo}–{hi}")));
                        }
                        // a target of 0 takes every stem of the growing stock at each entry
                        // (trial 38: the stand was gone by year 137, without a word); a
                        // clear-cut is `kind = "harvest"`, `method = "clear_cut"`
                        if f.starts_with("target_") && v <= 0.0 {
                            return Err(bad(f, v.to_string(), &format!("a number > 0 and ≤ {hi} (0 would remove every stem of at least 7 cm DBH at each entry: for that, use kind = \"harvest\", method = \"clear_cut\")")));
                        }
                    }
                }
            }
            "harvest" => {
                refuse(&thinning_only, "kind = \"thinning\"")?;
                refuse(&planting_only, "kind = \"planting\"")?;
                refuse(&crop_only, "kind = \"thinning\", method = \"crop_trees\"")?;
                const METHODS: &str = "\"clear_cut\", \"patch\" or \"shelterwood\"";
                match method {
                    Some("clear_cut") => refuse(&harvest_only, "kind = \"harvest\", method = \"patch\" or \"shelterwood\"")?,
                    Some("shelterwood") => {
                        refuse(&harvest_only[..2], "kind = \"harvest\", method = \"patch\"")?;
                        let st = self.stages.as_ref().ok_or_else(|| bad("stages", "(missing)".into(), "the stages, e.g. stages = [{ year = 100, share = 0.5 }, { year = 110, share = 0.5 }, { year = 120, share = 1.0 }]"))?;
                        if st.is_empty() {
                            return Err(bad("stages", "[]".into(), "at least one stage { year = Y, share = S }"));
                        }
                        for (k, g) in st.iter().enumerate() {
                            if !(1..=10_000).contains(&g.year) {
                                return Err(bad(&format!("stages[{k}].year"), g.year.to_string(), "1–10000 (a harvest acts at the end of a simulated year)"));
                            }
                            if k > 0 && g.year <= st[k - 1].year {
                                return Err(bad(&format!("stages[{k}].year"), g.year.to_string(), &format!("a year after the previous stage's ({})", st[k - 1].year)));
                            }
                            if !(g.share > 0.0 && g.share <= 1.0) {
                                return Err(bad(&format!("stages[{k}].share"), g.share.to_string(), "> 0 and ≤ 1 (the share of the overstorey's basal area the stage removes)"));
                            }
                        }
                    }
                    Some("patch") => {
                        refuse(&harvest_only[2..], "kind = \"harvest\", method = \"shelterwood\"")?;
                        let s = self.patch_size_m.ok_or_else(|| bad("patch_size_m", "(missing)".into(), "the side of the square patches, 5–1000 m"))?;
                        if !(s.is_finite() && (5.0..=1000.0).contains(&s)) {
                            return Err(bad("patch_size_m", s.to_string(), "5–1000 m"));
                        }
                        let sh = self.share.ok_or_else(|| bad("share", "(missing)".into(), "the share of the area cut at each entry, > 0 and ≤ 1"))?;
                        if !(sh > 0.0 && sh <= 1.0) {
                            return Err(bad("share", sh.to_string(), "> 0 and ≤ 1"));
                        }
                    }
                    Some(m) => return Err(bad("method", format!("{m:?}"), METHODS)),
                    None => return Err(bad("method", "(missing)".into(), METHODS)),
                }
            }
            "planting" => {
                refuse(&thinning_only, "kind = \"thinning\"")?;
                refuse(&harvest_only, "kind = \"harvest\"")?;
                refuse(&crop_only, "kind = \"thinning\", method = \"crop_trees\"")?;
                if let Some(m) = method {
                    return Err(bad("method", format!("{m:?}"), "no method for a planting"));
                }
                let mix = self.mix.as_ref().ok_or_else(|| bad("mix", "(missing)".into(), "a species mix, e.g. mix = { beech = 0.7, sessile_oak = 0.3 }"))?;
                if mix.is_empty() {
                    return Err(bad("mix", "{}".into(), "at least one species with a share > 0"));
                }
                for (sp, s) in mix {
                    if !(s.is_finite() && *s > 0.0 && *s <= 1.0) {
                        return Err(bad(&format!("mix.{sp}"), s.to_string(), "a share > 0 and at most 1 (the shares of a mix sum to 1)"));
                    }
                }
                // shares off by more than MIX_SUM_TOLERANCE are an error (trial 46: 0.7 + 0.7
                // was scaled with a warning that scrolled away; such a sum is a typo far more
                // often than an intent); within it they are scaled to 1 without a word
                let total: f64 = mix.values().sum();
                if (total - 1.0).abs() > MIX_SUM_TOLERANCE + 1e-9 {
                    let listed: Vec<String> = mix.iter().map(|(sp, s)| format!("{sp} = {s}")).collect();
                    return Err(bad("mix", format!("{{ {} }} (shares summing to {})", listed.join(", "), (total * 1e6).round() / 1e6), &format!("shares summing to 1 (within {MIX_SUM_TOLERANCE}), e.g. mix = {{ beech = 0.7, sessile_oak = 0.3 }}")));
                }
                let sp = self.spacing_m.ok_or_else(|| bad("spacing_m", "(missing)".into(), "the lattice spacing, 0.5–50 m"))?;
                if !(sp.is_finite() && (0.5..=50.0).contains(&sp)) {
                    return Err(bad("spacing_m", sp.to_string(), "0.5–50 m"));
                }
                if let Some(a) = self.age_yr {
                    if !(a.is_finite() && (0.0..=1000.0).contains(&a)) {
                        return Err(bad("age_yr", a.to_string(), "0–1000 years"));
                    }
                }
            }
            "keep_open" => {
                refuse(&thinning_only, "kind = \"thinning\"")?;
                refuse(&harvest_only, "kind = \"harvest\"")?;
                refuse(&crop_only, "kind = \"thinning\", method = \"crop_trees\"")?;
                refuse(&planting_only, "kind = \"planting\"")?;
                if let Some(m) = method {
                    return Err(bad("method", format!("{m:?}"), "no method for kind = \"keep_open\" (it removes every tree and sapling cohort taller than max_height_m)"));
                }
                if let Some(h) = self.max_height_m {
                    if !(h.is_finite() && (0.0..=50.0).contains(&h)) {
                        return Err(bad("max_height_m", h.to_string(), "0–50 m (the height above which trees and sapling cohorts are removed)"));
                    }
                }
            }
            k => return Err(bad("kind", format!("{k:?}"), KINDS)),
        }
        if self.kind != "thinning" && given(self.trigger_relative_density.is_some() || self.trigger_top_height_m.is_some()) {
            return Err(bad("trigger_*", "given".into(), "triggers only with kind = \"thinning\""));
        }
        // timing (a shelterwood's stages carry its years)
        let n = self.year.is_some() as u8 + self.years.is_some() as u8 + self.from_year.is_some() as u8;
        let given_names = || {
            let g: Vec<&str> = [("year", self.year.is_some()), ("years", self.years.is_some()), ("from_year", self.from_year.is_some())].iter().filter(|x| x.1).map(|x| x.0).collect();
            if g.is_empty() { "none of them given".to_string() } else { format!("{} given", g.join(" and ")) }
        };
        if self.stages.is_some() && n > 0 {
            return Err(bad("year/years/from_year", given_names(), "none with method = \"shelterwood\": its stages carry the years"));
        }
        if self.stages.is_none() && n != 1 {
            return Err(bad("year/years/from_year", given_names(), "exactly one of year = Y, years = [...], from_year = Y (with every_years, until_year)"));
        }
        if self.from_year.is_none() && (self.every_years.is_some() || self.until_year.is_some()) {
            return Err(bad("every_years/until_year", "given".into(), "only with from_year"));
        }
        let min_year = if self.kind == "planting" { 0 } else { 1 };
        let check_year = |f: &str, y: u32| -> Result<()> {
            if !(min_year..=10_000).contains(&y) {
                let why = if min_year == 1 { "1–10000 (a thinning or harvest acts at the end of a simulated year; year 0 is the start)" } else { "0–10000" };
                return Err(bad(f, y.to_string(), why));
            }
            Ok(())
        };
        if let Some(y) = self.year {
            check_year("year", y)?;
        }
        if let Some(ys) = &self.years {
            if ys.is_empty() {
                return Err(bad("years", "[]".into(), "at least one year"));
            }
            for (k, y) in ys.iter().enumerate() {
                check_year(&format!("years[{k}]"), *y)?;
                if ys[..k].contains(y) {
                    return Err(bad(&format!("years[{k}]"), y.to_string(), "each year once"));
                }
                // ascending, as `stages` must be (round 34's trial: [30, 20] was accepted)
                if k > 0 && *y < ys[k - 1] {
                    return Err(bad(&format!("years[{k}]"), y.to_string(), &format!("a year after the previous one ({}): list the years in ascending order", ys[k - 1])));
                }
            }
        }
        if let Some(f) = self.from_year {
            check_year("from_year", f)?;
            if let Some(e) = self.every_years {
                if !(1..=1000).contains(&e) {
                    return Err(bad("every_years", e.to_string(), "1–1000 years"));
                }
            }
            if let Some(u) = self.until_year {
                if u < f || u > 10_000 {
                    return Err(bad("until_year", u.to_string(), &format!("{f}–10000 (from from_year)")));
                }
            }
        }
        // area
        let n = self.area.is_some() as u8 + self.polygons.is_some() as u8 + self.area_file.is_some() as u8;
        if n > 1 {
            return Err(bad("area/polygons/area_file", format!("{n} given"), "at most one of area, polygons, area_file (the whole site when none)"));
        }
        if self.filter.is_some() && self.area_file.is_none() {
            return Err(bad("filter", "given".into(), "only with area_file"));
        }
        if let Some(l) = &self.layer {
            if !self.area_file.as_deref().is_some_and(is_gpkg) {
                return Err(bad("layer", format!("{l:?}"), "only with a GeoPackage area_file (`.gpkg`)"));
            }
        }
        if let Some(a) = self.area {
            if !(a.iter().all(|v| v.is_finite()) && a[2] > a[0] && a[3] > a[1]) {
                return Err(bad("area", format!("{a:?}"), "[x0, y0, x1, y1] with x1 > x0 and y1 > y0"));
            }
        }
        if let Some(ps) = &self.polygons {
            if ps.is_empty() {
                return Err(bad("polygons", "[]".into(), "at least one polygon [[[x, y], ...]]"));
            }
            for (k, p) in ps.iter().enumerate() {
                check_rings(p).map_err(|e| bad(&format!("polygons[{k}]"), format!("{p:?}"), &e))?;
            }
        }
        Ok(())
    }

    /// Whether entry is due in year `year`, and if so the how-manieth time (0 the first; a
    /// shelterwood's stage).
    pub fn due(&self, year: u32) -> Option<u32> {
        if let Some(st) = &self.stages {
            return st.iter().position(|g| g.year == year).map(|k| k as u32);
        }
        if let Some(y) = self.year {
            return (y == year).then_some(0);
        }
        if let Some(ys) = &self.years {
            return ys.contains(&year).then(|| ys.iter().filter(|y| **y < year).count() as u32);
        }
        let f = self.from_year?;
        let e = self.every_years.unwrap_or(1);
        (year >= f && (year - f) % e == 0 && self.until_year.is_none_or(|u| year <= u)).then(|| (year - f) / e)
    }
}

impl Management {
    /// The years this entry lists that lie beyond a run's last year `last` (the stand table's
    /// year), as `(field, year)`: `year`, `years[k]`, `from_year` or `stages[k].year`. Such years
    /// never come; a recurring entry's `until_year` beyond the run is not listed (it is open).
    pub fn years_beyond(&self, last: u32) -> Vec<(String, u32)> {
        let mut out = Vec::new();
        let mut add = |f: String, y: u32| {
            if y > last {
                out.push((f, y));
            }
        };
        if let Some(y) = self.year {
            add("year".into(), y);
        }
        for (k, y) in self.years.iter().flatten().enumerate() {
            add(format!("years[{k}]"), *y);
        }
        if let Some(y) = self.from_year {
            add("from_year".into(), y);
        }
        for (k, g) in self.stages.iter().flatten().enumerate() {
            add(format!("stages[{k}].year"), g.year);
        }
        out
    }

    /// The entry's name in `management_table.csv`: its `name`; else, where an `area_file`
    /// filter picks its area, the filter's value (a text without quotes, a number or boolean as
    /// written: the parcel's attribute value); else `KIND#i` (`i` its index in the scenario, 0
    /// the first).
    pub fn display_name(&self, i: usize) -> String {
        if let Some(n) = &self.name {
            return n.clone();
        }
        match self.filter.as_ref().filter(|_| self.area_file.is_some()) {
            Some(AreaFilter { equals: toml::Value::String(v), .. }) => v.clone(),
            Some(f) => f.equals.to_string(),
            None => format!("{}#{i}", self.kind),
        }
    }

    /// The field naming the entry's first year ([`Management::first_year`]) and that year:
    /// `year`, `years[0]`, `from_year` or `stages[0].year`.
    pub fn first_year_field(&self) -> (String, u32) {
        let f = if self.year.is_some() {
            "year"
        } else if self.years.is_some() {
            "years[0]"
        } else if self.from_year.is_some() {
            "from_year"
        } else {
            "stages[0].year"
        };
        (f.to_string(), self.first_year())
    }

    /// The first year the entry acts in (its earliest listed year, `from_year` or first stage).
    pub fn first_year(&self) -> u32 {
        let listed = self.year.into_iter().chain(self.years.iter().flatten().copied()).chain(self.from_year).chain(self.stages.iter().flatten().map(|g| g.year));
        listed.min().unwrap_or(0)
    }
}

/// Checks a polygon's rings: at least one, each of at least 3 finite points, and no two edges
/// of its rings crossing (a self-intersecting "bowtie" outline, or a hole crossing the outline,
/// has no well-defined inside). A ring may repeat its first point at its end (GeoJSON does).
fn check_rings(rings: &[Vec<[f64; 2]>]) -> std::result::Result<(), String> {
    if rings.is_empty() {
        return Err("a polygon: a list of rings, the first the outline".into());
    }
    for r in rings {
        let pts: Vec<&[f64; 2]> = r.iter().collect();
        if pts.len() < 3 || pts.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
            return Err("rings of at least 3 finite [x, y] points".into());
        }
    }
    if let Some((a, b)) = crossing_edges(rings) {
        return Err(format!("a simple polygon: edges that do not cross (ring {} edge {} crosses ring {} edge {}: a self-intersecting outline such as a bowtie has no well-defined inside; split it into polygons)", a.0, a.1, b.0, b.1));
    }
    Ok(())
}

/// The first pair of edges of `rings` that cross properly (each edge's end points strictly on
/// either side of the other's line), as `((ring, edge), (ring, edge))`; `None` for a simple
/// polygon. Edges sharing an end point (neighbours in a ring) and zero-length edges are not
/// compared; touching without crossing is allowed. Edges are compared pairwise after a
/// bounding-box test (quadratic in the edges; fine for parcel outlines).
fn crossing_edges(rings: &[Vec<[f64; 2]>]) -> Option<((usize, usize), (usize, usize))> {
    // (ring, edge index) and its end points
    type Edge = ((usize, usize), [f64; 2], [f64; 2]);
    let mut edges: Vec<Edge> = Vec::new();
    for (ri, r) in rings.iter().enumerate() {
        for k in 0..r.len() {
            let (a, b) = (r[k], r[(k + 1) % r.len()]);
            if a != b {
                edges.push(((ri, k), a, b));
            }
        }
    }
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).signum();
    for i in 0..edges.len() {
        let (ei, a, b) = edges[i];
        for &(ej, c, d) in &edges[i + 1..] {
            if a[0].max(b[0]) < c[0].min(d[0]) || c[0].max(d[0]) < a[0].min(b[0]) {
                continue;
            }
            if a == c || a == d || b == c || b == d {
                continue;
            }
            let (o1, o2, o3, o4) = (orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b));
            if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
                return Some((ei, ej));
            }
        }
    }
    None
}

/// The area an entry acts on, in world metres.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Bounding box `[x0, y0, x1, y1]` (m), clipped to the site.
    pub bbox: [f64; 4],
    /// Polygons (each a list of rings, even-odd rule); `None`: the whole bounding box.
    pub polygons: Option<Vec<Vec<Vec<[f64; 2]>>>>,
    /// Unmasked area inside the region (ha), counted on the light grid's cells.
    pub area_ha: f64,
}

impl Region {
    /// Whether world point `(x, y)` lies in the region (inside the box and, where polygons are
    /// given, inside one of them by the even-odd rule over its rings).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let b = &self.bbox;
        if !(x >= b[0] && x < b[2] && y >= b[1] && y < b[3]) {
            return false;
        }
        match &self.polygons {
            None => true,
            Some(ps) => ps.iter().any(|rings| rings.iter().filter(|r| ring_crosses(r, x, y)).count() % 2 == 1),
        }
    }
}

/// Ray casting: whether a ray from `(x, y)` towards +x crosses ring `r` an odd number of times
/// (the ring closed implicitly).
fn ring_crosses(r: &[[f64; 2]], x: f64, y: f64) -> bool {
    let mut inside = false;
    let n = r.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (r[i], r[j]);
        if (a[1] > y) != (b[1] > y) && x < (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]) + a[0] {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// What an [`Operation`] does.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// A thinning to a target.
    Thinning {
        /// Smallest DBH first (`from_below`) or largest first (`from_above`).
        from_below: bool,
        /// What is thinned to.
        target: Target,
        /// Act only at or above this relative density of the area.
        trigger_rd: Option<f64>,
        /// Act only at or above this top height (m) of the area.
        trigger_top_height_m: Option<f64>,
    },
    /// A crop-tree thinning: the release of crop trees by removing their competitors
    /// (`sim::phases::management`).
    CropTrees {
        /// Crop trees per hectare.
        n_ha: f64,
        /// Least distance between crop trees (m).
        distance_m: f64,
        /// What is thinned to; `None`: every competitor whose crown touches a crop tree's.
        target: Option<Target>,
        /// Act only at or above this relative density of the area.
        trigger_rd: Option<f64>,
        /// Act only at or above this top height (m) of the area.
        trigger_top_height_m: Option<f64>,
    },
    /// Every tree of the area.
    ClearCut,
    /// A shelterwood harvest in stages: the share (0–1) of the overstorey's basal area each
    /// stage removes, in stage order (the years are the entry's `stages`).
    Shelterwood {
        /// Share per stage.
        shares: Vec<f64>,
    },
    /// Square patches of side `size_m` (m), a share `share` of the area's patches each time.
    Patch {
        /// Side (m).
        size_m: f64,
        /// Share (0–1) per entry.
        share: f64,
    },
    /// Keep open: every tree taller than `max_height_m` (m) in the area, and every sapling
    /// cohort of a light cell whose centre lies in it with a mean height above it, is removed
    /// (`sim::phases::management`).
    KeepOpen {
        /// Height (m) above which trees and cohorts go.
        max_height_m: f64,
    },
    /// A planted lattice.
    Planting {
        /// Species and their cumulative shares (0–1, the last 1), in species-id order.
        mix: Vec<(SpeciesId, f64)>,
        /// Spacing (m).
        spacing_m: f64,
        /// Age (years).
        age_yr: f32,
    },
}

/// The square patches of side `size_m` (m) over `region`'s bounding box, laid from its SW
/// corner: `(columns, rows, the squares that hold part of the region)`, squares numbered
/// row-major from the SW corner. A square holds part of the region when its part on the box
/// ([`Region::bbox`]; the last row and column reach past it) is crossed by an edge of one of
/// the region's polygons, or, crossed by none, lies wholly inside the region (its centre
/// inside, [`Region::contains`]); a region without polygons is the box, which every square
/// meets. Until round 44 only squares whose centre lay in the region were cut, so a row of
/// squares reaching less than half their side into the box, and squares straddling a
/// polygon's edge, were never cut: a 10 m strip along the north edge of the shipped
/// `parcels.toml` central parcel (400 m high, 30 m patches) stood after entries whose shares
/// summed to 1 (trial 43 defect 10).
pub fn patch_squares(region: &Region, size_m: f64) -> (usize, usize, Vec<usize>) {
    let b = region.bbox;
    let nx = (((b[2] - b[0]) / size_m).ceil() as usize).max(1);
    let ny = (((b[3] - b[1]) / size_m).ceil() as usize).max(1);
    let inside = (0..nx * ny)
        .filter(|&p| {
            let (x0, y0) = (b[0] + (p % nx) as f64 * size_m, b[1] + (p / nx) as f64 * size_m);
            let r = [x0, y0, (x0 + size_m).min(b[2]), (y0 + size_m).min(b[3])];
            if r[2] <= r[0] || r[3] <= r[1] {
                return false;
            }
            match &region.polygons {
                None => true,
                Some(ps) => ps.iter().flatten().any(|ring| (0..ring.len()).any(|k| segment_meets_rect(ring[k], ring[(k + 1) % ring.len()], r))) || region.contains(0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3])),
            }
        })
        .collect();
    (nx, ny, inside)
}

/// The squares (positions `lo..hi` in a patch cut's drawn order of its `n` squares) that entry
/// `k` (0 the first) of a patch cut of `share` cuts: `round(k · share · n)` to
/// `round((k + 1) · share · n)`, at least one, within `n`. Rounded cumulatively, so `m` entries
/// whose shares sum to 1 cut all `n` squares (round 44: with `round(share · n)` squares an
/// entry, five entries of 0.2 over 12 squares cut 10).
pub fn patch_range(n: usize, share: f64, k: u32) -> (usize, usize) {
    let at = |j: f64| ((j * share * n as f64).round().max(0.0) as usize).min(n);
    let lo = at(k as f64);
    (lo, at(k as f64 + 1.0).max(lo + 1).min(n))
}

/// Whether segment `a`–`b` meets the open rectangle `r = [x0, y0, x1, y1]` (its interior):
/// Liang–Barsky clipping of the segment's parameter range to the rectangle's slabs (Liang &
/// Barsky 1984, *A new concept and method for line clipping*, ACM TOG 3(1)).
fn segment_meets_rect(a: [f64; 2], b: [f64; 2], r: [f64; 4]) -> bool {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let d = [b[0] - a[0], b[1] - a[1]];
    for (p, q) in [(-d[0], a[0] - r[0]), (d[0], r[2] - a[0]), (-d[1], a[1] - r[1]), (d[1], r[3] - a[1])] {
        if p == 0.0 {
            if q <= 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 < t1
}

/// A thinning target over the thinned area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// Basal area (m²/ha) of the stems ≥ 1.3 m.
    BasalArea(f64),
    /// Relative density ([`super::phases::management::stand_rd`]).
    RelativeDensity(f64),
    /// Stems/ha ≥ 1.3 m.
    Stems(f64),
}

/// A `[[management]]` entry resolved against the site: what it does, where, and when.
#[derive(Debug, Clone, PartialEq)]
pub struct Operation {
    /// Position of the entry in the scenario (its random streams are keyed by it).
    pub index: usize,
    /// The entry as written (timing).
    pub spec: Management,
    /// What it does.
    pub action: Action,
    /// Where.
    pub region: Region,
    /// The warning that part of the area as given lies outside the site and was clipped off
    /// (the field, its share and the site's extent, [`resolve`]; [`warnings`] gives it with the
    /// scenario's name); `None` when it lies inside.
    pub clipped: Option<String>,
    /// The warning that a thinning's `target_stems_ha` lies above the most stems of the growing
    /// stock any stand of the pool holds ([`unreachable_stems`]), so the entry never removes a
    /// tree; `None` otherwise.
    pub unreachable: Option<String>,
}

/// The least DBH (cm) of the growing stock a thinning's targets count: 7 cm, as
/// [`super::density::MIN_DBH_CM`] (the yield tables' and the relative density's).
const GROWING_STOCK_DBH_CM: f64 = 7.0;

/// The warning (without the scenario's name) for entry `i`, a thinning to `target` stems/ha
/// of the growing stock (stems of at least [`super::density::MIN_DBH_CM`], 7 cm, DBH) when the
/// target lies above the most such stems per hectare a stand of the pool's species can hold:
/// the largest over the pool of the stems on a species' maximum-density line at Dq 7 cm
/// ([`super::density::max_stems`] with its `life.density`: `SDI_max · (7/25)^slope`, Reineke
/// 1933); a stand of stems of 7 cm or more has Dq ≥ 7 cm, and a mixed stand's relative
/// densities share the line, so its stems stay below that (round 44, trial 43 defect 11: a
/// target of 100,000 stems/ha was only reported year by year in the log). `None` when the
/// target can be exceeded or the pool is empty.
pub fn unreachable_stems(i: usize, target: f64, lib: &SpeciesLibrary, pool: &[SpeciesId]) -> Option<String> {
    // `density::max_stems(sdi_max, slope, 7 cm)` written out: `sim::density` reads the world,
    // which reads the scenario and so this module (tests/layers.rs: no import cycles)
    let (dq, d_ref) = (GROWING_STOCK_DBH_CM, 25.0);
    let (id, d, n) = pool
        .iter()
        .map(|&s| {
            let sp = &lib.species[s as usize];
            let d = &sp.life.density;
            (sp.id.as_str(), d, d.sdi_max as f64 * (dq / d_ref).powf(d.reineke_slope as f64))
        })
        .max_by(|a, b| a.2.total_cmp(&b.2))?;
    (target > n).then(|| {
        format!(
            "management[{i}].target_stems_ha = {target} lies above the most stems of 7 cm DBH or more a stand of the pool holds per hectare ({n:.0}: {id}'s maximum-density line at Dq 7 cm, SDI_max {} with Reineke slope {}): the thinning never finds its area above the target and removes nothing (a target below it, e.g. a yield table's stems per hectare after thinning)",
            d.sdi_max, d.reineke_slope
        )
    })
}

/// Converts a point of the DEM's CRS to world metres (origin SW corner) on `site`: through the
/// grid's georeferencing (pixel coordinates times the cell size).
///
/// A site without georeferencing (a uniform or generated terrain, [`crate::grid::Crs::Local`])
/// has the local GeoRef of [`crate::grid::GeoRef::local`]: origin (0, 0) at the top-left (NW)
/// corner, one CRS unit a metre, rows going south. So its area files are read in the
/// coordinates the run's outputs are written in (the GeoPackage and GeoParquet inventories,
/// the GeoTIFF maps; [`crate::output::georef::PointGeoRef`]): x from 0 to the width W east,
/// y from −H (the south edge) to 0 (the north edge), so a polygon drawn in QGIS over the
/// outputs lands where it was drawn; world y = H + file y. (Inline `area` and `polygons` are
/// world metres, origin the SW corner, y from 0 to H, as the `[[start]]` areas.)
fn crs_to_world(site: &SiteConditions, x: f64, y: f64) -> [f64; 2] {
    let g = &site.geo;
    let col = (x - g.origin_x) / g.pixel_w;
    let row = (g.origin_y - y) / g.pixel_h;
    [col * site.cell_x_m, (site.height() as f64 - row) * site.cell_y_m]
}

/// The inverse of [`crs_to_world`]: the DEM's CRS coordinates of world point `(x, y)` (m,
/// origin SW corner) on `site` (for messages).
pub(crate) fn world_to_crs(site: &SiteConditions, x: f64, y: f64) -> [f64; 2] {
    let g = &site.geo;
    [g.origin_x + x / site.cell_x_m * g.pixel_w, g.origin_y - (site.height() as f64 - y / site.cell_y_m) * g.pixel_h]
}

/// Whether a GeoJSON property value equals the filter's value (texts as texts, numbers as
/// numbers, booleans as booleans).
fn matches(v: &serde_json::Value, want: &toml::Value) -> bool {
    match (v, want) {
        (serde_json::Value::String(a), toml::Value::String(b)) => a == b,
        (serde_json::Value::Number(a), toml::Value::Integer(b)) => a.as_f64() == Some(*b as f64),
        (serde_json::Value::Number(a), toml::Value::Float(b)) => a.as_f64() == Some(*b),
        (serde_json::Value::Bool(a), toml::Value::Boolean(b)) => a == b,
        (serde_json::Value::Number(a), toml::Value::String(b)) => b.parse::<f64>().ok() == a.as_f64(),
        (serde_json::Value::String(a), toml::Value::Integer(b)) => a.parse::<i64>().ok() == Some(*b),
        _ => false,
    }
}

/// A polygon of an area file (rings of `[x, y]` in the file's coordinates) with the feature it
/// came from, as messages name it (`feature 2 (id "B")`, `layer `parcels`, feature 7`).
pub type FilePolygon = (String, Vec<Vec<[f64; 2]>>);

/// The geometry types an area file's features may have.
const ACCEPTED: &str = "Polygon or MultiPolygon (the only geometry types an area is read from)";

/// The EPSG code a GeoJSON `crs` member names (the legacy named CRS of GeoJSON 2008, §3.1, as
/// GDAL writes it): `urn:ogc:def:crs:EPSG::NNNN`, `urn:ogc:def:crs:EPSG:V:NNNN`, `EPSG:NNNN`,
/// or OGC's CRS84 (longitude/latitude on WGS 84: 4326). `Err` with the name (or the member as
/// JSON) where it names none of these.
pub fn geojson_crs_epsg(crs: &serde_json::Value) -> std::result::Result<u32, String> {
    let name = crs.get("properties").and_then(|p| p.get("name")).and_then(|n| n.as_str()).ok_or_else(|| crs.to_string())?;
    let upper = name.trim().to_ascii_uppercase();
    if upper.ends_with("CRS84") {
        return Ok(4326);
    }
    let code = upper.strip_prefix("URN:OGC:DEF:CRS:EPSG:").map(|r| r.rsplit(':').next().unwrap_or("")).or_else(|| upper.strip_prefix("EPSG:"));
    code.and_then(|c| c.parse::<u32>().ok()).ok_or_else(|| format!("{name:?}"))
}

/// The polygons (rings of `[x, y]` in the file's coordinates) of the Polygon and MultiPolygon
/// features of GeoJSON file `path` that pass `filter` ([`read_geojson_area`] without the
/// features' names).
///
/// Errors: as [`read_geojson_area`].
pub fn read_geojson_polygons(path: &Path, filter: Option<&AreaFilter>, dem_epsg: Option<u32>, ctx: &str, field: &str) -> Result<Vec<Vec<Vec<[f64; 2]>>>> {
    Ok(read_geojson_area(path, filter, dem_epsg, ctx, field)?.into_iter().map(|p| p.1).collect())
}

/// The polygons of the features of GeoJSON file `path` (a FeatureCollection, a Feature or a
/// bare geometry) that pass `filter`, each with its feature (`feature k`, its index in the
/// file, and its `id` where it has one). When the DEM has an EPSG code (`dem_epsg`) and the
/// file a `crs` member, the member must name that code ([`geojson_crs_epsg`]); a file without
/// one is taken to be in the DEM's CRS. `field` names the scenario field in messages.
///
/// Errors: [`Error::Invalid`] naming the scenario (`ctx`), `field`, the file and what is wrong:
/// unreadable, not JSON (with the parser's message), a `crs` other than the DEM's (found and
/// expected, with the `ogr2ogr -t_srs` command that reprojects it), a feature passing the
/// filter without a geometry (null) or with another type than Polygon or MultiPolygon (naming
/// the feature and the type), malformed coordinates, a self-crossing polygon, no polygon, or no
/// feature passing the filter.
pub fn read_geojson_area(path: &Path, filter: Option<&AreaFilter>, dem_epsg: Option<u32>, ctx: &str, field: &str) -> Result<Vec<FilePolygon>> {
    let bad = |expected: String| Error::Invalid { context: ctx.to_string(), field: field.to_string(), value: path.display().to_string(), expected };
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("a readable GeoJSON file ({e})")))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(format!("a GeoJSON file of Polygon or MultiPolygon features (the file does not parse: {e})")))?;
    if let (Some(want), Some(crs)) = (dem_epsg, v.get("crs")) {
        let found = match geojson_crs_epsg(crs) {
            Ok(code) if code == want => None,
            Ok(code) => Some(format!("EPSG:{code}")),
            Err(name) => Some(format!("{name}, not an EPSG code")),
        };
        if let Some(found) = found {
            return Err(bad(format!("polygons in the DEM's CRS, EPSG:{want} (the file's `crs` member names {found}; reproject it, e.g. `ogr2ogr -t_srs EPSG:{want} out.geojson {}`)", path.display())));
        }
    }
    let kind = v.get("type").and_then(|t| t.as_str()).unwrap_or("");
    // (feature name, properties, geometry)
    let feats: Vec<(String, Option<&serde_json::Value>, Option<&serde_json::Value>)> = match kind {
        "FeatureCollection" => {
            let fs = v.get("features").and_then(|f| f.as_array()).ok_or_else(|| bad("a FeatureCollection with a `features` array".into()))?;
            fs.iter()
                .enumerate()
                .map(|(k, f)| {
                    let name = match f.get("id") {
                        Some(id) if !id.is_null() => format!("feature {k} (id {id})"),
                        _ => format!("feature {k}"),
                    };
                    (name, f.get("properties"), f.get("geometry"))
                })
                .collect()
        }
        "Feature" => vec![("feature 0".into(), v.get("properties"), v.get("geometry"))],
        _ => vec![("the file's geometry".into(), None, Some(&v))],
    };
    let mut out = Vec::new();
    let mut seen = 0usize;
    let props_seen: Vec<Option<&serde_json::Value>> = feats.iter().map(|f| f.1).collect();
    for (name, props, geom) in feats.iter().cloned() {
        if let Some(f) = filter {
            let p = props.and_then(|p| p.get(&f.property));
            if !p.is_some_and(|p| matches(p, &f.equals)) {
                continue;
            }
        }
        seen += 1;
        let Some(g) = geom.filter(|g| !g.is_null()) else {
            return Err(bad(format!("{ACCEPTED} geometries ({name} has none: its geometry is null; give it a polygon, or leave it out with a `filter`)")));
        };
        let ty = g.get("type").and_then(|t| t.as_str()).unwrap_or("(no type)");
        if ty != "Polygon" && ty != "MultiPolygon" {
            let curved = ["CurvePolygon", "MultiSurface", "CompoundCurve", "CircularString", "MultiCurve"].contains(&ty);
            let hint = if curved { "; curved geometries are not read: linearise them, e.g. `ogr2ogr -nlt MULTIPOLYGON out.geojson in.geojson`" } else { "" };
            return Err(bad(format!("{ACCEPTED} geometries ({name} is a {ty}{hint})")));
        }
        let parsed: geojson::Geometry = serde_json::from_value(g.clone()).map_err(|e| bad(format!("a GeoJSON {ty} ({name} does not parse: {e})")))?;
        // a position needs x and y (a third number, the height, is ignored)
        // RFC 7946 §3.1.6: a linear ring is closed, its first and last positions the same (a
        // ring left open is refused rather than closed silently: found by a break-it pass)
        let rings_of = |p: &[Vec<geojson::Position>]| -> Result<Vec<Vec<[f64; 2]>>> {
            p.iter()
                .enumerate()
                .map(|(k, r)| {
                    let ring = r.iter().map(|q| if q.len() >= 2 { Ok([q[0], q[1]]) } else { Err(bad(format!("positions of two numbers [x, y] ({name} has one of {}: {q:?})", q.len()))) }).collect::<std::result::Result<Vec<_>, _>>()?;
                    match (ring.first(), ring.last()) {
                        (Some(a), Some(b)) if ring.len() >= 4 && a == b => Ok(ring),
                        (Some(a), Some(b)) if ring.len() >= 2 && a != b => Err(bad(format!("closed linear rings, the last position equal to the first (RFC 7946 §3.1.6; ring {k} of {name} starts at {a:?} and ends at {b:?})"))),
                        _ => Err(bad(format!("linear rings of at least four positions, the last equal to the first (RFC 7946 §3.1.6; ring {k} of {name} has {})", ring.len()))),
                    }
                })
                .collect::<std::result::Result<Vec<_>, _>>()
        };
        match &parsed.value {
            geojson::GeometryValue::Polygon { coordinates } => out.push((name.clone(), rings_of(coordinates)?)),
            geojson::GeometryValue::MultiPolygon { coordinates } => {
                for p in coordinates {
                    out.push((name.clone(), rings_of(p)?));
                }
            }
            _ => {}
        }
    }
    if out.is_empty() {
        // the properties the features have, for a filter naming none of them (trial 38, item
        // 10: a typo said only "none does")
        let mut names: Vec<&str> = Vec::new();
        for p in props_seen.iter().filter_map(|p| p.and_then(|p| p.as_object())) {
            for k in p.keys() {
                if !names.contains(&k.as_str()) {
                    names.push(k);
                }
            }
        }
        return Err(bad(match (filter, seen) {
            (_, 0) if props_seen.is_empty() => format!("at least one {ACCEPTED} feature (the file has 0 features)"),
            (Some(f), 0) if !names.contains(&f.property.as_str()) => format!(
                "a feature whose property `{}` equals {} (no feature has a property `{}`; the file's features have {})",
                f.property,
                f.equals,
                f.property,
                if names.is_empty() { "no properties".to_string() } else { names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ") }
            ),
            (Some(f), 0) => format!("a feature whose property `{}` equals {} (none does, of its {} features)", f.property, f.equals, props_seen.len()),
            _ => format!("at least one {ACCEPTED} feature (none found)"),
        }));
    }
    for (k, (name, p)) in out.iter().enumerate() {
        check_rings(p).map_err(|e| bad(format!("polygon {k} of the file ({name}): {e}")))?;
    }
    Ok(out)
}

/// Extensions (lower case) of vector formats GDAL/OGR reads and `ogr2ogr` converts to a
/// GeoPackage (GDAL's vector drivers: ESRI Shapefile, KML/KMZ, GML, FlatGeobuf, MapInfo TAB/MIF,
/// GPX, SQLite/SpatiaLite, File Geodatabase, DXF, GeoJSONSeq): an area file of
/// such an extension is refused with the `ogr2ogr` command that converts it; any other with
/// what `area_file` must be.
const OGR_VECTOR_EXTENSIONS: [&str; 12] = ["shp", "kml", "kmz", "gml", "fgb", "tab", "mif", "gpx", "sqlite", "gdb", "dxf", "geojsonl"];

/// Whether `path` names a GeoPackage (extension `.gpkg`, any case).
pub fn is_gpkg(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gpkg"))
}

/// The polygons (rings of `[x, y]` in the file's coordinates) of the Polygon and MultiPolygon
/// features of layer `layer` (the first feature layer when `None`) of GeoPackage `path`
/// (OGC GeoPackage 1.3 §2.1: [`crate::gpkg::read_polygons`]) whose attribute column passes
/// `filter` (the property is a column: texts as texts, numbers as numbers, `BOOLEAN` columns
/// as booleans). When the DEM has an EPSG code (`dem_epsg`) a layer whose SRS is an EPSG code
/// must have that one. `field` names the scenario field in messages.
///
/// Errors: [`Error::Invalid`] naming the scenario (`ctx`), `field`, the file and what is wrong:
/// not a readable GeoPackage, no such layer (the layers listed), no such filter column (the
/// columns listed), a geometry other than Polygon/MultiPolygon (naming the layer, the feature
/// id and the type found), the layer in another CRS, no polygon, or no feature passing the
/// filter.
pub fn read_gpkg_polygons(path: &Path, layer: Option<&str>, filter: Option<&AreaFilter>, dem_epsg: Option<u32>, ctx: &str, field: &str) -> Result<Vec<Vec<Vec<[f64; 2]>>>> {
    Ok(read_gpkg_area(path, layer, filter, dem_epsg, ctx, field)?.into_iter().map(|p| p.1).collect())
}

/// As [`read_gpkg_polygons`], each polygon with its feature (`layer `parcels`, feature 7`: the
/// layer and the feature's fid).
///
/// Errors: as [`read_gpkg_polygons`].
pub fn read_gpkg_area(path: &Path, layer: Option<&str>, filter: Option<&AreaFilter>, dem_epsg: Option<u32>, ctx: &str, field: &str) -> Result<Vec<FilePolygon>> {
    let bad = |expected: String| Error::Invalid { context: ctx.to_string(), field: field.to_string(), value: path.display().to_string(), expected };
    let keep = filter.map(|f| move |v: &serde_json::Value| matches(v, &f.equals));
    let fil = filter.zip(keep.as_ref()).map(|(f, k)| (f.property.as_str(), k as &dyn Fn(&serde_json::Value) -> bool));
    let got = crate::gpkg::read_polygons(path, layer, fil).map_err(|e| bad(e.0))?;
    let info = got.layer.clone();
    // OGC GeoPackage 1.3 §1.1.2.1.1: srs_id 0 is the undefined geographic SRS (longitude and
    // latitude in degrees, never the DEM's metres), and a layer's srs_id must be a row of
    // gpkg_spatial_ref_sys (an id without one says nothing of its coordinates); both were read
    // as the DEM's CRS (found by a trial)
    if info.srs_id == 0 {
        return Err(bad(format!("a layer in the DEM's projected CRS{} (layer `{}` has srs_id 0, the GeoPackage's undefined geographic SRS: degrees of longitude and latitude; reproject it, e.g. `ogr2ogr -s_srs EPSG:4326 -t_srs {} out.gpkg {}`)", dem_epsg.map(|c| format!(", EPSG:{c}")).unwrap_or_default(), info.table, dem_epsg.map(|c| format!("EPSG:{c}")).unwrap_or_else(|| "EPSG:<the DEM's code>".into()), path.display())));
    }
    if info.organization.is_none() && info.srs_id != -1 {
        return Err(bad(format!("a layer whose srs_id is defined in gpkg_spatial_ref_sys (layer `{}` has srs_id {}, which the file does not define)", info.table, info.srs_id)));
    }
    if let (Some(want), Some((org, code))) = (dem_epsg, &info.organization) {
        if org.eq_ignore_ascii_case("EPSG") && *code != want as i64 {
            return Err(bad(format!("polygons in the DEM's CRS, EPSG:{want} (layer `{}` is in EPSG:{code}; reproject it, e.g. `ogr2ogr -t_srs EPSG:{want} out.gpkg {}`)", info.table, path.display())));
        }
    }
    if got.polygons.is_empty() {
        return Err(bad(match (filter, got.features) {
            // an empty layer (trial 38, item 10: it said only "none does")
            (_, 0) if got.rows == 0 => format!("at least one Polygon or MultiPolygon feature in layer `{}` (the layer has 0 features)", info.table),
            (Some(f), 0) => format!("a feature of layer `{}` whose column `{}` equals {} (none does, of its {} features)", info.table, f.property, f.equals, got.rows),
            _ => format!("at least one Polygon or MultiPolygon feature in layer `{}` (none found)", info.table),
        }));
    }
    let mut out = Vec::with_capacity(got.polygons.len());
    for (k, (fid, p)) in got.polygons.into_iter().enumerate() {
        let name = format!("layer `{}`, feature {fid}", info.table);
        check_rings(&p).map_err(|e| bad(format!("polygon {k} of the file ({name}): {e}")))?;
        out.push((name, p));
    }
    Ok(out)
}

/// The parts of a site that [`resolve`] reads: its conditions (extent, georeferencing), light
/// grid and the site cell of each light cell of `span` (`u32::MAX` where masked), and the
/// species pool.
pub struct SiteView<'a> {
    /// Site conditions.
    pub conditions: &'a SiteConditions,
    /// World extent (m).
    pub extent: (f64, f64),
    /// The light grid.
    pub light: &'a LightGrid,
    /// The light cells `light_site` covers: the whole grid (one process), or a tile's rectangle
    /// (a tiled run's rank, whose counts [`resolve_by`] sums over the ranks).
    pub span: super::light_grid::Span,
    /// Site cell of each light cell of `span`, in span order (`u32::MAX`: masked).
    pub light_site: &'a [u32],
    /// Pool species.
    pub pool: &'a [SpeciesId],
}

/// How [`resolve_by`] measures each area's unmasked ground (`Region::area_ha`).
pub enum Areas<'a> {
    /// Counted over the view's light cells alone (the whole grid: one process).
    Local,
    /// Counted over the view's light cells (a tile's rectangle), then summed over the ranks of
    /// a tiled run by the all-sum given (every rank calls it the same number of times, with one
    /// word per entry: the centre count, then for an area that holds no centre the fine
    /// count); integer counts, so the area is one process's bit for bit (issue 37, round 36).
    Summed(&'a mut dyn FnMut(Vec<u64>) -> Result<Vec<u64>>),
    /// Not measured (`area_ha` 0, no refusal of an area without unmasked ground): the checks a
    /// rank holding a band of the site can make before the run's folders are written (species,
    /// area files, extents, patch sizes, spacings); the ranks measure the areas as the run
    /// starts.
    Unmeasured,
}

/// Sub-samples per light-cell side of [`fine_area_points`] (8: 64 points a cell, 0.6 m apart in 5 m
/// cells).
const FINE_SAMPLES: usize = 8;

/// The unmasked ground of `region` measured on a lattice of [`FINE_SAMPLES`]² points in every
/// light cell of `site.span` its box touches (a tile's part of the count in a tiled run;
/// [`fine_points_ha`] gives the area): for regions that hold no light-cell centre (narrower
/// than a cell), whose area the count of cell centres gives as 0.
fn fine_area_points(region: &Region, site: &SiteView<'_>) -> u64 {
    let l = site.light;
    let step = l.cell_m / FINE_SAMPLES as f64;
    let mut n = 0u64;
    for k in (0..site.span.len()).filter(|&k| site.light_site[k] != u32::MAX) {
        let (cx, cy) = l.centre(site.span.cell(k));
        let (x0, y0) = (cx - 0.5 * l.cell_m, cy - 0.5 * l.cell_m);
        let b = &region.bbox;
        if x0 >= b[2] || y0 >= b[3] || x0 + l.cell_m <= b[0] || y0 + l.cell_m <= b[1] {
            continue;
        }
        for j in 0..FINE_SAMPLES {
            for k in 0..FINE_SAMPLES {
                n += u64::from(region.contains(x0 + (k as f64 + 0.5) * step, y0 + (j as f64 + 0.5) * step));
            }
        }
    }
    n
}

/// The area (ha) of `n` points of [`fine_area_points`] on light cells of `cell_m` (m).
fn fine_points_ha(n: u64, cell_m: f64) -> f64 {
    let step = cell_m / FINE_SAMPLES as f64;
    n as f64 * (step * step / 10_000.0)
}

/// Resolves the scenario's entries against the site (its extent, mask, light grid and
/// georeferencing) and the species library: regions in world metres with their areas, species
/// ids of plantings. Entries come out in scenario order.
///
/// Errors: [`Error::Invalid`] naming `management[i].<field>`: a planted species outside the
/// library or the pool, an area outside the site or without unmasked ground, an area file that
/// cannot be read ([`read_geojson_polygons`], [`read_gpkg_polygons`]).
pub fn resolve(entries: &[Management], site: &SiteView<'_>, lib: &SpeciesLibrary, ctx: &str) -> Result<Vec<Operation>> {
    resolve_by(entries, site, lib, ctx, Areas::Local)
}

/// [`resolve`] with the areas measured as `areas` says: [`Areas::Summed`] by a tiled run's
/// ranks, each counting the light cells of its own tile (`site.span`; issue 37, round 36: until
/// then every rank held the whole site to count them), [`Areas::Unmeasured`] for the checks of
/// a rank that holds a band of the site.
///
/// Errors: as [`resolve`]; the all-sum's (a failed exchange). With [`Areas::Summed`] every rank
/// gets the same counts, so the same refusals.
pub fn resolve_by(entries: &[Management], site: &SiteView<'_>, lib: &SpeciesLibrary, ctx: &str, mut areas: Areas<'_>) -> Result<Vec<Operation>> {
    let (ex, ey) = site.extent;
    let mut ops = Vec::with_capacity(entries.len());
    for (i, m) in entries.iter().enumerate() {
        let polygons = match (&m.polygons, &m.area_file) {
            (Some(p), _) => Some(p.clone()),
            (_, Some(f)) => Some(read_area_file(f, m, site, (ex, ey), ctx, &format!("management[{i}].area_file"))?),
            _ => None,
        };
        let bbox = match (&m.area, &polygons) {
            (Some(a), _) => *a,
            (_, Some(ps)) => bbox_of(ps.iter().flatten().flatten()),
            _ => [0.0, 0.0, ex, ey],
        };
        let clipped = [bbox[0].max(0.0), bbox[1].max(0.0), bbox[2].min(ex), bbox[3].min(ey)];
        let mut region = Region { bbox: clipped, polygons, area_ha: 0.0 };
        let l = site.light;
        let measured = !matches!(areas, Areas::Unmeasured);
        let mut sum = |n: u64| -> Result<u64> {
            match &mut areas {
                Areas::Summed(f) => {
                    let v = f(vec![n])?;
                    v.first().copied().ok_or_else(|| Error::Exchange { peer: 0, reason: format!("no summed count of management[{i}]'s area") })
                }
                _ => Ok(n),
            }
        };
        let centres = (0..site.span.len()).filter(|&k| site.light_site[k] != u32::MAX && {
            let (x, y) = l.centre(site.span.cell(k));
            region.contains(x, y)
        });
        let centres = if measured { sum(centres.count() as u64)? } else { 0 };
        region.area_ha = centres as f64 * l.cell_m * l.cell_m / 10_000.0;
        if measured && region.area_ha <= 0.0 {
            // narrower than a light cell (a skid trail, a small square between cell centres):
            // its unmasked ground measured finer (round 32's trial: a 4 m strip inside the site
            // was refused as if it lay outside it)
            region.area_ha = fine_points_ha(sum(fine_area_points(&region, site))?, l.cell_m);
        }
        if measured && region.area_ha <= 0.0 {
            let field = if m.area.is_some() { "area" } else if m.area_file.is_some() { "area_file" } else { "polygons" };
            let inside = clipped[0] < clipped[2] && clipped[1] < clipped[3];
            let expected = if inside { "an area that covers unmasked ground: this one lies on the site but only where its DEM has no data (masked cells)".to_string() } else { format!("an area covering unmasked ground of the site, 0 ≤ x < {ex} m and 0 ≤ y < {ey} m (origin SW corner; an area file in the DEM's CRS)") };
            return Err(invalid(ctx, i, field, format!("{bbox:?} (bounding box, m)"), &expected));
        }
        let action = match (m.kind.as_str(), m.method.as_deref()) {
            ("thinning", Some("crop_trees")) => {
                let n_ha = m.crop_trees_ha.unwrap_or(100.0);
                let target = match (m.target_basal_area_m2_ha, m.target_relative_density, m.target_stems_ha) {
                    (Some(b), _, _) => Some(Target::BasalArea(b)),
                    (_, Some(r), _) => Some(Target::RelativeDensity(r)),
                    (_, _, s) => s.map(Target::Stems),
                };
                Action::CropTrees { n_ha, distance_m: m.crop_tree_distance_m.unwrap_or_else(|| crop_tree_distance(n_ha)), target, trigger_rd: m.trigger_relative_density, trigger_top_height_m: m.trigger_top_height_m }
            }
            ("thinning", method) => Action::Thinning {
                from_below: method == Some("from_below"),
                target: match (m.target_basal_area_m2_ha, m.target_relative_density, m.target_stems_ha) {
                    (Some(b), _, _) => Target::BasalArea(b),
                    (_, Some(r), _) => Target::RelativeDensity(r),
                    (_, _, s) => Target::Stems(s.unwrap_or(0.0)),
                },
                trigger_rd: m.trigger_relative_density,
                trigger_top_height_m: m.trigger_top_height_m,
            },
            ("harvest", Some("patch")) => {
                let size_m = m.patch_size_m.unwrap_or(50.0);
                let (w, h) = (clipped[2] - clipped[0], clipped[3] - clipped[1]);
                // found by a break-it pass: such patches never cut and nothing said so
                if size_m > w.min(h) {
                    return Err(invalid(ctx, i, "patch_size_m", size_m, &format!("a patch that fits in the area: at most {:.1} m, the shorter side of the area's bounding box ({w:.1} m × {h:.1} m on the site)", w.min(h))));
                }
                if patch_squares(&region, size_m).2.is_empty() {
                    return Err(invalid(ctx, i, "patch_size_m", size_m, "a patch size whose squares (laid from the SW corner of the area's bounding box) hold part of the area (none does: use smaller patches)"));
                }
                Action::Patch { size_m, share: m.share.unwrap_or(1.0) }
            }
            ("harvest", Some("shelterwood")) => Action::Shelterwood { shares: m.stages.iter().flatten().map(|g| g.share).collect() },
            ("harvest", _) => Action::ClearCut,
            ("keep_open", _) => Action::KeepOpen { max_height_m: m.max_height_m.unwrap_or(0.0) },
            _ => {
                let mix = m.mix.clone().unwrap_or_default();
                let total: f64 = mix.values().sum();
                let mut acc = 0.0;
                let mut out = Vec::new();
                for (sp, s) in &mix {
                    let id = lib.find(sp).ok_or_else(|| invalid(ctx, i, &format!("mix.{sp}"), sp, &format!("a species id of the library{}", lib.did_you_mean(sp))))?;
                    if !site.pool.contains(&id) {
                        return Err(invalid(ctx, i, &format!("mix.{sp}"), sp, "a species of the scenario's pool (add it to `species`)"));
                    }
                    // a planted tree older than its species lives dies at once (found by a
                    // break-it pass: 1,000-year spruce all died in year 2)
                    let age = m.age_yr.unwrap_or(2.0);
                    let max_age = lib.species[id as usize].life.max_age_yr;
                    if age > max_age {
                        return Err(invalid(ctx, i, "age_yr", age, &format!("at most the maximum age of {sp} ({max_age} years, `life.max_age_yr` in its species file)")));
                    }
                    acc += s / total;
                    out.push((id, acc));
                }
                if let Some(last) = out.last_mut() {
                    last.1 = 1.0;
                }
                let sp = m.spacing_m.unwrap_or(2.0);
                let n = ((clipped[2] - clipped[0]) / sp).floor().max(0.0) * ((clipped[3] - clipped[1]) / sp).floor().max(0.0);
                if n > MAX_PLANTED_TREES as f64 {
                    return Err(invalid(ctx, i, "spacing_m", sp, &format!("a spacing that plants at most {} trees ({n} on this area)", MAX_PLANTED_TREES)));
                }
                Action::Planting { mix: out, spacing_m: m.spacing_m.unwrap_or(2.0), age_yr: m.age_yr.unwrap_or(2.0) }
            }
        };
        let clipped = outside_note(m, bbox, region.polygons.as_deref(), site, i);
        let unreachable = match action {
            Action::Thinning { target: Target::Stems(n), .. } => unreachable_stems(i, n, lib, site.pool),
            _ => None,
        };
        ops.push(Operation { index: i, spec: m.clone(), action, region, clipped, unreachable });
    }
    Ok(ops)
}

/// The polygons of entry `m`'s `area_file` `f` in world metres on `site` (extent `(ex, ey)`,
/// m): read as a GeoPackage ([`read_gpkg_area`]) or GeoJSON ([`read_geojson_area`]) in the
/// DEM's CRS, converted by [`crs_to_world`]. `field` names the scenario field in messages.
///
/// Errors: [`Error::Invalid`] naming `ctx`, `field` and the file: a folder where a file is
/// expected, the readers' errors, and a polygon wholly outside the site (naming its feature,
/// its bounding box and the site's in the file's coordinates).
fn read_area_file(f: &Path, m: &Management, site: &SiteView<'_>, (ex, ey): (f64, f64), ctx: &str, field: &str) -> Result<Vec<Vec<Vec<[f64; 2]>>>> {
    let bad = |expected: String| Error::Invalid { context: ctx.to_string(), field: field.to_string(), value: f.display().to_string(), expected };
    if f.is_dir() {
        return Err(bad("a GeoPackage (`.gpkg`) or GeoJSON file (it is a folder: name the file in it)".into()));
    }
    let g = &site.conditions.geo;
    let epsg = if g.crs == crate::grid::Crs::Local { None } else { g.epsg };
    let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if !is_gpkg(f) && !["geojson", "json"].contains(&ext.as_str()) {
        let what = if ext.is_empty() { "file without an extension".to_string() } else { format!("`.{ext}` file") };
        // only a vector format GDAL reads gets the command that converts it; a scenario, a
        // table or a text is no vector file (trial 43 defect 11: a `.toml` got the hint
        // `ogr2ogr -f GPKG parcels.gpkg s.toml`)
        let how = if OGR_VECTOR_EXTENSIONS.contains(&ext.as_str()) {
            format!(": convert it, e.g. `ogr2ogr -f GPKG parcels.gpkg {}`", f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default())
        } else {
            " and is no vector file: area_file names a GeoPackage or GeoJSON file holding the area's polygons (a rectangle or polygons in the scenario itself are `area` or `polygons`)".to_string()
        };
        return Err(bad(format!("a GeoPackage (`.gpkg`) or GeoJSON file (`.geojson`, `.json`); a {what} is not read{how}")));
    }
    let ps = if is_gpkg(f) { read_gpkg_area(f, m.layer.as_deref(), m.filter.as_ref(), epsg, ctx, field)? } else { read_geojson_area(f, m.filter.as_ref(), epsg, ctx, field)? };
    let mut out = Vec::with_capacity(ps.len());
    for (k, (name, rings)) in ps.into_iter().enumerate() {
        let world: Vec<Vec<[f64; 2]>> = rings.iter().map(|r| r.iter().map(|p| crs_to_world(site.conditions, p[0], p[1])).collect()).collect();
        let w = bbox_of(world.iter().flatten());
        if w[2] <= 0.0 || w[3] <= 0.0 || w[0] >= ex || w[1] >= ey {
            let fb = bbox_of(rings.iter().flatten());
            let (s0, s1) = (world_to_crs(site.conditions, 0.0, 0.0), world_to_crs(site.conditions, ex, ey));
            let crs = match epsg {
                Some(c) => format!("EPSG:{c}"),
                None => "the coordinates of the run's outputs: a site without georeferencing runs from y = −H at its south edge to 0 at its north edge, x from 0 to W".into(),
            };
            // RFC 7946 GeoJSON has no `crs` member and is always longitude/latitude on WGS 84
            // (geojson.io, `ogr2ogr -lco RFC7946=YES`); read in a projected DEM's CRS it lands
            // near the origin (trial 40): say so, with the command that reprojects it
            let degrees = |b: [f64; 4]| b[0] >= -180.0 && b[2] <= 180.0 && b[1] >= -90.0 && b[3] <= 90.0;
            let site_b = [s0[0].min(s1[0]), s0[1].min(s1[1]), s0[0].max(s1[0]), s0[1].max(s1[1])];
            let hint = match epsg {
                Some(c) if c != 4326 && degrees(fb) && !degrees(site_b) => format!(
                    "; its coordinates look like longitude/latitude in degrees: a GeoJSON file without a `crs` member (RFC 7946) is longitude/latitude on WGS 84, so reproject it to the DEM's CRS, e.g. `ogr2ogr -s_srs EPSG:4326 -t_srs EPSG:{c} out.geojson {}`",
                    f.display()
                ),
                _ => String::new(),
            };
            return Err(bad(format!("polygons on the site: polygon {k} of the file ({name}) lies wholly outside it (its bounding box x {:.2}–{:.2}, y {:.2}–{:.2}; the site covers x {:.2}–{:.2}, y {:.2}–{:.2} in the file's CRS, {crs}){hint}", fb[0], fb[2], fb[1], fb[3], s0[0], s1[0], s0[1], s1[1])));
        }
        out.push(world);
    }
    Ok(out)
}

/// Shares (0–1) of an area cut off by the site's edge that are worth a warning: above 1 %
/// (a polygon drawn along the site's edge may stick out by a sliver).
const OUTSIDE_WARN_SHARE: f64 = 0.01;

/// The warning (without the scenario's name, which [`warnings`] adds) for entry `i` (`m`, its bounding box `bbox` as given and its `polygons` in
/// world metres) when more than [`OUTSIDE_WARN_SHARE`] of its area lies outside the site's
/// extent (round 34's trial: a GeoJSON polygon shifted 300 m west, half of it off the site, and
/// `area = [500, 500, 900, 900]` on a 600 m site, both clipped without a word): the field, the
/// share and area outside, the area left and the site's extent (in the area file's CRS for an
/// `area_file`). Geometric areas: a box's, or the polygons' (outer ring less holes, each ring
/// clipped to the site by Sutherland–Hodgman); the site's masked cells do not count as outside.
fn outside_note(m: &Management, bbox: [f64; 4], polygons: Option<&[Vec<Vec<[f64; 2]>>]>, site: &SiteView<'_>, i: usize) -> Option<String> {
    let (ex, ey) = site.extent;
    let (full, inside) = match polygons {
        Some(ps) => ps.iter().fold((0.0, 0.0), |(f, n), rings| {
            let area = |clip: bool| -> f64 {
                let a: Vec<f64> = rings.iter().map(|r| if clip { ring_area(&clip_ring(r, ex, ey)) } else { ring_area(r) }).collect();
                (a.first().copied().unwrap_or(0.0) - a.iter().skip(1).sum::<f64>()).max(0.0)
            };
            (f + area(false), n + area(true))
        }),
        None => {
            let w = |a: f64, b: f64| (b - a).max(0.0);
            (w(bbox[0], bbox[2]) * w(bbox[1], bbox[3]), w(bbox[0].max(0.0), bbox[2].min(ex)) * w(bbox[1].max(0.0), bbox[3].min(ey)))
        }
    };
    if full <= 0.0 || 1.0 - inside / full <= OUTSIDE_WARN_SHARE {
        return None;
    }
    let field = if m.area.is_some() { "area" } else if m.area_file.is_some() { "area_file" } else { "polygons" };
    let g = &site.conditions.geo;
    let extent = if m.area_file.is_some() {
        // in the file's coordinates, as the message of a polygon wholly outside gives them
        let (s0, s1) = (world_to_crs(site.conditions, 0.0, 0.0), world_to_crs(site.conditions, ex, ey));
        let crs = match g.epsg.filter(|_| g.crs != crate::grid::Crs::Local) {
            Some(c) => format!("EPSG:{c}"),
            None => "the coordinates of the run's outputs".into(),
        };
        format!("x {:.2}–{:.2}, y {:.2}–{:.2} in {crs}", s0[0], s1[0], s0[1], s1[1])
    } else {
        format!("x 0–{ex:.0} m, y 0–{ey:.0} m from its SW corner")
    };
    Some(format!(
        "management[{i}].{field}: {:.0} % of the area ({:.2} of {:.2} ha) lies outside the site, which covers {extent}; the entry acts on the {:.2} ha inside only (a shifted polygon or a wrong window?)",
        100.0 * (1.0 - inside / full),
        (full - inside) / 10_000.0,
        full / 10_000.0,
        inside / 10_000.0
    ))
}

/// Area (m², ≥ 0) of a ring of points by the shoelace formula, either orientation, closed or
/// not.
fn ring_area(r: &[[f64; 2]]) -> f64 {
    let n = r.len();
    (0..n).map(|k| r[k][0] * r[(k + 1) % n][1] - r[(k + 1) % n][0] * r[k][1]).sum::<f64>().abs() / 2.0
}

/// Ring `r` clipped to the rectangle 0 ≤ x ≤ `ex`, 0 ≤ y ≤ `ey` (Sutherland–Hodgman, one edge of
/// the rectangle at a time; a concave ring may come out with edges along the rectangle's sides,
/// which add no area).
fn clip_ring(r: &[[f64; 2]], ex: f64, ey: f64) -> Vec<[f64; 2]> {
    // each edge: inside test and the crossing of segment p–q with it
    let edges: [(usize, f64, bool); 4] = [(0, 0.0, true), (0, ex, false), (1, 0.0, true), (1, ey, false)];
    let mut pts = r.to_vec();
    for (axis, v, lower) in edges {
        let inside = |p: &[f64; 2]| if lower { p[axis] >= v } else { p[axis] <= v };
        let mut out = Vec::with_capacity(pts.len() + 4);
        for k in 0..pts.len() {
            let (p, q) = (pts[k], pts[(k + 1) % pts.len()]);
            let (pi, qi) = (inside(&p), inside(&q));
            if pi {
                out.push(p);
            }
            if pi != qi {
                let t = (v - p[axis]) / (q[axis] - p[axis]);
                out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        pts = out;
        if pts.is_empty() {
            break;
        }
    }
    pts
}

/// The bounding box `[x0, y0, x1, y1]` of points.
fn bbox_of<'a>(points: impl IntoIterator<Item = &'a [f64; 2]>) -> [f64; 4] {
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for p in points {
        b = [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])];
    }
    b
}

/// Warnings about resolved entries `ops` of a run of `last_year` years (`ctx` names the
/// scenario): every year an entry lists beyond the last ([`Management::years_beyond`]), which
/// never comes (found by a break-it pass: such entries were ignored without a word), and a
/// patch cut scheduled more often in the run than it has squares to open (the later entries
/// find every square cut and cut nothing), and an area partly outside the site
/// ([`Operation::clipped`]). Warnings, not errors: a run shortened with
/// `--years` keeps its scenario's later entries, and a patch cut may be meant to stop.
pub fn warnings(ops: &[Operation], last_year: u32, ctx: &str) -> Vec<String> {
    let mut out = Vec::new();
    for op in ops {
        out.extend(op.clipped.as_ref().map(|c| format!("{ctx}: {c}")));
        out.extend(op.unreachable.as_ref().map(|c| format!("{ctx}: {c}")));
        for (f, y) in op.spec.years_beyond(last_year) {
            out.push(format!("{ctx}: management[{}].{f} = {y} lies beyond the run's last year {last_year}: the entry does not act in that year", op.index));
        }
        // found by a trial: these entries acted on nothing and said nothing
        if let Action::CropTrees { n_ha, .. } = op.action {
            if (n_ha * op.region.area_ha).round() < 1.0 {
                out.push(format!("{ctx}: management[{}]: {n_ha} crop trees per hectare on {:.4} ha is less than one crop tree: the entry releases none (a larger area or more crop trees per hectare)", op.index, op.region.area_ha));
            }
        }
        // a relative-density trigger at or below the target: the stand is thinned to a
        // density at which the entry would not have been triggered, so each entry may remove
        // little or nothing and the trigger fires again at once (round 32's trial: accepted
        // without a word)
        if let (Some(trig), Some(target)) = (op.spec.trigger_relative_density, op.spec.target_relative_density) {
            if trig <= target {
                out.push(format!("{ctx}: management[{}].trigger_relative_density = {trig} is not above target_relative_density = {target}: a thinning is triggered at a density it does not lower the stand from (a trigger above the target, e.g. 0.8 with 0.65)", op.index));
            }
        }
        if let Action::Shelterwood { shares } = &op.action {
            if let Some(k) = shares.iter().position(|&s| s >= 1.0).filter(|&k| k + 1 < shares.len()) {
                out.push(format!("{ctx}: management[{}].stages[{k}] removes the whole overstorey (share 1): the {} later stages find nothing to cut", op.index, shares.len() - k - 1));
            }
        }
        if let Action::Patch { size_m, share } = op.action {
            let n = patch_squares(&op.region, size_m).2.len();
            let per = ((share * n as f64).round() as usize).max(1);
            let needed = (1..=n as u32).find(|&k| patch_range(n, share, k - 1).1 >= n).unwrap_or(n as u32) as usize;
            let due: Vec<u32> = (1..=last_year).filter(|&y| op.spec.due(y).is_some()).collect();
            if due.len() > needed {
                out.push(format!("{ctx}: management[{}]: a patch cut of {n} squares of {size_m} m, about {per} per entry, has cut them all after {needed} entries (year {}); its {} later entries in the run cut nothing", op.index, due[needed - 1], due.len() - needed));
            }
        }
    }
    out.extend(overlapping_plantings(ops, last_year, ctx));
    out
}

/// Warnings for two plantings due in the same year whose areas overlap (trial 36: a beech and
/// an oak planting over the same hectare planted 2,500 of each, on lattices that put each oak
/// 1.4 cm from a beech). The shared area is estimated on a grid of at most 256 × 256 points
/// over the two regions' common bounding box ([`Region::contains`]); it is said when it could
/// hold a lattice point of the denser entry (more than half its spacing squared).
fn overlapping_plantings(ops: &[Operation], last_year: u32, ctx: &str) -> Vec<String> {
    let plantings: Vec<(&Operation, f64)> = ops.iter().filter_map(|op| if let Action::Planting { spacing_m, .. } = op.action { Some((op, spacing_m)) } else { None }).collect();
    let mut out = Vec::new();
    for (a, (oa, sa)) in plantings.iter().enumerate() {
        for (ob, sb) in &plantings[a + 1..] {
            let Some(year) = (0..=last_year).find(|&y| oa.spec.due(y).is_some() && ob.spec.due(y).is_some()) else { continue };
            let (ba, bb) = (oa.region.bbox, ob.region.bbox);
            let (x0, y0, x1, y1) = (ba[0].max(bb[0]), ba[1].max(bb[1]), ba[2].min(bb[2]), ba[3].min(bb[3]));
            if x1 <= x0 || y1 <= y0 {
                continue;
            }
            let (nx, ny) = (((x1 - x0) / 0.5).ceil().clamp(1.0, 256.0) as usize, ((y1 - y0) / 0.5).ceil().clamp(1.0, 256.0) as usize);
            let (dx, dy) = ((x1 - x0) / nx as f64, (y1 - y0) / ny as f64);
            let both = (0..ny).flat_map(|r| (0..nx).map(move |c| (x0 + (c as f64 + 0.5) * dx, y0 + (r as f64 + 0.5) * dy))).filter(|&(x, y)| oa.region.contains(x, y) && ob.region.contains(x, y)).count();
            let shared_m2 = both as f64 * dx * dy;
            if shared_m2 > 0.5 * sa.min(*sb).powi(2) {
                out.push(format!(
                    "{ctx}: management[{}] and management[{}] both plant in year {year} on about {:.2} ha they share: each plants its own lattice there, so the density is doubled and trees stand centimetres apart (one entry with a mix of both, or areas that do not overlap)",
                    oa.index,
                    ob.index,
                    shared_m2 / 10_000.0
                ));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygons_even_odd_and_schedule() {
        let sq = vec![vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]], vec![[4.0, 4.0], [6.0, 4.0], [6.0, 6.0], [4.0, 6.0]]];
        let r = Region { bbox: [0.0, 0.0, 10.0, 10.0], polygons: Some(vec![sq]), area_ha: 0.0 };
        assert!(r.contains(1.0, 1.0));
        assert!(!r.contains(5.0, 5.0), "hole");
        assert!(!r.contains(11.0, 5.0));
        let m = Management { from_year: Some(15), every_years: Some(5), until_year: Some(30), ..Default::default() };
        assert_eq!(m.due(15), Some(0));
        assert_eq!(m.due(25), Some(2));
        assert_eq!(m.due(26), None);
        assert_eq!(m.due(35), None);
        let m = Management { years: Some(vec![30, 10]), ..Default::default() };
        assert_eq!(m.due(30), Some(1));
        let m = Management { stages: Some(vec![Stage { year: 10, share: 0.5 }, Stage { year: 20, share: 1.0 }]), ..Default::default() };
        assert_eq!((m.due(10), m.due(20), m.due(15)), (Some(0), Some(1), None));
        assert_eq!(m.first_year(), 10);
        assert_eq!(m.years_beyond(15), vec![("stages[1].year".to_string(), 20)]);
    }

    #[test]
    fn entries_serialise_to_toml_for_the_checkpoint_identity() {
        // the identity hashes the entry's TOML form: it must serialise (tables after values)
        let m = Management {
            kind: "harvest".into(),
            method: Some("shelterwood".into()),
            stages: Some(vec![Stage { year: 10, share: 0.5 }]),
            mix: Some([("beech".to_string(), 1.0)].into()),
            filter: Some(AreaFilter { property: "n".into(), equals: toml::Value::Integer(2) }),
            polygons: Some(vec![vec![vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]]]),
            ..Default::default()
        };
        let t = toml::to_string(&m).unwrap();
        assert!(t.contains("shelterwood") && !t.contains("crop_trees_ha"), "{t}");
        assert_eq!(toml::from_str::<Management>(&t).unwrap(), m);
    }

    #[test]
    fn crossing_edges_find_bowties_and_pass_holes() {
        let bowtie = vec![vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]]];
        assert!(crossing_edges(&bowtie).is_some());
        let holed = vec![vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]], vec![[4.0, 4.0], [6.0, 4.0], [6.0, 6.0], [4.0, 6.0]]];
        assert!(crossing_edges(&holed).is_none());
        let crossing_hole = vec![holed[0].clone(), vec![[8.0, 4.0], [12.0, 4.0], [12.0, 6.0], [8.0, 6.0]]];
        assert_eq!(crossing_edges(&crossing_hole).map(|(a, b)| (a.0, b.0)), Some((0, 1)));
    }
}

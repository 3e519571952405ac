//! A changing climate: the yearly temperature offset and precipitation factor of a scenario
//! (`[climate] warming_k_per_century`, `anomalies_file`) and how they move the living
//! conditions of every cell.
//!
//! How T follows temperature: a cell's mean annual temperature is
//! `t = reference_temperature_c + lapse_rate_k_per_km · (z − reference_elevation_m) / 1000`
//! (`terrain::fields`), and its temperature index is
//! [`crate::conditions::temperature_index`]`(t) = clamp(1 + 8 (t + 2) / 20, 1, 9)`: 0.4 index
//! units per kelvin ([`T_INDEX_PER_K`]). A warming of ΔT moves every cell's T by `0.4 ΔT`
//! (clamped to 1–9), which is the T of the cell `ΔT / |lapse rate|` lower down: with the default
//! −6.5 K/km, +1 K moves a temperature isoline about 154 m upslope (ECOLOGY.md). Species respond
//! through their niche (the Ellenberg suitability of the shifted indices), which feeds growth
//! (every tree's suitability) and establishment (every cell's suitability) from that year on.
//!
//! Warming and the precipitation factor also act on water (round 44): each year every cell's
//! monthly soil-water balance ([`crate::climate::water`]: Thornthwaite's PET, a bucket, ForClim's
//! drought index) under the year's temperature and precipitation, against the same balance
//! under the base climate; the rise of the drought index cuts each species by its drought
//! tolerance ([`crate::species::Species::drought_response`]). The precipitation factor acts
//! through the water balance only (until round 43 it moved F by `5 (p − 1)`, an estimate with
//! no water balance behind it). The terrain fields, the maps and the site's identity are those
//! of the base climate.

use crate::climate::Climate;
use crate::conditions::factor;
use crate::climate::water::WaterClimate;
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// Temperature index units per kelvin: the slope `8 / 20` of
/// [`crate::conditions::temperature_index`].
pub const T_INDEX_PER_K: f32 = 0.4;

/// Most a temperature anomaly may be (K, either sign).
pub const MAX_ANOMALY_K: f64 = 30.0;

/// The climate's change over the run: a linear ramp and yearly anomalies, and the base
/// climate's water-balance constants they act on.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClimateChange {
    /// Warming (K per century) from year 0.
    pub warming_k_per_century: f64,
    /// Anomalies by simulation year: (temperature K, precipitation factor).
    pub anomalies: BTreeMap<u32, (f64, f64)>,
    /// The base climate's precipitation, annual temperature range and soil water capacity
    /// ([`crate::climate::water`]).
    pub water: WaterClimate,
}

impl ClimateChange {
    /// The change of `climate`: its ramp, and its anomalies file read and checked
    /// ([`parse_anomalies`]). `ctx` names the scenario.
    ///
    /// Errors: [`Error::Invalid`] naming `climate.anomalies_file` when the file cannot be read,
    /// or the file and line of a malformed line.
    pub fn of(climate: &Climate, ctx: &str) -> Result<ClimateChange> {
        let mut c = ClimateChange { warming_k_per_century: climate.warming_k_per_century as f64, anomalies: BTreeMap::new(), water: WaterClimate::of(climate) };
        if let Some(p) = &climate.anomalies_file {
            let text = std::fs::read_to_string(p).map_err(|e| Error::Invalid {
                context: ctx.to_string(),
                field: "climate.anomalies_file".into(),
                value: p.display().to_string(),
                expected: format!("a readable CSV file `year,temperature_k[,precipitation_factor]` ({e})"),
            })?;
            // a byte-order mark (files saved by spreadsheet programs) is not part of the header
            c.anomalies = parse_anomalies(text.strip_prefix('\u{feff}').unwrap_or(&text), p)?;
        }
        Ok(c)
    }

    /// The anomaly years after `last_year` (ascending): they never come in a run of
    /// `last_year` years (a run shortened with `--years` keeps its file, so a warning, not an
    /// error).
    pub fn years_beyond(&self, last_year: u32) -> Vec<u32> {
        self.anomalies.range(last_year.saturating_add(1)..).map(|(&y, _)| y).collect()
    }

    /// Whether the climate changes at all (a ramp or any anomaly).
    pub fn is_active(&self) -> bool {
        self.warming_k_per_century != 0.0 || !self.anomalies.is_empty()
    }

    /// Temperature offset (K) and precipitation factor of simulation year `year` (the stand
    /// table's year: 1 = the first simulated year): `warming · year / 100` plus the year's
    /// anomaly, and the anomaly's factor (1 when none).
    pub fn of_year(&self, year: u32) -> (f64, f64) {
        let (a, p) = self.anomalies.get(&year).copied().unwrap_or((0.0, 1.0));
        (self.warming_k_per_century * year as f64 / 100.0 + a, p)
    }
}

/// The indices `ix` (`[L, T, K, F, R, N]`) under a temperature offset `dt_k` (K): T moved by
/// [`T_INDEX_PER_K`]` · dt_k` (clamped 1–9), the others unchanged (the precipitation factor acts
/// through the water balance, [`crate::climate::water`], not on F).
pub fn shifted_indices(ix: &[f32; 6], dt_k: f64) -> [f32; 6] {
    let mut v = *ix;
    v[factor::T] = (v[factor::T] + T_INDEX_PER_K * dt_k as f32).clamp(1.0, 9.0);
    v
}

/// The indices `ix` of a year `dt_k` kelvin warmer than the base climate whose cell's drought
/// index lies `di_rise` (≥ 0) above the base climate's (round 45): T moved as
/// [`shifted_indices`], and F lowered by the rise on the scale of the site's water balance,
/// `F − 10 · di_rise` (clamped 1–12; [`crate::conditions::moisture_index_of_water`], whose F is
/// the base climate's drought index read onto Ellenberg's scale, 10 F units per unit of drought
/// index). Through F the year's drought acts on both the species' moisture niche and its
/// drought limit ([`crate::species::Species::drought_limit`]).
pub fn year_indices(ix: &[f32; 6], dt_k: f64, di_rise: f32) -> [f32; 6] {
    let mut v = shifted_indices(ix, dt_k);
    v[factor::F] = (v[factor::F] - crate::conditions::F_PER_DROUGHT_INDEX as f32 * di_rise.max(0.0)).clamp(1.0, 12.0);
    v
}

/// Parses an anomalies CSV: lines `year,temperature_k[,precipitation_factor]` (year 1–10000,
/// each once; temperature −30–30 K; factor 0.05–5, default 1), every line with as many values
/// as the header names (a decimal comma is an error, not a third value); a file without a
/// header has the two columns `year,temperature_k`, and a precipitation factor column needs the
/// header (a headerless `1,0,5` is refused, not read as 0 K and a factor of 5); blank lines and `#` comments (whole lines, or from `#` to the end
/// of a line) skipped; a first line starting with a letter is a header, which must name the columns in
/// that order (`year,temperature_k` or `year,temperature_k,precipitation_factor`, any case):
/// a header in another order or with other names is refused rather than read by position
/// (round 30: `year,precipitation_factor` gave its factors as temperatures without a word).
///
/// Errors: [`Error::Invalid`] whose context names `path` and the line number, with the line's
/// text and what was expected; a file with no data line is refused too (its context names the
/// file).
pub fn parse_anomalies(text: &str, path: &Path) -> Result<BTreeMap<u32, (f64, f64)>> {
    let mut out = BTreeMap::new();
    let mut first = true;
    // values a line must have: the header's columns, else the first data line's
    let mut columns: Option<usize> = None;
    let mut from_header = false;
    for (n, raw) in text.lines().enumerate() {
        // a comment runs from `#` to the end of the line (whole lines or after the values)
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad = |expected: &str| Error::Invalid { context: format!("{} line {}", path.display(), n + 1), field: "climate.anomalies_file".into(), value: line.to_string(), expected: expected.to_string() };
        if std::mem::take(&mut first) && line.starts_with(|c: char| c.is_ascii_alphabetic()) {
            let names: Vec<String> = line.split(',').map(|c| c.trim().to_ascii_lowercase()).collect();
            if names != ["year", "temperature_k"] && names != ["year", "temperature_k", "precipitation_factor"] {
                return Err(bad("a header `year,temperature_k` or `year,temperature_k,precipitation_factor` (the columns in this order), or no header"));
            }
            columns = Some(names.len());
            from_header = true;
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if !(2..=3).contains(&f.len()) {
            return Err(bad("`year,temperature_k[,precipitation_factor]`: 2 or 3 comma-separated values (numbers with a decimal point: 0.5, not 0,5)"));
        }
        // every line as many values as the header names (or as the first line has): a decimal
        // comma (`1,0,5` for 0.5 K) read as a precipitation factor of 5 was a silent wrong
        // climate (round 32's trial)
        match columns {
            Some(c) if c != f.len() => {
                return Err(bad(&format!("{c} comma-separated values, as the {} has (`year,temperature_k{}`; numbers with a decimal point: 0.5, not 0,5)", if from_header { "header" } else { "first data line" }, if c == 3 { ",precipitation_factor" } else { "" })));
            }
            // without a header only `year,temperature_k`: a headerless file whose every line
            // has a decimal comma in its temperature (`1,0,5` for 0.5 K) has three values on every
            // line and was read as 0 K with a precipitation factor of 5 (round 43's trial,
            // defect 4); a precipitation factor column must be named by the header
            None if f.len() == 3 => {
                return Err(bad("`year,temperature_k` without a header; a third column (a precipitation factor) only under the header `year,temperature_k,precipitation_factor` (and numbers with a decimal point: 0.5, not 0,5)"));
            }
            None => columns = Some(f.len()),
            _ => {}
        }
        // year 0 is the start, simulated under the base climate: an anomaly there would never
        // act (found by a break-it pass: it was ignored without a word)
        let year: u32 = f[0].parse().ok().filter(|y| (1..=10_000).contains(y)).ok_or_else(|| bad("a year: a whole number 1–10000 (year Y is the Y-th simulated year, the stand table's; year 0, the start, keeps the base climate and takes no anomaly)"))?;
        let t: f64 = f[1].parse().ok().filter(|t: &f64| t.is_finite() && t.abs() <= MAX_ANOMALY_K).ok_or_else(|| bad("a temperature anomaly: a number −30–30 K"))?;
        let p: f64 = match f.get(2) {
            Some(s) => s.parse().ok().filter(|p: &f64| p.is_finite() && (0.05..=5.0).contains(p)).ok_or_else(|| bad("a precipitation factor: a number 0.05–5"))?,
            None => 1.0,
        };
        if out.insert(year, (t, p)).is_some() {
            return Err(bad("each year once"));
        }
    }
    if out.is_empty() {
        return Err(Error::Invalid { context: path.display().to_string(), field: "climate.anomalies_file".into(), value: "no data line".into(), expected: "at least one line `year,temperature_k[,precipitation_factor]`".into() });
    }
    Ok(out)
}

impl ClimateChange {
    /// The years between the first and the last anomaly that the file has no line for
    /// (ascending): they take no anomaly (0 K, precipitation factor 1), which a file with a
    /// forgotten line does not mean (World::new warns; round 32's trial found them silent).
    pub fn anomaly_gaps(&self) -> Vec<u32> {
        match (self.anomalies.keys().next(), self.anomalies.keys().next_back()) {
            (Some(&a), Some(&b)) => (a..=b).filter(|y| !self.anomalies.contains_key(y)).collect(),
            _ => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_anomalies_and_index_shift() {
        let mut c = ClimateChange { warming_k_per_century: 4.0, anomalies: BTreeMap::new(), ..Default::default() };
        assert_eq!(c.of_year(50), (2.0, 1.0));
        c.anomalies.insert(50, (0.5, 0.8));
        assert_eq!(c.of_year(50), (2.5, 0.8));
        c.anomalies.insert(500, (1.0, 1.0));
        assert_eq!(c.years_beyond(100), vec![500]);
        assert_eq!(c.years_beyond(500), Vec::<u32>::new());
        let ix = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0];
        let s = shifted_indices(&ix, 2.5);
        assert_eq!(s[factor::T], 6.0);
        assert_eq!(s[factor::F], 5.0);
        assert_eq!(shifted_indices(&[5.0, 8.9, 2.0, 5.0, 6.0, 6.0], 5.0)[factor::T], 9.0);
        // the slope is temperature_index's
        let d = crate::conditions::temperature_index(9.0) - crate::conditions::temperature_index(8.0);
        assert!((d - T_INDEX_PER_K).abs() < 1e-6);
    }

    #[test]
    fn anomalies_file_errors_name_line() {
        let p = Path::new("a.csv");
        let m = parse_anomalies("year,temperature_k,precipitation_factor\n1,0.5,1\n# c\n2,-1,0.9\n", p).unwrap();
        assert_eq!((m[&1], m[&2]), ((0.5, 1.0), (-1.0, 0.9)));
        let e = parse_anomalies("year,temperature_k\n1,0.5\n2,hot\n", p).unwrap_err().to_string();
        assert!(e.contains("a.csv line 3") && e.contains("hot") && e.contains("temperature"), "{e}");
        let e = parse_anomalies("1,0.5\n1,0.6\n", p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("once"), "{e}");
        // a header is checked, not skipped: a factor column read as temperatures was a silent
        // wrong climate (round 30's trial)
        let e = parse_anomalies("year,precipitation_factor\n1,0.8\n", p).unwrap_err().to_string();
        assert!(e.contains("a.csv line 1") && e.contains("year,temperature_k"), "{e}");
        let e = parse_anomalies("temperature_k,year\n2,3\n", p).unwrap_err().to_string();
        assert!(e.contains("line 1"), "{e}");
        assert_eq!(parse_anomalies("Year, Temperature_K, Precipitation_Factor\n3,1.5,1.1\n", p).unwrap()[&3], (1.5, 1.1));
        let e = parse_anomalies("year,temperature_k\n# none yet\n", p).unwrap_err().to_string();
        assert!(e.contains("a.csv") && e.contains("at least one line"), "{e}");
        // a decimal comma makes one value more than the header names (round 32's trial: `1,0,5`
        // was read as 0 K and a precipitation factor of 5)
        let e = parse_anomalies("year,temperature_k\n1,0,5\n", p).unwrap_err().to_string();
        assert!(e.contains("a.csv line 2") && e.contains("2 comma-separated values") && e.contains("header") && e.contains("0.5, not 0,5"), "{e}");
        let e = parse_anomalies("year,temperature_k,precipitation_factor\n1,0.5\n", p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("3 comma-separated values"), "{e}");
        // without a header, every line as many values as the first
        let e = parse_anomalies("1,0.5\n2,0,5\n", p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("first data line"), "{e}");
        // every line with a decimal comma and no header (round 43's trial, defect 4: read as
        // 0 K and a precipitation factor of 5 without a word)
        let e = parse_anomalies("1,0,5\n2,1,5\n", p).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("header") && e.contains("0,5"), "{e}");
        assert_eq!(parse_anomalies("1,0.5\n2,1\n", p).unwrap()[&2], (1.0, 1.0));
        // comments after the values
        let m = parse_anomalies("# hot decade\nyear,temperature_k\n1,0.5 # hot\n3,1.5#hotter\n", p).unwrap();
        assert_eq!((m[&1], m[&3]), ((0.5, 1.0), (1.5, 1.0)));
        let c = ClimateChange { warming_k_per_century: 0.0, anomalies: m, ..Default::default() };
        assert_eq!(c.anomaly_gaps(), vec![2]);
        assert_eq!(ClimateChange::default().anomaly_gaps(), Vec::<u32>::new());
    }
}

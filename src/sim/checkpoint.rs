//! Checkpoints: the evolving state of a [`World`] (trees, regeneration cohorts and their ledger,
//! seeds, year, death counts) and the stand table so far, in a compact little-endian binary
//! with exact float bits, so that a resumed run continues bit for bit. Site conditions and
//! species are rebuilt from the scenario; the checkpoint keeps the run's *identity* (seed,
//! species pool and each species' parameters, terrain, site conditions, light cell, obstacles,
//! seed rain) and refuses a resume whose scenario differs in any of them, naming the field with
//! its old and new value. A length field and a CRC-32 over the whole file (IEEE polynomial,
//! `crc32fast`) refuse a truncated or corrupted file before anything is decoded.
//!
//! Layout (all little-endian): `SYLVACK` `V` `u32` layout version | `u64` file length in bytes |
//! one zstd frame ([`ZSTD_LEVEL`], with its content size and checksum) of: identity: `u64` n,
//! n × (string key, string value) | body (year, trees, seeds, cohorts, tallies, stand table) |
//! `u32` CRC-32 of every byte before it (the compressed bytes). Strings are a `u64` byte count
//! and UTF-8 bytes. Older layouts (6: uncompressed; 7 and the managed 9, whose stand tables
//! have no year 0 and no per-species rows) are refused, naming their version.

use super::stats::StandRow;
use super::cohorts::{Cohorts, RegenLedger, N_REGEN_CAUSES};
use super::trees::{TreeStore, F32_COLUMN_NAMES, N_CAUSES};
use super::world::World;
use super::codec::{Count, Dec, Enc, Short, Sink};
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// File signature: 7 bytes, then `V` and the little-endian `u32` [`LAYOUT_VERSION`]. Files
/// from before the version field (`SYLVACK1`…`SYLVACK3`) have a digit in place of the `V`.
const MAGIC: &[u8; 7] = b"SYLVACK";

/// Hand-kept part of the layout version: bump it whenever the order, kind or number of the
/// stored fields changes (the cause counts below are folded in by themselves). 5: file length,
/// run identity and CRC-32 added (issue 16). 6: the stand table's volume, harvest and climate
/// columns (issue 35). 7: identity and body zstd-compressed (issue 34: the default run's
/// checkpoint of 1 M trees went from 64 to 36 MB). 10 (round 42, trial 41 defects 2 and 7):
/// each stand-table row also holds the natural deaths' volume and the per-species rows, and
/// the stand table starts with year 0; checkpoints of layouts 6 and 7 are refused, naming
/// their version (their stand tables have neither). 12 (round 44): each row also holds the
/// year's site-mean drought index, each per-species row the species' top height over its own
/// area ([`super::stats::SpeciesRow::top_height_own_area_m`]; trial 43 defect 8), and each
/// sapling cohort its consecutive stress years (after the vigour column; trial 44 defect 4);
/// checkpoints of layout 10 are refused, naming their version. 14 (round 45): the seed grids
/// hold fine cells (`SeedGrid::block` of them to a coarse cell side: the two-scale dispersal
/// kernel), so their lengths differ; checkpoints of layout 12 are refused, naming their version.
const LAYOUT_BASE: u32 = 14;

/// The layout base of a checkpoint of a run with `[[management]]`: [`LAYOUT_BASE`]'s layout and
/// the management table's rows after the stand table (issue 35 round 38). Written only by such
/// runs, so every other run keeps layout 7's bytes, and a Sylva before it refuses a managed
/// run's checkpoint naming both versions (rather than as corrupt). 9 (round 41): each row also
/// holds the entry's name, the basal area it removed, the saplings it cut and the species
/// shares of its area (a managed checkpoint of base 8 is refused, naming its version). 11
/// (round 42): [`LAYOUT_BASE`] 10's rows, and each entry's row holds whether its
/// `max_removal_share` stopped it (`capped`). 13 (round 44): [`LAYOUT_BASE`] 12's rows and cohorts.
/// 15 (round 45): [`LAYOUT_BASE`] 14's fine seed grids. 16 (round 46, trial 46 D5): each
/// entry's row also holds the trees planted and the trees below 1.3 m per ha of its area.
const MANAGED_BASE: u32 = 16;

/// zstd level of the checkpoint (1: 36.2 MB for the default run's 64 MB, 0.6 s; 3 saved 0.7 %
/// more for 1.6 times the time).
const ZSTD_LEVEL: i32 = 1;

/// Version of the checkpoint layout, written in the header and required on reading:
/// `LAYOUT_BASE · 65536 + N_CAUSES · 256 + N_REGEN_CAUSES`, so that adding a cause of death
/// of trees ([`crate::sim::trees::N_CAUSES`]) or of the regeneration layer
/// ([`N_REGEN_CAUSES`]), which changes the size of the stored counts, changes the version.
pub const LAYOUT_VERSION: u32 = LAYOUT_BASE << 16 | (N_CAUSES as u32) << 8 | N_REGEN_CAUSES as u32;

/// Bytes before the identity: header (12) and file length (8).
const PREFIX: usize = 20;
/// Bytes of the trailing CRC-32.
const CRC_LEN: usize = 4;

/// The header of this layout: [`MAGIC`], `V`, [`LAYOUT_VERSION`] (12 bytes); with `managed`
/// (the rows hold a management table) the version's base is [`MANAGED_BASE`].
fn header(managed: bool) -> Vec<u8> {
    let mut h = MAGIC.to_vec();
    h.push(b'V');
    let v = if managed { MANAGED_BASE << 16 | (LAYOUT_VERSION & 0xffff) } else { LAYOUT_VERSION };
    h.extend_from_slice(&v.to_le_bytes());
    h
}

/// Describes a layout version for messages: `5.4.2 (base, tree death causes, regeneration causes)`.
fn describe(v: u32) -> String {
    format!("{}.{}.{} (layout, tree death causes, regeneration death causes)", v >> 16, (v >> 8) & 0xff, v & 0xff)
}

/// Checks the header of `bytes`; returns whether the identity and body are compressed (every
/// layout this build reads is).
///
/// Errors: [`Error::Format`] naming `path`: not a checkpoint; a checkpoint of an older Sylva
/// (before layout versions) or of another layout version, saying which and what to do.
fn check_header(bytes: &[u8], path: &Path) -> Result<bool> {
    let again = "start the run again without --resume (or with the Sylva version that wrote it)";
    if bytes.len() < 8 || &bytes[..7] != MAGIC {
        return Err(Error::format(path, "not a Sylva checkpoint (no SYLVACK signature)"));
    }
    match bytes[7] {
        b'V' => {
            let v = bytes.get(8..12).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]])).ok_or_else(|| Error::format(path, "checkpoint header truncated (no layout version)"))?;
            if v != LAYOUT_VERSION && v != MANAGED_BASE << 16 | (LAYOUT_VERSION & 0xffff) {
                return Err(Error::format(path, format!("checkpoint layout version {} differs from this build's {}: {again}", describe(v), describe(LAYOUT_VERSION))));
            }
            Ok(true)
        }
        d if d.is_ascii_digit() => Err(Error::format(
            path,
            format!("checkpoint from an older Sylva (layout SYLVACK{}, before layout versions; this build reads version {}): {again}", d as char, describe(LAYOUT_VERSION)),
        )),
        _ => Err(Error::format(path, "not a Sylva checkpoint (unknown header after SYLVACK)")),
    }
}

/// Checks the file length field and the CRC-32 of `bytes` (after [`check_header`]); returns
/// the end of the body (the offset of the checksum).
///
/// Errors: [`Error::Format`] naming `path`: shorter than its length field says (truncated,
/// with both lengths), longer (bytes appended), or a checksum that does not match (corrupt,
/// with both checksums).
fn check_seal(bytes: &[u8], path: &Path) -> Result<usize> {
    let again = "the file was damaged (cut short by a full disk or an interrupted copy, or altered); restore a copy or start the run again without --resume";
    if bytes.len() < PREFIX + CRC_LEN {
        return Err(Error::format(path, format!("checkpoint truncated: {} bytes, shorter than its {}-byte header and checksum: {again}", bytes.len(), PREFIX + CRC_LEN)));
    }
    let mut l = [0u8; 8];
    l.copy_from_slice(&bytes[12..20]);
    let want = u64::from_le_bytes(l);
    let have = bytes.len() as u64;
    if have < want {
        return Err(Error::format(path, format!("checkpoint truncated: {have} of {want} bytes: {again}")));
    }
    if have > want {
        return Err(Error::format(path, format!("checkpoint corrupt: {have} bytes, its length field says {want}: {again}")));
    }
    let end = bytes.len() - CRC_LEN;
    let stored = u32::from_le_bytes([bytes[end], bytes[end + 1], bytes[end + 2], bytes[end + 3]]);
    let computed = crc32fast::hash(&bytes[..end]);
    if stored != computed {
        return Err(Error::format(path, format!("checkpoint corrupt: CRC-32 stored {stored:08x}, computed {computed:08x}: {again}")));
    }
    Ok(end)
}

/// Rewrites the length field and the CRC-32 of a checkpoint in place after its bytes were
/// edited (fuzzing and tools: the body's own checks are then reached). Does nothing to a
/// buffer shorter than the header, length field and checksum (24 bytes).
pub fn reseal(bytes: &mut [u8]) {
    if bytes.len() < PREFIX + CRC_LEN {
        return;
    }
    let n = bytes.len() as u64;
    bytes[12..20].copy_from_slice(&n.to_le_bytes());
    let end = bytes.len() - CRC_LEN;
    let c = crc32fast::hash(&bytes[..end]);
    bytes[end..].copy_from_slice(&c.to_le_bytes());
}

/// CRC-32 of a slice of `f32`s' bits (little-endian).
fn crc_f32(h: &mut crc32fast::Hasher, v: &[f32]) {
    for x in v {
        h.update(&x.to_bits().to_le_bytes());
    }
}

/// A band of site rows' share of [`site_identity`] (issue 37 Build 1, round 33: a tiled run's
/// rank 0 holds its band of the site only, so the whole site's identity is joined from the
/// ranks' bands): per byte stream of the identity — elevations, mask, indices, insolation,
/// temperature, wind exposure, TWI, each the band's cells in row order — its CRC-32 and length
/// (bytes), with the band's count of unmasked cells and the lowest and highest elevation of
/// those (∞ and −∞ when none). Joined in row order by [`site_identity_of`]
/// (`crc32fast::Hasher::combine`), the bands give the whole site's strings bit for bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentityPart {
    /// (CRC-32, bytes) of the seven streams, in the order above.
    pub crcs: [(u32, u64); 7],
    /// Unmasked cells of the band.
    pub valid: u64,
    /// Lowest elevation of the band's unmasked cells (m; `f32::INFINITY` when none).
    pub lo: f32,
    /// Highest elevation of the band's unmasked cells (m; `f32::NEG_INFINITY` when none).
    pub hi: f32,
}

/// The [`IdentityPart`] of the held rows `rows` of `c` (rows of its held grids, 0 the first
/// held row; a band of the site when `c` holds whole rows, [`SiteConditions::held`]).
/// Panics when `rows` reaches past the rows held (a defect: a rank reads its own band).
///
/// [`SiteConditions::held`]: crate::conditions::SiteConditions::held
pub fn identity_part(c: &crate::conditions::SiteConditions, rows: std::ops::Range<usize>) -> IdentityPart {
    let hw = c.held.width;
    let span = |r: usize| r * hw..(r + 1) * hw;
    let stream = |f: &dyn Fn(&mut crc32fast::Hasher, std::ops::Range<usize>) -> u64| {
        let mut h = crc32fast::Hasher::new();
        let n: u64 = rows.clone().map(|r| f(&mut h, span(r))).sum();
        (h.finalize(), n)
    };
    let f32s = |g: &crate::grid::Grid<f32>| stream(&|h, s| {
        crc_f32(h, &g.data[s.clone()]);
        4 * s.len() as u64
    });
    let mask = stream(&|h, s| {
        h.update(&c.mask.data[s.clone()].iter().map(|&m| m as u8).collect::<Vec<u8>>());
        s.len() as u64
    });
    let indices = stream(&|h, s| {
        for ix in &c.indices.data[s.clone()] {
            crc_f32(h, ix);
        }
        24 * s.len() as u64
    });
    let (mut valid, mut lo, mut hi) = (0u64, f32::INFINITY, f32::NEG_INFINITY);
    for r in rows.clone() {
        let s = span(r);
        for (e, _) in c.elevation_m.data[s.clone()].iter().zip(&c.mask.data[s]).filter(|(_, m)| **m) {
            valid += 1;
            (lo, hi) = (lo.min(*e), hi.max(*e));
        }
    }
    IdentityPart { crcs: [f32s(&c.elevation_m), mask, indices, f32s(&c.insolation_kwh_m2), f32s(&c.temperature_c), f32s(&c.wind_exposure), f32s(&c.twi)], valid, lo, hi }
}

/// The `terrain` and `site conditions` entries of [`identity`] of a site of `w × h` cells of
/// `cell_x_m × cell_y_m` (m) from its bands' [`IdentityPart`]s, `parts` in row order (bands
/// that together are the site's rows once: [`site_identity`] is this of one part).
pub fn site_identity_of(w: usize, h: usize, cell_x_m: f64, cell_y_m: f64, parts: &[IdentityPart]) -> Vec<(String, String)> {
    let join = |hs: &mut crc32fast::Hasher, s: usize| {
        for p in parts {
            hs.combine(&crc32fast::Hasher::new_with_initial_len(p.crcs[s].0, p.crcs[s].1));
        }
    };
    let mut out = Vec::with_capacity(2);
    let mut hs = crc32fast::Hasher::new();
    hs.update(&(w as u64).to_le_bytes());
    hs.update(&(h as u64).to_le_bytes());
    hs.update(&cell_x_m.to_bits().to_le_bytes());
    hs.update(&cell_y_m.to_bits().to_le_bytes());
    join(&mut hs, 0);
    join(&mut hs, 1);
    let valid: u64 = parts.iter().map(|p| p.valid).sum();
    let (lo, hi) = parts.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), p| (a.min(p.lo), b.max(p.hi)));
    out.push(("terrain".to_string(), format!("{w} × {h} cells of {cell_x_m} m × {cell_y_m} m, {valid} valid, elevation {lo:.2}–{hi:.2} m, CRC-32 {:08x}", hs.finalize())));
    let mut hs = crc32fast::Hasher::new();
    for s in 2..7 {
        join(&mut hs, s);
    }
    out.push(("site conditions".into(), format!("CRC-32 {:08x} of the per-cell indices, insolation, temperature, wind exposure and TWI", hs.finalize())));
    out
}

/// The `terrain` and `site conditions` entries of [`identity`] for the site `c` (the whole
/// site: a tile keeps them from before its cut, [`super::world::Site::whole_identity`]; a
/// tiled run's rank 0 that holds its band joins them from the ranks' bands,
/// [`site_identity_of`]).
pub fn site_identity(c: &crate::conditions::SiteConditions) -> Vec<(String, String)> {
    site_identity_of(c.width(), c.height(), c.cell_x_m, c.cell_y_m, &[identity_part(c, 0..c.held.height)])
}

/// The identity of the run of `w`: what a resumed run must share with the one that wrote the
/// checkpoint, as (field, value) pairs in a fixed order. Fields: `seed`; `light_cell_m`;
/// `light diffuse` (only for `[light] diffuse = "sky"`);
/// `species pool` (ids in pool order); `species <id>` (the species' parameters as TOML, so a
/// difference names the parameter); `terrain` (grid size, cell size, elevation range and a
/// CRC-32 of the elevations and the valid-cell mask: a changed DEM file or window);
/// `site conditions` (CRC-32 of the per-cell indices L T K F R N, insolation, temperature,
/// wind exposure and TWI: changes with the climate and soil constants); `seed rain`
/// (seeds per m² and year per pool species); `obstacles` (count and CRC-32); where the
/// scenario has them, `management` (a CRC-32 per entry of the entry as TOML, the area file's
/// path left out, with its resolved action and area) and
/// `climate change` (the ramp and a CRC-32 of the anomalies).
pub fn identity(w: &World) -> Vec<(String, String)> {
    let s = &w.site;
    let mut out = vec![("seed".to_string(), s.seed.to_string()), ("light_cell_m".to_string(), format!("{}", s.light.cell_m))];
    let ids: Vec<&str> = s.pool.iter().map(|&p| s.lib.species[p as usize].id.as_str()).collect();
    out.push(("species pool".into(), ids.join(", ")));
    for &p in &s.pool {
        let sp = &s.lib.species[p as usize];
        out.push((format!("species {}", sp.id), sp.to_toml_string().unwrap_or_else(|_| format!("{sp:?}"))));
    }
    out.extend(s.whole_identity.clone().unwrap_or_else(|| site_identity(&s.conditions)));
    // the sky model of the diffuse light, only where the scenario takes it (`[light] diffuse`)
    if s.light.diffuse != crate::sim::light_grid::Diffuse::Column {
        out.push(("light diffuse".into(), format!("{:?}", s.light.diffuse).to_lowercase()));
    }
    out.push(("seed rain".into(), format!("{:?} seeds/m²/yr", s.seed_rain)));
    out.push(("obstacles".into(), format!("{} obstacles, CRC-32 {:08x}", s.obstacles.len(), crc32fast::hash(format!("{:?}", s.obstacles).as_bytes()))));
    // management and a changing climate, only where the scenario has them (so that the identity
    // of other runs keeps its fields)
    if !s.management.is_empty() {
        // one CRC per entry (so a refusal shows which entry changed), of the entry and its
        // resolved area without the area file's path (a project folder moved elsewhere with
        // the same file resumes; found by a break-it pass)
        let crcs: Vec<String> = s
            .management
            .iter()
            .enumerate()
            .map(|(i, op)| {
                // the entry as TOML (the fields given only, so an optional field added in a
                // later version leaves the CRC of entries without it alone), what it does and
                // where
                let mut spec = op.spec.clone();
                spec.area_file = None;
                let written = toml::to_string(&spec).unwrap_or_else(|_| format!("{spec:?}"));
                // the entry and its area apart, so a refusal can say which changed (round 44,
                // trial 43 defect 11: a moved parcel was named by CRC-32s only)
                format!("management[{i}] entry {:08x} area {:08x}", crc32fast::hash(format!("{written}{:?}", op.action).as_bytes()), crc32fast::hash(format!("{:?}", op.region).as_bytes()))
            })
            .collect();
        out.push(("management".into(), format!("{} entries, CRC-32 of each and of its resolved area: {}", s.management.len(), crcs.join(", "))));
    }
    if s.climate_change.is_active() {
        let c = &s.climate_change;
        out.push(("climate change".into(), format!("{} K per century, {} anomaly years, CRC-32 {:08x}", c.warming_k_per_century, c.anomalies.len(), crc32fast::hash(format!("{:?}", c.anomalies).as_bytes()))));
    }
    out
}

/// Flattens a TOML document into `path = value` pairs (for naming a changed species parameter).
fn flatten(prefix: &str, v: &toml::Value, out: &mut BTreeMap<String, String>) {
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t {
                let p = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                flatten(&p, x, out);
            }
        }
        _ => {
            out.insert(prefix.to_string(), v.to_string());
        }
    }
}

/// The fields in which two lists of `[[management]]` entries differ, one line each:
/// `management[i].FIELD: OLD → NEW` (TOML values; `(absent)` where a field is not given), an
/// entry only in one list as `management[i] (KIND): added` / `removed`; entry order, fields in
/// name order. `area_file`'s path is left out, as [`identity`] leaves it out (a project folder
/// moved elsewhere resumes). For naming what changed when a resume is refused (trial 38, item
/// 8: the refusal listed a CRC-32 of every entry; `job::run` compares the run directory's
/// `scenario.toml`).
pub fn entry_changes(old: &[super::management::Management], new: &[super::management::Management]) -> Vec<String> {
    let flat = |m: &super::management::Management| {
        let mut m = m.clone();
        m.area_file = None;
        let mut out = BTreeMap::new();
        if let Ok(v) = toml::Value::try_from(&m) {
            flatten("", &v, &mut out);
        }
        out
    };
    let mut out = Vec::new();
    for i in 0..old.len().max(new.len()) {
        match (old.get(i), new.get(i)) {
            (Some(a), Some(b)) => {
                let (fa, fb) = (flat(a), flat(b));
                let mut keys: Vec<&String> = fa.keys().chain(fb.keys()).collect();
                keys.sort();
                keys.dedup();
                for k in keys {
                    let (x, y) = (fa.get(k), fb.get(k));
                    if x != y {
                        let show = |v: Option<&String>| v.cloned().unwrap_or_else(|| "(absent)".into());
                        out.push(format!("management[{i}].{k}: {} → {}", show(x), show(y)));
                    }
                }
            }
            (Some(a), None) => out.push(format!("management[{i}] ({}): removed", a.kind)),
            (None, Some(b)) => out.push(format!("management[{i}] ({}): added", b.kind)),
            (None, None) => {}
        }
    }
    out
}

/// The differences between two species' TOML texts as `parameter: checkpoint X, now Y`
/// (at most 4, then a count); the whole texts' first difference when either does not parse.
fn species_diff(old: &str, new: &str) -> String {
    let parse = |t: &str| t.parse::<toml::Table>().ok().map(|t| {
        let mut m = BTreeMap::new();
        flatten("", &toml::Value::Table(t), &mut m);
        m
    });
    let (Some(a), Some(b)) = (parse(old), parse(new)) else { return "parameters differ".into() };
    let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
    let absent = "(absent)".to_string();
    let diffs: Vec<String> = keys.into_iter().filter(|k| a.get(*k) != b.get(*k)).map(|k| format!("{k}: checkpoint {}, now {}", a.get(k).unwrap_or(&absent), b.get(k).unwrap_or(&absent))).collect();
    match diffs.len() {
        0 => "parameters differ in formatting only".into(),
        n if n <= 4 => diffs.join(", "),
        n => format!("{} and {} more", diffs[..4].join(", "), n - 4),
    }
}

/// Compares the identity stored in a checkpoint with the world's.
///
/// Errors: [`Error::Format`] naming `path` and every changed field with its value in the
/// checkpoint and now.
fn check_identity(stored: &[(String, String)], w: &World, path: &Path) -> Result<()> {
    let now = identity(w);
    let get = |v: &[(String, String)], k: &str| v.iter().find(|(x, _)| x == k).map(|(_, y)| y.clone());
    let mut keys: Vec<&str> = stored.iter().map(|(k, _)| k.as_str()).collect();
    for (k, _) in &now {
        if !keys.contains(&k.as_str()) {
            keys.push(k);
        }
    }
    let mut changes = Vec::new();
    for k in keys {
        let (a, b) = (get(stored, k), get(&now, k));
        if a == b {
            continue;
        }
        changes.push(match (k.strip_prefix("species "), &a, &b) {
            (Some(id), Some(a), Some(b)) if k != "species pool" => format!("species `{id}` changed: {}", species_diff(a, b)),
            (Some(id), None, Some(_)) if k != "species pool" => format!("species `{id}`: not in the checkpoint's pool"),
            (Some(id), Some(_), None) if k != "species pool" => format!("species `{id}`: no longer in the pool"),
            _ if k == "management" && a.is_some() && b.is_some() => format!("management: {}", management_changes(a.as_deref().unwrap_or(""), b.as_deref().unwrap_or(""))),
            _ => format!("{k}: checkpoint {}, now {}", a.as_deref().unwrap_or("(absent)"), b.as_deref().unwrap_or("(absent)")),
        });
    }
    if changes.is_empty() {
        return Ok(());
    }
    Err(Error::format(
        path,
        format!(
            "--resume refused: the scenario differs from the run that wrote this checkpoint: {} (a resumed run keeps its seed, species, terrain, site conditions, light cell, seed rain, obstacles, management and climate change; only `years` and the output cadence may change; or start the run again without --resume)",
            changes.join("; ")
        ),
    ))
}

/// What changed between two `management` identities ([`identity`]: `management[i] entry X area
/// Y` per entry): the entries whose area changed (the polygons of an area file moved, another
/// rectangle) and those whose entry changed (a field, what it does), runs of consecutive
/// entries joined (`management[3–5]: area changed`), and entries added or removed; the two
/// texts whole when either does not parse (an identity of another version).
pub fn management_changes(old: &str, new: &str) -> String {
    // (index, entry CRC, area CRC) of each entry
    let parse = |s: &str| -> Option<Vec<(usize, String, String)>> {
        let list = s.split_once(": ")?.1;
        list.split(", ")
            .map(|e| {
                let w: Vec<&str> = e.split(' ').collect();
                let i = w.first()?.strip_prefix("management[")?.strip_suffix(']')?.parse().ok()?;
                (w.len() == 5 && w[1] == "entry" && w[3] == "area").then(|| (i, w[2].to_string(), w[4].to_string()))
            })
            .collect()
    };
    let (Some(a), Some(b)) = (parse(old), parse(new)) else { return format!("checkpoint {old}, now {new}") };
    let mut what: Vec<(usize, &str)> = Vec::new();
    for k in 0..a.len().max(b.len()) {
        match (a.get(k), b.get(k)) {
            (Some(x), Some(y)) => match (x.1 != y.1, x.2 != y.2) {
                (true, true) => what.push((k, "entry and area changed")),
                (true, false) => what.push((k, "entry changed")),
                (false, true) => what.push((k, "area changed (its polygons or rectangle as resolved on the site: an area file's polygons moved or were edited?)")),
                _ => {}
            },
            (Some(_), None) => what.push((k, "removed")),
            (None, Some(_)) => what.push((k, "added")),
            _ => {}
        }
    }
    let mut parts = Vec::new();
    let mut k = 0;
    while k < what.len() {
        let mut j = k;
        while j + 1 < what.len() && what[j + 1].1 == what[k].1 && what[j + 1].0 == what[j].0 + 1 {
            j += 1;
        }
        let idx = if j > k { format!("management[{}–{}]", what[k].0, what[j].0) } else { format!("management[{}]", what[k].0) };
        parts.push(format!("{idx}: {}", what[k].1));
        k = j + 1;
    }
    parts.join(", ")
}

/// Writes to `w`; after an error it writes nothing more.
struct Out<'a, X: std::io::Write> {
    w: &'a mut X,
    err: Option<std::io::Error>,
}
impl<X: std::io::Write> Sink for Out<'_, X> {
    fn put(&mut self, b: &[u8]) {
        if self.err.is_none() {
            if let Err(e) = self.w.write_all(b) {
                self.err = Some(e);
            }
        }
    }
}

/// Writes to `w`, hashing and counting what it writes.
struct Hashed<'a, X: std::io::Write> {
    w: &'a mut X,
    crc: crc32fast::Hasher,
    n: u64,
}
impl<X: std::io::Write> std::io::Write for Hashed<'_, X> {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        let k = self.w.write(b)?;
        self.crc.update(&b[..k]);
        self.n += k as u64;
        Ok(k)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.w.flush()
    }
}

/// Serialises the world's evolving state, the run's [`identity`] and the stand table, with the
/// file length and a CRC-32 (layout in the module documentation), into memory.
pub fn to_bytes(w: &World, rows: &[StandRow]) -> Vec<u8> {
    let mut v = std::io::Cursor::new(Vec::new());
    // writing into a Vec cannot fail
    let _ = write_to(w, rows, &mut v);
    v.into_inner()
}

/// Streams the checkpoint of [`to_bytes`] into `out` (the same bytes) without building it in
/// memory: a counting pass gives the uncompressed size (the zstd frame's content size), the
/// second compresses and writes, hashing the compressed bytes; then the file length is written
/// into the header (`out` seeks back to it) and the CRC-32 at the end.
///
/// Errors: the first I/O error of `out` (or of zstd).
pub fn write_to<X: std::io::Write + std::io::Seek>(w: &World, rows: &[StandRow], out: &mut X) -> std::io::Result<()> {
    use std::io::SeekFrom;
    let id = identity(w);
    let mut count = Count(0);
    encode(w, rows, &id, &mut Enc(&mut count));
    let managed = rows.iter().any(|r| !r.management.is_empty());
    let start = out.stream_position()?;
    out.write_all(&header(managed))?;
    // the file length, known once the body is compressed
    out.write_all(&[0u8; 8])?;
    let mut body = Hashed { w: out, crc: crc32fast::Hasher::new(), n: 0 };
    let mut z = zstd::stream::write::Encoder::new(&mut body, ZSTD_LEVEL)?;
    z.include_checksum(true)?;
    z.include_contentsize(true)?;
    z.set_pledged_src_size(Some(count.0))?;
    let mut o = Out { w: &mut z, err: None };
    encode(w, rows, &id, &mut Enc(&mut o));
    if let Some(e) = o.err {
        return Err(e);
    }
    z.finish()?;
    let (n, body_crc) = (body.n, body.crc);
    let len = PREFIX as u64 + n + CRC_LEN as u64;
    let mut crc = crc32fast::Hasher::new();
    crc.update(&header(managed));
    crc.update(&len.to_le_bytes());
    crc.combine(&body_crc);
    out.seek(SeekFrom::Start(start + 12))?;
    out.write_all(&len.to_le_bytes())?;
    out.seek(SeekFrom::Start(start + PREFIX as u64 + n))?;
    out.write_all(&crc.finalize().to_le_bytes())
}

/// The identity and body of a sealed checkpoint (`sealed`: the bytes between the file length
/// and the checksum, already checked), decompressed when `compressed`.
///
/// Errors: [`Error::Format`] naming `path` when the zstd frame does not decode (a checkpoint
/// written with a wrong checksum on purpose: the CRC-32 passed).
fn body<'a>(sealed: &'a [u8], compressed: bool, path: &Path) -> Result<std::borrow::Cow<'a, [u8]>> {
    if !compressed {
        return Ok(std::borrow::Cow::Borrowed(sealed));
    }
    let bad = |e: String| Error::format(path, format!("checkpoint corrupt: its compressed body does not decode ({e}); start the run again without --resume"));
    // the frame's content size sizes the buffer (bounded: a frame claims at most 2 GiB more
    // than a thousandfold its compressed size)
    let size = zstd::zstd_safe::get_frame_content_size(sealed).ok().flatten().unwrap_or(0);
    let cap = size.min(sealed.len() as u64 * 1000 + (1 << 31)) as usize;
    let mut v = Vec::with_capacity(cap);
    let mut d = zstd::stream::read::Decoder::with_buffer(sealed).map_err(|e| bad(e.to_string()))?;
    std::io::Read::read_to_end(&mut d, &mut v).map_err(|e| bad(e.to_string()))?;
    Ok(std::borrow::Cow::Owned(v))
}

/// The identity and the body (everything between the file length and the checksum).
fn encode<S: Sink>(w: &World, rows: &[StandRow], id: &[(String, String)], o: &mut Enc<S>) {
    o.u64(id.len() as u64);
    for (k, v) in id {
        o.str(k);
        o.str(v);
    }
    o.u64(w.stand.year as u64);
    let t = &w.stand.trees;
    o.u64(t.next_id);
    o.u64(t.len() as u64);
    o.each(&t.id, |x| x.to_le_bytes());
    o.u64(t.species.len() as u64);
    o.each(&t.species, |x| x.to_le_bytes());
    for c in t.f32_columns() {
        o.f32s(c);
    }
    o.u64(w.stand.seeds.len() as u64);
    for s in &w.stand.seeds {
        o.f32s(&s.data);
    }
    for d in w.tallies.deaths_total {
        o.u64(d);
    }
    // regeneration layer
    let c = &w.stand.cohorts;
    o.u32s(&c.cell);
    o.u64(c.pool.len() as u64);
    o.each(&c.pool, |p| (p as u32).to_le_bytes());
    o.u32s(&c.stems);
    for v in [&c.height, &c.age, &c.vigour] {
        o.f32s(v);
    }
    o.u64(c.stress_years.len() as u64);
    o.each(&c.stress_years, |y| (y as u32).to_le_bytes());
    let l = &w.tallies.regen_ledger;
    o.u64(l.germinated.len() as u64);
    for p in 0..l.germinated.len() {
        o.u64(l.germinated[p]);
        o.u64(l.recruited[p]);
        for d in l.dead[p] {
            o.u64(d);
        }
    }
    o.u64(rows.len() as u64);
    for r in rows {
        o.u64(r.year as u64);
        for v in [r.stems_ha, r.seedlings_ha, r.basal_area_m2_ha, r.mean_height_m, r.top_height_m, r.qmd_cm, r.stems_7cm_ha, r.qmd_7cm_cm] {
            o.f64(v);
        }
        o.u64(r.share_ba.len() as u64);
        for (a, b) in r.share_ba.iter().zip(&r.share_stems) {
            o.f64(*a);
            o.f64(*b);
        }
        for d in r.deaths {
            o.u64(d);
        }
        o.f64(r.regeneration_ha);
        o.u64(r.regen_germinated);
        o.u64(r.regen_recruited);
        for d in r.regen_deaths {
            o.u64(d);
        }
        // layout 12 (round 44): the drought index after the precipitation factor
        for v in [r.volume_m3_ha, r.harvest_stems_ha, r.harvest_volume_m3_ha, r.temperature_offset_k, r.precipitation_factor, r.drought_index] {
            o.f64(v);
        }
        // layout 10 (round 42)
        o.f64(r.deaths_volume_m3_ha);
        o.u64(r.species.len() as u64);
        for sp in &r.species {
            for v in [sp.stems_ha, sp.basal_area_m2_ha, sp.qmd_cm, sp.top_height_m, sp.volume_m3_ha, sp.top_height_own_area_m].iter().chain(&sp.deaths_stems_ha).chain(&sp.deaths_volume_m3_ha) {
                o.f64(*v);
            }
        }
    }
    // the management table (issue 35 round 38), after the stand table and only in a run with
    // `[[management]]` (layout [`MANAGED_BASE`]): a run without it keeps the bytes of layout 7
    // as they were, and a managed run's checkpoint of layout 7 (before the table) reads as one
    // without rows for its years
    if rows.iter().any(|r| !r.management.is_empty()) {
        for r in rows {
            o.u64(r.management.len() as u64);
            for e in &r.management {
                o.u64(e.entry as u64);
                o.str(&e.kind);
                o.str(&e.method);
                for v in [e.area_ha, e.stems_ha, e.basal_area_m2_ha, e.volume_m3_ha, e.qmd_cm, e.top_height_m, e.harvest_stems_ha, e.harvest_volume_m3_ha] {
                    o.f64(v);
                }
                // layout 9 (round 41)
                o.str(&e.name);
                o.f64(e.harvest_basal_area_m2_ha);
                o.f64(e.cut_saplings_ha);
                for shares in [&e.ba_share, &e.stem_share] {
                    o.u64(shares.len() as u64);
                    for &v in shares {
                        o.f64(v);
                    }
                }
                // layout 11 (round 42)
                o.u64(e.capped as u64);
                // layout 16 (round 46)
                o.f64(e.planted_ha);
                o.f64(e.seedlings_ha);
            }
        }
    }
}

/// The error of a checkpoint that ends early or holds a malformed value at byte `at`.
fn corrupt(path: &Path, at: usize) -> Error {
    Error::format(path, format!("checkpoint truncated or corrupt at byte {at}"))
}

/// Restores a checkpoint into `w` (built from the same scenario) and returns the stand table.
///
/// Errors: [`Error::Format`] naming `path` when the bytes are not a checkpoint (or of another
/// layout version), are truncated (both lengths named), fail the CRC-32 (both checksums
/// named), belong to a run whose identity differs from `w`'s (each changed field named with
/// its value in the checkpoint and now: seed, species pool, a species' parameter, terrain,
/// site conditions, light cell, seed rain, obstacles), or hold out-of-range values.
pub fn restore(w: &mut World, bytes: &[u8], path: &Path) -> Result<Vec<StandRow>> {
    let compressed = check_header(bytes, path)?;
    let end = check_seal(bytes, path)?;
    let bytes = body(&bytes[PREFIX..end], compressed, path)?;
    let fail = |s: Short| corrupt(path, s.at());
    let mut r = Dec::at(&bytes, 0, &fail);
    let n_id = r.count(16)?;
    let mut stored = Vec::with_capacity(n_id);
    for _ in 0..n_id {
        stored.push((r.str()?, r.str()?));
    }
    check_identity(&stored, w, path)?;
    let year = r.u64()? as u32;
    let mut t = TreeStore { next_id: r.u64()?, ..Default::default() };
    let n = r.count(8)?;
    t.id = r.u64s_n(n)?;
    let n = r.count(2)?;
    t.species = r.u16s_n(n)?;
    if t.species.len() != t.id.len() {
        return Err(Error::format(path, format!("checkpoint has {} tree ids but {} tree species (corrupt)", t.id.len(), t.species.len())));
    }
    let n_trees = t.id.len();
    for c in t.f32_columns_mut() {
        *c = r.f32s()?;
        if c.len() != n_trees {
            return Err(corrupt(path, r.pos()));
        }
    }
    if t.species.iter().any(|&s| s as usize >= w.site.lib.species.len()) {
        return Err(Error::format(path, "checkpoint names a species index outside the library"));
    }
    // positions inside the terrain, sizes finite and non-negative: a corrupt value would
    // otherwise index outside the light grid or spread NaN through the stand
    let (ex, ey) = (w.site.extent.0 as f32, w.site.extent.1 as f32);
    // (every column finite and, but for the elevation z, non-negative)
    let columns = t.f32_columns();
    for i in 0..t.id.len() {
        let ok = t.x[i] <= ex && t.y[i] <= ey && columns.iter().zip(F32_COLUMN_NAMES).all(|(c, name)| c[i].is_finite() && (name == "z" || c[i] >= 0.0));
        if !ok {
            return Err(Error::format(path, format!("checkpoint tree {} (id {}): position or size out of range (x {}, y {}, height {}, dbh {}): corrupt", i, t.id[i], t.x[i], t.y[i], t.height[i], t.dbh[i])));
        }
    }
    let ns = r.u64()? as usize;
    if ns != w.site.pool.len() {
        return Err(Error::format(path, format!("checkpoint has {ns} species in the pool, the scenario {}", w.site.pool.len())));
    }
    // each grid as `w` holds it: whole, or a tile's window (a per-rank checkpoint, issue 37
    // Build 1); a whole grid read into a window (a per-rank checkpoint of an earlier Sylva,
    // which saved the whole grids) is cut to it
    let mut seeds = w.stand.seeds.clone();
    for g in seeds.iter_mut() {
        let s = r.f32s()?;
        if s.len() == g.data.len() {
            g.data = s;
        } else if s.len() == g.cols * g.rows {
            let win = g.held;
            let mut whole = super::world::SeedGrid { data: s, ..super::world::SeedGrid::new(g.cell_m, g.block, g.cols, g.rows) };
            if !whole.hold(win) {
                return Err(Error::format(path, "checkpoint seed grid does not match the terrain"));
            }
            *g = whole;
        } else {
            return Err(Error::format(path, "checkpoint seed grid does not match the terrain"));
        }
    }
    let mut deaths = [0u64; super::trees::N_CAUSES];
    for d in deaths.iter_mut() {
        *d = r.u64()?;
    }
    let mut cohorts = Cohorts { cell: r.u32s()?, ..Default::default() };
    cohorts.pool = r.u32s()?.into_iter().map(|p| p as u16).collect();
    cohorts.stems = r.u32s()?;
    cohorts.height = r.f32s()?;
    cohorts.age = r.f32s()?;
    cohorts.vigour = r.f32s()?;
    cohorts.stress_years = r.u32s()?.into_iter().map(|y| y.min(u16::MAX as u32) as u16).collect();
    let nc = cohorts.cell.len();
    if [cohorts.pool.len(), cohorts.stems.len(), cohorts.height.len(), cohorts.age.len(), cohorts.vigour.len(), cohorts.stress_years.len()].iter().any(|&l| l != nc) {
        return Err(corrupt(path, r.pos()));
    }
    let bad_f = |v: &[f32]| v.iter().any(|x| !(x.is_finite() && *x >= 0.0));
    if bad_f(&cohorts.height) || bad_f(&cohorts.age) || bad_f(&cohorts.vigour) || seeds.iter().any(|g| bad_f(&g.data)) {
        return Err(Error::format(path, "checkpoint holds a negative, NaN or infinite cohort height, age, vigour or seed count: corrupt"));
    }
    if cohorts.cell.iter().any(|&c| c as usize >= w.site.light.len()) || cohorts.pool.iter().any(|&p| p as usize >= w.site.pool.len()) {
        return Err(Error::format(path, "checkpoint cohorts lie outside the light grid or the species pool"));
    }
    let np = r.u64()? as usize;
    if np != w.site.pool.len() {
        return Err(corrupt(path, r.pos()));
    }
    let mut ledger = RegenLedger::new(np);
    for p in 0..np {
        ledger.germinated[p] = r.u64()?;
        ledger.recruited[p] = r.u64()?;
        for d in ledger.dead[p].iter_mut() {
            *d = r.u64()?;
        }
    }
    let nr = r.count(8)?;
    let mut rows = Vec::with_capacity(nr);
    for _ in 0..nr {
        let year = r.u64()? as u32;
        let mut v = [0f64; 8];
        for x in v.iter_mut() {
            *x = r.f64()?;
        }
        let k = r.count(16)?;
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for _ in 0..k {
            a.push(r.f64()?);
            b.push(r.f64()?);
        }
        let mut d = [0u64; super::trees::N_CAUSES];
        for x in d.iter_mut() {
            *x = r.u64()?;
        }
        let regeneration_ha = r.f64()?;
        let (regen_germinated, regen_recruited) = (r.u64()?, r.u64()?);
        let mut regen_deaths = [0u64; N_REGEN_CAUSES];
        for x in regen_deaths.iter_mut() {
            *x = r.u64()?;
        }
        let mut m = [0f64; 6];
        for x in m.iter_mut() {
            *x = r.f64()?;
        }
        let deaths_volume_m3_ha = r.f64()?;
        let k = r.count(8 * (5 + 2 * super::trees::N_CAUSES))?;
        let mut species = Vec::with_capacity(k);
        for _ in 0..k {
            let mut v = [0f64; 6 + 2 * super::trees::N_CAUSES];
            for x in v.iter_mut() {
                *x = r.f64()?;
            }
            let mut ds = [0f64; super::trees::N_CAUSES];
            let mut dv = [0f64; super::trees::N_CAUSES];
            ds.copy_from_slice(&v[6..6 + super::trees::N_CAUSES]);
            dv.copy_from_slice(&v[6 + super::trees::N_CAUSES..]);
            species.push(super::stats::SpeciesRow { stems_ha: v[0], basal_area_m2_ha: v[1], qmd_cm: v[2], top_height_m: v[3], volume_m3_ha: v[4], top_height_own_area_m: v[5], deaths_stems_ha: ds, deaths_volume_m3_ha: dv });
        }
        rows.push(StandRow {
            year,
            stems_ha: v[0],
            seedlings_ha: v[1],
            regeneration_ha,
            basal_area_m2_ha: v[2],
            mean_height_m: v[3],
            top_height_m: v[4],
            qmd_cm: v[5],
            stems_7cm_ha: v[6],
            qmd_7cm_cm: v[7],
            share_ba: a,
            share_stems: b,
            deaths: d,
            regen_germinated,
            regen_recruited,
            regen_deaths,
            volume_m3_ha: m[0],
            harvest_stems_ha: m[1],
            harvest_volume_m3_ha: m[2],
            temperature_offset_k: m[3],
            precipitation_factor: m[4],
            drought_index: m[5],
            management: Vec::new(),
            deaths_volume_m3_ha,
            species,
        });
    }
    if r.rest() != 0 {
        // the management table's rows (written only by a run with `[[management]]`)
        for row in rows.iter_mut() {
            let n = r.count(8 + 16 + 64)?;
            for _ in 0..n {
                let entry = r.u64()? as usize;
                let (kind, method) = (r.str()?, r.str()?);
                let mut v = [0f64; 8];
                for x in v.iter_mut() {
                    *x = r.f64()?;
                }
                let name = r.str()?;
                let (harvest_basal_area_m2_ha, cut_saplings_ha) = (r.f64()?, r.f64()?);
                let mut shares = [Vec::new(), Vec::new()];
                for sh in shares.iter_mut() {
                    let k = r.count(8)?;
                    for _ in 0..k {
                        sh.push(r.f64()?);
                    }
                }
                let [ba_share, stem_share] = shares;
                let capped = match r.u64()? {
                    0 => false,
                    1 => true,
                    _ => return Err(corrupt(path, r.pos())),
                };
                let (planted_ha, seedlings_ha) = (r.f64()?, r.f64()?);
                row.management.push(super::stats::EntryRow {
                    entry,
                    kind,
                    method,
                    area_ha: v[0],
                    stems_ha: v[1],
                    basal_area_m2_ha: v[2],
                    volume_m3_ha: v[3],
                    qmd_cm: v[4],
                    top_height_m: v[5],
                    harvest_stems_ha: v[6],
                    harvest_volume_m3_ha: v[7],
                    name,
                    harvest_basal_area_m2_ha,
                    cut_saplings_ha,
                    ba_share,
                    stem_share,
                    capped,
                    planted_ha,
                    seedlings_ha,
                });
            }
        }
    }
    if r.rest() != 0 {
        return Err(Error::format(path, format!("checkpoint has {} bytes after its stand table: corrupt", r.rest())));
    }
    w.stand.trees = t;
    w.stand.year = year;
    w.stand.seeds = seeds;
    w.tallies.deaths_total = deaths;
    w.stand.cohorts = cohorts;
    w.tallies.regen_ledger = ledger;
    w.scratch.regen_year = Default::default();
    w.scratch.dead.clear();
    Ok(rows)
}

//! Checkpoints: the evolving state of a [`World`] (trees, regeneration cohorts and their ledger,
//! seeds, year, death counts) and the
//! stand table so far, in a compact little-endian binary with exact float bits, so that a
//! resumed run continues bit for bit. Site conditions and species are rebuilt from the scenario.

use super::stats::StandRow;
use super::cohorts::{Cohorts, RegenLedger, N_REGEN_CAUSES};
use super::trees::{TreeStore, N_CAUSES};
use super::world::World;
use crate::error::{Error, Result};
use std::path::Path;

/// File signature: 7 bytes, then `V` and the little-endian `u32` [`LAYOUT_VERSION`]. Files
/// from before the version field (`SYLVACK1`…`SYLVACK3`) have a digit in place of the `V`.
const MAGIC: &[u8; 7] = b"SYLVACK";

/// Hand-kept part of the layout version: bump it whenever the order, kind or number of the
/// stored fields changes (the cause counts below are folded in by themselves).
const LAYOUT_BASE: u32 = 4;

/// Version of the checkpoint layout, written in the header and required on reading:
/// `LAYOUT_BASE · 65536 + N_CAUSES · 256 + N_REGEN_CAUSES`, so that adding a cause of death
/// of trees ([`crate::sim::trees::N_CAUSES`]) or of the regeneration layer
/// ([`N_REGEN_CAUSES`]), which changes the size of the stored counts, changes the version.
pub const LAYOUT_VERSION: u32 = LAYOUT_BASE << 16 | (N_CAUSES as u32) << 8 | N_REGEN_CAUSES as u32;

/// The header of this layout: [`MAGIC`], `V`, [`LAYOUT_VERSION`] (12 bytes).
fn header() -> Vec<u8> {
    let mut h = MAGIC.to_vec();
    h.push(b'V');
    h.extend_from_slice(&LAYOUT_VERSION.to_le_bytes());
    h
}

/// Describes a layout version for messages: `4.4.2 (base, tree death causes, regeneration causes)`.
fn describe(v: u32) -> String {
    format!("{}.{}.{} (layout, tree death causes, regeneration death causes)", v >> 16, (v >> 8) & 0xff, v & 0xff)
}

/// Checks the header of `bytes`; returns the offset of the body.
///
/// Errors: [`Error::Format`] naming `path`: not a checkpoint; a checkpoint of an older Sylva
/// (before layout versions) or of another layout version, saying which and what to do.
fn check_header(bytes: &[u8], path: &Path) -> Result<usize> {
    let again = "start the run again without --resume (or with the Sylva version that wrote it)";
    if bytes.len() < 8 || &bytes[..7] != MAGIC {
        return Err(Error::format(path, "not a Sylva checkpoint (no SYLVACK signature)"));
    }
    match bytes[7] {
        b'V' => {
            let v = bytes.get(8..12).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]])).ok_or_else(|| Error::format(path, "checkpoint header truncated (no layout version)"))?;
            if v != LAYOUT_VERSION {
                return Err(Error::format(path, format!("checkpoint layout version {} differs from this build's {}: {again}", describe(v), describe(LAYOUT_VERSION))));
            }
            Ok(12)
        }
        d if d.is_ascii_digit() => Err(Error::format(
            path,
            format!("checkpoint from an older Sylva (layout SYLVACK{}, before layout versions; this build reads version {}): {again}", d as char, describe(LAYOUT_VERSION)),
        )),
        _ => Err(Error::format(path, "not a Sylva checkpoint (unknown header after SYLVACK)")),
    }
}

struct W(Vec<u8>);
impl W {
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32s(&mut self, v: &[f32]) {
        self.u64(v.len() as u64);
        for x in v {
            self.0.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn u32s(&mut self, v: &[u32]) {
        self.u64(v.len() as u64);
        for x in v {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }
}

struct R<'a> {
    b: &'a [u8],
    p: usize,
    path: &'a Path,
}
impl R<'_> {
    fn err(&self) -> Error {
        Error::format(self.path, format!("checkpoint truncated or corrupt at byte {}", self.p))
    }
    fn u64(&mut self) -> Result<u64> {
        let s = self.b.get(self.p..self.p + 8).ok_or_else(|| self.err())?;
        self.p += 8;
        let mut a = [0u8; 8];
        a.copy_from_slice(s);
        Ok(u64::from_le_bytes(a))
    }
    fn len(&mut self, elem: usize) -> Result<usize> {
        let n = self.u64()? as usize;
        if n.saturating_mul(elem) > self.b.len() - self.p.min(self.b.len()) {
            return Err(self.err());
        }
        Ok(n)
    }
    fn f32s(&mut self) -> Result<Vec<f32>> {
        let n = self.len(4)?;
        let s = &self.b[self.p..self.p + 4 * n];
        self.p += 4 * n;
        Ok(s.chunks_exact(4).map(|c| f32::from_bits(u32::from_le_bytes([c[0], c[1], c[2], c[3]]))).collect())
    }
    fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn u32s(&mut self) -> Result<Vec<u32>> {
        let n = self.len(4)?;
        let s = &self.b[self.p..self.p + 4 * n];
        self.p += 4 * n;
        Ok(s.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
    }
}

/// Serialises the world's evolving state and the stand table.
pub fn to_bytes(w: &World, rows: &[StandRow]) -> Vec<u8> {
    let mut o = W(header());
    o.u64(w.stand.year as u64);
    o.u64(w.site.seed);
    let t = &w.stand.trees;
    o.u64(t.next_id);
    o.u64(t.len() as u64);
    for v in &t.id {
        o.u64(*v);
    }
    o.u64(t.species.len() as u64);
    for v in &t.species {
        o.0.extend_from_slice(&v.to_le_bytes());
    }
    for c in [&t.x, &t.y, &t.z, &t.age, &t.height, &t.dbh, &t.crown_radius, &t.crown_base, &t.light, &t.vigour, &t.suitability] {
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
    o.u32s(&c.pool.iter().map(|&p| p as u32).collect::<Vec<_>>());
    o.u32s(&c.stems);
    for v in [&c.height, &c.age, &c.vigour] {
        o.f32s(v);
    }
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
    }
    o.0
}

/// Restores a checkpoint into `w` (built from the same scenario) and returns the stand table.
///
/// Errors: [`Error::Format`] naming `path` when the bytes are not a checkpoint, are truncated, or
/// belong to a different scenario (seed or species pool).
pub fn restore(w: &mut World, bytes: &[u8], path: &Path) -> Result<Vec<StandRow>> {
    let body = check_header(bytes, path)?;
    let mut r = R { b: bytes, p: body, path };
    let year = r.u64()? as u32;
    let seed = r.u64()?;
    if seed != w.site.seed {
        return Err(Error::format(path, format!("checkpoint seed {seed} differs from the scenario's seed {}", w.site.seed)));
    }
    let mut t = TreeStore { next_id: r.u64()?, ..Default::default() };
    let n = r.len(8)?;
    t.id = (0..n).map(|_| r.u64()).collect::<Result<_>>()?;
    let n = r.len(2)?;
    let s = &bytes[r.p..r.p + 2 * n];
    r.p += 2 * n;
    t.species = s.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect();
    if t.species.len() != t.id.len() {
        return Err(Error::format(path, format!("checkpoint has {} tree ids but {} tree species (corrupt)", t.id.len(), t.species.len())));
    }
    for c in [&mut t.x, &mut t.y, &mut t.z, &mut t.age, &mut t.height, &mut t.dbh, &mut t.crown_radius, &mut t.crown_base, &mut t.light, &mut t.vigour, &mut t.suitability] {
        *c = r.f32s()?;
        if c.len() != t.id.len() {
            return Err(r.err());
        }
    }
    if t.species.iter().any(|&s| s as usize >= w.site.lib.species.len()) {
        return Err(Error::format(path, "checkpoint names a species index outside the library"));
    }
    // positions inside the terrain, sizes finite and non-negative: a corrupt value would
    // otherwise index outside the light grid or spread NaN through the stand
    let (ex, ey) = (w.site.extent.0 as f32, w.site.extent.1 as f32);
    for i in 0..t.id.len() {
        let ok = (0.0..=ex).contains(&t.x[i]) && (0.0..=ey).contains(&t.y[i]) && t.z[i].is_finite()
            && [t.age[i], t.height[i], t.dbh[i], t.crown_radius[i], t.crown_base[i], t.light[i], t.vigour[i], t.suitability[i]].iter().all(|v| v.is_finite() && *v >= 0.0);
        if !ok {
            return Err(Error::format(path, format!("checkpoint tree {} (id {}): position or size out of range (x {}, y {}, height {}, dbh {}): corrupt", i, t.id[i], t.x[i], t.y[i], t.height[i], t.dbh[i])));
        }
    }
    let ns = r.u64()? as usize;
    if ns != w.site.pool.len() {
        return Err(Error::format(path, format!("checkpoint has {ns} species in the pool, the scenario {}", w.site.pool.len())));
    }
    let mut seeds = w.stand.seeds.clone();
    for g in seeds.iter_mut() {
        let s = r.f32s()?;
        if s.len() != g.data.len() {
            return Err(Error::format(path, "checkpoint seed grid does not match the terrain"));
        }
        g.data = s;
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
    let nc = cohorts.cell.len();
    if [cohorts.pool.len(), cohorts.stems.len(), cohorts.height.len(), cohorts.age.len(), cohorts.vigour.len()].iter().any(|&l| l != nc) {
        return Err(r.err());
    }
    let bad_f = |v: &[f32]| v.iter().any(|x| !(x.is_finite() && *x >= 0.0));
    if bad_f(&cohorts.height) || bad_f(&cohorts.age) || bad_f(&cohorts.vigour) || seeds.iter().any(|g| bad_f(&g.data)) {
        return Err(Error::format(path, "checkpoint holds a negative, NaN or infinite cohort height, age, vigour or seed count: corrupt"));
    }
    if cohorts.cell.iter().any(|&c| c as usize >= w.site.light_site.len()) || cohorts.pool.iter().any(|&p| p as usize >= w.site.pool.len()) {
        return Err(Error::format(path, "checkpoint cohorts lie outside the light grid or the species pool"));
    }
    let np = r.u64()? as usize;
    if np != w.site.pool.len() {
        return Err(r.err());
    }
    let mut ledger = RegenLedger::new(np);
    for p in 0..np {
        ledger.germinated[p] = r.u64()?;
        ledger.recruited[p] = r.u64()?;
        for d in ledger.dead[p].iter_mut() {
            *d = r.u64()?;
        }
    }
    let nr = r.len(8)?;
    let mut rows = Vec::with_capacity(nr);
    for _ in 0..nr {
        let year = r.u64()? as u32;
        let mut v = [0f64; 8];
        for x in v.iter_mut() {
            *x = r.f64()?;
        }
        let k = r.len(16)?;
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
        });
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

//! The regeneration layer's state: sapling cohorts below the recruitment height, one per light
//! cell and species, and its counts (the phase that updates them is
//! [`crate::sim::phases::regen`]).

/// Height (m) at which a cohort's stems become individual trees (iLand: 4 m).
pub const RECRUIT_HEIGHT_M: f32 = 4.0;
/// Number of causes of death in the regeneration layer ([`RegenDeath::ALL`]).
pub const N_REGEN_CAUSES: usize = 2;

/// Why sapling stems of a cohort died.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RegenDeath {
    /// Light- and site-dependent (stress) mortality: the growth-dependent shade mortality of
    /// stems, a vigour below the species' threshold, and cohorts dead whole after too many
    /// consecutive stress years ([`crate::sim::phases::regen`], step 3).
    Shade,
    /// The density cap [`crate::sim::phases::regen::max_density_ha`] of the cell.
    Crowding,
}

impl RegenDeath {
    /// All causes in output order.
    pub const ALL: [RegenDeath; N_REGEN_CAUSES] = [RegenDeath::Shade, RegenDeath::Crowding];
    /// Lower-case name used in outputs (`regen_deaths_<name>`).
    pub fn name(self) -> &'static str {
        match self {
            RegenDeath::Shade => "shade",
            RegenDeath::Crowding => "crowding",
        }
    }
}

/// One cohort.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cohort {
    /// Light cell index (row-major, row 0 south).
    pub cell: u32,
    /// Position of the species in the pool.
    pub pool: u16,
    /// Number of stems.
    pub stems: u32,
    /// Mean height (m), below [`RECRUIT_HEIGHT_M`].
    pub height: f32,
    /// Age (years).
    pub age: f32,
    /// Vigour memory (0–1), as for trees.
    pub vigour: f32,
    /// Consecutive years (up to this one) in which the cohort's realised relative height growth
    /// stayed below its species' stress threshold (iLand's sapling stress years; the cohort dies
    /// once it exceeds [`crate::sim::phases::regen::max_stress_years`]).
    pub stress_years: u16,
}

/// All cohorts, struct of arrays sorted by (cell, pool position); at most one per pair.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Cohorts {
    /// Light cell index.
    pub cell: Vec<u32>,
    /// Pool position of the species.
    pub pool: Vec<u16>,
    /// Stems.
    pub stems: Vec<u32>,
    /// Mean height (m).
    pub height: Vec<f32>,
    /// Age (years).
    pub age: Vec<f32>,
    /// Vigour memory (0–1).
    pub vigour: Vec<f32>,
    /// Consecutive stress years ([`Cohort::stress_years`]).
    pub stress_years: Vec<u16>,
}

impl Cohorts {
    /// Number of cohorts.
    pub fn len(&self) -> usize {
        self.cell.len()
    }
    /// True when there is no cohort.
    pub fn is_empty(&self) -> bool {
        self.cell.is_empty()
    }
    /// Cohort `i`.
    pub fn get(&self, i: usize) -> Cohort {
        Cohort { cell: self.cell[i], pool: self.pool[i], stems: self.stems[i], height: self.height[i], age: self.age[i], vigour: self.vigour[i], stress_years: self.stress_years[i] }
    }
    /// Appends a cohort (the caller keeps the (cell, pool) order).
    pub fn push(&mut self, c: Cohort) {
        self.cell.push(c.cell);
        self.pool.push(c.pool);
        self.stems.push(c.stems);
        self.height.push(c.height);
        self.age.push(c.age);
        self.vigour.push(c.vigour);
        self.stress_years.push(c.stress_years);
    }
    /// Total stems.
    pub fn total_stems(&self) -> u64 {
        self.stems.iter().map(|&n| n as u64).sum()
    }
    /// Stems per pool species (`np` species).
    pub fn stems_per_species(&self, np: usize) -> Vec<u64> {
        let mut v = vec![0u64; np];
        for (p, n) in self.pool.iter().zip(&self.stems) {
            if let Some(x) = v.get_mut(*p as usize) {
                *x += *n as u64;
            }
        }
        v
    }
    /// Approximate heap size in bytes.
    pub fn heap_bytes(&self) -> usize {
        self.cell.capacity() * 24
    }
}

/// Cumulative counts of the regeneration layer per pool species (pool order), since the start.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RegenLedger {
    /// Stems germinated.
    pub germinated: Vec<u64>,
    /// Stems recruited into the tree store.
    pub recruited: Vec<u64>,
    /// Stems dead by cause ([`RegenDeath::ALL`] order).
    pub dead: Vec<[u64; N_REGEN_CAUSES]>,
}

impl RegenLedger {
    /// An empty ledger for `np` pool species.
    pub fn new(np: usize) -> Self {
        RegenLedger { germinated: vec![0; np], recruited: vec![0; np], dead: vec![[0; N_REGEN_CAUSES]; np] }
    }
}

/// The regeneration layer's counts of one year (all species).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RegenYear {
    /// Stems germinated.
    pub germinated: u64,
    /// Stems recruited into the tree store.
    pub recruited: u64,
    /// Stems dead by cause ([`RegenDeath::ALL`] order).
    pub dead: [u64; N_REGEN_CAUSES],
}

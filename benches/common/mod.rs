//! Helpers shared by the plain-program benches.
#![allow(dead_code)]
use std::time::Instant;

/// Median wall time (ms) of `runs` calls of `f`.
pub fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(|a, b| a.total_cmp(b));
    t[t.len() / 2]
}

/// Scenario TOML of the afforestation benches (ecosystem, load): `name`, `years`, seed 1, any
/// further top-level `head` lines, the `[terrain]` source line, then seed rain of silver birch
/// (5,000 seeds/ha/yr), beech and Norway spruce (500 each).
pub fn afforestation_toml(name: &str, years: u32, head: &str, terrain: &str) -> String {
    format!(
        r#"
name = "{name}"
years = {years}
seed = 1
{head}
species = ["beech", "norway_spruce", "silver_birch"]
[terrain]
{terrain}
[[start]]
kind = "seed_rain"
species = "silver_birch"
seeds_per_ha = 5000
[[start]]
kind = "seed_rain"
species = "beech"
seeds_per_ha = 500
[[start]]
kind = "seed_rain"
species = "norway_spruce"
seeds_per_ha = 500
"#
    )
}

/// CPU seconds (user + system) of this process so far (getrusage).
pub fn cpu() -> f64 {
    // SAFETY: getrusage writes into the zeroed struct we own.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: a valid pointer to a rusage struct.
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) };
    let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    s(u.ru_utime) + s(u.ru_stime)
}

//! Where the main job's time goes: wall and process CPU seconds of its phases ([`Clock`],
//! [`PhaseTime`]; `timings.csv` of `sylva run`, round 47).

use std::time::Instant;

/// The process's CPU seconds so far: user and system time of all its threads
/// (`getrusage(RUSAGE_SELF)`, POSIX); NaN where the platform gives none.
pub fn process_cpu_s() -> f64 {
    #[cfg(unix)]
    {
        // SAFETY: getrusage only writes the struct it is given, which is plain data
        let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut ru) } == 0 {
            let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
            return s(ru.ru_utime) + s(ru.ru_stime);
        }
    }
    f64::NAN
}

/// A stopwatch of wall and process CPU seconds ([`process_cpu_s`]) for [`PhaseTime`]s.
#[derive(Debug, Clone, Copy)]
pub struct Clock {
    wall: Instant,
    cpu: f64,
}

impl Clock {
    /// Started now.
    pub fn start() -> Clock {
        Clock { wall: Instant::now(), cpu: process_cpu_s() }
    }

    /// Wall and CPU seconds since the start.
    pub fn elapsed(&self) -> (f64, f64) {
        (self.wall.elapsed().as_secs_f64(), process_cpu_s() - self.cpu)
    }

    /// Adds [`Clock::elapsed`] to `sum` (wall, CPU).
    pub fn add_to(&self, sum: &mut (f64, f64)) {
        let (w, c) = self.elapsed();
        sum.0 += w;
        sum.1 += c;
    }

    /// Appends a [`PhaseTime`] named `phase` with [`Clock::elapsed`] to `timings`.
    pub fn push(&self, timings: &mut Vec<PhaseTime>, phase: &str) {
        let (wall_s, cpu_s) = self.elapsed();
        timings.push(PhaseTime { phase: phase.to_string(), wall_s, cpu_s });
    }
}

/// Where a phase of `sylva run` spent its time: a row of `timings.csv`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PhaseTime {
    /// What ran ("simulation", "close-up", ...; a phase "X: of which Y" is part of X).
    pub phase: String,
    /// Wall seconds (≥ 0), which a loaded machine stretches.
    pub wall_s: f64,
    /// CPU seconds of the process (user + system, all threads; ≥ 0, up to the cores × wall),
    /// which load stretches far less; NaN where not measured (serialised as null, written
    /// empty in the CSV).
    #[serde(with = "nan_as_null")]
    pub cpu_s: f64,
}

/// An `f64` that may be NaN, as JSON `null`.
mod nan_as_null {
    /// NaN as `null`.
    pub fn serialize<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_nan() { s.serialize_none() } else { s.serialize_some(v) }
    }
    /// `null` as NaN.
    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(<Option<f64> as serde::Deserialize>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

//! Wall-clock time and parallel loops per phase of [`super::adapt_group`] (issue 31, round 36:
//! where a two-thread wall move waits). Off unless the environment variable
//! `SYLVA_PLASTIC_PHASES` is set (read once per process): `cpu` times each phase by the CPU
//! time of the thread that runs it (a figure hardly affected by other jobs on the machine:
//! with one thread, the work of the phase), any other value by the wall clock. Off, a phase
//! costs one load of a flag and no clock reading. The figures are process-wide sums over
//! every call since the last [`take`] (`benches/plastic.rs` prints them with
//! `SYLVA_PLASTIC_PHASES` set and `SYLVA_PLASTIC_PROFILE`).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::Instant;

/// The phases timed, in the order [`take`] lists them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Step 1: the signatures (solids' masks and the other trees' shade per node).
    Signatures,
    /// The call's set-up: the query region, the per-tree work lists.
    Setup,
    /// A level's prepositioning of its season's nodes (one core).
    Preposition,
    /// A level's stage occluders ([`super::transform`]'s `stage_occluders_with`).
    StageOccluders,
    /// A level's shade casters (one sphere per foliage lobe).
    ShadeCasters,
    /// A level's changed casters and its shadow volumes' set-up.
    Volumes,
    /// Bending, pass 1 of a depth batch: fates, the kept nodes, the unbent positions.
    BendPass1,
    /// Bending: the solids' masks of a depth batch's points.
    BendMasks,
    /// Grid builds before queries (`ShadowVolumes::prepare`), bending and clusters.
    GridBuilds,
    /// Bending: the light queries of a depth batch.
    BendQueries,
    /// Bending, pass 2 of a depth batch: eq. (6), rotations, collisions.
    BendPass2,
    /// The scan for the stage clusters to light, their solids' masks and reused rows.
    LitScan,
    /// The lit clusters' light queries.
    ClusterQueries,
    /// Pruning: ψ of eq. (10) and the fates of eq. (11).
    Pruning,
    /// After the levels: wood, final occluders, the report.
    Finish,
}

const N: usize = Phase::Finish as usize + 1;

const NAMES: [&str; N] = [
    "signatures",
    "set-up",
    "preposition",
    "stage occluders",
    "shade casters",
    "volumes, changed casters",
    "bend pass 1",
    "bend masks",
    "grid builds (prepare)",
    "bend queries",
    "bend pass 2",
    "lit-cluster scan and masks",
    "cluster queries",
    "pruning (psi, fates)",
    "finish (wood, final occluders, report)",
];

#[allow(clippy::declare_interior_mutable_const)]
const ZERO: AtomicU64 = AtomicU64::new(0);
static NANOS: [AtomicU64; N] = [ZERO; N];
static SPANS: [AtomicU64; N] = [ZERO; N];
static FORKS: [AtomicU64; N] = [ZERO; N];

/// 0: off, 1: wall clock, 2: thread CPU time.
fn mode() -> u8 {
    static MODE: OnceLock<u8> = OnceLock::new();
    *MODE.get_or_init(|| match std::env::var("SYLVA_PLASTIC_PHASES") {
        Ok(v) if v == "cpu" => 2,
        Ok(_) => 1,
        Err(_) => 0,
    })
}

/// Whether the timer is on (`SYLVA_PLASTIC_PHASES` set).
pub fn on() -> bool {
    mode() != 0
}

/// Whether the phases are timed by thread CPU time (`SYLVA_PLASTIC_PHASES=cpu`).
pub fn cpu() -> bool {
    mode() == 2
}

/// CPU time of the calling thread (ns).
fn thread_ns() -> u64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec; CLOCK_THREAD_CPUTIME_ID is always available on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

enum Start {
    Wall(Instant),
    Cpu(u64),
}

/// A running phase: its time is added when dropped (nothing when the timer is off).
pub struct Span(Option<(Phase, Start)>);

impl Drop for Span {
    fn drop(&mut self) {
        if let Some((p, t)) = &self.0 {
            let ns = match t {
                Start::Wall(i) => i.elapsed().as_nanos() as u64,
                Start::Cpu(c) => thread_ns().saturating_sub(*c),
            };
            NANOS[*p as usize].fetch_add(ns, Ordering::Relaxed);
            SPANS[*p as usize].fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// Starts timing phase `p` until the returned span is dropped.
#[inline]
pub fn span(p: Phase) -> Span {
    match mode() {
        0 => Span(None),
        1 => Span(Some((p, Start::Wall(Instant::now())))),
        _ => Span(Some((p, Start::Cpu(thread_ns())))),
    }
}

/// Counts `n` parallel loops (rayon forks and joins) started in phase `p`.
#[inline]
pub fn forks(p: Phase, n: u64) {
    if on() {
        FORKS[p as usize].fetch_add(n, Ordering::Relaxed);
    }
}

/// (name, ms (wall or thread CPU, [`cpu`]), spans, parallel loops) of every phase since the last call, and resets them.
pub fn take() -> Vec<(&'static str, f64, u64, u64)> {
    (0..N)
        .map(|i| (NAMES[i], NANOS[i].swap(0, Ordering::Relaxed) as f64 * 1e-6, SPANS[i].swap(0, Ordering::Relaxed), FORKS[i].swap(0, Ordering::Relaxed)))
        .collect()
}

//! The MPI [`Transport`] of tiled runs (cargo feature `mpi`; the `mpi` crate over Open MPI,
//! Debian's `libopenmpi-dev`): each exchange first passes every pair of ranks its message
//! length (`MPI_Alltoall` of one `u64` per rank), then the messages point to point
//! (non-blocking sends, blocking receives of the announced lengths; empty messages are not
//! sent at all). Messages between two ranks never overtake each other (same communicator and
//! tag, MPI's ordering rule), and the collective count exchange separates the rounds. Sums
//! (the stand table's, `Transport::all_sum`) are one `MPI_Allreduce`.

use crate::sim::tiles::Transport;
use crate::Error;
use mpi::traits::*;

/// The world communicator of an MPI job (initialised by [`MpiTransport::from_env`], finalised
/// when dropped).
pub struct MpiTransport {
    world: mpi::topology::SimpleCommunicator,
    rank: usize,
    size: usize,
    sent: u64,
    /// Wall time (s) spent in exchanges and all-reduces so far, waits for the other ranks
    /// included ([`MpiTransport::seconds_in_exchanges`]).
    in_exchanges: f64,
    // dropped last: finalises MPI
    _universe: mpi::environment::Universe,
}

impl MpiTransport {
    /// Initialises MPI when this process was started by an MPI launcher (`mpirun`, `srun`:
    /// one of `OMPI_COMM_WORLD_SIZE`, `PMI_SIZE`, `PMIX_RANK` set); `None` otherwise or when
    /// MPI cannot be initialised (then the run is a single process).
    pub fn from_env() -> Option<MpiTransport> {
        let launched = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"].iter().any(|v| std::env::var_os(v).is_some());
        if !launched {
            return None;
        }
        let universe = mpi::initialize()?;
        let world = universe.world();
        let (rank, size) = (world.rank().max(0) as usize, world.size().max(1) as usize);
        Some(MpiTransport { world, rank, size, sent: 0, in_exchanges: 0.0, _universe: universe })
    }

    /// Wall time (s) this rank has spent in exchanges and all-reduces so far: passing the
    /// messages and waiting for the other ranks to arrive (what the rank's wall time minus it
    /// leaves is its own work; Open MPI polls while it waits, so the CPU time counts the waits
    /// too).
    pub fn seconds_in_exchanges(&self) -> f64 {
        self.in_exchanges
    }
}

impl Transport for MpiTransport {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }
    fn exchange(&mut self, mut out: Vec<Vec<u8>>) -> crate::Result<Vec<Vec<u8>>> {
        let (me, n) = (self.rank, self.size);
        if out.len() != n {
            return Err(Error::Exchange { peer: me, reason: format!("{} messages for {n} ranks", out.len()) });
        }
        if let Some((p, m)) = out.iter().enumerate().find(|(_, m)| m.len() > i32::MAX as usize) {
            return Err(Error::Exchange { peer: p, reason: format!("message of {} bytes, more than MPI's {} per message", m.len(), i32::MAX) });
        }
        let t0 = std::time::Instant::now();
        let lens: Vec<u64> = out.iter().map(|m| m.len() as u64).collect();
        let mut incoming = vec![0u64; n];
        self.world.all_to_all_into(&lens[..], &mut incoming[..]);
        let mut got: Vec<Vec<u8>> = vec![Vec::new(); n];
        got[me] = std::mem::take(&mut out[me]);
        let world = &self.world;
        mpi::request::scope(|scope| {
            let mut pending = Vec::new();
            for (p, m) in out.iter().enumerate() {
                if p != me && !m.is_empty() {
                    pending.push(world.process_at_rank(p as i32).immediate_send(scope, &m[..]));
                }
            }
            for (p, g) in got.iter_mut().enumerate() {
                if p != me && incoming[p] > 0 {
                    let mut buf = vec![0u8; incoming[p] as usize];
                    world.process_at_rank(p as i32).receive_into(&mut buf[..]);
                    *g = buf;
                }
            }
            for r in pending {
                r.wait();
            }
        });
        self.sent += lens.iter().enumerate().filter(|(p, _)| *p != me).map(|(_, l)| *l).sum::<u64>();
        self.in_exchanges += t0.elapsed().as_secs_f64();
        Ok(got)
    }
    fn bytes_sent(&self) -> u64 {
        self.sent
    }
    /// `MPI_Allreduce` with `MPI_SUM` over u64 (wrapping). Counted as the bytes of `v` sent
    /// (what each rank contributes; the traffic of Open MPI's algorithm for it is of that
    /// order: a recursive doubling sends it log₂ ranks times, a ring about twice).
    fn all_sum(&mut self, v: Vec<u64>) -> crate::Result<Vec<u64>> {
        let mut out = vec![0u64; v.len()];
        if self.size > 1 {
            let t0 = std::time::Instant::now();
            self.world.all_reduce_into(&v[..], &mut out[..], mpi::collective::SystemOperation::sum());
            self.sent += 8 * v.len() as u64;
            self.in_exchanges += t0.elapsed().as_secs_f64();
        } else {
            out = v;
        }
        Ok(out)
    }
}

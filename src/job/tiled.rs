//! Tiled runs with outputs (`mpirun -np N sylva simulate …`, `sylva simulate --tiles N`): the
//! landscape cut into one tile per rank ([`crate::sim::tiles`]); every rank steps its tile;
//! rank 0 also runs the run driver ([`run_scenario_with`]) and writes the whole run directory
//! from the world it gathers, so the directory is the one a single process writes, byte for
//! byte (stand table every year from the gathered stand-table columns; inventories, maps and
//! the checkpoint in the years that write them, from every rank's whole stand).
//!
//! Checkpoints and `--resume`: rank 0 writes the one `checkpoint.bin` of a single process
//! (the gathered world); a resumed run, on any number of ranks, reads it on rank 0 and sends
//! every rank its part, so a run stopped on 3 ranks can go on with 2, or with one process.
//!
//! Protocol: before every collective step rank 0 sends every rank a command ([`Command`]); the
//! other ranks ([`work`]) wait for it, so all ranks take part in the same exchanges in the same
//! order.

use super::run::{run_scenario_with, RunOptions, RunSummary, Stepper};
use super::Result;
use crate::conditions::SiteConditions;
use crate::sim::scenario::Scenario;
use crate::sim::step::YearReport;
use crate::sim::tiles::{Layout, LocalTransport, Tile, Transport};
use crate::sim::world::{Tallies, World};
use crate::species::{Season, SpeciesLibrary};
use crate::Error;

/// What rank 0 tells the other ranks to do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Command {
    /// Take your part of rank 0's world ([`Tile::scatter`]).
    Begin = 1,
    /// Step a year, sending rank 0 the stand table's columns.
    Step = 2,
    /// Step a year, then send rank 0 the whole stand ([`Tile::gather`]).
    StepFull = 3,
    /// Send rank 0 the whole stand.
    Complete = 4,
    /// The run is over.
    End = 5,
}

impl Command {
    fn from_byte(b: u8) -> Option<Command> {
        [Command::Begin, Command::Step, Command::StepFull, Command::Complete, Command::End].into_iter().find(|c| *c as u8 == b)
    }
}

/// Rank 0 sends `c` to every rank; the others pass `None` and get it.
///
/// Errors: [`Error::Exchange`] from the transport or an unknown command byte.
fn command(t: &mut dyn Transport, c: Option<Command>) -> Result<Command> {
    let n = t.size();
    let out = match c {
        Some(c) => vec![vec![c as u8]; n],
        None => vec![Vec::new(); n],
    };
    let got = t.exchange(out)?;
    let b = got.first().and_then(|m| m.first()).copied().unwrap_or(0);
    Ok(Command::from_byte(b).ok_or(Error::Exchange { peer: 0, reason: format!("unknown command byte {b} (expected 1–5)") })?)
}

/// Tiles across and up for `n` ranks on a light grid of `cols × rows` cells: the factor pair
/// `nx · ny = n` whose tiles are closest to square (`|ln(cols / nx) − ln(rows / ny)|` least),
/// more tiles across on a tie.
pub fn grid_for(n: usize, cols: usize, rows: usize) -> (usize, usize) {
    let n = n.max(1);
    (1..=n)
        .filter(|nx| n % nx == 0)
        .map(|nx| (nx, n / nx))
        .min_by(|a, b| {
            let f = |(nx, ny): (usize, usize)| ((cols as f64 / nx as f64).ln() - (rows as f64 / ny as f64).ln()).abs();
            f(*a).total_cmp(&f(*b)).then(b.0.cmp(&a.0))
        })
        .unwrap_or((n, 1))
}

/// Refuses what a tiled run does not do: seasonal snapshots (they would need every rank's
/// stand in the middle of a year).
///
/// Errors: [`Error::Invalid`] naming the scenario and the field.
fn check(scenario: &Scenario) -> Result<()> {
    if scenario.seasonal_snapshots {
        return Err(Error::Invalid { context: scenario.name.clone(), field: "seasonal_snapshots".into(), value: "true".into(), expected: "false in a tiled run (MPI ranks or --tiles): run seasonal snapshots in one process".into() }.into());
    }
    Ok(())
}

/// The layout of a run of `n` ranks on `world`'s site ([`grid_for`], [`Layout::new`]).
///
/// Errors: [`Error::Invalid`] when the light grid has fewer columns or rows than the tiles.
pub fn layout_for(world: &World, n: usize) -> Result<Layout> {
    let (nx, ny) = grid_for(n, world.site.light.cols, world.site.light.rows);
    Ok(Layout::new(&world.site, nx, ny)?)
}

/// Rank 0's [`Stepper`]: its own tile, the transport, the tallies at the start.
pub struct Root<'t> {
    t: &'t mut dyn Transport,
    tile: Option<Tile>,
    base: Tallies,
    /// The other ranks were told to end (or failed with rank 0 in a collective step).
    done: bool,
}

impl<'t> Root<'t> {
    /// Rank 0 of the transport `t`.
    pub fn new(t: &'t mut dyn Transport) -> Self {
        Root { t, tile: None, base: Tallies::default(), done: false }
    }

    /// Bytes rank 0 has sent to other ranks (halo copies, its part of the gathers, commands).
    pub fn bytes_sent(&self) -> u64 {
        self.t.bytes_sent()
    }

    /// Tells the other ranks the run is over.
    ///
    /// Errors: [`Error::Exchange`] from the transport.
    pub fn end(&mut self) -> Result<()> {
        if !self.done {
            self.done = true;
            command(self.t, Some(Command::End))?;
        }
        Ok(())
    }

    /// Runs `f` on the tile and the transport; an error there is every rank's (the collective
    /// steps fail together), so the others are not told to end afterwards.
    fn collective<T>(&mut self, f: impl FnOnce(&mut Tile, &mut dyn Transport) -> Result<T>) -> Result<T> {
        let Some(tile) = self.tile.as_mut() else {
            return Err(Error::Exchange { peer: 0, reason: "a year stepped before the run began".into() }.into());
        };
        let r = f(tile, self.t);
        if r.is_err() {
            self.done = true;
        }
        r
    }
}

impl Drop for Root<'_> {
    fn drop(&mut self) {
        // rank 0 failed outside a collective step (an output it could not write): release the
        // others, which wait for a command
        let _ = self.end();
    }
}

impl Stepper for Root<'_> {
    fn begin(&mut self, world: &World) -> Result<()> {
        let layout = layout_for(world, self.t.size())?;
        command(self.t, Some(Command::Begin))?;
        self.base = world.tallies.clone();
        self.tile = Some(Tile::new(world, layout, 0));
        self.collective(|tile, t| Ok(tile.scatter(Some(world), t)?))
    }
    fn step(&mut self, world: &mut World, _: &Scenario, report: &mut YearReport, full: bool, _: &mut dyn FnMut(Season, &World)) -> Result<()> {
        command(self.t, Some(if full { Command::StepFull } else { Command::Step }))?;
        let base = self.base.clone();
        *report = self.collective(|tile, t| {
            let r = tile.step(t)?;
            if full {
                tile.gather(Some((world, &base)), t)?;
            }
            Ok(r)
        })?;
        world.stand.year = report.row.as_ref().map_or(world.stand.year + 1, |r| r.year);
        Ok(())
    }
    fn complete(&mut self, world: &mut World) -> Result<()> {
        command(self.t, Some(Command::Complete))?;
        let base = self.base.clone();
        self.collective(|tile, t| Ok(tile.gather(Some((world, &base)), t)?))
    }
}

/// A rank other than 0: builds the world of `scenario` (for the site), then follows rank 0's
/// commands until [`Command::End`]. Writes no files.
///
/// Errors: unknown species or points outside the site (as [`World::new`]); the tiles' errors
/// (a halo too narrow, a failed exchange); a command out of order.
pub fn work(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, t: &mut dyn Transport) -> Result<()> {
    check(scenario)?;
    let world = World::new(site, lib, scenario)?;
    let layout = layout_for(&world, t.size())?;
    let me = t.rank();
    let mut tile: Option<Tile> = None;
    loop {
        let c = command(t, None)?;
        match (c, tile.as_mut()) {
            (Command::End, _) => return Ok(()),
            (Command::Begin, _) => {
                let mut tl = Tile::new(&world, layout.clone(), me);
                tl.scatter(None, t)?;
                tile = Some(tl);
            }
            (Command::Step, Some(tl)) => {
                tl.step(t)?;
            }
            (Command::StepFull, Some(tl)) => {
                tl.step(t)?;
                tl.gather(None, t)?;
            }
            (Command::Complete, Some(tl)) => tl.gather(None, t)?,
            (c, None) => return Err(Error::Exchange { peer: 0, reason: format!("command {c:?} before the run began") }.into()),
        }
    }
}

/// Runs `scenario` as a tiled run over the transport `t`, one tile per rank: rank 0 writes the
/// run directory of `opts` and returns its summary; the other ranks return `None`.
///
/// Errors: as [`run_scenario_with`] on rank 0 and [`work`] on the others; a scenario with
/// seasonal snapshots.
pub fn run_tiled(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, opts: RunOptions, t: &mut dyn Transport) -> Result<Option<RunSummary>> {
    check(scenario)?;
    if t.rank() != 0 {
        work(scenario, site, lib, t)?;
        return Ok(None);
    }
    let mut root = Root::new(t);
    let s = run_scenario_with(scenario, site, lib, opts, &mut root)?;
    root.end()?;
    Ok(Some(s))
}

/// Runs `scenario` as `n` tiles in this process, one thread per tile over a
/// [`LocalTransport`] (the same exchanges as over MPI); writes the run directory of `opts`.
/// Returns the summary and the bytes each rank sent to the others.
///
/// Errors: as [`run_tiled`]; the light grid too small for `n` tiles.
pub fn run_local_tiles(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, opts: RunOptions, n: usize) -> Result<(RunSummary, Vec<u64>)> {
    check(scenario)?;
    // the layout is checked before any thread waits for another
    layout_for(&World::new(site.clone(), lib, scenario)?, n)?;
    let mut ends = LocalTransport::group(n.max(1)).into_iter();
    let Some(mut t0) = ends.next() else {
        return Err(Error::Exchange { peer: 0, reason: "no ranks".into() }.into());
    };
    std::thread::scope(|s| {
        let workers: Vec<_> = ends
            .map(|mut t| {
                let site = site.clone();
                s.spawn(move || work(scenario, site, lib, &mut t).map(|_| t.bytes_sent()))
            })
            .collect();
        let root = (|| {
            let mut root = Root::new(&mut t0);
            let s = run_scenario_with(scenario, site, lib, opts, &mut root)?;
            root.end()?;
            Ok::<_, super::JobError>((s, root.bytes_sent()))
        })();
        let mut bytes = vec![0u64];
        let mut first_err = None;
        for w in workers {
            match w.join() {
                Ok(Ok(b)) => bytes.push(b),
                Ok(Err(e)) => {
                    first_err.get_or_insert(e);
                }
                Err(_) => {
                    first_err.get_or_insert(Error::Exchange { peer: 1, reason: "a tile's thread panicked".into() }.into());
                }
            }
        }
        let (s, b0) = root?;
        if let Some(e) = first_err {
            return Err(e);
        }
        bytes[0] = b0;
        Ok((s, bytes))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_grids_are_close_to_square() {
        assert_eq!(grid_for(1, 100, 50), (1, 1));
        assert_eq!(grid_for(2, 100, 50), (2, 1));
        assert_eq!(grid_for(3, 100, 50), (3, 1));
        assert_eq!(grid_for(4, 100, 100), (2, 2));
        assert_eq!(grid_for(8, 100, 50), (4, 2));
        assert_eq!(grid_for(6, 40, 120), (2, 3), "a tie (1 × 6, 2 × 3) goes to more tiles across");
        for c in [Command::Begin, Command::Step, Command::StepFull, Command::Complete, Command::End] {
            assert_eq!(Command::from_byte(c as u8), Some(c));
        }
        assert_eq!(Command::from_byte(0), None);
    }
}

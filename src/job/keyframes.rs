//! The main job's key frames (the render instances of every snapshot, taken from the
//! in-memory world) kept on disk instead of in memory: [`KeyFrames::push`] appends a
//! snapshot's instances to an unlinked temporary file in the run directory, [`KeyFrames::get`]
//! reads one back. Holding the 31 snapshots of the default run in memory took about 1.2 GB
//! (issue 34); now one or two are in memory at a time.
//!
//! Records are lossless: every field of [`TreeInstance`] comes back bit for bit. The fields
//! that repeat across trees (species, leaf amount, opacity, sky fade) are kept once in a
//! per-snapshot palette, so a record is 50 bytes instead of 64. The leaf colour is the
//! record's own: round 46 gave every tree its own tint ([`crate::job::scene::tree_tint`]), and
//! with the colour in the palette the default run's year-50 snapshot (about 100,000 trees)
//! overflowed its 65,535 entries, so `sylva run` ended after its simulation without a picture
//! (found in round 47).

use crate::render::scene::TreeInstance;
use crate::Error;
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Bytes of one record: id (8), position (12), height, crown radius, crown base, rotation
/// (16), leaf colour (12), palette index (2).
pub const RECORD: usize = 50;

/// The fields of a [`TreeInstance`] that repeat across trees, as bit patterns: species,
/// leaf amount, opacity, sky fade.
type Shared = [u32; 4];

/// Where one snapshot's records lie in the file and the palette they index (kept in the
/// pictures' state file of a linked store, [`KeyFrames::index`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Entry {
    year: u32,
    offset: u64,
    count: usize,
    palette: Vec<Shared>,
}

/// Key frames on disk: an unlinked temporary file (removed again by [`Drop`] where the
/// platform keeps it linked while open), or a linked one that outlives the process
/// ([`KeyFrames::linked`], for finishing a stopped run's pictures), and an index of the
/// snapshots in it.
pub struct KeyFrames {
    path: PathBuf,
    file: File,
    len: u64,
    entries: Vec<Entry>,
    /// Remove the file on drop (an unlinked store, or a linked one given up).
    remove_on_drop: bool,
}

/// Name of a linked key-frame store in its run directory ([`KeyFrames::linked`]).
pub const LINKED_FILE: &str = ".sylva_keyframes.bin";

impl KeyFrames {
    /// A new, empty store in the folder `dir` (which must exist): the file is created there and
    /// unlinked at once where the platform allows it, so that nothing is left behind even when
    /// the process is killed.
    ///
    /// Errors: [`Error::Io`] naming the file.
    pub fn new(dir: &Path) -> crate::Result<Self> {
        let path = dir.join(format!(".sylva_keyframes_{}.tmp", std::process::id()));
        let file = std::fs::OpenOptions::new().read(true).write(true).create(true).truncate(true).open(&path).map_err(|e| Error::io(&path, e))?;
        // unlinked while open (Unix); elsewhere it is removed on drop
        let _ = std::fs::remove_file(&path);
        Ok(KeyFrames { path, file, len: 0, entries: Vec::new(), remove_on_drop: true })
    }

    /// A new, empty store in `dir/`[`LINKED_FILE`] that stays on disk when the process ends
    /// (trial 46 D10: a `sylva run` killed while drawing its pictures finishes them on the
    /// next `sylva run` from this file and [`KeyFrames::index`]), and, once
    /// [`KeyFrames::keep`] is called, when the store is dropped; an earlier file of that name
    /// is truncated.
    ///
    /// Errors: [`Error::Io`] naming the file.
    pub fn linked(dir: &Path) -> crate::Result<Self> {
        let path = dir.join(LINKED_FILE);
        let file = std::fs::OpenOptions::new().read(true).write(true).create(true).truncate(true).open(&path).map_err(|e| Error::io(&path, e))?;
        Ok(KeyFrames { path, file, len: 0, entries: Vec::new(), remove_on_drop: true })
    }

    /// Reopens the linked store `dir/`[`LINKED_FILE`] with the index `entries` that
    /// [`KeyFrames::index`] gave when it was written.
    ///
    /// Errors: [`Error::Io`] naming the file; [`Error::Format`] naming it when its length is
    /// not the `entries`' records (a store cut short).
    pub fn reopen(dir: &Path, entries: Vec<Entry>) -> crate::Result<Self> {
        let path = dir.join(LINKED_FILE);
        // read only: a reopened store is read, never pushed to
        let file = File::open(&path).map_err(|e| Error::io(&path, e))?;
        let len: u64 = entries.iter().map(|e| (e.count * RECORD) as u64).sum();
        let on_disk = file.metadata().map_err(|e| Error::io(&path, e))?.len();
        let contiguous = entries.iter().scan(0u64, |at, e| {
            let ok = e.offset == *at;
            *at += (e.count * RECORD) as u64;
            Some(ok)
        });
        if on_disk != len || !contiguous.into_iter().all(|ok| ok) {
            return Err(Error::format(&path, format!("{on_disk} bytes; expected {len} (the key frames of {} snapshots, {RECORD} bytes a tree)", entries.len())));
        }
        Ok(KeyFrames { path, file, len, entries, remove_on_drop: false })
    }

    /// The index of the snapshots stored (to [`KeyFrames::reopen`] a linked store).
    pub fn index(&self) -> &[Entry] {
        &self.entries
    }

    /// Keeps a [`KeyFrames::linked`] store's file on disk when the store is dropped (from the
    /// moment the pictures' state that indexes it is written); until then a dropped store
    /// removes its file.
    pub fn keep(&mut self) {
        self.remove_on_drop = false;
    }

    /// Appends the instances `inst` of the snapshot of `year`.
    ///
    /// Errors: [`Error::Io`] naming the file.
    pub fn push(&mut self, year: u32, inst: &[TreeInstance]) -> crate::Result<()> {
        let mut palette: Vec<Shared> = Vec::new();
        let mut index: HashMap<Shared, u16> = HashMap::new();
        let io = |e| Error::io(&self.path, e);
        self.file.seek(SeekFrom::Start(self.len)).map_err(io)?;
        let mut w = BufWriter::with_capacity(1 << 20, &self.file);
        for t in inst {
            let shared: Shared = [t.species, t.leaf_amount.to_bits(), t.opacity.to_bits(), t.sky_fade.to_bits()];
            let k = match index.get(&shared) {
                Some(&k) => k,
                None => {
                    let k = u16::try_from(palette.len()).map_err(|_| Error::Invalid { context: "key frames".into(), field: "palette".into(), value: format!("more than {} distinct foliages in year {year}", u16::MAX), expected: "at most 65,535".into() })?;
                    palette.push(shared);
                    index.insert(shared, k);
                    k
                }
            };
            let mut rec = [0u8; RECORD];
            rec[0..8].copy_from_slice(&t.id.to_le_bytes());
            for (j, v) in [t.position[0], t.position[1], t.position[2], t.height, t.crown_radius, t.crown_base, t.rotation, t.leaf_color[0], t.leaf_color[1], t.leaf_color[2]].into_iter().enumerate() {
                rec[8 + 4 * j..12 + 4 * j].copy_from_slice(&v.to_bits().to_le_bytes());
            }
            rec[48..50].copy_from_slice(&k.to_le_bytes());
            w.write_all(&rec).map_err(io)?;
        }
        w.flush().map_err(io)?;
        drop(w);
        self.entries.push(Entry { year, offset: self.len, count: inst.len(), palette });
        self.len += (inst.len() * RECORD) as u64;
        Ok(())
    }

    /// Years stored, in the order pushed.
    pub fn years(&self) -> Vec<u32> {
        self.entries.iter().map(|e| e.year).collect()
    }

    /// The instances of the `k`-th snapshot pushed (empty when there is none), exactly as
    /// pushed.
    ///
    /// Errors: [`Error::Io`] naming the file.
    pub fn get(&mut self, k: usize) -> crate::Result<Vec<TreeInstance>> {
        let Some(e) = self.entries.get(k) else { return Ok(Vec::new()) };
        let io = |err| Error::io(&self.path, err);
        self.file.seek(SeekFrom::Start(e.offset)).map_err(io)?;
        let mut r = BufReader::with_capacity(1 << 20, &self.file);
        let mut out = Vec::with_capacity(e.count);
        let mut rec = [0u8; RECORD];
        for _ in 0..e.count {
            r.read_exact(&mut rec).map_err(io)?;
            let f = |j: usize| f32::from_bits(u32::from_le_bytes([rec[8 + 4 * j], rec[9 + 4 * j], rec[10 + 4 * j], rec[11 + 4 * j]]));
            let id = u64::from_le_bytes([rec[0], rec[1], rec[2], rec[3], rec[4], rec[5], rec[6], rec[7]]);
            let s = e.palette[u16::from_le_bytes([rec[48], rec[49]]) as usize];
            let b = f32::from_bits;
            let mut t = TreeInstance::new(id, [f(0), f(1), f(2)], f(3), f(4), s[0], [f(7), f(8), f(9)]);
            t.crown_base = f(5);
            t.rotation = f(6);
            t.leaf_amount = b(s[1]);
            t.opacity = b(s[2]);
            t.sky_fade = b(s[3]);
            out.push(t);
        }
        Ok(out)
    }

    /// The instances of the snapshot of `year` (empty when there is none).
    ///
    /// Errors: as [`KeyFrames::get`].
    pub fn get_year(&mut self, year: u32) -> crate::Result<Vec<TreeInstance>> {
        match self.entries.iter().position(|e| e.year == year) {
            Some(k) => self.get(k),
            None => Ok(Vec::new()),
        }
    }
}

impl Drop for KeyFrames {
    fn drop(&mut self) {
        // an unlinked store: already unlinked on Unix; elsewhere the handle is closed first by
        // the field's drop order, so the removal is tried after it in a best-effort way
        if self.remove_on_drop {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instances_come_back_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("sylva_keyframes_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut a = TreeInstance::new(7, [1.5, -2.25, 800.125], 21.5, 3.25, 2, [0.1, 0.3, 0.05]);
        a.crown_base = 0.4;
        let mut b = TreeInstance { rotation: 1.0, opacity: 0.5, sky_fade: 0.25, leaf_amount: 0.0, ..a };
        b.id = (1 << 63) | 12345;
        let c = TreeInstance::new(u64::MAX >> 2, [f32::MAX, 0.0, -0.0], 1.0, 0.2, 0, [0.0; 3]);
        let mut k = KeyFrames::new(&dir).unwrap();
        k.push(0, &[a, b, c]).unwrap();
        k.push(10, &[]).unwrap();
        k.push(20, &[c, a]).unwrap();
        // nothing is left in the folder (Unix: unlinked at once)
        #[cfg(unix)]
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        let bits = |v: &[TreeInstance]| format!("{v:?}");
        assert_eq!(bits(&k.get(0).unwrap()), bits(&[a, b, c]));
        assert!(k.get(1).unwrap().is_empty());
        assert_eq!(bits(&k.get_year(20).unwrap()), bits(&[c, a]));
        assert_eq!(k.get(0).unwrap(), vec![a, b, c]);
        assert_eq!(k.years(), vec![0, 10, 20]);
        assert!(k.get_year(5).unwrap().is_empty());
        drop(k);
        // a linked store outlives its handle and reopens with its index, bit for bit; a store
        // cut short is refused naming the file
        let mut k = KeyFrames::linked(&dir).unwrap();
        k.push(0, &[a, b]).unwrap();
        k.push(5, &[c]).unwrap();
        let index = k.index().to_vec();
        k.keep();
        drop(k);
        let p = dir.join(LINKED_FILE);
        assert_eq!(std::fs::metadata(&p).unwrap().len(), 3 * RECORD as u64);
        let mut k = KeyFrames::reopen(&dir, index.clone()).unwrap();
        assert_eq!(k.years(), vec![0, 5]);
        assert_eq!(bits(&k.get_year(5).unwrap()), bits(&[c]));
        assert_eq!(bits(&k.get(0).unwrap()), bits(&[a, b]));
        drop(k);
        std::fs::OpenOptions::new().write(true).open(&p).unwrap().set_len(2 * RECORD as u64).unwrap();
        let e = KeyFrames::reopen(&dir, index.clone()).err().unwrap().to_string();
        assert!(e.contains(LINKED_FILE) && e.contains("100 bytes; expected 150"), "{e}");
        // a linked store not kept removes its file when dropped (a stopped simulation)
        let mut k = KeyFrames::linked(&dir).unwrap();
        k.push(0, &[a]).unwrap();
        drop(k);
        assert!(!p.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

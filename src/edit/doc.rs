//! The species file being edited, without a window: a `toml_edit` document (so comments, key
//! order and formatting survive every edit and the save), typed getters and setters by dotted
//! field path (`life.growth.k`, `architecture.ecomod.ks_g`, `niche.l.value`), undo/redo, the
//! validation of `sylva species check` ([`crate::species::parse_text`]) and saving (atomic; "save
//! as new species" as `sylva species new` does).

use std::path::{Path, PathBuf};

use toml_edit::{DocumentMut, Item, Value};

use crate::species::schema::{self, Kind};
use crate::species::{self, Problem, Species};
use super::{EditError, Result};
use crate::Error;

/// Most undo steps kept.
pub const UNDO_DEPTH: usize = 200;

/// One species file in the editor.
#[derive(Debug, Clone)]
pub struct SpeciesDoc {
    /// Where [`SpeciesDoc::save`] writes.
    pub path: PathBuf,
    doc: DocumentMut,
    undo: Vec<(String, String)>,
    redo: Vec<(String, String)>,
    /// Field of the last edit, for merging a drag into one undo step.
    last_field: Option<String>,
    saved: String,
}

/// Rounds `v` to 5 significant digits (what a slider or a dragged point is read to; keeps the
/// file free of float noise such as 0.30000001).
pub fn tidy(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let k = 4 - v.abs().log10().floor() as i32;
    let p = 10f64.powi(k.clamp(-10, 15));
    (v * p).round() / p
}

impl SpeciesDoc {
    /// A document of `text`, saved to `path`.
    ///
    /// # Errors
    /// [`Error::Format`] naming `path` and the TOML syntax error.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| Error::format(path, format!("TOML syntax error: {}", e.message().trim())))?;
        Ok(SpeciesDoc { path: path.to_path_buf(), doc, undo: Vec::new(), redo: Vec::new(), last_field: None, saved: text.to_string() })
    }

    /// Reads the species file `path`.
    ///
    /// # Errors
    /// [`Error::Io`] when it cannot be read; as [`SpeciesDoc::parse`].
    pub fn open(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(&text, path)
    }

    /// The current text of the file.
    pub fn text(&self) -> String {
        self.doc.to_string()
    }

    /// Whether the text differs from the last one saved or opened.
    pub fn is_dirty(&self) -> bool {
        self.text() != self.saved
    }

    fn item(&self, path: &str) -> Option<&Item> {
        let mut it = self.doc.as_item();
        for k in path.split('.') {
            it = it.get(k)?;
        }
        Some(it)
    }

    fn item_mut(&mut self, path: &str) -> Option<&mut Item> {
        let mut it = self.doc.as_item_mut();
        for k in path.split('.') {
            it = it.get_mut(k)?;
        }
        Some(it)
    }

    /// The number at `path` (integers included).
    pub fn number(&self, path: &str) -> Option<f64> {
        let v = self.item(path)?.as_value()?;
        v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
    }

    /// The string at `path`.
    pub fn string(&self, path: &str) -> Option<String> {
        self.item(path)?.as_value()?.as_str().map(str::to_string)
    }

    /// The boolean at `path`.
    pub fn boolean(&self, path: &str) -> Option<bool> {
        self.item(path)?.as_value()?.as_bool()
    }

    /// The poly-line `[[x, y], ...]` at `path`.
    pub fn polyline(&self, path: &str) -> Option<Vec<[f64; 2]>> {
        let a = self.item(path)?.as_value()?.as_array()?;
        let num = |v: &Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        a.iter().map(|p| {
            let p = p.as_array()?;
            Some([num(p.get(0)?)?, num(p.get(1)?)?])
        }).collect()
    }

    /// The colour `[r, g, b]` at `path`.
    pub fn colour(&self, path: &str) -> Option<[u8; 3]> {
        let a = self.item(path)?.as_value()?.as_array()?;
        let c: Option<Vec<u8>> = a.iter().map(|v| v.as_integer().and_then(|i| u8::try_from(i).ok())).collect();
        let c = c?;
        (c.len() == 3).then(|| [c[0], c[1], c[2]])
    }

    /// Replaces the value at `path`, keeping its comments and spacing. With `merge`, an edit of
    /// the same field as the last edit joins its undo step (a drag is one step).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the field when the file has no such field.
    pub fn set_value(&mut self, path: &str, mut new: Value, merge: bool) -> Result<()> {
        let before = self.text();
        let Some(item) = self.item_mut(path) else {
            return Err(EditError::Input(Error::Invalid { context: "species editor".into(), field: path.into(), value: String::new(), expected: "a field present in the file".into() }));
        };
        if let Some(old) = item.as_value() {
            *new.decor_mut() = old.decor().clone();
        }
        *item = Item::Value(new);
        if self.text() == before {
            return Ok(());
        }
        let same = merge && self.last_field.as_deref() == Some(path) && !self.undo.is_empty();
        if !same {
            self.undo.push((before, path.to_string()));
            if self.undo.len() > UNDO_DEPTH {
                self.undo.remove(0);
            }
        }
        self.redo.clear();
        self.last_field = Some(path.to_string());
        Ok(())
    }

    /// Sets a number, written as an integer for integer fields of the schema and rounded with
    /// [`tidy`] otherwise.
    ///
    /// # Errors
    /// As [`SpeciesDoc::set_value`].
    pub fn set_number(&mut self, path: &str, v: f64, merge: bool) -> Result<()> {
        let int = matches!(schema::field(path).map(|f| f.kind), Some(Kind::Int { .. }));
        let value = if int { Value::from(v.round() as i64) } else { Value::from(tidy(v)) };
        self.set_value(path, value, merge)
    }

    /// Sets a string.
    ///
    /// # Errors
    /// As [`SpeciesDoc::set_value`].
    pub fn set_string(&mut self, path: &str, s: &str, merge: bool) -> Result<()> {
        self.set_value(path, Value::from(s), merge)
    }

    /// Sets a boolean.
    ///
    /// # Errors
    /// As [`SpeciesDoc::set_value`].
    pub fn set_bool(&mut self, path: &str, b: bool) -> Result<()> {
        self.set_value(path, Value::from(b), false)
    }

    /// Sets a poly-line (points rounded with [`tidy`]), written inline as `[[x, y], ...]`.
    ///
    /// # Errors
    /// As [`SpeciesDoc::set_value`].
    pub fn set_polyline(&mut self, path: &str, pts: &[[f64; 2]], merge: bool) -> Result<()> {
        let mut a = toml_edit::Array::new();
        for p in pts {
            let mut q = toml_edit::Array::new();
            q.push(tidy(p[0]));
            q.push(tidy(p[1]));
            a.push(q);
        }
        a.fmt();
        self.set_value(path, Value::Array(a), merge)
    }

    /// Sets a colour `[r, g, b]`.
    ///
    /// # Errors
    /// As [`SpeciesDoc::set_value`].
    pub fn set_colour(&mut self, path: &str, c: [u8; 3], merge: bool) -> Result<()> {
        let mut a = toml_edit::Array::new();
        for v in c {
            a.push(v as i64);
        }
        a.fmt();
        self.set_value(path, Value::Array(a), merge)
    }

    /// Whether there is an edit to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is an undone edit to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Field of the edit that [`SpeciesDoc::undo`] would revert.
    pub fn undo_field(&self) -> Option<&str> {
        self.undo.last().map(|u| u.1.as_str())
    }

    fn restore(&mut self, text: &str) {
        if let Ok(d) = text.parse::<DocumentMut>() {
            self.doc = d;
        }
    }

    /// Reverts the last edit; false when there is none.
    pub fn undo(&mut self) -> bool {
        let Some((text, field)) = self.undo.pop() else { return false };
        self.redo.push((self.text(), field));
        self.restore(&text);
        self.last_field = None;
        true
    }

    /// Applies the last undone edit again; false when there is none.
    pub fn redo(&mut self) -> bool {
        let Some((text, field)) = self.redo.pop() else { return false };
        self.undo.push((self.text(), field));
        self.restore(&text);
        self.last_field = None;
        true
    }

    /// The species and every problem `sylva species check` would report for the current text.
    pub fn check(&self) -> (Option<Species>, Vec<Problem>) {
        species::parse_text(&self.text(), &self.path)
    }

    /// Writes the text to [`SpeciesDoc::path`] (atomically; the folder is created).
    ///
    /// # Errors
    /// [`Error::Io`] naming the file or folder.
    pub fn save(&mut self) -> Result<()> {
        let text = self.text();
        write(&self.path, &text)?;
        self.saved = text;
        Ok(())
    }

    /// "Save as new species": writes the current text with its `id` replaced by `new_id` into
    /// `dir/new_id.toml` (as `sylva species new` does, comments kept) and makes that file the
    /// one edited (undo history kept). Returns its path.
    ///
    /// # Errors
    /// [`Error::Invalid`] when `new_id` is not a species id (lower-case letters, digits, `_`,
    /// starting with a letter) or the file exists; [`Error::Io`] when it cannot be written.
    pub fn save_as_new(&mut self, new_id: &str, dir: &Path) -> Result<PathBuf> {
        if !crate::species::is_species_id(new_id) {
            return Err(Error::Invalid { context: "save as new species".into(), field: "id".into(), value: new_id.into(), expected: "lower-case letters, digits and `_`, starting with a letter".into() }.into());
        }
        let target = dir.join(format!("{new_id}.toml"));
        if target.exists() {
            return Err(Error::Invalid { context: "save as new species".into(), field: "file".into(), value: target.display().to_string(), expected: "a file that does not exist yet (not overwriting it)".into() }.into());
        }
        let from = self.string("id").unwrap_or_default();
        let text = species::replace_id(&self.text(), new_id, &target)?;
        let text = text.replacen("Sylva species file.", &format!("Sylva species file (copied from `{from}`)."), 1);
        write(&target, &text)?;
        let undo = std::mem::take(&mut self.undo);
        *self = SpeciesDoc::parse(&text, &target)?;
        self.undo = undo;
        Ok(target)
    }
}

fn write(path: &Path, text: &str) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| crate::output::OutputError::io(dir, e))?;
    }
    crate::output::write_atomic(path, text.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn beech() -> SpeciesDoc {
        SpeciesDoc::parse(species::embedded_text("beech").unwrap(), Path::new("beech.toml")).unwrap()
    }

    #[test]
    fn tidy_keeps_five_significant_digits() {
        assert_eq!(tidy(0.30000001), 0.3);
        assert_eq!(tidy(123.456789), 123.46);
        assert_eq!(tidy(0.000123456), 0.00012346);
        assert_eq!(tidy(0.0), 0.0);
    }

    #[test]
    fn edits_keep_comments_order_and_inline_tables() {
        let mut d = beech();
        let before = d.text();
        d.set_number("life.max_height_m", 45.5, false).unwrap();
        d.set_number("life.growth.k", 0.0131, false).unwrap();
        d.set_number("architecture.ecomod.strands", 1200.4, false).unwrap();
        d.set_number("niche.t.tolerance", 2.5, false).unwrap();
        let t = d.text();
        assert!(t.contains("max_height_m = 45.5  # iLand (LandClim: 45)"), "trailing comment kept");
        assert!(t.contains("growth = { k = 0.0131, p = 1.652, h_max_m = 41.75 }"), "inline table edited in place");
        assert!(t.contains("strands = 1200\n"), "integer field stays an integer");
        assert!(t.contains("t = { value = 5, tolerance = 2.5 }"));
        // every comment line is still there, in order
        let comments = |s: &str| s.lines().filter(|l| l.trim_start().starts_with('#')).map(str::to_string).collect::<Vec<_>>();
        assert_eq!(comments(&before), comments(&t));
        // only the four edited lines differ
        let changed = before.lines().zip(t.lines()).filter(|(a, b)| a != b).count();
        assert_eq!(changed, 4);
        assert_eq!(before.lines().count(), t.lines().count());
    }

    #[test]
    fn undo_and_redo_walk_the_history_and_a_drag_is_one_step() {
        let mut d = beech();
        let orig = d.text();
        d.set_polyline("architecture.ecomod.ks_g", &[[0.0, 0.7], [15.0, 0.9]], true).unwrap();
        d.set_polyline("architecture.ecomod.ks_g", &[[0.0, 0.65], [15.0, 0.9]], true).unwrap();
        d.set_polyline("architecture.ecomod.ks_g", &[[0.0, 0.6], [15.0, 0.9]], true).unwrap();
        let dragged = d.text();
        d.set_number("architecture.ecomod.k_c", 0.5, false).unwrap();
        assert_eq!(d.polyline("architecture.ecomod.ks_g").unwrap(), vec![[0.0, 0.6], [15.0, 0.9]]);
        assert!(d.undo());
        assert_eq!(d.text(), dragged);
        assert_eq!(d.number("architecture.ecomod.k_c"), Some(0.3));
        assert!(d.undo(), "the three drag moves are one step");
        assert_eq!(d.text(), orig);
        assert!(!d.undo());
        assert!(d.redo() && d.redo());
        assert_eq!(d.number("architecture.ecomod.k_c"), Some(0.5));
        assert!(!d.redo());
        // a new edit clears the redo list
        d.undo();
        d.set_number("architecture.ecomod.k_d", 0.02, false).unwrap();
        assert!(!d.can_redo());
    }

    #[test]
    fn validation_is_the_species_check_one() {
        let mut d = beech();
        assert!(d.check().1.is_empty(), "{:?}", d.check().1);
        d.set_number("architecture.ecomod.k_c", 1.5, false).unwrap();
        d.set_polyline("architecture.ecomod.ks_g", &[[0.0, 0.75], [20.0, 0.9]], false).unwrap();
        let (_, problems) = d.check();
        let fields: Vec<&str> = problems.iter().map(|p| p.field.as_str()).collect();
        assert!(fields.contains(&"architecture.ecomod.k_c"), "{problems:?}");
        assert!(fields.contains(&"architecture.ecomod.ks_g"), "{problems:?}");
        let msg = problems.iter().find(|p| p.field == "architecture.ecomod.k_c").unwrap().to_string();
        assert!(msg.contains("beech.toml") && msg.contains("1.5"), "{msg}");
    }

    #[test]
    fn save_round_trip_and_save_as_new() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("beech.toml");
        std::fs::write(&p, species::embedded_text("beech").unwrap()).unwrap();
        let mut d = SpeciesDoc::open(&p).unwrap();
        d.set_polyline("architecture.ecomod.min_len_g", &[[0.0, 1.0], [5.0, 0.3], [15.0, 1.0]], false).unwrap();
        assert!(d.is_dirty());
        d.save().unwrap();
        assert!(!d.is_dirty());
        let back = std::fs::read_to_string(&p).unwrap();
        assert!(back.contains("min_len_g = [[0.0, 1.0], [5.0, 0.3], [15.0, 1.0]]"), "{back}");
        assert!(back.contains("# EcoMod: the paper's published beech model"));
        let sp = Species::from_toml_str(&back, "beech.toml").unwrap();
        assert_eq!(sp.architecture.ecomod.min_len_g, vec![[0.0, 1.0], [5.0, 0.3], [15.0, 1.0]]);
        let np = d.save_as_new("my_beech", dir.path()).unwrap();
        assert_eq!(np, dir.path().join("my_beech.toml"));
        let t = std::fs::read_to_string(&np).unwrap();
        assert!(t.contains("id = \"my_beech\"") && t.contains("copied from `beech`"), "{t}");
        assert!(species::parse_text(&t, &np).1.is_empty());
        assert!(d.save_as_new("my_beech", dir.path()).is_err(), "no overwrite");
        assert!(d.save_as_new("Bad-Id", dir.path()).is_err());
    }
}

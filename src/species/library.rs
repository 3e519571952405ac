//! Reading, validating and writing species files; the species library of a folder or the
//! library compiled into the binary.
//!
//! Every problem is reported with file, line (from the TOML spans), dotted field path, the
//! offending value and the allowed values; [`check_dir`] collects every problem of every file at
//! once.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::schema::{self, Kind};
use super::{Species, SpeciesLibrary};
use crate::{Error, Result};

/// The species files shipped in `species/`, compiled into the binary (file name, text). A test
/// checks that this list matches the folder.
pub const EMBEDDED_FILES: &[(&str, &str)] = &[
    ("ash.toml", include_str!("../../species/ash.toml")),
    ("aspen.toml", include_str!("../../species/aspen.toml")),
    ("beech.toml", include_str!("../../species/beech.toml")),
    ("black_alder.toml", include_str!("../../species/black_alder.toml")),
    ("european_larch.toml", include_str!("../../species/european_larch.toml")),
    ("hornbeam.toml", include_str!("../../species/hornbeam.toml")),
    ("norway_maple.toml", include_str!("../../species/norway_maple.toml")),
    ("norway_spruce.toml", include_str!("../../species/norway_spruce.toml")),
    ("pedunculate_oak.toml", include_str!("../../species/pedunculate_oak.toml")),
    ("rowan.toml", include_str!("../../species/rowan.toml")),
    ("scots_pine.toml", include_str!("../../species/scots_pine.toml")),
    ("sessile_oak.toml", include_str!("../../species/sessile_oak.toml")),
    ("silver_birch.toml", include_str!("../../species/silver_birch.toml")),
    ("silver_fir.toml", include_str!("../../species/silver_fir.toml")),
    ("small_leaved_lime.toml", include_str!("../../species/small_leaved_lime.toml")),
    ("sycamore.toml", include_str!("../../species/sycamore.toml")),
    ("wych_elm.toml", include_str!("../../species/wych_elm.toml")),
];

/// One problem found in a species file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problem {
    /// The file (or folder) involved.
    pub file: PathBuf,
    /// 1-based line of the offending field, where known.
    pub line: Option<usize>,
    /// Dotted field path (`life.growth.k`), or empty for whole-file problems.
    pub field: String,
    /// The offending value as text (empty where there is none, e.g. a missing field).
    pub value: String,
    /// What is allowed / what went wrong.
    pub expected: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        match (self.field.is_empty(), self.value.is_empty()) {
            (true, _) => write!(f, ": {}", self.expected),
            (false, true) => write!(f, ": field `{}`: {}", self.field, self.expected),
            (false, false) => write!(f, ": field `{}` = {}: expected {}", self.field, self.value, self.expected),
        }
    }
}

impl Problem {
    /// The problem as a library error (`Error::Invalid` with context `file:line`).
    pub fn to_error(&self) -> Error {
        let context = match self.line {
            Some(l) => format!("{}:{l}", self.file.display()),
            None => self.file.display().to_string(),
        };
        if self.field.is_empty() || self.value.is_empty() {
            Error::Format {
                path: self.file.clone(),
                message: self.to_string(),
            }
        } else {
            Error::Invalid {
                context,
                field: self.field.clone(),
                value: self.value.clone(),
                expected: self.expected.clone(),
            }
        }
    }
}

/// Turns a non-empty list of problems into one error (the problem itself if there is one, else a
/// `Format` error listing all of them, one per line).
pub fn problems_to_error(problems: &[Problem]) -> Error {
    match problems {
        [] => Error::Invalid { context: "species check".into(), field: "problems".into(), value: "none".into(), expected: "at least one problem to report".into() },
        [p] => p.to_error(),
        ps => {
            // problems in several files: the header names each of them, under their common
            // folder (trial 38, item 7: it named the first file only)
            let mut files: Vec<&PathBuf> = Vec::new();
            for p in ps {
                if !files.contains(&&p.file) {
                    files.push(&p.file);
                }
            }
            let list = ps.iter().map(|p| format!("  {p}")).collect::<Vec<_>>().join("\n");
            if files.len() == 1 {
                return Error::Format { path: ps[0].file.clone(), message: format!("{} problems:\n{list}", ps.len()) };
            }
            let parent = files[0].parent().filter(|d| files.iter().all(|f| f.parent() == Some(*d)));
            let names: Vec<String> = files.iter().map(|f| if parent.is_some() { f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default() } else { f.display().to_string() }).collect();
            Error::Format {
                path: parent.map(Path::to_path_buf).unwrap_or_else(|| ps[0].file.clone()),
                message: format!("{} problems in {} files ({}):\n{list}", ps.len(), files.len(), names.join(", ")),
            }
        }
    }
}

fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end].iter().filter(|&&b| b == b'\n').count() + 1
}

/// The span of the value at dotted `path` in a parsed document (deepest existing prefix).
fn span_of(root: &DeTable<'_>, path: &str) -> Option<std::ops::Range<usize>> {
    let mut table = root;
    let mut best = None;
    for key in path.split('.') {
        let (k, v) = table.iter().find(|(k, _)| k.get_ref().as_ref() == key)?;
        best = Some(if v.span().is_empty() { k.span() } else { v.span() });
        match v.get_ref() {
            DeValue::Table(t) => table = t,
            _ => break,
        }
    }
    best
}

/// The dotted path of the deepest key or value whose span contains `pos`.
fn path_at(table: &DeTable<'_>, pos: usize, prefix: &str) -> Option<String> {
    for (k, v) in table.iter() {
        let kspan = k.span();
        let vspan = v.span();
        let inside = (kspan.start <= pos && pos < kspan.end.max(kspan.start + 1)) || (vspan.start <= pos && pos < vspan.end);
        let name = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        if let DeValue::Table(t) = v.get_ref() {
            if let Some(p) = path_at(t, pos, &name) {
                return Some(p);
            }
        }
        if inside {
            return Some(name);
        }
    }
    None
}

fn fmt_num(x: f64) -> String {
    format!("{}", x as f32)
}

fn fmt_value(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) => fmt_num(*x),
        toml::Value::String(s) => format!("{s:?}"),
        toml::Value::Array(a) => format!("[{}]", a.iter().map(fmt_value).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// `x` within `[min, max]` compared in f32 (values are stored as f32).
fn in_range(x: f64, min: f64, max: f64, min_exclusive: bool) -> bool {
    let (x, min, max) = (x as f32, min as f32, max as f32);
    x.is_finite() && x <= max && if min_exclusive { x > min } else { x >= min }
}

/// Checks one leaf value against its kind; `Err(value text)` if it is not allowed.
fn check_leaf(kind: &Kind, v: &toml::Value) -> std::result::Result<(), String> {
    let bad = || Err(fmt_value(v));
    match *kind {
        Kind::Text { non_empty } => match v.as_str() {
            Some(s) if !non_empty || !s.trim().is_empty() => Ok(()),
            _ => bad(),
        },
        Kind::Ident => match v.as_str() {
            Some(s) if super::is_species_id(s) => Ok(()),
            _ => bad(),
        },
        Kind::TextList => match v.as_array() {
            Some(a) if a.iter().all(|e| e.is_str()) => Ok(()),
            _ => bad(),
        },
        Kind::Bool => {
            if v.is_bool() {
                Ok(())
            } else {
                bad()
            }
        }
        Kind::Enum(allowed) => match v.as_str() {
            Some(s) if allowed.contains(&s) => Ok(()),
            _ => bad(),
        },
        Kind::Range { min, max, min_exclusive } => match as_f64(v) {
            Some(x) if in_range(x, min, max, min_exclusive) => Ok(()),
            _ => bad(),
        },
        Kind::Int { min, max } => match v.as_integer() {
            Some(i) if (min..=max).contains(&i) => Ok(()),
            _ => bad(),
        },
        Kind::Indicator { max } => match v {
            toml::Value::String(s) if s == "x" => Ok(()),
            _ => match as_f64(v) {
                Some(x) if in_range(x, 1.0, max, false) => Ok(()),
                _ => bad(),
            },
        },
        Kind::PolyLine { x, y } => {
            let Some(points) = v.as_array() else { return bad() };
            if points.is_empty() {
                return bad();
            }
            let mut last = f64::NEG_INFINITY;
            for p in points {
                let xy = p.as_array().filter(|a| a.len() == 2).and_then(|a| Some((as_f64(&a[0])?, as_f64(&a[1])?)));
                match xy {
                    Some((px, py)) if in_range(px, x.0, x.1, false) && in_range(py, y.0, y.1, false) && px >= last => last = px,
                    _ => return Err(format!("{} (point {})", fmt_value(v), fmt_value(p))),
                }
            }
            Ok(())
        }
        Kind::Colour => match v.as_array() {
            Some(a) if a.len() == 3 && a.iter().all(|c| c.as_integer().is_some_and(|i| (0..=255).contains(&i))) => Ok(()),
            _ => bad(),
        },
    }
}

/// A range violation found by [`Species::validate`]: dotted field path, value, allowed values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// Dotted field path.
    pub field: String,
    /// The offending value as text.
    pub value: String,
    /// The allowed values in words.
    pub expected: String,
}

fn walk(v: &toml::Value, prefix: &str, out: &mut Vec<(String, toml::Value)>) {
    match v {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let p = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                walk(v, &p, out);
            }
        }
        _ => out.push((prefix.to_string(), v.clone())),
    }
}

/// All leaf fields of a species as (dotted path, value), in the serialiser's order.
pub fn leaf_fields(s: &Species) -> Result<Vec<(String, toml::Value)>> {
    let v = toml::Value::try_from(s).map_err(|e| Error::Serialize { what: format!("species `{}`", s.id), format: "TOML", message: e.to_string() })?;
    let mut out = Vec::new();
    walk(&v, "", &mut out);
    Ok(out)
}

impl Species {
    /// Checks every field against its allowed range ([`schema::FIELDS`]) and the cross-field
    /// rules (maturity below maximum age, maximum dispersal distance ≥ mean); returns every
    /// violation (empty when the species is valid).
    pub fn validate(&self) -> Vec<Violation> {
        let mut out = Vec::new();
        let leaves = match leaf_fields(self) {
            Ok(l) => l,
            Err(e) => {
                out.push(Violation {
                    field: "id".into(),
                    value: self.id.clone(),
                    expected: e.to_string(),
                });
                return out;
            }
        };
        for (path, v) in &leaves {
            match schema::field(path) {
                Some(spec) => {
                    if let Err(value) = check_leaf(&spec.kind, v) {
                        out.push(Violation {
                            field: path.clone(),
                            value,
                            expected: spec.kind.expected(),
                        });
                    }
                }
                None => out.push(Violation {
                    field: path.clone(),
                    value: fmt_value(v),
                    expected: "a field of the schema (internal: field missing from schema::FIELDS)".into(),
                }),
            }
        }
        out.extend(self.cross_checks());
        out
    }

    /// The rules between fields: maturity below maximum age, maximum dispersal distance ≥ mean,
    /// leaf-out before autumn colour before leaf fall.
    fn cross_checks(&self) -> Vec<Violation> {
        let mut out = Vec::new();
        let l = &self.life;
        if l.maturity_age_yr.is_finite() && l.max_age_yr.is_finite() && l.maturity_age_yr >= l.max_age_yr {
            out.push(Violation {
                field: "life.maturity_age_yr".into(),
                value: fmt_num(l.maturity_age_yr as f64),
                expected: format!("less than life.max_age_yr = {}", l.max_age_yr),
            });
        }
        if l.bai_bwinpro.is_some() && (l.stand_crown.is_none() || l.stand_crown_base.is_none()) {
            out.push(Violation {
                field: "life.bai_bwinpro".into(),
                value: "given".into(),
                expected: "life.stand_crown and life.stand_crown_base given too (the crown width and crown base the BWINPro increment reads)".into(),
            });
        }
        let a = &self.appearance;
        for (field, v, after, before) in [("appearance.autumn_doy", a.autumn_doy, "appearance.leaf_out_doy", a.leaf_out_doy), ("appearance.leaf_fall_doy", a.leaf_fall_doy, "appearance.autumn_doy", a.autumn_doy)] {
            if v.is_finite() && before.is_finite() && v <= before {
                out.push(Violation { field: field.into(), value: fmt_num(v as f64), expected: format!("a later day than {after} = {before}") });
            }
        }
        if let Some(m) = &self.architecture.mature_form {
            if m.full_age_yr.is_finite() && m.from_age_yr.is_finite() && m.full_age_yr <= m.from_age_yr {
                out.push(Violation {
                    field: "architecture.mature_form.full_age_yr".into(),
                    value: fmt_num(m.full_age_yr as f64),
                    expected: format!("more than architecture.mature_form.from_age_yr = {}", m.from_age_yr),
                });
            }
        }
        // heights stop at max_height_m (`growth::grow`), so an asymptote above it is a curve cut
        // short, never reached (trial 44: 100 m against 48 m was accepted without a word)
        if let Some(h) = l.growth.h_max_m {
            if h.is_finite() && l.max_height_m.is_finite() && h > l.max_height_m {
                out.push(Violation {
                    field: "life.growth.h_max_m".into(),
                    value: fmt_num(h as f64),
                    expected: format!("at most life.max_height_m = {} (heights stop there)", l.max_height_m),
                });
            }
        }
        if l.dispersal.max_m.is_finite() && l.dispersal.mean_m.is_finite() && l.dispersal.max_m < l.dispersal.mean_m {
            out.push(Violation {
                field: "life.dispersal.max_m".into(),
                value: fmt_num(l.dispersal.max_m as f64),
                expected: format!("at least life.dispersal.mean_m = {}", l.dispersal.mean_m),
            });
        }
        out
    }

    /// Parses and validates one species file's text; `file_name` is used in messages.
    ///
    /// # Errors
    /// `Error::Format` for TOML syntax errors, wrong types, unknown or missing fields (naming
    /// the line and field); `Error::Invalid` for one out-of-range value; a `Format` error listing
    /// all problems when there are several.
    pub fn from_toml_str(text: &str, file_name: &str) -> Result<Species> {
        let (s, problems) = parse_text(text, Path::new(file_name));
        match s {
            Some(s) if problems.is_empty() => Ok(s),
            _ => Err(problems_to_error(&problems)),
        }
    }

    /// Serialises to TOML (without the comments of the original file); reading the result
    /// back gives an equal `Species`.
    pub fn to_toml_string(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::Serialize { what: format!("species `{}`", self.id), format: "TOML", message: e.to_string() })
    }
}

/// Whether `path` names a table of the schema (a strict prefix of some field path).
fn is_table_path(path: &str) -> bool {
    path.is_empty()
        || schema::FIELDS
            .iter()
            .any(|f| f.path.len() > path.len() && f.path.starts_with(path) && f.path.as_bytes()[path.len()] == b'.')
}

fn walk_doc(t: &toml::Table, prefix: &str, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in t {
        let p = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
        match v {
            toml::Value::Table(sub) if is_table_path(&p) => walk_doc(sub, &p, out),
            _ => out.push((p, v.clone())),
        }
    }
}

/// Checks a parsed document against the schema without deserialising it, so that every
/// unknown field, missing field, wrong type and out-of-range value is found in one pass.
/// Returns (dotted path, value text, expected) triples.
fn check_document(doc: &toml::Table) -> Vec<Violation> {
    let mut leaves = Vec::new();
    walk_doc(doc, "", &mut leaves);
    let mut out = Vec::new();
    for (path, v) in &leaves {
        match schema::field(path) {
            Some(spec) => {
                if let Err(value) = check_leaf(&spec.kind, v) {
                    out.push(Violation {
                        field: path.clone(),
                        value,
                        expected: spec.kind.expected(),
                    });
                }
            }
            None if is_table_path(path) => out.push(Violation {
                field: path.clone(),
                value: fmt_value(v),
                expected: "a table (see species/README.md)".into(),
            }),
            None => {
                let parent = path.rsplit_once('.').map(|(p, _)| p).unwrap_or("");
                let known: Vec<&str> = schema::FIELDS
                    .iter()
                    .filter_map(|f| {
                        let rest = if parent.is_empty() {
                            Some(f.path)
                        } else {
                            f.path.strip_prefix(parent).and_then(|r| r.strip_prefix('.'))
                        };
                        rest.map(|r| r.split('.').next().unwrap_or(r))
                    })
                    .fold(Vec::new(), |mut acc, k| {
                        if !acc.contains(&k) {
                            acc.push(k);
                        }
                        acc
                    });
                out.push(Violation {
                    field: path.clone(),
                    value: fmt_value(v),
                    expected: format!(
                        "a known field (`{}` is an unknown field); known here: {}",
                        path.rsplit('.').next().unwrap_or(path),
                        known.join(", ")
                    ),
                });
            }
        }
    }
    for spec in schema::FIELDS {
        // the crown profile's fork and hanging twigs (round 46) are optional within it
        if matches!(spec.path, "architecture.ecomod.crown_profile.fork_depth" | "architecture.ecomod.crown_profile.fork_limbs" | "architecture.ecomod.crown_profile.fork_angle_deg" | "architecture.ecomod.crown_profile.twig_droop_deg") {
            continue;
        }
        if spec.path == "identity.sources" || spec.path == "life.form_factor" || spec.path == "life.growth.h_max_m" || spec.path.starts_with("life.stand_crown.") || spec.path.starts_with("life.stand_crown_base.") || spec.path.starts_with("life.dense_hd.") || spec.path.starts_with("life.open_hd.") || spec.path.starts_with("life.bai_competition.") || spec.path.starts_with("life.bai_bwinpro.") || spec.path.starts_with("life.foliage.") || spec.path == "appearance.leaf_length_m" || spec.path == "life.drought_tolerance" || spec.path == "life.shade_survival_class" || spec.path == "life.closed_hd" || spec.path == "life.closed_hd_scope" || spec.path == "life.closed_hd_mixed" {
            continue; // optional (drought tolerance: no drought response; shade survival class: the shade tolerance; form factor: default 0.5; height curve asymptote: max_height_m; stand crown, stand crown base, dense-stand and open-grown H/D, BAI competition, BWINPro growth, foliage, drawn leaf length: none)
        }
        // the mature form is optional as a table; where it is given, each of its fields is
        // required (none has a default)
        if spec.path.starts_with("architecture.mature_form.") && !leaves.iter().any(|(p, _)| p.starts_with("architecture.mature_form.")) {
            continue;
        }
        // and its crown profile (optional within the mature form)
        if spec.path.starts_with("architecture.mature_form.crown_profile.") && !leaves.iter().any(|(p, _)| p.starts_with("architecture.mature_form.crown_profile.")) {
            continue;
        }
        // so is the whorled stem of EcoMod (each of its fields required where it is given)
        if spec.path.starts_with("architecture.ecomod.whorls.") && !leaves.iter().any(|(p, _)| p.starts_with("architecture.ecomod.whorls.")) {
            continue;
        }
        // and the limbs' profile by depth into the crown
        if spec.path.starts_with("architecture.ecomod.limbs.") && !leaves.iter().any(|(p, _)| p.starts_with("architecture.ecomod.limbs.")) {
            continue;
        }
        // and a broadleaf's crown profile
        if spec.path.starts_with("architecture.ecomod.crown_profile.") && !leaves.iter().any(|(p, _)| p.starts_with("architecture.ecomod.crown_profile.")) {
            continue;
        }
        if leaves.iter().any(|(p, _)| p == spec.path) {
            continue;
        }
        // Report a missing field only if its parent table exists or is itself missing at the top.
        let present_prefix = leaves.iter().any(|(p, _)| spec.path.starts_with(&format!("{p}.")));
        if !present_prefix {
            out.push(Violation {
                field: spec.path.to_string(),
                value: String::new(),
                expected: format!("missing field: {} ({})", spec.kind.expected(), spec.doc),
            });
        }
    }
    out
}

/// Parses and validates one file's text; returns the species (if it is valid enough to build)
/// and all problems.
pub fn parse_text(text: &str, file: &Path) -> (Option<Species>, Vec<Problem>) {
    let mut problems = Vec::new();
    // an empty file is one problem, not every field missing (a trial got 88 lines)
    if text.trim().is_empty() {
        problems.push(Problem {
            file: file.into(),
            line: None,
            field: String::new(),
            value: String::new(),
            expected: "the file is empty; expected a species file (start from a copy: `sylva species new ID --from beech`)".into(),
        });
        return (None, problems);
    }
    let doc = match DeTable::parse(text) {
        Ok(d) => d,
        Err(e) => {
            let line = e.span().map(|s| line_of(text, s.start));
            problems.push(Problem {
                file: file.into(),
                line,
                field: String::new(),
                value: String::new(),
                expected: format!("TOML syntax error: {}", e.message().trim()),
            });
            return (None, problems);
        }
    };
    let doc: &Spanned<DeTable<'_>> = &doc;
    let problem = |v: Violation| {
        let line = span_of(doc.get_ref(), &v.field).or_else(|| {
            // Missing field: point at its parent table.
            let parent = v.field.rsplit_once('.').map(|(p, _)| p)?;
            span_of(doc.get_ref(), parent)
        });
        Problem {
            file: file.into(),
            line: line.map(|s| line_of(text, s.start)),
            field: v.field,
            value: v.value,
            expected: v.expected,
        }
    };
    let table: toml::Table = match toml::from_str(text) {
        Ok(t) => t,
        Err(e) => {
            let line = e.span().map(|s| line_of(text, s.start));
            problems.push(Problem {
                file: file.into(),
                line,
                field: String::new(),
                value: String::new(),
                expected: format!("TOML error: {}", e.message().trim()),
            });
            return (None, problems);
        }
    };
    let structural = check_document(&table);
    if !structural.is_empty() {
        problems.extend(structural.into_iter().map(problem));
        problems.sort_by_key(|p| p.line);
        return (None, problems);
    }
    let species: Species = match toml::from_str(text) {
        Ok(s) => s,
        Err(e) => {
            let span = e.span();
            let line = span.as_ref().map(|s| line_of(text, s.start));
            let field = span.and_then(|s| path_at(doc.get_ref(), s.start, "")).unwrap_or_default();
            problems.push(Problem {
                file: file.into(),
                line,
                field,
                value: String::new(),
                expected: e.message().trim().to_string(),
            });
            return (None, problems);
        }
    };
    problems.extend(species.validate().into_iter().map(problem));
    problems.sort_by_key(|p| p.line);
    (Some(species), problems)
}

/// Parses one file's bytes (refusing non-UTF-8 with the byte offset and line).
pub fn parse_bytes(bytes: &[u8], file: &Path) -> (Option<Species>, Vec<Problem>) {
    match std::str::from_utf8(bytes) {
        Ok(text) => parse_text(text, file),
        Err(e) => {
            let ok = e.valid_up_to();
            let line = bytes[..ok].iter().filter(|&&b| b == b'\n').count() + 1;
            let p = Problem {
                file: file.into(),
                line: Some(line),
                field: String::new(),
                value: String::new(),
                expected: format!("not valid UTF-8 (invalid byte at offset {ok}); species files must be UTF-8 text"),
            };
            (None, vec![p])
        }
    }
}

/// The `*.toml` files directly in `dir`, sorted by name.
pub fn species_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut files = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let p = entry.path();
        if p.is_file() && p.extension().is_some_and(|x| x == "toml") {
            files.push(p);
        }
    }
    files.sort();
    Ok(files)
}

/// Reads and checks every file, then the uniqueness of ids; returns species and all problems.
fn scan<'a>(files: impl Iterator<Item = (PathBuf, std::borrow::Cow<'a, [u8]>)>) -> (Vec<(PathBuf, Species)>, Vec<Problem>) {
    let mut all = Vec::new();
    let mut problems = Vec::new();
    // (file, id) of every file whose id can be read, valid or not, so that a duplicate id is
    // reported even when one of the two files has other errors.
    let mut ids: Vec<(PathBuf, String)> = Vec::new();
    for (path, bytes) in files {
        let (s, mut p) = parse_bytes(&bytes, &path);
        problems.append(&mut p);
        if let Some(s) = s {
            ids.push((path.clone(), s.id.clone()));
            all.push((path, s));
        } else if let Some(id) = std::str::from_utf8(&bytes).ok().and_then(|t| DeTable::parse(t).ok()).and_then(|d| d.get_ref().get("id").and_then(|v| v.get_ref().as_str().map(str::to_string))) {
            ids.push((path, id));
        }
    }
    let mut seen: BTreeMap<&str, &Path> = BTreeMap::new();
    let mut dups = Vec::new();
    for (path, id) in &ids {
        if let Some(first) = seen.get(id.as_str()) {
            dups.push(Problem {
                file: path.clone(),
                line: Some(1),
                field: "id".into(),
                value: format!("{id:?}"),
                expected: format!("a unique id: species `{id}` is defined in both {} and {}", first.display(), path.display()),
            });
        } else {
            seen.insert(id, path);
        }
    }
    // Line of the id in the duplicate file.
    for d in &mut dups {
        if let Ok(text) = std::fs::read_to_string(&d.file) {
            if let Ok(doc) = DeTable::parse(&text) {
                d.line = span_of(doc.get_ref(), "id").map(|s| line_of(&text, s.start));
            }
        }
    }
    problems.extend(dups);
    (all, problems)
}

/// Checks every species file in `dir`; returns every problem of every file (empty = all good).
/// An unreadable folder is reported as one problem.
pub fn check_dir(dir: &Path) -> Vec<Problem> {
    match read_dir_files(dir) {
        Ok(files) => scan(files.into_iter()).1,
        Err(e) => vec![Problem {
            file: dir.into(),
            line: None,
            field: String::new(),
            value: String::new(),
            expected: e.to_string(),
        }],
    }
}

fn read_dir_files(dir: &Path) -> Result<Vec<(PathBuf, std::borrow::Cow<'static, [u8]>)>> {
    let mut out = Vec::new();
    for p in species_files(dir)? {
        let bytes = std::fs::read(&p).map_err(|e| Error::io(&p, e))?;
        out.push((p, std::borrow::Cow::Owned(bytes)));
    }
    Ok(out)
}

fn into_library(mut all: Vec<(PathBuf, Species)>) -> SpeciesLibrary {
    all.sort_by(|a, b| a.1.id.cmp(&b.1.id));
    SpeciesLibrary {
        species: all.into_iter().map(|(_, s)| s).collect(),
    }
}

impl SpeciesLibrary {
    /// Loads every `*.toml` file in `dir` (not recursive), sorted by id.
    ///
    /// # Errors
    /// I/O errors; every problem of every file (see [`check_dir`]) including duplicate ids
    /// (naming both files), gathered into one error; an empty folder.
    pub fn load_dir(dir: &Path) -> Result<SpeciesLibrary> {
        let files = read_dir_files(dir)?;
        if files.is_empty() {
            return Err(Error::format(dir, "no species files (*.toml) in this folder"));
        }
        let (all, problems) = scan(files.into_iter());
        if !problems.is_empty() {
            return Err(problems_to_error(&problems));
        }
        Ok(into_library(all))
    }

    /// Adds every species of the `*.toml` files in `dir` to this library, replacing any species
    /// with the same id (an edited copy of a shipped species overrides it), keeping the library
    /// sorted by id. Used for `--species-dir` and for the `species/` folder a simulation writes
    /// into its run directory.
    ///
    /// # Errors
    /// As [`SpeciesLibrary::load_dir`]: I/O errors, every problem of every file (with file and
    /// line), duplicate ids within `dir`, an empty folder.
    pub fn overlay_dir(&mut self, dir: &Path) -> Result<()> {
        let extra = SpeciesLibrary::load_dir(dir)?;
        for sp in extra.species {
            match self.species.iter_mut().find(|s| s.id == sp.id) {
                Some(slot) => *slot = sp,
                None => self.species.push(sp),
            }
        }
        self.species.sort_by(|a, b| a.id.cmp(&b.id));
        Ok(())
    }

    /// The species shipped with Sylva ([`EMBEDDED_FILES`]), sorted by id.
    ///
    /// # Errors
    /// Only if a shipped file were invalid (a test guarantees they are not).
    pub fn embedded() -> Result<SpeciesLibrary> {
        let files = EMBEDDED_FILES
            .iter()
            .map(|(n, t)| (Path::new("species").join(n), std::borrow::Cow::Borrowed(t.as_bytes())));
        let (all, problems) = scan(files);
        if !problems.is_empty() {
            return Err(problems_to_error(&problems));
        }
        Ok(into_library(all))
    }

    /// The species with this id, scientific or common name (case-insensitive).
    pub fn get(&self, name: &str) -> Option<&Species> {
        self.find(name).map(|i| &self.species[i as usize])
    }

    /// Number of species.
    pub fn len(&self) -> usize {
        self.species.len()
    }

    /// Whether the library is empty.
    pub fn is_empty(&self) -> bool {
        self.species.is_empty()
    }
}

/// The text of an embedded species file by id (file `<id>.toml`), if shipped.
pub fn embedded_text(id: &str) -> Option<&'static str> {
    let name = format!("{id}.toml");
    EMBEDDED_FILES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// Replaces the value of the top-level `id` key in a species file's text, keeping everything
/// else (comments included) unchanged.
///
/// # Errors
/// `Error::Format` if the text is not TOML or has no top-level `id` string.
pub fn replace_id(text: &str, new_id: &str, file: &Path) -> Result<String> {
    let doc = DeTable::parse(text).map_err(|e| Error::format(file, format!("TOML syntax error: {}", e.message().trim())))?;
    let (_, v) = doc
        .get_ref()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == "id")
        .ok_or_else(|| Error::format(file, "no top-level `id` field"))?;
    let span = v.span();
    if !matches!(v.get_ref(), DeValue::String(_)) || span.end > text.len() {
        return Err(Error::format(file, "top-level `id` is not a string"));
    }
    Ok(format!("{}\"{}\"{}", &text[..span.start], new_id, &text[span.end..]))
}

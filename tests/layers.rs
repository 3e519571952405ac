//! The layers of ARCHITECTURE.md, checked on the source text (issue 13).
//!
//! Reads every `.rs` file under `src/`, collects the module paths each one names
//! (`crate::a::b`, `super::…`, `sylva::…` in the binary, grouped `crate::{a, b::c}` imports
//! included; comments and the `#[cfg(test)]` tail of a file excluded) and checks:
//! 1. no core module (`grid`, `rng`, `climate`, `terrain`, `conditions`, `species`, `sim`,
//!    `structure`, `mesh`) names a shell module (`output`, `render`, `job`, `cli`, `app`, and the
//!    windows `gui`, `view`, `edit`);
//! 2. no two top-level modules name each other, directly or through a chain (no cycle);
//! 3. no two second-level modules (`sim::world`, `render::scene`, `terrain::fields`, …) form a
//!    cycle either (edges between a module and its own parent — `mod` declarations and
//!    re-exports — are structural and left out);
//! 4. the command line (`src/main.rs`, `src/cli/`) names no simulation internals, only
//!    `sim::Scenario` and `sim::tiles::Transport` (issue 33: the main job is `job::main_job`);
//! 5. no field of `job::pictures::Stage` is set outside `job`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const CORE: &[&str] = &["grid", "rng", "sun", "obstacle", "climate", "terrain", "conditions", "species", "sim", "structure", "mesh"];
const SHELL: &[&str] = &["output", "render", "job", "cli", "app", "gui", "view", "edit"];

/// Module path of a source file: `src/sim/phases/growth.rs` → `[sim, phases, growth]`,
/// `src/sim/mod.rs` → `[sim]`, `src/lib.rs` and `src/main.rs` → `[]`.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_string());
    }
    parts
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file without comments and without its `#[cfg(test)]` tail.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines().map(|l| l.find("//").map_or(l, |i| &l[..i])).collect::<Vec<_>>().join("\n")
}

fn ident_at(s: &[u8], mut i: usize) -> (String, usize) {
    let st = i;
    while i < s.len() && (s[i].is_ascii_alphanumeric() || s[i] == b'_') {
        i += 1;
    }
    (String::from_utf8_lossy(&s[st..i]).into_owned(), i)
}

/// Paths (segment lists) starting at byte `i` of `s`: `a::b::c` or `a::{b, c::d}` (nested).
fn paths_at(s: &[u8], i: usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut cur = prefix;
    let mut i = i;
    loop {
        while i < s.len() && s[i].is_ascii_whitespace() {
            i += 1;
        }
        if i < s.len() && s[i] == b'{' {
            // split the group at top-level commas
            let mut depth = 0;
            let mut start = i + 1;
            let mut j = i;
            while j < s.len() {
                match s[j] {
                    b'{' => depth += 1,
                    b'}' => {
                        depth -= 1;
                        if depth == 0 {
                            paths_at(s, start, cur.clone(), out);
                            return;
                        }
                    }
                    b',' if depth == 1 => {
                        paths_at(s, start, cur.clone(), out);
                        start = j + 1;
                    }
                    _ => {}
                }
                j += 1;
            }
            return;
        }
        let (id, j) = ident_at(s, i);
        if id.is_empty() {
            break;
        }
        cur.push(id);
        i = j;
        if s.get(i..i + 2) == Some(b"::") {
            i += 2;
        } else {
            break;
        }
    }
    out.push(cur);
}

/// Every module path named in `code`, resolved to absolute segments (crate root = `[]`).
fn referenced(code: &str, me: &[String]) -> Vec<Vec<String>> {
    let s = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let boundary = i == 0 || !(s[i - 1].is_ascii_alphanumeric() || s[i - 1] == b'_' || s[i - 1] == b':');
        if boundary {
            for (kw, is_super) in [("crate::", false), ("sylva::", false), ("super::", true)] {
                if s[i..].starts_with(kw.as_bytes()) {
                    let mut base: Vec<String> = Vec::new();
                    let mut j = i + kw.len();
                    if is_super {
                        // `super` names the parent of this file's module (for a `mod.rs`, the
                        // parent of its directory's module)
                        base = me.to_vec();
                        base.pop();
                        while s[j..].starts_with(b"super::") {
                            base.pop();
                            j += 7;
                        }
                    }
                    let mut ps = Vec::new();
                    paths_at(s, j, base, &mut ps);
                    out.extend(ps);
                    i = j;
                    break;
                }
            }
        }
        i += 1;
    }
    out
}

struct Tree {
    /// Every module (absolute segments) that has a file.
    modules: BTreeSet<Vec<String>>,
    /// (from module, to path) for every reference.
    refs: Vec<(Vec<String>, Vec<String>)>,
}

fn read_tree() -> Tree {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut modules = BTreeSet::new();
    let mut refs = Vec::new();
    for f in &files {
        let mut me = module_of(&src, f);
        // the binary's modules live in `cli` (src/main.rs is its root)
        if f.ends_with("main.rs") {
            me = vec!["cli".into()];
        }
        modules.insert(me.clone());
        let text = std::fs::read_to_string(f).unwrap();
        for p in referenced(&code(&text), &me) {
            refs.push((me.clone(), p));
        }
    }
    Tree { modules, refs }
}

/// The node of `path` at `depth`: its longest prefix that is a module with a file, cut to
/// `depth` segments. `None` for the crate root.
fn node(t: &Tree, path: &[String], depth: usize) -> Option<Vec<String>> {
    let mut n = path.len();
    while n > 0 && !t.modules.contains(&path[..n]) {
        n -= 1;
    }
    (n > 0).then(|| path[..n.min(depth)].to_vec())
}

fn graph(t: &Tree, depth: usize) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut g: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (from, to) in &t.refs {
        let (Some(a), Some(b)) = (node(t, from, depth), node(t, to, depth)) else { continue };
        if a == b || a.starts_with(&b) || b.starts_with(&a) {
            continue;
        }
        g.entry(a).or_default().insert(b);
    }
    g
}

/// Strongly connected components with more than one node (Tarjan), as sorted lists of names.
fn cycles(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<String>> {
    let nodes: BTreeSet<&Vec<String>> = g.keys().chain(g.values().flatten()).collect();
    let nodes: Vec<&Vec<String>> = nodes.into_iter().collect();
    let idx: BTreeMap<&Vec<String>, usize> = nodes.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let adj: Vec<Vec<usize>> = nodes.iter().map(|n| g.get(*n).map(|s| s.iter().map(|m| idx[m]).collect()).unwrap_or_default()).collect();
    struct St {
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(v: usize, adj: &[Vec<usize>], st: &mut St) {
        st.index[v] = Some(st.next);
        st.low[v] = st.next;
        st.next += 1;
        st.stack.push(v);
        st.on[v] = true;
        for &w in &adj[v] {
            match st.index[w] {
                None => {
                    visit(w, adj, st);
                    st.low[v] = st.low[v].min(st.low[w]);
                }
                Some(iw) if st.on[w] => st.low[v] = st.low[v].min(iw),
                _ => {}
            }
        }
        if Some(st.low[v]) == st.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = st.stack.pop() {
                st.on[w] = false;
                comp.push(w);
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                st.out.push(comp);
            }
        }
    }
    let n = nodes.len();
    let mut st = St { index: vec![None; n], low: vec![0; n], on: vec![false; n], stack: Vec::new(), next: 0, out: Vec::new() };
    for v in 0..n {
        if st.index[v].is_none() {
            visit(v, &adj, &mut st);
        }
    }
    let mut out: Vec<Vec<String>> = st.out.iter().map(|c| {
        let mut names: Vec<String> = c.iter().map(|&i| nodes[i].join("::")).collect();
        names.sort();
        names
    }).collect();
    out.sort();
    out
}

#[test]
fn core_imports_no_shell() {
    let t = read_tree();
    let mut bad = BTreeSet::new();
    for (from, to) in &t.refs {
        let (Some(a), Some(b)) = (node(&t, from, 2), node(&t, to, 1)) else { continue };
        if CORE.contains(&a[0].as_str()) && SHELL.contains(&b[0].as_str()) {
            bad.insert(format!("{} -> {}", a.join("::"), b.join("::")));
        }
    }
    assert!(bad.is_empty(), "core modules naming shell modules:\n{}", bad.into_iter().collect::<Vec<_>>().join("\n"));
}

#[test]
fn no_cycles_between_top_level_modules() {
    let c = cycles(&graph(&read_tree(), 1));
    assert!(c.is_empty(), "import cycles between top-level modules: {c:?}");
}

#[test]
fn no_cycles_between_second_level_modules() {
    let c = cycles(&graph(&read_tree(), 2));
    assert!(c.is_empty(), "import cycles between second-level modules: {c:?}");
}

/// The checker itself: a cycle and a core → shell import are found in a small made-up tree.
#[test]
fn checker_finds_planted_violations() {
    let m = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
    let text = "use crate::{sim::world::World, output};\nuse super::super::world::X; // crate::render::x\n";
    let r = referenced(&code(text), &m("sim::phases::growth"));
    assert!(r.contains(&m("sim::world::World")) && r.contains(&m("output")) && r.contains(&m("sim::world::X")), "{r:?}");
    assert!(!r.iter().any(|p| p.first().is_some_and(|s| s == "render")), "comments are skipped: {r:?}");
    let t = Tree {
        modules: ["sim", "sim::world", "sim::regen", "output", "grid"].iter().map(|s| m(s)).collect(),
        refs: vec![(m("sim::world"), m("sim::regen::Cohorts")), (m("sim::regen"), m("sim::world::World")), (m("grid"), m("sim::World")), (m("sim::world"), m("grid::Grid"))],
    };
    assert_eq!(cycles(&graph(&t, 2)), vec![vec!["sim::regen".to_string(), "sim::world".to_string()]]);
    assert_eq!(cycles(&graph(&t, 1)), vec![vec!["grid".to_string(), "sim".to_string()]]);
}

/// ARCHITECTURE.md quotes the phase list of `sim::step::PHASES`, in order, between its
/// `<!-- phases` markers, one line `N. \`name\` — summary` per phase.
#[test]
fn architecture_md_quotes_the_phase_list() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md")).unwrap();
    let start = doc.find("<!-- phases").expect("ARCHITECTURE.md has a <!-- phases ... --> block");
    let end = doc[start..].find("<!-- /phases -->").expect("the phases block is closed") + start;
    let quoted: Vec<&str> = doc[start..end].lines().skip(1).filter(|l| !l.trim().is_empty()).collect();
    let want: Vec<String> = sylva::sim::step::PHASES.iter().enumerate().map(|(k, p)| format!("{}. `{}` — {}", k + 1, p.name, p.summary)).collect();
    assert_eq!(quoted, want, "ARCHITECTURE.md's phase list differs from sim::step::PHASES; paste:\n{}", want.join("\n"));
}

/// The `sim` paths the command line may name: the scenario it loads and the transport trait an
/// MPI rank implements. Everything else of the simulation is reached through `job`.
const CLI_SIM_PATHS: &[&str] = &["sim::Scenario", "sim::tiles::Transport"];

/// The `sim` paths named by the command line's modules (`src/main.rs`, `src/cli/`) that
/// [`CLI_SIM_PATHS`] does not allow.
fn cli_sim_paths(t: &Tree) -> BTreeSet<String> {
    t.refs
        .iter()
        .filter(|(from, to)| from.first().is_some_and(|m| m == "cli") && to.first().is_some_and(|m| m == "sim"))
        .map(|(from, to)| (from.join("::"), to.join("::")))
        .filter(|(_, to)| !CLI_SIM_PATHS.contains(&to.as_str()))
        .map(|(from, to)| format!("{from} -> {to}"))
        .collect()
}

/// The command line only parses arguments, draws progress and handles Ctrl-C: it names no
/// internals of the simulation (the main job is `job::main_job`).
#[test]
fn cli_names_no_sim_internals() {
    let bad = cli_sim_paths(&read_tree());
    assert!(bad.is_empty(), "the command line names simulation internals (go through job::main_job):\n{}", bad.into_iter().collect::<Vec<_>>().join("\n"));
}

/// The public fields of `job::pictures::Stage` (read from its definition).
fn stage_fields() -> Vec<String> {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/job/pictures.rs")).unwrap();
    let start = text.find("pub struct Stage {").expect("job::pictures defines Stage");
    let body = &text[start..start + text[start..].find("\n}").unwrap()];
    body.lines().filter_map(|l| l.trim().strip_prefix("pub ")?.split_once(':').map(|(n, _)| n.trim().to_string())).collect()
}

/// Where `code` sets a field of a `Stage` (`stage.adapt = …`, `.take()`, `.replace(…)`,
/// `&mut stage.adapt`): the variables bound to a stage (`let [mut] x = …Stage::…(` or
/// `…stage_for(`, parameters `x: &mut Stage`) followed by one of `fields`.
fn stage_writes(code: &str, fields: &[String]) -> Vec<String> {
    let mut vars: BTreeSet<String> = BTreeSet::new();
    for l in code.lines() {
        let l = l.trim();
        if let Some(rest) = l.strip_prefix("let ") {
            if l.contains("Stage::") || l.contains("stage_for(") {
                let rest = rest.trim_start_matches("mut ");
                vars.insert(rest.split([' ', ':', '=']).next().unwrap_or("").to_string());
            }
        }
        let mut s = l;
        while let Some(i) = s.find(": &mut Stage") {
            let name = s[..i].rsplit([' ', '(', ',']).next().unwrap_or("");
            vars.insert(name.to_string());
            s = &s[i + 1..];
        }
    }
    let mut out = Vec::new();
    for v in vars.iter().filter(|v| !v.is_empty()) {
        for f in fields {
            let at = format!("{v}.{f}");
            let mut from = 0;
            while let Some(i) = code[from..].find(&at) {
                let (b, e) = (from + i, from + i + at.len());
                from = e;
                let before_ok = b == 0 || !code.as_bytes()[b - 1].is_ascii_alphanumeric() && code.as_bytes()[b - 1] != b'_' && code.as_bytes()[b - 1] != b'.';
                let after = &code[e..];
                if !before_ok || after.starts_with(|c: char| c.is_ascii_alphanumeric() || c == '_') {
                    continue;
                }
                // a field of the field (`stage.scene.sun = …`) is the field set too
                let mut rest = after;
                while let Some(r) = rest.strip_prefix('.') {
                    let n = r.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(r.len());
                    if n == 0 || r[n..].starts_with('(') {
                        break;
                    }
                    rest = &r[n..];
                }
                let t = rest.trim_start();
                let assign = t.starts_with('=') && !t.starts_with("==") || ["+=", "-=", "*=", "/="].iter().any(|o| t.starts_with(o));
                let mutate = [".take()", ".replace(", ".push(", ".clear()", ".extend", ".truncate(", ".insert("].iter().any(|m| rest.starts_with(m));
                let borrowed = code[..b].trim_end().ends_with("&mut");
                if assign || mutate || borrowed {
                    out.push(at.clone());
                }
            }
        }
    }
    out
}

/// `job::pictures::Stage`'s fields are set only in `job` (through its methods elsewhere).
#[test]
fn no_stage_field_set_outside_job() {
    let fields = stage_fields();
    assert!(fields.contains(&"adapt".to_string()) && fields.contains(&"renderer".to_string()), "{fields:?}");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut bad = Vec::new();
    for f in files.iter().filter(|f| !f.starts_with(src.join("job"))) {
        for w in stage_writes(&code(&std::fs::read_to_string(f).unwrap()), &fields) {
            bad.push(format!("{}: {w}", f.strip_prefix(&src).unwrap().display()));
        }
    }
    assert!(bad.is_empty(), "Stage fields set outside job (use Stage's methods):\n{}", bad.join("\n"));
}

/// The two checkers find planted violations.
#[test]
fn cli_and_stage_checkers_find_planted_violations() {
    let fields: Vec<String> = ["adapt", "scene"].iter().map(|s| s.to_string()).collect();
    let text = "fn f(st: &mut Stage) {\n    let mut stage = stage_for(&dir, None)?;\n    stage.adapt = None;\n    let a = stage.adapt.take();\n    if stage.adapt == None {}\n    st.scene.sun = x;\n    g(&mut st.scene);\n    stage.adapted = 1;\n}\n";
    assert_eq!(stage_writes(text, &fields), vec!["st.scene".to_string(), "st.scene".to_string(), "stage.adapt".to_string(), "stage.adapt".to_string()]);
    let m = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
    let t = Tree { modules: ["cli", "cli::run", "sim", "sim::world"].iter().map(|s| m(s)).collect(), refs: vec![(m("cli::run"), m("sim::Scenario")), (m("cli::run"), m("sim::world::World"))] };
    assert_eq!(cli_sim_paths(&t).into_iter().collect::<Vec<_>>(), vec!["cli::run -> sim::world::World".to_string()]);
}

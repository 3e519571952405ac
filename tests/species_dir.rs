//! A species made with `sylva species new` is usable everywhere: `simulate --species-dir`,
//! the run keeps its species files in `RUN/species/`, and `render` finds them there.
use std::process::Command;

const SC: &str = r#"
name = "custom species"
years = 3
seed = 5
snapshot_every = 3
species = ["my_beech"]
[terrain]
uniform = { width = 4, height = 4, cell_m = 20.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }
[[start]]
kind = "planted"
species = "my_beech"
spacing_m = 5.0
age_yr = 15.0
"#;

fn sylva(args: &[&str], cwd: &std::path::Path) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).current_dir(cwd).output().unwrap();
    (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
}

#[test]
fn a_new_species_simulates_and_renders_from_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ok, log) = sylva(&["species", "new", "my_beech", "--from", "beech", "--dir", "mine"], d);
    assert!(ok, "{log}");
    std::fs::write(d.join("sc.toml"), SC).unwrap();
    // without the folder the species is unknown, and the error says which one
    let (ok, log) = sylva(&["simulate", "sc.toml", "--out", "run0"], d);
    assert!(!ok && log.contains("my_beech"), "{log}");
    let (ok, log) = sylva(&["simulate", "sc.toml", "--out", "run", "--species-dir", "mine"], d);
    assert!(ok, "{log}");
    let saved = std::fs::read_to_string(d.join("run/species/my_beech.toml")).unwrap();
    assert!(saved.contains("my_beech"));
    let inv = sylva::job::inventory::read(&d.join("run/inventory/year_0003.parquet")).unwrap();
    let planted = inv.iter().filter(|r| r.species == "my_beech").count();
    assert!(planted >= 9, "16 planted trees at 5 m on 80 m × 80 m, {planted} in the inventory");
    // render finds the species in the run directory without being told
    let (ok, log) = sylva(&["render", "run", "--size", "64x48", "--out", "f.png"], d);
    assert!(ok, "{log}");
    // every planted tree is drawn, as a mesh or billboard or in the far-field canopy layer
    let counts: Vec<usize> = log
        .split("year 3: ")
        .nth(1)
        .map(|rest| rest.split(|c: char| !c.is_ascii_digit()).filter(|t| !t.is_empty()).take(2).filter_map(|t| t.parse().ok()).collect())
        .unwrap_or_default();
    assert!(counts.len() == 2 && counts[0] + counts[1] >= planted, "{counts:?} of {planted}: {log}");
    // a species folder with a broken file is refused, naming the file
    std::fs::write(d.join("mine/broken.toml"), "id = 3\n").unwrap();
    let (ok, log) = sylva(&["simulate", "sc.toml", "--out", "run2", "--species-dir", "mine"], d);
    assert!(!ok && log.contains("broken.toml"), "{log}");
}

/// Trial 38, item 7: problems in several species files (through `simulate --species-dir` they
/// said `range.toml: 7 problems:`, naming one of the three files) name every file in the
/// header, under their folder.
#[test]
fn problems_in_several_species_files_name_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let beech = sylva::species::embedded_text("beech").unwrap();
    let a = sylva::species::replace_id(beech, "a_beech", std::path::Path::new("a.toml")).unwrap().replace("max_age_yr = 600.0", "max_age_yr = -5.0");
    let b = sylva::species::replace_id(beech, "b_beech", std::path::Path::new("b.toml")).unwrap().replace("shade_tolerance = 5.0", "shade_tolerance = 9.0");
    std::fs::write(dir.path().join("a.toml"), &a).unwrap();
    std::fs::write(dir.path().join("b.toml"), &b).unwrap();
    let e = sylva::species::SpeciesLibrary::load_dir(dir.path()).unwrap_err().to_string();
    assert!(e.contains(" problems in 2 files (a.toml, b.toml):") && e.contains("max_age_yr") && e.contains("shade_tolerance"), "{e}");
    assert!(e.starts_with(&dir.path().display().to_string()), "the folder first: {e}");
}

/// Trial 38, item 12: `species new ID --from X` gives the copy names of its own
/// (`Fagus sylvatica (my_beech)`), so `species show "Fagus sylvatica" --dir` gives the shipped
/// beech, as `tree grow --species "Fagus sylvatica" --species-dir` does (it gave the copy); the
/// copy is still found by its id. A `[[start]]` naming a pool species by its scientific name is
/// refused with the id to write.
#[test]
fn a_copied_species_gets_names_of_its_own_and_a_start_by_scientific_name_gets_the_id() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ok, log) = sylva(&["species", "new", "my_beech", "--from", "beech", "--dir", "mine"], d);
    assert!(ok, "{log}");
    let text = std::fs::read_to_string(d.join("mine/my_beech.toml")).unwrap();
    assert!(text.contains("scientific_name = \"Fagus sylvatica (my_beech)\"") && text.contains("common_name = \"European beech (my_beech)\""), "{text}");
    let (ok, log) = sylva(&["species", "show", "Fagus sylvatica", "--dir", "mine"], d);
    assert!(ok && log.contains("id = \"beech\"") && !log.contains("my_beech"), "{log}");
    let (ok, log) = sylva(&["species", "show", "my_beech", "--dir", "mine"], d);
    assert!(ok && log.contains("id = \"my_beech\""), "{log}");
    let e = sylva::sim::Scenario::from_toml_str(&SC.replace("species = [\"my_beech\"]", "species = [\"beech\"]").replace("species = \"my_beech\"", "species = \"Fagus sylvatica\""), "sc.toml").unwrap_err().to_string();
    assert!(e.contains("start[0].species") && e.contains("species = \"beech\" (species[0])"), "{e}");
}

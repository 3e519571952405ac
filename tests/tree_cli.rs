//! `sylva tree grow` sizes the light-guided and Laplacian trees by species and age: the voxel
//! space spans the species' potential height at that age (Chapman–Richards, species file).

use std::process::Command;

fn grown_height(model: &str, species: &str, age: &str, dir: &std::path::Path) -> f32 {
    let out = dir.join(format!("{model}_{species}_{age}.glb"));
    let res = Command::new(env!("CARGO_BIN_EXE_sylva"))
        .args(["tree", "grow", "--species", species, "--model", model, "--age", age, "--seed", "3", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&res.stdout).into_owned();
    assert!(res.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&res.stderr));
    assert!(out.is_file() && out.with_extension("png").is_file());
    let line = stdout.lines().find(|l| l.contains("height")).unwrap();
    let h = line.split("height ").nth(1).unwrap().split(' ').next().unwrap();
    h.parse().unwrap()
}

#[test]
fn light_and_laplacian_trees_grow_with_age_to_the_species_height() {
    let dir = tempfile::tempdir().unwrap();
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    let beech = &lib.species[lib.find("beech").unwrap() as usize];
    for model in ["light", "laplacian"] {
        let young = grown_height(model, "beech", "10", dir.path());
        let old = grown_height(model, "beech", "60", dir.path());
        let target = beech.potential_height_m(60.0);
        assert!(old > 2.5 * young, "{model}: 60-year beech {old} m vs 10-year {young} m");
        assert!(old > 0.6 * target && old < 1.2 * target, "{model}: 60-year beech {old} m, species potential {target} m");
    }
}

#[test]
fn bad_obstacles_are_refused_naming_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.glb");
    for (arg, want) in [("box:2,0,0,1,1,1", "x0 < x1"), ("sphere:0,0,3,0", "sphere radius"), ("sphere:0,0,3,-1", "sphere radius"), ("box:0,0,NaN,1,1,1", "finite")] {
        let res = Command::new(env!("CARGO_BIN_EXE_sylva"))
            .args(["tree", "grow", "--species", "beech", "--model", "light", "--age", "5", "--obstacle", arg, "--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&res.stderr).into_owned();
        assert!(!res.status.success(), "{arg} accepted");
        assert!(err.contains("--obstacle") && err.contains(want), "{arg}: {err}");
        assert!(!out.exists());
    }
}

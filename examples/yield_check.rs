//! Pure, unmanaged stands of every shipped species planted at 1.5 m on a flat site at the
//! species' niche optimum (1 ha unless `--side M` is given): top height H100, stems/ha N,
//! basal area BA, quadratic mean DBH Dq (stems ≥ 7 cm DBH) and Reineke's SDI at ages 30, 50, 100
//! and 120, against the species' maximum-density line and, for beech and spruce, the yield
//! tables in tests/data/stands/.
//!
//! `cargo run --release --example yield_check [-- --side 100 --species beech,norway_spruce]`
use sylva::sim::density::{run_pure_stand, sdi};
use sylva::species::SpeciesLibrary;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: &str| args.iter().position(|a| a == k).and_then(|i| args.get(i + 1)).cloned();
    let side: f64 = arg("--side").map(|s| s.parse()).transpose()?.unwrap_or(100.0);
    let lib = SpeciesLibrary::embedded()?;
    let ids: Vec<String> = match arg("--species") {
        Some(s) => s.split(',').map(String::from).collect(),
        None => lib.species.iter().map(|s| s.id.clone()).collect(),
    };
    println!("species            age   H100     N     BA    Dq    SDI   SDImax   RD  | all stems: N   Dq   RD");
    for id in &ids {
        let sp = lib.species.iter().find(|s| &s.id == id).ok_or("unknown species")?;
        let rows = run_pure_stand(&lib, id, side, 1.5, 3.0, 150.0, 7)?;
        let ds = sp.life.density;
        for r in rows.iter().filter(|r| [30.0, 50.0, 100.0, 120.0, 150.0].contains(&r.age)) {
            let d = &r.d7;
            println!(
                "{:<18} {:>4} {:>6.1} {:>5.0} {:>6.1} {:>5.1} {:>6.0} {:>6.0} {:>5.2} | {:>6.0} {:>5.1} {:>5.2}",
                id,
                r.age,
                r.h100_m,
                d.n_ha,
                d.ba_m2_ha,
                d.dq_cm,
                sdi(d.n_ha, d.dq_cm, ds.reineke_slope as f64),
                ds.sdi_max,
                d.rd,
                r.all.n_ha,
                r.all.dq_cm,
                r.all.rd
            );
        }
    }
    Ok(())
}

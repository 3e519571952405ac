//! Pure, unmanaged stands of every shipped species planted at 1.5 m on a flat site at the
//! species' niche optimum (1 ha unless `--side M` is given): top height H100, stems/ha N,
//! basal area BA, quadratic mean DBH Dq (stems ≥ 7 cm DBH) and Reineke's SDI at ages 30, 50, 100,
//! 120 and 150, against the species' maximum-density line and, for beech, spruce, the oaks and
//! Scots pine, the yield tables in tests/data/stands/.
//!
//! `cargo run --release --example yield_check [-- --side 100 --species beech,norway_spruce --docs docs/density]`
//!
//! With `--docs DIR`, also writes `DIR/table.md` (simulated against tabulated H, N, BA, Dq at
//! ages 50 and 100) and `DIR/<species>.png` (ln N against ln Dq with the maximum-density line;
//! basal area over age with the tables).
use std::path::PathBuf;
use sylva::output::plot::{plot_panels_png, Panel, Series};
use sylva::sim::density::{max_stems, sdi};
use sylva::sim::pure_stand::{run_pure_stand, PureStandYear};
use sylva::species::SpeciesLibrary;

/// Yield-table rows (age, H, N, BA, Dq) of `file` (tests/data/stands/) at `site`: the
/// ForestElementsR tables (columns site_index, age, `h_col`, n_ha, ba_m2_ha, d_q_cm) or the NW-FVA
/// 2021 tables (Ekl, Alter, H100, N, G, Dg; `h_col` ignored).
fn table(file: &str, site: f64, h_col: &str) -> Vec<[f64; 5]> {
    let Ok(text) = std::fs::read_to_string(format!("{}/tests/data/stands/{file}", env!("CARGO_MANIFEST_DIR"))) else {
        return Vec::new();
    };
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap_or("").split(',').map(|h| h.trim_matches('"').to_string()).collect();
    let ix = |n: &str| head.iter().position(|h| h == n);
    let cols = if file.starts_with("nwfva") { ["Ekl", "Alter", "H100", "N", "G", "Dg"] } else { ["site_index", "age", h_col, "n_ha", "ba_m2_ha", "d_q_cm"] };
    let (Some(si), Some(a), Some(h), Some(n), Some(b), Some(d)) = (ix(cols[0]), ix(cols[1]), ix(cols[2]), ix(cols[3]), ix(cols[4]), ix(cols[5])) else {
        return Vec::new();
    };
    lines
        .filter_map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(f64::NAN)).collect();
            (f.get(si) == Some(&site)).then(|| [f[a], f[h], f[n], f[b], f[d]])
        })
        .collect()
}

/// The tables each species is compared with: (label, rows).
fn tables(id: &str) -> Vec<(&'static str, Vec<[f64; 5]>)> {
    match id {
        "beech" => vec![
            ("Wiedemann 1931 moderate, class I (h_q)", table("ForestElementsR_fe_ytable_beech_wiedemann_moderate_1931.csv", 1.0, "h_q_m")),
            ("NW-FVA 2021, class I (H100; heavy thinning)", table("nwfva2021_yieldtable_et_bu.csv", 1.0, "")),
        ],
        "norway_spruce" => vec![
            ("Wiedemann 1936/42 moderate, class I (h_q)", table("ForestElementsR_fe_ytable_spruce_wiedemann_moderate_1936_42.csv", 1.0, "h_q_m")),
            ("Assmann & Franz 1963 fully stocked, SI 36 (H100)", table("ForestElementsR_fe_ytable_spruce_assmann_franz_mean_yield_level_1963.csv", 36.0, "h_100_m")),
            ("NW-FVA 2021, class I (H100; heavy thinning)", table("nwfva2021_yieldtable_et_fi.csv", 1.0, "")),
        ],
        "sessile_oak" | "pedunculate_oak" => vec![("NW-FVA 2021 oak, class I (H100; heavy thinning)", table("nwfva2021_yieldtable_et_ei.csv", 1.0, ""))],
        "scots_pine" => vec![("NW-FVA 2021 pine, class I (H100; heavy thinning)", table("nwfva2021_yieldtable_et_ki.csv", 1.0, ""))],
        _ => vec![],
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: &str| args.iter().position(|a| a == k).and_then(|i| args.get(i + 1)).cloned();
    let side: f64 = arg("--side").map(|s| s.parse()).transpose()?.unwrap_or(100.0);
    let docs = arg("--docs").map(PathBuf::from);
    let lib = SpeciesLibrary::embedded()?;
    let ids: Vec<String> = match arg("--species") {
        Some(s) => s.split(',').map(String::from).collect(),
        None => lib.species.iter().map(|s| s.id.clone()).collect(),
    };
    let mut md = String::from(
        "| species | SDI_max, slope | age | H100 sim | N sim | BA sim | Dq sim | RD sim | table | H tab | N tab | BA tab | Dq tab |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    println!("species            age   H100     N     BA    Dq    SDI   SDImax   RD  | all stems: N   Dq   RD");
    for id in &ids {
        let sp = lib.species.iter().find(|s| &s.id == id).ok_or("unknown species")?;
        let rows = run_pure_stand(&lib, id, side, 1.5, 3.0, 150.0, 7)?;
        let ds = sp.life.density;
        for r in rows.iter().filter(|r| [30.0, 50.0, 100.0, 120.0, 150.0].contains(&r.age)) {
            let d = &r.d7;
            println!(
                "{:<18} {:>4} {:>6.1} {:>5.0} {:>6.1} {:>5.1} {:>6.0} {:>6.0} {:>5.2} | {:>6.0} {:>5.1} {:>5.2}",
                id, r.age, r.h100_m, d.n_ha, d.ba_m2_ha, d.dq_cm, sdi(d.n_ha, d.dq_cm, ds.reineke_slope as f64), ds.sdi_max, d.rd, r.all.n_ha, r.all.dq_cm, r.all.rd
            );
        }
        let tabs = tables(id);
        for age in [50.0, 100.0] {
            let Some(r) = rows.iter().find(|r| r.age == age) else { continue };
            let d = &r.d7;
            let sim = format!("| {id} | {:.0}, {:.3} | {age} | {:.1} | {:.0} | {:.1} | {:.1} | {:.2} ", ds.sdi_max, ds.reineke_slope, r.h100_m, d.n_ha, d.ba_m2_ha, d.dq_cm, d.rd);
            let mut any = false;
            for (lab, t) in &tabs {
                if let Some(t) = t.iter().find(|t| t[0] == age) {
                    md += &format!("{sim}| {lab} | {:.1} | {:.0} | {:.1} | {:.1} |\n", t[1], t[2], t[3], t[4]);
                    any = true;
                }
            }
            if !any {
                let nmax = max_stems(ds.sdi_max as f64, ds.reineke_slope as f64, d.dq_cm);
                md += &format!("{sim}| maximum-density line at the simulated Dq | — | {nmax:.0} | {:.1} | — |\n", nmax * std::f64::consts::FRAC_PI_4 * (d.dq_cm / 100.0).powi(2));
            }
        }
        if let Some(dir) = &docs {
            std::fs::create_dir_all(dir)?;
            figure(&dir.join(format!("{id}.png")), id, &rows, ds.sdi_max as f64, ds.reineke_slope as f64, &tabs)?;
        }
    }
    if let Some(dir) = &docs {
        let cmd = format!("cargo run --release --example yield_check -- --side {side} --docs {}", dir.display());
        let text = format!(
            "# Pure-stand density of every shipped species\n\nUnmanaged pure stands planted at 1.5 m (4,444/ha) at age 3 on a flat {side} m × {side} m site at the species' niche optimum (latitude 51° N), stems ≥ 7 cm DBH. RD: relative density against the species' maximum-density line (`life.density`; 1 = on the line). Tables are moderately thinned (Wiedemann), fully stocked (Assmann & Franz) or heavily thinned (NW-FVA 2021: today's crown thinnings, fewer and thicker stems); where no table is shipped, the maximum-density line's N and BA at the simulated Dq are given.\n\nMade by `{cmd}`.\n\n{md}"
        );
        let figs: String = ids.iter().map(|id| format!("\n### {id}\n\n![{id}]({id}.png)\n")).collect();
        std::fs::write(dir.join("table.md"), format!("{text}\n## Figures\n\nLeft: ln N against ln Dq (stems ≥ 7 cm) with the species' maximum-density line; right: basal area over age, with the yield tables where shipped.\n{figs}"))?;
    }
    Ok(())
}

/// ln N against ln Dq with the maximum-density line; basal area over age with the tables.
fn figure(path: &std::path::Path, id: &str, rows: &[PureStandYear], sdi_max: f64, slope: f64, tabs: &[(&str, Vec<[f64; 5]>)]) -> Result<(), Box<dyn std::error::Error>> {
    let traj: Vec<(f64, f64)> = rows.iter().filter(|r| r.d7.n_ha > 0.0 && r.d7.dq_cm > 0.0).map(|r| (r.d7.dq_cm.ln(), r.d7.n_ha.ln())).collect();
    let (d0, d1) = traj.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let line: Vec<(f64, f64)> = (0..=20).map(|k| d0 + (d1 - d0) * k as f64 / 20.0).map(|x| (x, max_stems(sdi_max, slope, x.exp()).ln())).collect();
    let colors = [[200, 60, 30], [60, 60, 200], [150, 40, 150]];
    let mut p1 = vec![
        Series { name: "Sylva, unmanaged (DBH ≥ 7 cm)".into(), points: traj, color: [30, 110, 40], markers: false },
        Series { name: format!("maximum density: SDI_max {sdi_max:.0}, slope {slope:.3}"), points: line, color: [0, 0, 0], markers: false },
    ];
    let mut p2 = vec![Series { name: "Sylva, unmanaged (DBH ≥ 7 cm)".into(), points: rows.iter().map(|r| (r.age, r.d7.ba_m2_ha)).collect(), color: [30, 110, 40], markers: false }];
    for ((lab, t), c) in tabs.iter().zip(colors) {
        p1.push(Series { name: (*lab).into(), points: t.iter().filter(|t| t[2] > 0.0 && t[4] > 0.0).map(|t| (t[4].ln(), t[2].ln())).collect(), color: c, markers: true });
        p2.push(Series { name: (*lab).into(), points: t.iter().filter(|t| t[0] <= 150.0 && t[3] > 0.0).map(|t| (t[0], t[3])).collect(), color: c, markers: true });
    }
    let panels = vec![
        Panel { title: format!("{id}: self-thinning"), x_label: "ln Dq (cm)".into(), y_label: "ln N (stems/ha)".into(), series: p1 },
        Panel { title: format!("{id}: basal area"), x_label: "age (years)".into(), y_label: "BA (m²/ha)".into(), series: p2 },
    ];
    plot_panels_png(path, &panels, 2, (1100, 450))?;
    Ok(())
}

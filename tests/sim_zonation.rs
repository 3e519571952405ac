//! Zonation on the real DEM shipped in terrains/ (a 3.2 km × 3.2 km window spanning 324–1071 m,
//! with cells below 550 m masked as water through `sea_level_m`): after 25 years of uniform
//! seed rain, spruce (cold-tolerant) stands higher on average than oak (warmth-loving), no tree
//! stands on a masked cell, and black alder (high F) is favoured on wet cells (high TWI).
mod common;

#[test]
fn spruce_high_oak_low_alder_wet() {
    let lib = common::embedded();
    let toml = common::ScenarioToml::new("zonation", 25, 21)
        .species(&["norway_spruce", "pedunculate_oak", "black_alder"])
        .line("light_cell_m = 10.0")
        .line("climate = { sea_level_m = 550.0 }")
        .default_terrain([200, 300, 40, 40])
        .seed_rain("norway_spruce", 400.0)
        .seed_rain("pedunculate_oak", 400.0)
        .seed_rain("black_alder", 400.0)
        .build();
    let (sc, mut w) = common::world_with(&toml, &lib);
    let masked = w.site.conditions.mask.data.iter().filter(|m| !**m).count();
    assert!(masked > 0, "the window should contain masked (water) cells");
    common::run(&sc, &mut w, 25);
    let t = &w.stand.trees;
    let (spruce, oak, alder) = (lib.find("norway_spruce").unwrap(), lib.find("pedunculate_oak").unwrap(), lib.find("black_alder").unwrap());
    for &c in &w.stand.cohorts.cell {
        assert!(w.site.light_site[c as usize] != u32::MAX, "regeneration cohort on a masked light cell {c}");
    }
    let mut sum = std::collections::BTreeMap::<u16, (f64, f64, usize)>::new();
    for i in 0..t.len() {
        let (c, r) = w.site.conditions.cell_at(t.x[i] as f64, t.y[i] as f64).expect("tree outside the terrain");
        assert!(*w.site.conditions.mask.get(c, r), "tree {} on a masked cell", t.id[i]);
        let e = sum.entry(t.species[i]).or_default();
        e.0 += *w.site.conditions.elevation_m.get(c, r) as f64;
        e.1 += *w.site.conditions.twi.get(c, r) as f64;
        e.2 += 1;
    }
    let mean = |s: u16| {
        let e = sum.get(&s).copied().unwrap_or_default();
        assert!(e.2 >= 30, "too few trees of species {s}: {}", e.2);
        (e.0 / e.2 as f64, e.1 / e.2 as f64, e.2)
    };
    let (ms, mo, ma) = (mean(spruce), mean(oak), mean(alder));
    let valid: Vec<usize> = (0..w.site.conditions.mask.len()).filter(|&k| w.site.conditions.mask.data[k]).collect();
    let twi_all = valid.iter().map(|&k| w.site.conditions.twi.data[k] as f64).sum::<f64>() / valid.len() as f64;
    eprintln!("spruce {ms:?} oak {mo:?} alder {ma:?}; mean TWI of the land {twi_all:.2}");
    // The margin to expect: the suitability-weighted mean elevation of the land per species
    // (seed rain is uniform and germination is proportional to suitability, so this is where
    // germinants stand; growth ∝ suitability only sharpens the contrast among trees ≥ 4 m).
    let weighted = |s: u16| {
        let p = w.pool_index(s).unwrap();
        let (mut se, mut sw) = (0.0, 0.0);
        for &k in &valid {
            let su = w.site.suitability[p][k] as f64;
            se += su * w.site.conditions.elevation_m.data[k] as f64;
            sw += su;
        }
        se / sw
    };
    let (es, eo) = (weighted(spruce), weighted(oak));
    eprintln!("suitability-weighted mean elevation: spruce {es:.0} m, oak {eo:.0} m (gap {:.0} m); simulated gap {:.0} m", es - eo, ms.0 - mo.0);
    assert!(es > eo, "suitability: spruce {es:.0} m should exceed oak {eo:.0} m");
    assert!(ms.0 - mo.0 >= es - eo, "spruce mean elevation {:.0} m should exceed oak's {:.0} m by at least the suitability-weighted gap {:.0} m", ms.0, mo.0, es - eo);
    assert!(ma.1 > twi_all && ma.1 > ms.1 && ma.1 > mo.1, "alder should stand on wetter cells: TWI alder {:.2}, spruce {:.2}, oak {:.2}, land {twi_all:.2}", ma.1, ms.1, mo.1);
}

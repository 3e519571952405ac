//! Round 46 (issue 32 item 6, trial 45 defect 13): the shipped species' summer foliage colours
//! are one summer canopy, not "painted by numbers". Their CIELAB hues and chromas lie in the
//! ranges of `species/README.md` (measured green-leaf spectra share one shape: Hovi et al.
//! 2022, Silva Fennica 56(2) 10683), and each tree's own tint (`job::scene::tree_tint`) varies
//! the value about its species' colour. Before round 46 the broadleaves' hues spanned 110°–150°
//! (the oaks olive, beech teal) and all species' 110°–189°, chroma 10–62: these tests fail there.

use sylva::job::scene::{tree_tint, TREE_HUE_SHIFT, TREE_VALUE_RANGE};
use sylva::species::SpeciesLibrary;

/// CIELAB (D65) lightness, chroma and hue (degrees) of an sRGB colour.
fn lch(c: [u8; 3]) -> (f64, f64, f64) {
    let lin = |v: u8| {
        let c = v as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let (r, g, b) = (lin(c[0]), lin(c[1]), lin(c[2]));
    let x = 0.4124 * r + 0.3576 * g + 0.1805 * b;
    let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    let z = 0.0193 * r + 0.1192 * g + 0.9505 * b;
    let f = |t: f64| if t > 0.008856 { t.cbrt() } else { 7.787 * t + 16.0 / 116.0 };
    let (fx, fy, fz) = (f(x / 0.95047), f(y), f(z / 1.08883));
    let (l, a, bb) = (116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz));
    (l, a.hypot(bb), bb.atan2(a).to_degrees().rem_euclid(360.0))
}

#[test]
fn cielab_of_known_colours() {
    // sRGB white: L 100, chroma 0; pure sRGB green: L 87.7, C 119.8, h 136.0 (CIE 15:2004 formulae)
    let (l, c, _) = lch([255, 255, 255]);
    assert!((l - 100.0).abs() < 0.1 && c < 0.5, "{l} {c}");
    let (l, c, h) = lch([0, 255, 0]);
    assert!((l - 87.7).abs() < 0.3 && (c - 119.8).abs() < 0.5 && (h - 136.0).abs() < 0.5, "{l} {c} {h}");
}

#[test]
fn summer_colours_are_one_canopy() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let mut broad = Vec::new();
    let mut all = Vec::new();
    for sp in &lib.species {
        let (l, c, h) = lch(sp.appearance.leaf_summer);
        eprintln!("{:18} {:?}: L {l:.0} C {c:.0} h {h:.0}", sp.id, sp.appearance.leaf_summer);
        assert!((18.0..=50.0).contains(&l), "{}: lightness {l:.1} outside 18–50 (green leaf reflectance 0.05–0.15 at 550 nm)", sp.id);
        assert!((15.0..=40.0).contains(&c), "{}: chroma {c:.1} outside 15–40", sp.id);
        if sp.identity.deciduous && !sp.id.contains("larch") {
            broad.push((h, sp.id.clone()));
        }
        all.push((h, sp.id.clone()));
    }
    let spread = |v: &[(f64, String)]| {
        let lo = v.iter().cloned().fold((f64::INFINITY, String::new()), |a, b| if b.0 < a.0 { b } else { a });
        let hi = v.iter().cloned().fold((f64::NEG_INFINITY, String::new()), |a, b| if b.0 > a.0 { b } else { a });
        (hi.0 - lo.0, lo, hi)
    };
    let (sb, lo, hi) = spread(&broad);
    assert!(broad.len() >= 10, "{} broadleaves", broad.len());
    assert!(sb <= 15.0, "broadleaves' summer hues span {sb:.1}° ({} {:.0}° to {} {:.0}°), over 15°", lo.1, lo.0, hi.1, hi.0);
    let (sa, lo, hi) = spread(&all);
    assert!(sa <= 25.0, "all species' summer hues span {sa:.1}° ({} {:.0}° to {} {:.0}°), over 25°", lo.1, lo.0, hi.1, hi.0);
    // the characters kept: birch lighter than beech, spruce darker than both
    let l_of = |id: &str| lch(lib.species[lib.find(id).unwrap() as usize].appearance.leaf_summer).0;
    assert!(l_of("silver_birch") > l_of("beech") + 3.0 && l_of("norway_spruce") + 8.0 < l_of("beech"));
}

#[test]
fn tree_tints_vary_value_within_their_range() {
    let n = 20_000u64;
    let mut mean = 0.0f64;
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for id in 0..n {
        let k = tree_tint(id * 7919 + 3);
        assert_eq!(k, tree_tint(id * 7919 + 3), "deterministic");
        // value on green; red and blue shifted oppositely by at most TREE_HUE_SHIFT
        assert!(k[1] >= TREE_VALUE_RANGE.0 && k[1] <= TREE_VALUE_RANGE.1, "{k:?}");
        let h = k[0] / k[1] - 1.0;
        assert!(h.abs() <= TREE_HUE_SHIFT + 1e-6 && ((k[2] / k[1] - 1.0) + h).abs() < 1e-5, "{k:?}");
        mean += k[1] as f64;
        lo = lo.min(k[1]);
        hi = hi.max(k[1]);
    }
    mean /= n as f64;
    // uniform over the range: mean at its middle, the ends reached
    assert!((mean - 1.0).abs() < 0.005, "mean value {mean}");
    assert!(lo < TREE_VALUE_RANGE.0 + 0.01 && hi > TREE_VALUE_RANGE.1 - 0.01, "{lo} {hi}");
}

//! Why Table 1's type 3 fails for some seed sets (issue 31, `docs/plastic_table1.md`):
//! `cargo run --release --example plastic_t3_probe -- [SEED0] [PAIRS]` (defaults 101, 50) runs
//! type 3 at the main wall distance as `examples/plastic_table1` does and prints the per-pair
//! distances of the four groups (sorted), each set's share of the Welch t denominator, the t of
//! T–G vs G–G with each group's most distant pair left out, and the node counts of the sets.
use sylva::structure::plastic::evaluation::{evaluate_type, welch_p, EvalOptions, MAIN_WALL_FRACTION, PAPER_TYPES};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed0: u64 = args.first().map(|s| s.parse()).transpose()?.unwrap_or(101);
    let pairs: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(50);
    let o = EvalOptions { pairs, wall_fraction: MAIN_WALL_FRACTION, seed0, ..EvalOptions::default() };
    let r = evaluate_type(PAPER_TYPES[2], &o)?;
    let n = pairs as f64;
    for (name, g) in [("T–G", &r.tg), ("G–G", &r.gg), ("T–O", &r.to), ("T–T", &r.tt)] {
        let mut v = g.values.clone();
        v.sort_by(f64::total_cmp);
        println!("{name}: mean {:.1} sd {:.1} min {:.1} q25 {:.1} median {:.1} q75 {:.1} max {:.1}", g.mean, g.sd, v[0], v[v.len() / 4], v[v.len() / 2], v[3 * v.len() / 4], v[v.len() - 1]);
        println!("  sorted: {}", v.iter().map(|x| format!("{x:.0}")).collect::<Vec<_>>().join(" "));
    }
    let (va, vb) = (r.tg.sd.powi(2) / n, r.gg.sd.powi(2) / n);
    println!("T–G vs G–G: t {:.2}, p {:.3}; share of the denominator: T–G {:.2}, G–G {:.2}", (r.tg.mean - r.gg.mean) / (va + vb).sqrt(), r.p_tg_gg, va / (va + vb), vb / (va + vb));
    let drop_max = |v: &[f64]| {
        let mut w = v.to_vec();
        w.sort_by(f64::total_cmp);
        w.pop();
        w
    };
    println!("p without the largest T–G: {:.3}; without the largest G–G: {:.3}", welch_p(&drop_max(&r.tg.values), &r.gg.values)?, welch_p(&r.tg.values, &drop_max(&r.gg.values))?);
    println!("T–O vs T–T: p {:.3}", r.p_to_tt);
    for (name, c) in ["O", "G", "T"].iter().zip(&r.nodes) {
        println!("nodes {name}: mean {:.0} min {} max {}", c.mean, c.min, c.max);
    }
    Ok(())
}

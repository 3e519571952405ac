//! Stateless random streams keyed by (seed, entity, year, phase).
//!
//! Every random draw in Sylva comes from a stream derived by hashing the scenario seed with the
//! identity of what is being decided (a tree id or cell index, the year, a phase salt), never from a
//! generator shared between threads. Results therefore do not depend on the number of threads or on
//! the order in which rayon schedules work (DESIGN.md, "Data flow rules").
//!
//! The mixer is SplitMix64 (Steele, Lea & Flood 2014, "Fast splittable pseudorandom number
//! generators", OOPSLA), whose finaliser is a bijection on 64-bit words with full avalanche.

/// Phase salts: distinct constants so that two phases never share a stream.
pub mod salt {
    /// Seed dispersal.
    pub const DISPERSAL: u64 = 0x5EED_D15B;
    /// Establishment of seedlings.
    pub const ESTABLISH: u64 = 0xE57A_B115;
    /// Mortality draws.
    pub const MORTALITY: u64 = 0xDEAD_0001;
    /// Windthrow draws.
    pub const WIND: u64 = 0x0057_0A11;
    /// Growth noise.
    pub const GROWTH: u64 = 0x0006_A0F7;
    /// Initial planting / seed sources.
    pub const INIT: u64 = 0x0001_417E;
    /// Tree architecture (skeleton growth).
    pub const ARCHITECTURE: u64 = 0xA7C4_17EC;
    /// Terrain generation.
    pub const TERRAIN: u64 = 0x7E22_A111;
    /// Management: planted positions and species, the order of patch cuts.
    pub const MANAGEMENT: u64 = 0x3A4A_6E77;
}

/// SplitMix64 finaliser: a bijective 64-bit mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The golden-ratio increment of SplitMix64 (Steele, Lea & Flood 2014).
pub const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// A deterministic value in [0, 1) of the key `x`: the first output of a SplitMix64 sequence
/// started at `x` ([`mix64`] of `x + GOLDEN_GAMMA`), its top 24 bits as a fraction. For
/// per-position variation in pictures (instances, ground cells), where [`hash`] of several
/// keys is not needed.
#[inline]
pub fn unit_f32(x: u64) -> f32 {
    (mix64(x.wrapping_add(GOLDEN_GAMMA)) >> 40) as f32 / (1u64 << 24) as f32
}

/// Hashes a list of keys into one 64-bit value (order matters).
#[inline]
pub fn hash(keys: &[u64]) -> u64 {
    let mut h = GOLDEN_GAMMA;
    for &k in keys {
        h = mix64(h ^ k.wrapping_add(GOLDEN_GAMMA));
    }
    h
}

/// A small deterministic generator (SplitMix64 sequence) started from a hashed key.
#[derive(Debug, Clone)]
pub struct Stream {
    state: u64,
}

impl Stream {
    /// A stream keyed by `(seed, entity, year, salt)`.
    pub fn new(seed: u64, entity: u64, year: u64, salt: u64) -> Self {
        Stream { state: hash(&[seed, entity, year, salt]) }
    }
    /// A stream keyed by any list of keys.
    pub fn from_keys(keys: &[u64]) -> Self {
        Stream { state: hash(keys) }
    }
    /// Next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix64(self.state)
    }
    /// Uniform in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform in [lo, hi).
    #[inline]
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    /// Uniform integer in [0, n); `n` must be > 0 (returns 0 for n = 0).
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 {
            return 0;
        }
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }
    /// Standard normal draw (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
    /// Exponential draw with the given mean.
    pub fn exponential(&mut self, mean: f64) -> f64 {
        -mean * (1.0 - self.uniform()).ln()
    }
    /// Poisson draw with mean `lambda` (Knuth for small means, normal approximation above 30).
    pub fn poisson(&mut self, lambda: f64) -> u64 {
        if lambda <= 0.0 {
            return 0;
        }
        if lambda > 30.0 {
            let x = lambda + lambda.sqrt() * self.normal();
            return x.round().max(0.0) as u64;
        }
        let l = (-lambda).exp();
        let mut k = 0u64;
        let mut p = 1.0;
        loop {
            p *= self.uniform();
            if p <= l {
                return k;
            }
            k += 1;
        }
    }
    /// True with probability `p`.
    #[inline]
    pub fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }
}

#[cfg(test)]
mod tests {

    /// `unit_f32` is the three copies it replaced (render::scene, render::instanced,
    /// render::terrain), bit for bit.
    #[test]
    fn unit_f32_equals_the_copies_it_replaced() {
        let old = |mut x: u64| {
            x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            let without_last = (x >> 40) as f32 / (1u64 << 24) as f32;
            x ^= x >> 31;
            let with_last = (x >> 40) as f32 / (1u64 << 24) as f32;
            assert_eq!(without_last.to_bits(), with_last.to_bits());
            with_last
        };
        let mut s = Stream::new(1, 2, 3, 4);
        for k in [0u64, 1, 42, u64::MAX, 0x5DEE_CE66].into_iter().chain((0..1000).map(|_| s.next_u64())) {
            assert_eq!(unit_f32(k).to_bits(), old(k).to_bits(), "{k}");
            assert!((0.0..1.0).contains(&unit_f32(k)));
        }
    }

    use super::*;

    #[test]
    fn streams_are_keyed_not_shared() {
        let a: Vec<u64> = (0..4).map(|_| 0).scan(Stream::new(42, 7, 3, salt::GROWTH), |s, _| Some(s.next_u64())).collect();
        let b: Vec<u64> = (0..4).map(|_| 0).scan(Stream::new(42, 7, 3, salt::GROWTH), |s, _| Some(s.next_u64())).collect();
        assert_eq!(a, b);
        let c = Stream::new(42, 8, 3, salt::GROWTH).next_u64();
        assert_ne!(a[0], c);
    }

    #[test]
    fn uniform_mean_is_half() {
        let mut s = Stream::new(1, 2, 3, 4);
        let n = 100_000;
        let m: f64 = (0..n).map(|_| s.uniform()).sum::<f64>() / n as f64;
        assert!((m - 0.5).abs() < 0.01, "mean {m}");
        let mut s = Stream::new(1, 2, 3, 5);
        let pm: f64 = (0..n).map(|_| s.poisson(4.0) as f64).sum::<f64>() / n as f64;
        assert!((pm - 4.0).abs() < 0.05, "poisson mean {pm}");
    }
}

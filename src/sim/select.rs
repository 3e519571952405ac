//! Selection over parts by summed counts (issue 37): the `k`-th smallest of values held by the
//! ranks of a tiled run (or by one process), found with nothing per value passed, and the
//! reduction it takes. Used by the stand table's top height (`sim::stats`) and the site's
//! median insolation (`sim::world`); a module of its own so that neither imports the other.

/// Order-preserving key of an f32 under [`f32::total_cmp`] (as an unsigned integer).
#[inline]
pub(crate) fn total_key(v: f32) -> u32 {
    let b = v.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// The f32 of a [`total_key`].
#[inline]
pub(crate) fn from_total_key(k: u32) -> f32 {
    f32::from_bits(if k >> 31 == 1 { k & 0x7fff_ffff } else { !k })
}

/// An element-wise sum of u64 words over every part of a stand (the ranks of a tiled run:
/// `Transport::all_sum`, an MPI_Allreduce): every part passes words of the same length and
/// gets the sums. One process: the words themselves ([`alone`]).
pub type Reduce<'a> = dyn FnMut(Vec<u64>) -> crate::Result<Vec<u64>> + 'a;

/// The [`Reduce`] of a stand in one part.
pub fn alone(v: Vec<u64>) -> crate::Result<Vec<u64>> {
    Ok(v)
}

/// Widths (bits) of the digits [`kth_smallest_by`] selects by, from the top of the 32-bit key.
const DIGITS_32: [u32; 3] = [11, 11, 10];

/// The `k`-th smallest (0-based) of values held in parts (the ranks of a tiled run, or one
/// part), in `f32::total_cmp`'s order, each part passing its own `values`; `None` when the parts
/// hold `k` values or fewer. Nothing per value is passed: a radix selection over the monotone
/// 32-bit key of the values ([`total_key`]) digit by digit ([`DIGITS_32`]: 11, 11, 10 bits):
/// every part counts its candidates per digit value, the counts are summed (`reduce`), and
/// every part keeps the candidates of the digit value where the `k`-th falls. Three reductions
/// of 1,024–2,048 counts; the value found is the one a sort of all the parts' values puts at
/// `k`, bit for bit (e.g. the site's median insolation, `sim::world::insolation_median_by`).
///
/// Errors: those of `reduce`.
pub fn kth_smallest_by(values: &[f32], k: u64, reduce: &mut Reduce) -> crate::Result<Option<f32>> {
    let mut cand: Vec<u32> = values.iter().map(|&v| total_key(v)).collect();
    let (mut k, mut shift, mut prefix) = (k, 32u32, 0u32);
    for &w in DIGITS_32.iter() {
        shift -= w;
        let mask = (1u32 << w) - 1;
        let mut hist = vec![0u64; 1 << w];
        for &key in &cand {
            hist[((key >> shift) & mask) as usize] += 1;
        }
        let hist = reduce(hist)?;
        let mut acc = 0u64;
        let Some(pick) = (0..hist.len()).find(|&b| {
            if acc + hist[b] > k {
                return true;
            }
            acc += hist[b];
            false
        }) else {
            return Ok(None);
        };
        k -= acc;
        prefix |= (pick as u32) << shift;
        cand.retain(|&key| (key >> shift) & mask == pick as u32);
    }
    Ok(Some(from_total_key(prefix)))
}

//! Stable parallel counting sort ("bucketing") of items by a small integer key: the spatial
//! hash of the trees, the crowding cells. Deterministic whatever the thread count: the result
//! is exactly the serial stable counting sort (items of one key in ascending input order).
//!
//! Method: the input is cut into fixed chunks and the key range into fixed bands; each chunk
//! (in parallel) splits its items into per-band lists in input order; each band (in parallel)
//! then counts its keys and scatters its lists, chunk by chunk, into its own slice of the
//! output. Cost O(n + keys) work, two passes over the items; extra memory one `(key, item)`
//! pair per item for the lists.

use rayon::prelude::*;

/// Items per chunk of the first pass.
const CHUNK: usize = 1 << 16;

/// Stable counting sort of the items `item(i)`, `i` in `0..n`, by `key(i)` (< `nkeys`).
/// Returns `(start, items)`: the items of key `k` are `items[start[k]..start[k + 1]]`, in
/// ascending `i`; `start` has `nkeys + 1` entries, `start[nkeys] = n`. Panics when a key is
/// `nkeys` or more, or when `n` does not fit in `u32`.
pub fn bucket<T, K, I>(n: usize, nkeys: usize, key: K, item: I) -> (Vec<u32>, Vec<T>)
where
    T: Copy + Send + Sync + Default,
    K: Fn(usize) -> u32 + Sync,
    I: Fn(usize) -> T + Sync,
{
    assert!(n <= u32::MAX as usize, "bucket: {n} items do not fit u32 offsets");
    let mut start = vec![0u32; nkeys + 1];
    if n == 0 || nkeys == 0 {
        return (start, Vec::new());
    }
    // bands of keys: about 64 per thread's worth of work, at least 4096 keys each
    let band_keys = nkeys.div_ceil(256).max(4096).min(nkeys);
    let nbands = nkeys.div_ceil(band_keys);
    // pass 1: per chunk, per band, the (key, item) pairs in input order
    let lists: Vec<Vec<Vec<(u32, T)>>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out: Vec<Vec<(u32, T)>> = vec![Vec::new(); nbands];
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                let k = key(i);
                assert!((k as usize) < nkeys, "bucket: key {k} out of 0..{nkeys}");
                out[k as usize / band_keys].push((k, item(i)));
            }
            out
        })
        .collect();
    // band sizes, then each band's slices of `start` and of the output
    let sizes: Vec<usize> = (0..nbands).map(|b| lists.iter().map(|l| l[b].len()).sum()).collect();
    let mut items = vec![T::default(); n];
    let mut jobs = Vec::with_capacity(nbands);
    {
        let (mut s_rest, mut i_rest): (&mut [u32], &mut [T]) = (&mut start[..nkeys], &mut items[..]);
        let mut offset = 0u32;
        for (b, &size) in sizes.iter().enumerate() {
            let nk = band_keys.min(nkeys - b * band_keys);
            let (s, sr) = std::mem::take(&mut s_rest).split_at_mut(nk);
            let (it, ir) = std::mem::take(&mut i_rest).split_at_mut(size);
            s_rest = sr;
            i_rest = ir;
            jobs.push((b, offset, s, it));
            offset += size as u32;
        }
    }
    // pass 2: per band, count, prefix, scatter (chunk order, then input order: stable)
    jobs.into_par_iter().for_each(|(b, offset, s, it)| {
        let k0 = (b * band_keys) as u32;
        let mut count = vec![0u32; s.len()];
        for l in &lists {
            for &(k, _) in &l[b] {
                count[(k - k0) as usize] += 1;
            }
        }
        let mut acc = 0u32;
        for (j, c) in count.iter_mut().enumerate() {
            s[j] = offset + acc;
            let n = *c;
            *c = acc;
            acc += n;
        }
        for l in &lists {
            for &(k, v) in &l[b] {
                let p = &mut count[(k - k0) as usize];
                it[*p as usize] = v;
                *p += 1;
            }
        }
    });
    start[nkeys] = n as u32;
    (start, items)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equals_the_serial_stable_counting_sort() {
        for (n, nkeys) in [(0usize, 5usize), (1, 1), (10, 3), (200_000, 7), (300_001, 100_003)] {
            let keys: Vec<u32> = (0..n).map(|i| ((i as u64).wrapping_mul(2_654_435_761) % nkeys as u64) as u32).collect();
            let (start, items) = bucket(n, nkeys, |i| keys[i], |i| i as u32);
            // serial reference
            let mut s = vec![0u32; nkeys + 1];
            for &k in &keys {
                s[k as usize + 1] += 1;
            }
            for k in 0..nkeys {
                s[k + 1] += s[k];
            }
            let mut fill = s.clone();
            let mut want = vec![0u32; n];
            for (i, &k) in keys.iter().enumerate() {
                want[fill[k as usize] as usize] = i as u32;
                fill[k as usize] += 1;
            }
            assert_eq!(start, s, "n {n}, keys {nkeys}");
            assert_eq!(items, want, "n {n}, keys {nkeys}");
        }
    }
}

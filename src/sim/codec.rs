//! The one little-endian binary codec of the simulation: checkpoints ([`super::checkpoint`])
//! and the messages between tiles ([`super::tiles`]) are written with [`Enc`] and read with
//! [`Dec`]. Numbers are little-endian, floats with their exact bits; a run of values is a `u64`
//! count then the values ([`Enc::f32s`], [`Enc::u32s`]) where the format says so, strings a
//! `u64` byte count then UTF-8 bytes. Every read checks the length; what a short or malformed
//! input is called is the caller's ([`Dec::new`] takes the mapping from [`Short`] to its
//! error), so a checkpoint names its file and a tile message its rank.

use crate::error::{Error, Result};

/// Where an [`Enc`] puts its bytes: a `Vec<u8>`, a [`Count`] (the length only, known before
/// writing), or a caller's writer.
pub trait Sink {
    /// Appends `b`.
    fn put(&mut self, b: &[u8]);
    /// Counts `n` bytes without being given them (only a counter accepts this; the others
    /// return false and are given the bytes).
    fn skip(&mut self, _n: u64) -> bool {
        false
    }
}

impl Sink for Vec<u8> {
    fn put(&mut self, b: &[u8]) {
        self.extend_from_slice(b);
    }
}

impl<S: Sink + ?Sized> Sink for &mut S {
    fn put(&mut self, b: &[u8]) {
        (**self).put(b);
    }
    fn skip(&mut self, n: u64) -> bool {
        (**self).skip(n)
    }
}

/// Counts bytes.
pub struct Count(pub u64);

impl Sink for Count {
    fn put(&mut self, b: &[u8]) {
        self.0 += b.len() as u64;
    }
    fn skip(&mut self, n: u64) -> bool {
        self.0 += n;
        true
    }
}

/// Little-endian encoding into a [`Sink`]; arrays go through a small buffer, so a store of
/// millions of trees is streamed to a file without a copy of it in memory.
pub struct Enc<S: Sink>(pub S);

impl<S: Sink> Enc<S> {
    /// Raw bytes.
    pub fn bytes(&mut self, b: &[u8]) {
        self.0.put(b);
    }
    /// A `u16`.
    pub fn u16(&mut self, v: u16) {
        self.0.put(&v.to_le_bytes());
    }
    /// A `u64`.
    pub fn u64(&mut self, v: u64) {
        self.0.put(&v.to_le_bytes());
    }
    /// An `f32` (its bits).
    pub fn f32(&mut self, v: f32) {
        self.0.put(&v.to_bits().to_le_bytes());
    }
    /// An `f64` (its bits).
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    /// Each value of `v` as `f` encodes it, without a count.
    pub fn each<T: Copy, const N: usize>(&mut self, v: &[T], f: impl Fn(T) -> [u8; N]) {
        // the counting pass needs only the length
        if self.0.skip((N * v.len()) as u64) {
            return;
        }
        let mut buf = Vec::with_capacity(N * 4096);
        for c in v.chunks(4096) {
            buf.clear();
            for &x in c {
                buf.extend_from_slice(&f(x));
            }
            self.0.put(&buf);
        }
    }
    /// A `u64` count, then the `f32`s.
    pub fn f32s(&mut self, v: &[f32]) {
        self.u64(v.len() as u64);
        self.each(v, |x| x.to_bits().to_le_bytes());
    }
    /// A `u64` count, then the `u32`s.
    pub fn u32s(&mut self, v: &[u32]) {
        self.u64(v.len() as u64);
        self.each(v, |x| x.to_le_bytes());
    }
    /// A `u64` byte count, then the UTF-8 bytes.
    pub fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.0.put(s.as_bytes());
    }
}

/// Why a [`Dec`] read failed; the caller's mapping turns it into its error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Short {
    /// The input ends before a value.
    End {
        /// Bytes of the input.
        len: usize,
        /// Where the value starts.
        at: usize,
        /// Bytes the value needs.
        need: usize,
    },
    /// A count of more items than the rest of the input holds.
    Count {
        /// The count.
        n: usize,
        /// The byte after the count.
        at: usize,
        /// Bytes left after the count.
        rest: usize,
    },
    /// A string that is not UTF-8.
    Utf8 {
        /// The byte after the string.
        at: usize,
    },
}

impl Short {
    /// The byte where reading stopped.
    pub fn at(&self) -> usize {
        match *self {
            Short::End { at, .. } | Short::Count { at, .. } | Short::Utf8 { at } => at,
        }
    }
}

/// Reader of what [`Enc`] wrote; every read checks the length.
pub struct Dec<'a> {
    b: &'a [u8],
    p: usize,
    fail: &'a dyn Fn(Short) -> Error,
}

impl<'a> Dec<'a> {
    /// Reads `b` from its start; `fail` names a failed read.
    pub fn new(b: &'a [u8], fail: &'a dyn Fn(Short) -> Error) -> Self {
        Dec { b, p: 0, fail }
    }
    /// Reads `b` from byte `p`.
    pub fn at(b: &'a [u8], p: usize, fail: &'a dyn Fn(Short) -> Error) -> Self {
        Dec { b, p, fail }
    }
    /// The next byte to read.
    pub fn pos(&self) -> usize {
        self.p
    }
    /// Bytes not read yet.
    pub fn rest(&self) -> usize {
        self.b.len() - self.p.min(self.b.len())
    }
    /// The caller's error for `s`.
    pub fn fail(&self, s: Short) -> Error {
        (self.fail)(s)
    }
    /// The next `n` bytes.
    pub fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        if self.rest() < n {
            return Err(self.fail(Short::End { len: self.b.len(), at: self.p, need: n }));
        }
        let s = &self.b[self.p..self.p + n];
        self.p += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }
    /// A `u16`.
    pub fn u16(&mut self) -> Result<u16> {
        Ok(u16::from_le_bytes(self.array()?))
    }
    /// A `u32`.
    pub fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    /// A `u64`.
    pub fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    /// An `f32`.
    pub fn f32(&mut self) -> Result<f32> {
        Ok(f32::from_bits(self.u32()?))
    }
    /// An `f64`.
    pub fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A `u64` count of items of `item_bytes` bytes each, refused when the rest of the input
    /// cannot hold them.
    pub fn count(&mut self, item_bytes: usize) -> Result<usize> {
        let n = self.u64()? as usize;
        if n.saturating_mul(item_bytes) > self.rest() {
            return Err(self.fail(Short::Count { n, at: self.p, rest: self.rest() }));
        }
        Ok(n)
    }
    /// `n` values of `N` bytes each, decoded by `f` (the whole run at once where the input
    /// holds it, else value by value, so that a short input fails at the value it ends in).
    fn run<T, const N: usize>(&mut self, n: usize, f: impl Fn([u8; N]) -> T) -> Result<Vec<T>> {
        if n.saturating_mul(N) <= self.rest() {
            let s = self.take(N * n)?;
            return Ok(s.chunks_exact(N).map(|c| f(c.try_into().expect("chunks of N"))).collect());
        }
        (0..n).map(|_| self.array().map(&f)).collect()
    }
    /// `n` `u16`s.
    pub fn u16s_n(&mut self, n: usize) -> Result<Vec<u16>> {
        self.run(n, u16::from_le_bytes)
    }
    /// `n` `u64`s.
    pub fn u64s_n(&mut self, n: usize) -> Result<Vec<u64>> {
        self.run(n, u64::from_le_bytes)
    }
    /// `n` `f32`s.
    pub fn f32s_n(&mut self, n: usize) -> Result<Vec<f32>> {
        self.run(n, |b| f32::from_bits(u32::from_le_bytes(b)))
    }
    /// A `u64` count, then the `f32`s ([`Enc::f32s`]).
    pub fn f32s(&mut self) -> Result<Vec<f32>> {
        let n = self.count(4)?;
        self.f32s_n(n)
    }
    /// A `u64` count, then the `u32`s ([`Enc::u32s`]).
    pub fn u32s(&mut self) -> Result<Vec<u32>> {
        let n = self.count(4)?;
        self.run(n, u32::from_le_bytes)
    }
    /// A `u64` byte count, then UTF-8 bytes ([`Enc::str`]).
    pub fn str(&mut self) -> Result<String> {
        let n = self.count(1)?;
        let s = self.take(n)?;
        String::from_utf8(s.to_vec()).map_err(|_| self.fail(Short::Utf8 { at: self.p }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_enc_writes_dec_reads_and_short_input_fails_where_it_ends() {
        let mut e = Enc(Vec::new());
        e.u64(7);
        e.u16(3);
        e.f32(-1.5);
        e.f64(f64::NAN);
        e.f32s(&[1.0, 2.0]);
        e.u32s(&[9]);
        e.str("bö");
        e.each(&[5u64, 6], |x| x.to_le_bytes());
        let mut count = Count(0);
        let mut c = Enc(&mut count);
        c.u64(7);
        c.f32s(&[1.0, 2.0]);
        assert_eq!(count.0, 8 + 8 + 8);
        let fail = |s: Short| Error::Exchange { peer: 0, reason: format!("{s:?}") };
        let b = e.0;
        let mut d = Dec::new(&b, &fail);
        assert_eq!(d.u64().unwrap(), 7);
        assert_eq!(d.u16().unwrap(), 3);
        assert_eq!(d.f32().unwrap(), -1.5);
        assert!(d.f64().unwrap().is_nan());
        assert_eq!(d.f32s().unwrap(), vec![1.0, 2.0]);
        assert_eq!(d.u32s().unwrap(), vec![9]);
        assert_eq!(d.str().unwrap(), "bö");
        assert_eq!(d.u64s_n(2).unwrap(), vec![5, 6]);
        assert_eq!(d.rest(), 0);
        let e = d.u16().unwrap_err().to_string();
        assert!(e.contains(&format!("{:?}", Short::End { len: b.len(), at: b.len(), need: 2 })), "{e}");
        let mut d = Dec::new(&b[..10], &fail);
        d.u64().unwrap();
        let e = d.f32s_n(1).unwrap_err().to_string();
        assert!(e.contains(&format!("{:?}", Short::End { len: 10, at: 8, need: 4 })), "{e}");
        let mut big = Enc(Vec::new());
        big.u64(1000);
        big.f32(1.0);
        let mut d = Dec::new(&big.0, &fail);
        let e = d.f32s().unwrap_err().to_string();
        assert!(e.contains(&format!("{:?}", Short::Count { n: 1000, at: 8, rest: 4 })), "{e}");
    }
}

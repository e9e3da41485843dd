//! Little-endian encoding of what ranks send each other (particles, cells,
//! tets, image tiles): a [`Writer`] appends, a [`Reader`] takes in the same
//! order and fails with a [`WireError`] — never a panic — on short input.

use voxless_core::{Aabb, Vec3};

/// A message ended before a value it should hold.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("message ends inside a value (at byte {at} of {len})")]
pub struct WireError {
    pub at: usize,
    pub len: usize,
}

/// Appends values to a byte buffer.
#[derive(Clone, Debug, Default)]
pub struct Writer(Vec<u8>);

impl Writer {
    pub fn new() -> Self {
        Writer(Vec::new())
    }
    pub fn with_capacity(n: usize) -> Self {
        Writer(Vec::with_capacity(n))
    }
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    pub fn len(&self) -> usize {
        self.0.len()
    }
    pub fn into_bytes(self) -> Vec<u8> {
        self.0
    }
    pub fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    pub fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn vec3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }
    pub fn aabb(&mut self, b: &Aabb) {
        self.vec3(b.min);
        self.vec3(b.max);
    }
    /// A length-prefixed run of `f32`s.
    pub fn f32s(&mut self, v: &[f32]) {
        self.u64(v.len() as u64);
        self.0.reserve(4 * v.len());
        for x in v {
            self.f32(*x);
        }
    }
    /// A length-prefixed run of `f64`s.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for x in v {
            self.f64(*x);
        }
    }
    /// A length-prefixed UTF-8 string.
    pub fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
    /// Length-prefixed bytes.
    pub fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        self.0.extend_from_slice(b);
    }
}

/// Takes values from a byte buffer in the order a [`Writer`] wrote them.
#[derive(Clone, Debug)]
pub struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub fn new(buf: &'a [u8]) -> Self {
        Reader { buf, pos: 0 }
    }
    /// Whether every byte has been taken.
    pub fn is_done(&self) -> bool {
        self.pos >= self.buf.len()
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], WireError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len());
        match end {
            Some(end) => {
                let s = &self.buf[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(WireError {
                at: self.pos,
                len: self.buf.len(),
            }),
        }
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], WireError> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }
    pub fn u8(&mut self) -> Result<u8, WireError> {
        Ok(self.take(1)?[0])
    }
    pub fn u32(&mut self) -> Result<u32, WireError> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub fn u64(&mut self) -> Result<u64, WireError> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    pub fn f32(&mut self) -> Result<f32, WireError> {
        Ok(f32::from_le_bytes(self.array()?))
    }
    pub fn f64(&mut self) -> Result<f64, WireError> {
        Ok(f64::from_le_bytes(self.array()?))
    }
    pub fn vec3(&mut self) -> Result<Vec3, WireError> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    pub fn aabb(&mut self) -> Result<Aabb, WireError> {
        Ok(Aabb::new(self.vec3()?, self.vec3()?))
    }
    /// A length, checked against what is left (`unit` bytes per item), so a
    /// corrupt length cannot ask for a huge allocation.
    fn len(&mut self, unit: usize) -> Result<usize, WireError> {
        let n = self.u64()?;
        let left = (self.buf.len() - self.pos) as u64;
        if n.saturating_mul(unit.max(1) as u64) > left {
            return Err(WireError {
                at: self.pos,
                len: self.buf.len(),
            });
        }
        Ok(n as usize)
    }
    pub fn f32s(&mut self) -> Result<Vec<f32>, WireError> {
        let n = self.len(4)?;
        let b = self.take(4 * n)?;
        Ok(b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
    pub fn f64s(&mut self) -> Result<Vec<f64>, WireError> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    pub fn bytes(&mut self) -> Result<&'a [u8], WireError> {
        let n = self.len(1)?;
        self.take(n)
    }
    pub fn str(&mut self) -> Result<String, WireError> {
        Ok(String::from_utf8_lossy(self.bytes()?).into_owned())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_come_back_in_order_and_short_input_is_an_error() {
        let mut w = Writer::new();
        w.u32(7);
        w.f32s(&[1.0, -2.5]);
        w.str("rank");
        w.aabb(&Aabb::new(Vec3::ZERO, Vec3::ONE));
        let b = w.into_bytes();
        let mut r = Reader::new(&b);
        assert_eq!(r.u32().unwrap(), 7);
        assert_eq!(r.f32s().unwrap(), vec![1.0, -2.5]);
        assert_eq!(r.str().unwrap(), "rank");
        assert_eq!(r.aabb().unwrap().max, Vec3::ONE);
        assert!(r.is_done());
        assert!(r.u8().is_err());
        // A corrupt length fails instead of allocating.
        let mut w = Writer::new();
        w.u64(u64::MAX);
        assert!(Reader::new(&w.into_bytes()).f32s().is_err());
    }
}

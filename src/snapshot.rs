//! The byte format of saved system state: a header (magic, format version,
//! the system's fingerprint, payload length), the payload, and a checksum.
//! Reading never trusts the blob: every length is bounds-checked and a
//! truncated, corrupt or foreign blob is refused with `InvalidState`.

use crate::error::{Error, ErrorKind, Result};
use crate::rng::mix64;

const MAGIC: &[u8; 8] = b"PLUMAGE\x01";
/// Version of the payload layout; bump on any change. 4: the staleness
/// keeps each feather's recorded placements (net motion). 5: the frame
/// figures hold the neighbourhood time and the level count. 6: no timings
/// (the blob is byte-reproducible). 7: the settling flags. 9: the frame
/// figures hold the feathers kept in place. Blobs of another version are
/// refused.
pub(crate) const FORMAT_VERSION: u32 = 9;
const HEADER_LEN: usize = 8 + 4 + 8 + 8;
const TRAILER_LEN: usize = 8;

/// Appends little-endian values to a byte buffer.
#[derive(Default)]
pub struct Writer {
    bytes: Vec<u8>,
}

impl Writer {
    /// Starts a blob for a system with `fingerprint`.
    pub fn new(fingerprint: u64) -> Self {
        let mut bytes = Vec::new();
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&fingerprint.to_le_bytes());
        bytes.extend_from_slice(&0u64.to_le_bytes()); // payload length, patched by finish
        Self { bytes }
    }

    /// Bytes written so far (header included).
    pub fn len(&self) -> usize {
        self.bytes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
    pub fn u8(&mut self, v: u8) {
        self.bytes.push(v);
    }
    pub fn u32(&mut self, v: u32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    pub fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    /// A length-prefixed slice of f32.
    pub fn f32s(&mut self, v: &[f32]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|&x| self.f32(x));
    }
    /// A length-prefixed slice of u32.
    pub fn u32s(&mut self, v: &[u32]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|&x| self.u32(x));
    }

    /// Patches the payload length and appends the checksum.
    pub fn finish(mut self) -> Vec<u8> {
        let payload = (self.bytes.len() - HEADER_LEN) as u64;
        self.bytes[20..28].copy_from_slice(&payload.to_le_bytes());
        let sum = checksum(&self.bytes);
        self.bytes.extend_from_slice(&sum.to_le_bytes());
        self.bytes
    }
}

/// Reads values back, failing with `InvalidState` on any inconsistency.
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// Checks the header, the checksum and the fingerprint, and positions
    /// the reader at the start of the payload.
    pub fn open(blob: &'a [u8], fingerprint: u64) -> Result<Self> {
        if blob.len() < HEADER_LEN + TRAILER_LEN {
            return Err(invalid(format!("state blob of {} bytes is too short to be a Plumage state", blob.len())));
        }
        if &blob[..8] != MAGIC {
            return Err(invalid("not a Plumage state blob (bad magic)"));
        }
        let version = u32::from_le_bytes(blob[8..12].try_into().unwrap());
        if version != FORMAT_VERSION {
            return Err(invalid(format!("state format {version} is not the supported {FORMAT_VERSION}")));
        }
        let payload = u64::from_le_bytes(blob[20..28].try_into().unwrap());
        let expected = (HEADER_LEN as u64).checked_add(payload).and_then(|n| n.checked_add(TRAILER_LEN as u64));
        if expected != Some(blob.len() as u64) {
            return Err(invalid(format!(
                "state blob is truncated or padded ({} bytes, header says {:?})",
                blob.len(),
                expected
            )));
        }
        let body = &blob[..blob.len() - TRAILER_LEN];
        let stored = u64::from_le_bytes(blob[blob.len() - TRAILER_LEN..].try_into().unwrap());
        if checksum(body) != stored {
            return Err(invalid("state blob is corrupt (checksum mismatch)"));
        }
        let theirs = u64::from_le_bytes(blob[12..20].try_into().unwrap());
        if theirs != fingerprint {
            return Err(invalid("state blob belongs to another system (different mesh, roots or configuration)"));
        }
        Ok(Self { bytes: body, at: HEADER_LEN })
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| invalid("state blob ends early"))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    pub fn u8(&mut self) -> Result<u8> {
        Ok(self.take(1)?[0])
    }
    pub fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    pub fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    pub fn f32(&mut self) -> Result<f32> {
        Ok(f32::from_bits(self.u32()?))
    }
    pub fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A length-prefixed f32 slice into `out` (cleared first); the length must be `expect` when given.
    pub fn f32s_into(&mut self, out: &mut Vec<f32>, expect: Option<usize>) -> Result<()> {
        let n = self.len(4, expect)?;
        out.clear();
        for _ in 0..n {
            out.push(self.f32()?);
        }
        Ok(())
    }
    /// A length-prefixed u32 slice into `out` (cleared first).
    pub fn u32s_into(&mut self, out: &mut Vec<u32>, expect: Option<usize>) -> Result<()> {
        let n = self.len(4, expect)?;
        out.clear();
        for _ in 0..n {
            out.push(self.u32()?);
        }
        Ok(())
    }
    /// A length prefix, checked against what is left and against `expect`.
    pub fn len(&mut self, elem_bytes: usize, expect: Option<usize>) -> Result<usize> {
        let n = self.u64()?;
        let left = (self.bytes.len() - self.at) as u64;
        if n.checked_mul(elem_bytes as u64).is_none_or(|b| b > left) {
            return Err(invalid("state blob holds a length larger than its data"));
        }
        if expect.is_some_and(|e| e as u64 != n) {
            return Err(invalid(format!("state blob holds {n} elements where this system has {}", expect.unwrap())));
        }
        Ok(n as usize)
    }
    /// Fails unless every byte was consumed.
    pub fn finish(self) -> Result<()> {
        if self.at == self.bytes.len() { Ok(()) } else { Err(invalid("state blob has trailing bytes")) }
    }
}

fn invalid(message: impl Into<String>) -> Error {
    Error::new(ErrorKind::InvalidState, message)
}

/// A 64-bit checksum over 8-byte words (not cryptographic; catches damage).
fn checksum(bytes: &[u8]) -> u64 {
    let mut h = 0x6A09_E667_F3BC_C908u64 ^ bytes.len() as u64;
    for chunk in bytes.chunks(8) {
        let mut w = [0u8; 8];
        w[..chunk.len()].copy_from_slice(chunk);
        h = mix64(h ^ u64::from_le_bytes(w)).rotate_left(5);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<u8> {
        let mut w = Writer::new(42);
        w.u32(7);
        w.f32s(&[1.0, 2.5, -3.0]);
        w.f64(0.25);
        w.finish()
    }

    #[test]
    fn round_trip() {
        let blob = sample();
        let mut r = Reader::open(&blob, 42).unwrap();
        assert_eq!(r.u32().unwrap(), 7);
        let mut v = Vec::new();
        r.f32s_into(&mut v, Some(3)).unwrap();
        assert_eq!(v, [1.0, 2.5, -3.0]);
        assert_eq!(r.f64().unwrap(), 0.25);
        r.finish().unwrap();
    }

    #[test]
    fn an_older_format_is_refused_by_name() {
        let mut blob = sample();
        let older = FORMAT_VERSION - 1;
        blob[8..12].copy_from_slice(&older.to_le_bytes());
        let err = Reader::open(&blob, 42).err().unwrap();
        assert_eq!(err.kind(), ErrorKind::InvalidState);
        let expected = format!("state format {older} is not the supported {FORMAT_VERSION}");
        assert!(err.to_string().contains(&expected), "{err}");
    }

    #[test]
    fn damaged_blobs_are_refused() {
        let blob = sample();
        for cut in [0, 5, HEADER_LEN, blob.len() - 1] {
            assert_eq!(Reader::open(&blob[..cut], 42).err().unwrap().kind(), ErrorKind::InvalidState);
        }
        assert!(Reader::open(&blob, 43).is_err(), "foreign fingerprint");
        for i in 0..blob.len() {
            let mut bad = blob.clone();
            bad[i] ^= 0x10;
            assert!(Reader::open(&bad, 42).is_err(), "flipped bit at {i} must be caught");
        }
    }
}

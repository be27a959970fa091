//! Numbers and lists of the OpenFOAM syntax: ASCII and binary labels, scalars, vectors,
//! typed lists (`N (...)`, `N{value}`, binary blocks), read straight from the bytes.

use glam::DVec3;

use super::{MAX_LIST, Parser, is_delim};
use crate::MeshError;

impl<'a> Parser<'a> {
    /// An ASCII label.
    pub fn label(&mut self, entry: &str) -> Result<i64, MeshError> {
        self.skip_ws();
        let start = self.pos;
        let mut neg = false;
        if self.peek() == Some(b'-') {
            neg = true;
            self.pos += 1;
        }
        let mut v: i64 = 0;
        let digits = self.pos;
        while let Some(b) = self.peek() {
            if !b.is_ascii_digit() {
                break;
            }
            v = match v
                .checked_mul(10)
                .and_then(|v| v.checked_add((b - b'0') as i64))
            {
                Some(v) => v,
                None => return Err(self.err(entry, "label too large")),
            };
            self.pos += 1;
        }
        if self.pos == digits || self.peek().is_some_and(|b| !is_delim(b)) {
            self.pos = start;
            let w = String::from_utf8_lossy(self.raw_word()).into_owned();
            self.pos = start;
            return Err(self.err(
                entry,
                if w.is_empty() {
                    "expected an integer (truncated file?)".to_string()
                } else {
                    format!("expected an integer, found '{w}'")
                },
            ));
        }
        Ok(if neg { -v } else { v })
    }

    /// An ASCII scalar (finite or not: the caller checks).
    pub fn scalar(&mut self, entry: &str) -> Result<f64, MeshError> {
        self.skip_ws();
        let start = self.pos;
        let w = self.raw_word();
        match parse_number(w) {
            Some(x) => Ok(x),
            None => {
                let w = String::from_utf8_lossy(w).into_owned();
                self.pos = start;
                Err(self.err(
                    entry,
                    if w.is_empty() {
                        "expected a number (truncated file?)".to_string()
                    } else {
                        format!("expected a number, found '{w}'")
                    },
                ))
            }
        }
    }

    /// An ASCII vector `(x y z)`.
    pub fn vector(&mut self, entry: &str) -> Result<DVec3, MeshError> {
        self.expect(b'(', entry)?;
        let x = self.scalar(entry)?;
        let y = self.scalar(entry)?;
        let z = self.scalar(entry)?;
        self.expect(b')', entry)?;
        Ok(DVec3::new(x, y, z))
    }

    pub(super) fn take(&mut self, n: usize, entry: &str) -> Result<&'a [u8], MeshError> {
        match self.pos.checked_add(n) {
            Some(end) if end <= self.buf.len() => {
                let s = &self.buf[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            _ => Err(self.err(
                entry,
                format!(
                    "binary data of {n} bytes runs past the end of the file ({} left; truncated?)",
                    self.buf.len() - self.pos.min(self.buf.len())
                ),
            )),
        }
    }

    pub(super) fn label_size(&self) -> usize {
        if self.enc.label64 { 8 } else { 4 }
    }

    pub(super) fn scalar_size(&self) -> usize {
        if self.enc.scalar32 { 4 } else { 8 }
    }

    pub(super) fn bin_label(&self, b: &[u8]) -> i64 {
        match (self.enc.label64, self.enc.big_endian) {
            (false, false) => i32::from_le_bytes(b.try_into().unwrap_or_default()) as i64,
            (false, true) => i32::from_be_bytes(b.try_into().unwrap_or_default()) as i64,
            (true, false) => i64::from_le_bytes(b.try_into().unwrap_or_default()),
            (true, true) => i64::from_be_bytes(b.try_into().unwrap_or_default()),
        }
    }

    pub(super) fn bin_scalar(&self, b: &[u8]) -> f64 {
        match (self.enc.scalar32, self.enc.big_endian) {
            (false, false) => f64::from_le_bytes(b.try_into().unwrap_or_default()),
            (false, true) => f64::from_be_bytes(b.try_into().unwrap_or_default()),
            (true, false) => f32::from_le_bytes(b.try_into().unwrap_or_default()) as f64,
            (true, true) => f32::from_be_bytes(b.try_into().unwrap_or_default()) as f64,
        }
    }

    /// The list length before `(` or `{`.
    pub(super) fn list_len(&mut self, entry: &str) -> Result<usize, MeshError> {
        let n = self.label(entry)?;
        if n < 0 || n as usize > MAX_LIST {
            return Err(self.err(entry, format!("invalid list length {n}")));
        }
        Ok(n as usize)
    }

    /// A list `N ( ... )`, `N (<raw bytes>)` in binary, or `N{value}`.
    pub fn list<T: Clone>(&mut self, entry: &str, elem: Elem<T>) -> Result<Vec<T>, MeshError> {
        let n = self.list_len(entry)?;
        self.skip_ws();
        match self.peek() {
            Some(b'{') => {
                self.pos += 1;
                let v = self.ascii_elem(entry, &elem)?;
                self.expect(b'}', entry)?;
                // Bound what a uniform list may allocate by what its user may need.
                if n > (1 << 27) {
                    return Err(self.err(entry, format!("uniform list of {n} entries is too long")));
                }
                Ok(vec![v; n])
            }
            Some(b'(') => {
                self.pos += 1;
                let size = match elem {
                    Elem::Label(_) => Some(self.label_size()),
                    Elem::Scalar(_) => Some(self.scalar_size()),
                    Elem::Vector(_) => Some(3 * self.scalar_size()),
                    Elem::Tuple(k, _) => Some(k * self.scalar_size()),
                    // Faces are lists themselves: never raw bytes.
                    Elem::Face(_) => None,
                };
                let out = if let (true, Some(size)) = (self.enc.binary, size) {
                    let bytes = self.take(n.saturating_mul(size), entry)?;
                    let mut out = Vec::with_capacity(n);
                    for chunk in bytes.chunks_exact(size) {
                        out.push(self.bin_elem(chunk, &elem));
                    }
                    out
                } else {
                    // Never reserve more than the remaining bytes could hold.
                    let left = self.buf.len().saturating_sub(self.pos);
                    let mut out = Vec::with_capacity(n.min(left / 2 + 1));
                    for i in 0..n {
                        out.push(self.ascii_elem_at(entry, &elem, i)?);
                    }
                    out
                };
                self.expect(b')', entry)?;
                Ok(out)
            }
            Some(b) => Err(self.err(
                entry,
                format!(
                    "expected '(' or '{{' after the list length, found '{}'",
                    b.escape_ascii()
                ),
            )),
            None => Err(self.err(
                entry,
                "the list is cut off after its length (truncated file?)",
            )),
        }
    }

    pub(super) fn ascii_elem_at<T>(
        &mut self,
        entry: &str,
        elem: &Elem<T>,
        i: usize,
    ) -> Result<T, MeshError> {
        self.ascii_elem(entry, elem).map_err(|e| match e {
            MeshError::Invalid { file, message, .. } => MeshError::Invalid {
                file,
                entry: format!("{entry}[{i}]"),
                message,
            },
            e => e,
        })
    }

    pub(super) fn ascii_elem<T>(&mut self, entry: &str, elem: &Elem<T>) -> Result<T, MeshError> {
        Ok(match elem {
            Elem::Label(f) => f(self.label(entry)?),
            Elem::Scalar(f) => f(self.scalar(entry)?),
            Elem::Vector(f) => f(self.vector(entry)?),
            Elem::Tuple(1, f) => f(vec![self.scalar(entry)?]),
            Elem::Tuple(k, f) => {
                self.expect(b'(', entry)?;
                let mut v = Vec::with_capacity(*k);
                for _ in 0..*k {
                    v.push(self.scalar(entry)?);
                }
                self.expect(b')', entry)?;
                f(v)
            }
            Elem::Face(f) => {
                let enc = self.enc;
                // A face inside an ASCII faceList, or a binary labelListList entry.
                let v = self.list(entry, Elem::Label(|x| x))?;
                self.enc = enc;
                f(v)
            }
        })
    }

    pub(super) fn bin_elem<T>(&self, b: &[u8], elem: &Elem<T>) -> T {
        match elem {
            Elem::Label(f) => f(self.bin_label(b)),
            Elem::Scalar(f) => f(self.bin_scalar(b)),
            Elem::Vector(f) => {
                let s = self.scalar_size();
                f(DVec3::new(
                    self.bin_scalar(&b[..s]),
                    self.bin_scalar(&b[s..2 * s]),
                    self.bin_scalar(&b[2 * s..3 * s]),
                ))
            }
            Elem::Tuple(k, f) => {
                let s = self.scalar_size();
                f((0..*k)
                    .map(|i| self.bin_scalar(&b[i * s..(i + 1) * s]))
                    .collect())
            }
            // Not reached: faces are read as text lists.
            Elem::Face(f) => f(Vec::new()),
        }
    }
}

/// The element type of a list, with a conversion to the element stored.
pub(crate) enum Elem<T> {
    Label(fn(i64) -> T),
    Scalar(fn(f64) -> T),
    Vector(fn(DVec3) -> T),
    Face(fn(Vec<i64>) -> T),
    /// A tuple of this many scalars (tensors: `(xx xy ...)`, or a bare scalar for 1).
    Tuple(usize, fn(Vec<f64>) -> T),
}

/// Vectors, stored as they are.
pub(crate) const VECTOR: Elem<DVec3> = Elem::Vector(|v| v);
/// Scalars, stored as they are.
pub(crate) const SCALAR: Elem<f64> = Elem::Scalar(|v| v);
/// Labels, stored as they are.
pub(crate) const LABEL: Elem<i64> = Elem::Label(|v| v);

/// A number in OpenFOAM's ASCII form (also `nan`, `inf`, which callers reject).
pub(super) fn parse_number(w: &[u8]) -> Option<f64> {
    let first = *w.first()?;
    if !(first.is_ascii_digit() || matches!(first, b'-' | b'+' | b'.' | b'n' | b'N' | b'i' | b'I'))
    {
        return None;
    }
    let s = std::str::from_utf8(w).ok()?;
    // Words such as `inlet` or `name` must stay words.
    if first.is_ascii_alphabetic() {
        let l = s.to_ascii_lowercase();
        if !matches!(l.as_str(), "nan" | "inf" | "infinity") {
            return None;
        }
    }
    s.parse::<f64>().ok()
}

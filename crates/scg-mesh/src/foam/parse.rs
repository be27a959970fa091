//! The OpenFOAM file syntax: the `FoamFile` header, dictionaries, and ASCII or binary
//! lists, read from a byte buffer without ever panicking.
//!
//! The dictionary syntax is small (keywords, `{}` blocks, token streams ending in `;`), so it
//! is read by hand; the list scanner reads numbers straight from the bytes, which keeps a
//! 10⁶-cell ASCII mesh to a second or so.

use std::path::Path;

use glam::DVec3;

use crate::MeshError;

/// What the `FoamFile` header says about the encoding of the data.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Encoding {
    /// `format binary`.
    pub binary: bool,
    /// `label=64` in `arch`.
    pub label64: bool,
    /// `scalar=32` in `arch`.
    pub scalar32: bool,
    /// `MSB` in `arch` (big-endian binary data).
    pub big_endian: bool,
}

/// One item of an entry's token stream.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Token {
    /// A word (`uniform`, `wall`, `fixedValue`).
    Word(String),
    /// A quoted string, without the quotes.
    Str(String),
    /// A number.
    Num(f64),
    /// One of `( ) [ ]`.
    Punct(u8),
    /// A typed list read whole (`List<vector> N (...)`, `List<scalar>`, `List<label>`).
    List(ListData),
}

/// The data of a typed list.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum ListData {
    /// `List<vector>`.
    Vectors(Vec<DVec3>),
    /// `List<scalar>`.
    Scalars(Vec<f64>),
    /// `List<label>`.
    Labels(Vec<i64>),
    /// Lists of tensors (`List<symmTensor>`, …): the number of components and of entries,
    /// values checked for syntax and dropped.
    Tuples(usize, usize),
}

/// A dictionary entry's value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    /// A `{ ... }` sub-dictionary.
    Dict(Dict),
    /// A token stream ended by `;`.
    Tokens(Vec<Token>),
}

/// A dictionary: keyword–value pairs in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Dict {
    pub entries: Vec<(String, Value)>,
    /// Whether each entry's keyword was quoted (OpenFOAM reads those as regular expressions).
    pub quoted: Vec<bool>,
}

impl Dict {
    /// The value of `key`, the last one if it is repeated (as OpenFOAM does).
    pub fn get(&self, key: &str) -> Option<&Value> {
        self.entries
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v)
    }

    /// The single word or string of `key`, if it is one.
    pub fn word(&self, key: &str) -> Option<&str> {
        match self.get(key) {
            Some(Value::Tokens(t)) if t.len() == 1 => match &t[0] {
                Token::Word(w) | Token::Str(w) => Some(w),
                _ => None,
            },
            _ => None,
        }
    }

    /// The single number of `key`, if it is one.
    pub fn number(&self, key: &str) -> Option<f64> {
        match self.get(key) {
            Some(Value::Tokens(t)) if t.len() == 1 => match t[0] {
                Token::Num(x) => Some(x),
                _ => None,
            },
            _ => None,
        }
    }
}

/// Largest list length accepted (2^31 - 1 entries, the most a 32-bit label can count).
const MAX_LIST: usize = i32::MAX as usize;

/// A reader over the bytes of one file.
pub(crate) struct Parser<'a> {
    file: &'a Path,
    buf: &'a [u8],
    pos: usize,
    /// Nesting depth of `{ }` blocks being read.
    depth: usize,
    /// Data encoding, from the header.
    pub enc: Encoding,
}

/// Deepest `{ }` nesting accepted (real files nest 3 or 4 deep).
const MAX_DEPTH: usize = 64;

fn is_delim(b: u8) -> bool {
    b.is_ascii_whitespace() || matches!(b, b'(' | b')' | b'{' | b'}' | b'[' | b']' | b';' | b'"')
}

impl<'a> Parser<'a> {
    pub fn new(file: &'a Path, buf: &'a [u8]) -> Self {
        Parser {
            file,
            buf,
            pos: 0,
            depth: 0,
            enc: Encoding::default(),
        }
    }

    /// An error at `entry`, with the line of the current position.
    pub fn err(&self, entry: &str, message: impl AsRef<str>) -> MeshError {
        let line = 1 + self.buf[..self.pos.min(self.buf.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        MeshError::invalid(
            self.file,
            entry,
            format!("{} (line {line})", message.as_ref()),
        )
    }

    fn peek(&self) -> Option<u8> {
        self.buf.get(self.pos).copied()
    }

    /// Skip white space and `//`, `/* */` comments.
    pub fn skip_ws(&mut self) {
        loop {
            while self.pos < self.buf.len() && self.buf[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            if self.buf[self.pos.min(self.buf.len())..].starts_with(b"//") {
                while self.pos < self.buf.len() && self.buf[self.pos] != b'\n' {
                    self.pos += 1;
                }
            } else if self.buf[self.pos.min(self.buf.len())..].starts_with(b"/*") {
                match self.buf[self.pos + 2..].windows(2).position(|w| w == b"*/") {
                    Some(i) => self.pos += 2 + i + 2,
                    None => self.pos = self.buf.len(),
                }
            } else {
                return;
            }
        }
    }

    /// True at the end of the data (after white space and comments).
    pub fn at_end(&mut self) -> bool {
        self.skip_ws();
        self.pos >= self.buf.len()
    }

    /// Expect the byte `c` (after white space).
    pub fn expect(&mut self, c: u8, entry: &str) -> Result<(), MeshError> {
        self.skip_ws();
        match self.peek() {
            Some(b) if b == c => {
                self.pos += 1;
                Ok(())
            }
            Some(b) => Err(self.err(
                entry,
                format!("expected '{}', found '{}'", c as char, b.escape_ascii()),
            )),
            None => Err(self.err(
                entry,
                format!(
                    "expected '{}', found the end of the file (truncated?)",
                    c as char
                ),
            )),
        }
    }

    /// A word: bytes up to white space or a delimiter.
    fn raw_word(&mut self) -> &'a [u8] {
        let start = self.pos;
        while self.pos < self.buf.len() && !is_delim(self.buf[self.pos]) {
            self.pos += 1;
        }
        &self.buf[start..self.pos]
    }

    /// A quoted string (the opening `"` is current).
    fn string(&mut self, entry: &str) -> Result<String, MeshError> {
        self.pos += 1;
        let start = self.pos;
        while self.pos < self.buf.len() && self.buf[self.pos] != b'"' {
            if self.buf[self.pos] == b'\\' {
                self.pos += 1;
            }
            self.pos += 1;
        }
        if self.pos >= self.buf.len() {
            return Err(self.err(entry, "unterminated string"));
        }
        let s = String::from_utf8_lossy(&self.buf[start..self.pos]).into_owned();
        self.pos += 1;
        Ok(s)
    }

    /// A keyword: a word or a quoted string.
    fn keyword(&mut self, entry: &str) -> Result<String, MeshError> {
        self.skip_ws();
        match self.peek() {
            Some(b'"') => self.string(entry),
            Some(b) if !is_delim(b) => Ok(String::from_utf8_lossy(self.raw_word()).into_owned()),
            Some(b) => Err(self.err(
                entry,
                format!("expected a keyword, found '{}'", b.escape_ascii()),
            )),
            None => Err(self.err(entry, "expected a keyword, found the end of the file")),
        }
    }

    /// The `FoamFile { ... }` header, which also sets [`Parser::enc`]. Returns the header
    /// dictionary.
    pub fn header(&mut self) -> Result<Dict, MeshError> {
        self.skip_ws();
        let start = self.pos;
        let word = self.raw_word();
        if word != b"FoamFile" {
            self.pos = start;
            return Err(self.err("FoamFile", "the file does not start with a FoamFile header"));
        }
        self.expect(b'{', "FoamFile")?;
        let d = self.dict_body("FoamFile", true)?;
        match d.word("format") {
            Some("ascii") => self.enc.binary = false,
            Some("binary") => self.enc.binary = true,
            Some(f) => {
                return Err(self.err(
                    "FoamFile/format",
                    format!("unknown format '{f}' (ascii or binary)"),
                ));
            }
            None => self.enc.binary = false,
        }
        if let Some(arch) = d.word("arch") {
            for part in arch.split(';').map(str::trim) {
                match part {
                    "LSB" => self.enc.big_endian = false,
                    "MSB" => self.enc.big_endian = true,
                    "label=32" => self.enc.label64 = false,
                    "label=64" => self.enc.label64 = true,
                    "scalar=64" => self.enc.scalar32 = false,
                    "scalar=32" => self.enc.scalar32 = true,
                    "" => {}
                    p => {
                        return Err(self.err(
                            "FoamFile/arch",
                            format!("unsupported arch '{p}' in \"{arch}\""),
                        ));
                    }
                }
            }
        }
        Ok(d)
    }

    /// Entries up to the closing `}` (consumed) or, at the top level, the end of the file.
    pub fn dict_body(&mut self, path: &str, braced: bool) -> Result<Dict, MeshError> {
        let mut d = Dict::default();
        let here = if path.is_empty() { "top level" } else { path };
        loop {
            self.skip_ws();
            match self.peek() {
                None if braced => {
                    return Err(self.err(here, "missing '}' (truncated file?)"));
                }
                None => return Ok(d),
                Some(b'}') if braced => {
                    self.pos += 1;
                    return Ok(d);
                }
                Some(b'#') => {
                    let w = String::from_utf8_lossy(self.raw_word()).into_owned();
                    return Err(self.err(
                        here,
                        format!("directive '{w}' is not supported (#include, #inputMode, … are not expanded)"),
                    ));
                }
                _ => {}
            }
            self.skip_ws();
            let quoted = self.peek() == Some(b'"');
            let key = self.keyword(here)?;
            if key.starts_with('$') {
                return Err(self.err(
                    path,
                    format!("macro '{key}' is not supported ($var substitution is not expanded)"),
                ));
            }
            let sub = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}/{key}")
            };
            self.skip_ws();
            let value = if self.peek() == Some(b'{') {
                self.pos += 1;
                if self.depth >= MAX_DEPTH {
                    return Err(self.err(&sub, "dictionaries nested too deep"));
                }
                self.depth += 1;
                let d = self.dict_body(&sub, true);
                self.depth -= 1;
                Value::Dict(d?)
            } else {
                Value::Tokens(self.tokens(&sub)?)
            };
            d.entries.push((key, value));
            d.quoted.push(quoted);
        }
    }

    /// One `name { ... }` entry (in a list of dictionaries such as `boundary`).
    pub fn named_dict(&mut self, entry: &str) -> Result<(String, Dict), MeshError> {
        let name = self.keyword(entry)?;
        let sub = format!("boundary/{name}");
        self.expect(b'{', &sub)?;
        Ok((name, self.dict_body(&sub, true)?))
    }

    /// A token stream up to `;` (consumed).
    fn tokens(&mut self, entry: &str) -> Result<Vec<Token>, MeshError> {
        let mut out = Vec::new();
        let mut depth = 0usize;
        loop {
            self.skip_ws();
            let Some(b) = self.peek() else {
                return Err(self.err(entry, "missing ';' (truncated file?)"));
            };
            match b {
                b';' if depth == 0 => {
                    self.pos += 1;
                    return Ok(out);
                }
                b'(' | b'[' => {
                    depth += 1;
                    self.pos += 1;
                    out.push(Token::Punct(b));
                }
                b')' | b']' => {
                    depth = depth.saturating_sub(1);
                    self.pos += 1;
                    out.push(Token::Punct(b));
                }
                b'{' | b'}' | b';' => {
                    return Err(self.err(entry, format!("unexpected '{}' in the value", b as char)));
                }
                b'"' => out.push(Token::Str(self.string(entry)?)),
                b'$' => {
                    let w = String::from_utf8_lossy(self.raw_word()).into_owned();
                    return Err(self.err(
                        entry,
                        format!("macro '{w}' is not supported ($var substitution is not expanded)"),
                    ));
                }
                b'#' => {
                    let w = String::from_utf8_lossy(self.raw_word()).into_owned();
                    return Err(self.err(entry, format!("directive '{w}' is not supported")));
                }
                _ => {
                    let start = self.pos;
                    let w = self.raw_word();
                    if let Some(ty) = w.strip_prefix(b"List<").and_then(|r| r.strip_suffix(b">")) {
                        let data = match ty {
                            b"vector" => ListData::Vectors(self.list(entry, VECTOR)?),
                            b"scalar" => ListData::Scalars(self.list(entry, SCALAR)?),
                            b"label" => ListData::Labels(self.list(entry, LABEL)?),
                            b"sphericalTensor" | b"symmTensor" | b"tensor" | b"vector2D" => {
                                let k = match ty {
                                    b"sphericalTensor" => 1,
                                    b"symmTensor" => 6,
                                    b"tensor" => 9,
                                    _ => 2,
                                };
                                let v = self.list(entry, Elem::Tuple(k, |v| v))?;
                                ListData::Tuples(k, v.len())
                            }
                            // Lists of words (`inGroups List<word> 1(wall)`) and other
                            // non-numeric types are text even in binary files.
                            _ => {
                                out.push(Token::Word(String::from_utf8_lossy(w).into_owned()));
                                continue;
                            }
                        };
                        out.push(Token::List(data));
                    } else if let Some(x) = parse_number(w) {
                        out.push(Token::Num(x));
                    } else if w.is_empty() {
                        self.pos = start + 1;
                        return Err(self.err(entry, "unexpected byte"));
                    } else {
                        out.push(Token::Word(String::from_utf8_lossy(w).into_owned()));
                    }
                }
            }
        }
    }

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

    fn take(&mut self, n: usize, entry: &str) -> Result<&'a [u8], MeshError> {
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

    fn label_size(&self) -> usize {
        if self.enc.label64 { 8 } else { 4 }
    }

    fn scalar_size(&self) -> usize {
        if self.enc.scalar32 { 4 } else { 8 }
    }

    fn bin_label(&self, b: &[u8]) -> i64 {
        match (self.enc.label64, self.enc.big_endian) {
            (false, false) => i32::from_le_bytes(b.try_into().unwrap_or_default()) as i64,
            (false, true) => i32::from_be_bytes(b.try_into().unwrap_or_default()) as i64,
            (true, false) => i64::from_le_bytes(b.try_into().unwrap_or_default()),
            (true, true) => i64::from_be_bytes(b.try_into().unwrap_or_default()),
        }
    }

    fn bin_scalar(&self, b: &[u8]) -> f64 {
        match (self.enc.scalar32, self.enc.big_endian) {
            (false, false) => f64::from_le_bytes(b.try_into().unwrap_or_default()),
            (false, true) => f64::from_be_bytes(b.try_into().unwrap_or_default()),
            (true, false) => f32::from_le_bytes(b.try_into().unwrap_or_default()) as f64,
            (true, true) => f32::from_be_bytes(b.try_into().unwrap_or_default()) as f64,
        }
    }

    /// The list length before `(` or `{`.
    fn list_len(&mut self, entry: &str) -> Result<usize, MeshError> {
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

    fn ascii_elem_at<T>(&mut self, entry: &str, elem: &Elem<T>, i: usize) -> Result<T, MeshError> {
        self.ascii_elem(entry, elem).map_err(|e| match e {
            MeshError::Invalid { file, message, .. } => MeshError::Invalid {
                file,
                entry: format!("{entry}[{i}]"),
                message,
            },
            e => e,
        })
    }

    fn ascii_elem<T>(&mut self, entry: &str, elem: &Elem<T>) -> Result<T, MeshError> {
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

    fn bin_elem<T>(&self, b: &[u8], elem: &Elem<T>) -> T {
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
fn parse_number(w: &[u8]) -> Option<f64> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parser(s: &[u8]) -> Parser<'_> {
        Parser::new(Path::new("test"), s)
    }

    #[test]
    fn comments_and_dictionaries() {
        let src = b"/* c */ a 1; // x\n b { c (1 2 3); d \"q;s\"; } e [0 1 -1 0 0 0 0];";
        let d = parser(src).dict_body("", false).unwrap();
        assert_eq!(d.number("a"), Some(1.0));
        let Some(Value::Dict(b)) = d.get("b") else {
            panic!("b is a dict")
        };
        assert_eq!(b.word("d"), Some("q;s"));
        assert_eq!(
            b.get("c"),
            Some(&Value::Tokens(vec![
                Token::Punct(b'('),
                Token::Num(1.0),
                Token::Num(2.0),
                Token::Num(3.0),
                Token::Punct(b')')
            ]))
        );
    }

    #[test]
    fn lists_ascii_uniform_binary() {
        assert_eq!(parser(b"3(1 2 3)").list("l", LABEL).unwrap(), vec![1, 2, 3]);
        assert_eq!(parser(b"3{7}").list("l", LABEL).unwrap(), vec![7, 7, 7]);
        assert_eq!(
            parser(b"2{(1 2 3)}").list("l", VECTOR).unwrap(),
            vec![DVec3::new(1.0, 2.0, 3.0); 2]
        );
        let mut bytes = b"2\n(".to_vec();
        bytes.extend(5i32.to_le_bytes());
        bytes.extend((-1i32).to_le_bytes());
        bytes.push(b')');
        let mut p = parser(&bytes);
        p.enc.binary = true;
        assert_eq!(p.list("l", LABEL).unwrap(), vec![5, -1]);
        let mut bytes = b"1(".to_vec();
        for x in [1.5f32, -2.0, 3.25] {
            bytes.extend(x.to_be_bytes());
        }
        bytes.push(b')');
        let mut p = parser(&bytes);
        p.enc = Encoding {
            binary: true,
            label64: true,
            scalar32: true,
            big_endian: true,
        };
        assert_eq!(
            p.list("l", VECTOR).unwrap(),
            vec![DVec3::new(1.5, -2.0, 3.25)]
        );
    }

    #[test]
    fn word_and_tensor_lists() {
        let src = b"inGroups List<word> 1(wall); R nonuniform List<symmTensor> 2((1 2 3 4 5 6) (1 2 3 4 5 6)); nFaces 3;";
        let d = parser(src).dict_body("", false).unwrap();
        assert_eq!(d.number("nFaces"), Some(3.0));
        assert_eq!(
            d.get("R"),
            Some(&Value::Tokens(vec![
                Token::Word("nonuniform".into()),
                Token::List(ListData::Tuples(6, 2))
            ]))
        );
        let mut bytes = b"T nonuniform List<tensor> 1(".to_vec();
        for x in 0..9 {
            bytes.extend((x as f64).to_le_bytes());
        }
        bytes.extend(b"); g List<word> 2(a b);");
        let mut p = parser(&bytes);
        p.enc.binary = true;
        let d = p.dict_body("", false).unwrap();
        assert!(
            matches!(d.get("T"), Some(Value::Tokens(t)) if t[1] == Token::List(ListData::Tuples(9, 1)))
        );
        assert!(matches!(d.get("g"), Some(Value::Tokens(t)) if t.len() == 6));
    }

    #[test]
    fn errors_name_the_entry() {
        let e = parser(b"3(1 2").list("owner", LABEL).unwrap_err();
        assert!(e.to_string().contains("owner[2]"), "{e}");
        let e = parser(b"a uniform $x;").dict_body("", false).unwrap_err();
        assert!(e.to_string().contains("$x"), "{e}");
        let e = parser(b"2(1.0 x)").list("p", SCALAR).unwrap_err();
        assert!(
            e.to_string().contains("p[1]") && e.to_string().contains("'x'"),
            "{e}"
        );
    }
}

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
}

mod lists;

use lists::parse_number;
pub(crate) use lists::{Elem, LABEL, SCALAR, VECTOR};

#[cfg(test)]
mod tests;

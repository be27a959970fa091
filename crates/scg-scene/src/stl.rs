//! STL files (ASCII and binary, optionally gzip-compressed) → a triangle soup.
//!
//! Hand-written rather than `stl_io` so that every rejection names the triangle (and for
//! ASCII the line) and no input can panic: a binary file is recognised by its exact size
//! (84-byte header + 50 bytes per declared triangle), a file starting with `solid` that
//! is not binary-sized is read as ASCII, anything else is a truncated or foreign file.
//! Coordinates are read as written (binary: f32, ASCII: f64) and returned in f64; the
//! facet normals in the file are ignored (the corners' order defines the mesh).

use std::io::Read;
use std::path::Path;

use glam::{DMat3, DVec3};

/// Why an STL file was rejected: the triangle (0-based, file order) when one is to
/// blame, and what is wrong.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{message}", triangle.map(|t| format!("triangle {t}: ")).unwrap_or_default())]
pub struct StlError {
    /// The offending triangle, when known.
    pub triangle: Option<usize>,
    /// What is wrong.
    pub message: String,
}

fn fail(triangle: Option<usize>, message: impl Into<String>) -> StlError {
    StlError {
        triangle,
        message: message.into(),
    }
}

/// Read an STL file (`.stl` or gzip-compressed, recognised by its magic bytes).
pub fn read(path: &Path) -> Result<Vec<[DVec3; 3]>, StlError> {
    let bytes = std::fs::read(path).map_err(|e| fail(None, format!("cannot read: {e}")))?;
    parse(&bytes)
}

/// Most bytes a decompressed STL may have (4 GiB: 85 million binary triangles).
const MAX_BYTES: u64 = 1 << 32;

/// Parse the bytes of an STL file, decompressing gzip first.
pub fn parse(bytes: &[u8]) -> Result<Vec<[DVec3; 3]>, StlError> {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(bytes)
            .take(MAX_BYTES)
            .read_to_end(&mut out)
            .map_err(|e| fail(None, format!("bad gzip data: {e}")))?;
        return parse_plain(&out);
    }
    parse_plain(bytes)
}

fn parse_plain(bytes: &[u8]) -> Result<Vec<[DVec3; 3]>, StlError> {
    if bytes.is_empty() {
        return Err(fail(None, "empty file"));
    }
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        if 84 + 50 * n == bytes.len() as u64 {
            return Ok(binary(&bytes[84..]));
        }
    }
    let head = &bytes[..bytes.len().min(512)];
    let text_like = head
        .iter()
        .all(|&b| b == b'\n' || b == b'\r' || b == b'\t' || (0x20..0x7f).contains(&b));
    if text_like && head.trim_ascii_start().starts_with(b"solid") {
        let text = std::str::from_utf8(bytes)
            .map_err(|e| fail(None, format!("ASCII STL with invalid UTF-8: {e}")))?;
        return ascii(text);
    }
    if bytes.len() < 84 {
        return Err(fail(
            None,
            format!(
                "not an STL file: {} bytes, neither ASCII (`solid …`) nor a binary header (84 bytes)",
                bytes.len()
            ),
        ));
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    let whole = (bytes.len() as u64 - 84) / 50;
    Err(fail(
        (whole < n).then_some(whole as usize),
        format!(
            "binary STL declares {n} triangles ({} bytes) but the file has {} bytes{}",
            84 + 50 * n,
            bytes.len(),
            if whole < n { " (truncated)" } else { "" }
        ),
    ))
}

/// The facets of a binary STL body (50 bytes each: normal, 3 corners, attribute).
fn binary(body: &[u8]) -> Vec<[DVec3; 3]> {
    body.chunks_exact(50)
        .map(|f| {
            let x = |o: usize| f32::from_le_bytes([f[o], f[o + 1], f[o + 2], f[o + 3]]) as f64;
            let v = |k: usize| {
                let o = 12 + 12 * k;
                DVec3::new(x(o), x(o + 4), x(o + 8))
            };
            [v(0), v(1), v(2)]
        })
        .collect()
}

/// Whitespace-separated words of an ASCII STL with their 1-based lines.
struct Words<'a> {
    words: std::iter::Peekable<Box<dyn Iterator<Item = (usize, &'a str)> + 'a>>,
    last_line: usize,
}

impl<'a> Words<'a> {
    fn new(text: &'a str) -> Self {
        let it: Box<dyn Iterator<Item = (usize, &'a str)> + 'a> = Box::new(
            text.lines()
                .enumerate()
                .flat_map(|(l, line)| line.split_whitespace().map(move |w| (l + 1, w))),
        );
        Words {
            words: it.peekable(),
            last_line: text.lines().count(),
        }
    }
    fn next(&mut self) -> Option<(usize, &'a str)> {
        self.words.next()
    }
    /// Skip the rest of line `l` (a solid's name).
    fn skip_line(&mut self, l: usize) {
        while self.words.peek().is_some_and(|(l2, _)| *l2 == l) {
            self.words.next();
        }
    }
    fn expect(&mut self, t: usize, want: &str) -> Result<(), StlError> {
        match self.next() {
            Some((_, w)) if w == want => Ok(()),
            Some((l, w)) => Err(at(t, l, format!("expected `{want}`, found `{w}`"))),
            None => Err(at(t, self.last_line, format!("file ends before `{want}`"))),
        }
    }
    fn number(&mut self, t: usize) -> Result<f64, StlError> {
        match self.next() {
            Some((l, w)) => w
                .parse::<f64>()
                .map_err(|_| at(t, l, format!("expected a number, found `{w}`"))),
            None => Err(at(t, self.last_line, "file ends inside a facet".into())),
        }
    }
}

fn at(t: usize, line: usize, m: String) -> StlError {
    fail(Some(t), format!("line {line}: {m}"))
}

/// An ASCII STL: `solid [name]`, then facets `facet normal nx ny nz / outer loop /
/// vertex x y z (×3) / endloop / endfacet`, then `endsolid [name]`; several solids may
/// follow one another.
fn ascii(text: &str) -> Result<Vec<[DVec3; 3]>, StlError> {
    let mut words = Words::new(text);
    let mut soup = Vec::new();
    loop {
        match words.next() {
            None => break,
            Some((l, "solid")) => words.skip_line(l),
            Some((l, w)) => {
                return Err(fail(
                    None,
                    format!("line {l}: expected `solid`, found `{w}`"),
                ));
            }
        }
        loop {
            let t = soup.len();
            match words.next() {
                Some((l, "endsolid")) => {
                    words.skip_line(l);
                    break;
                }
                Some((_, "facet")) => {}
                Some((l, w)) => {
                    return Err(at(
                        t,
                        l,
                        format!("expected `facet` or `endsolid`, found `{w}`"),
                    ));
                }
                None => return Err(fail(None, "file ends without `endsolid`")),
            }
            words.expect(t, "normal")?;
            for _ in 0..3 {
                words.number(t)?;
            }
            words.expect(t, "outer")?;
            words.expect(t, "loop")?;
            let mut tri = [DVec3::ZERO; 3];
            for v in &mut tri {
                words.expect(t, "vertex")?;
                *v = DVec3::new(words.number(t)?, words.number(t)?, words.number(t)?);
            }
            words.expect(t, "endloop")?;
            words.expect(t, "endfacet")?;
            soup.push(tri);
        }
    }
    Ok(soup)
}

/// The rotation of a mesh wall's `rotate = [rx, ry, rz]` (degrees, about the fixed x,
/// y and z axes, x first): R = R_z(rz)·R_y(ry)·R_x(rx).
pub fn rotation(deg: DVec3) -> DMat3 {
    DMat3::from_rotation_z(deg.z.to_radians())
        * DMat3::from_rotation_y(deg.y.to_radians())
        * DMat3::from_rotation_x(deg.x.to_radians())
}

/// Place a mesh's vertices: x' = translate + R·(scale·x), R = [`rotation`]`(rotate_deg)`;
/// lengths in the file's unit times `scale` give metres.
pub fn place(vertices: Vec<DVec3>, scale: f64, rotate_deg: DVec3, translate: DVec3) -> Vec<DVec3> {
    let r = rotation(rotate_deg);
    vertices
        .into_iter()
        .map(|v| translate + r * (scale * v))
        .collect()
}

/// Write a binary STL (for tests and examples): an 80-byte header, the count, and per
/// triangle its unit normal, its corners (as f32) and a zero attribute.
pub fn write_binary(tris: &[[DVec3; 3]]) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out[..9].copy_from_slice(b"scg-test ");
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        for v in [n, t[0], t[1], t[2]] {
            for c in v.to_array() {
                out.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<[DVec3; 3]> {
        let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
        vec![
            [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)],
            [p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)],
        ]
    }

    const ASCII: &str = "solid sq\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid sq\n";

    #[test]
    fn binary_ascii_and_gzip_agree() {
        let bin = write_binary(&square());
        assert_eq!(parse(&bin).unwrap(), square());
        assert_eq!(parse(ASCII.as_bytes()).unwrap(), square());
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut gz, &bin).unwrap();
        assert_eq!(parse(&gz.finish().unwrap()).unwrap(), square());
        // A binary file whose header starts with `solid` is still binary (exact size).
        let mut b2 = bin.clone();
        b2[..5].copy_from_slice(b"solid");
        assert_eq!(parse(&b2).unwrap(), square());
    }

    #[test]
    fn bad_files_are_errors_not_panics() {
        let bin = write_binary(&square());
        let e = parse(&bin[..bin.len() - 7]).unwrap_err();
        assert_eq!(e.triangle, Some(1), "{e}");
        assert!(e.message.contains("truncated"), "{e}");
        let e = parse(&bin[..40]).unwrap_err();
        assert!(e.message.contains("not an STL"), "{e}");
        assert_eq!(parse(b"").unwrap_err().message, "empty file");
        let e = parse(
            ASCII
                .replace("vertex 1 1 0\n   vertex 0 1", "vertex 1 1 0\n   vertex 0 x")
                .as_bytes(),
        )
        .unwrap_err();
        assert_eq!(e.triangle, Some(1), "{e}");
        assert!(
            e.to_string()
                .contains("line 13: expected a number, found `x`"),
            "{e}"
        );
        let e = parse(
            ASCII
                .replace("endloop\n endfacet\nendsolid", "endloop")
                .as_bytes(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("triangle 1"), "{e}");
        let e = parse(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2").unwrap_err();
        assert!(e.message.contains("file ends"), "{e}");
        let e = parse(&[0x1f, 0x8b, 1, 2, 3]).unwrap_err();
        assert!(e.message.contains("gzip"), "{e}");
        // Zero triangles parse (the mesh refuses them, naming the file).
        assert!(parse(&write_binary(&[])).unwrap().is_empty());
        assert!(parse(b"solid e\nendsolid e\n").unwrap().is_empty());
        // NaN coordinates parse; the mesh refuses them naming the triangle.
        let nan = parse(ASCII.replace("vertex 1 0 0", "vertex nan 0 0").as_bytes()).unwrap();
        assert!(nan[0][1].x.is_nan());
    }

    proptest::proptest! {
        /// Arbitrary bytes (and arbitrary bytes after `solid`) never panic.
        #[test]
        fn garbage_never_panics(bytes in proptest::collection::vec(0u8..=255, 0..400), ascii in "[a-z0-9 .\\n-]{0,200}") {
            let _ = parse(&bytes);
            let _ = parse(format!("solid {ascii}").as_bytes());
            let _ = parse(format!("solid s\nfacet normal 0 0 1\nouter loop\n{ascii}").as_bytes());
        }
    }
}

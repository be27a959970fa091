//! Sanity checks of the sizes a VTK file declares, before vtkio sees it.
//!
//! vtkio allocates what headers say (`vec![0; nu * (nb - 1) + np]` for a compressed block,
//! capacities from `POINTS n`), so a corrupt count would abort the process on a failed
//! allocation, which no `catch_unwind` can stop. Every count is bounded here by what the
//! file's size can hold; the bound on compressed data allows a 10 000 : 1 ratio (zlib's
//! limit is about 1 000 : 1).

const RATIO: usize = 10_000;

/// Counts declared on the keyword lines of a legacy file (`POINTS n`, `CELLS n size`,
/// `CELL_TYPES n`, `POINT_DATA n`, `CELL_DATA n`, `OFFSETS`/`CONNECTIVITY` of 5.x files)
/// must not exceed the file's length in bytes.
pub fn check_legacy(bytes: &[u8]) -> Result<(), String> {
    const KEYS: [&str; 6] = [
        "POINTS",
        "CELLS",
        "CELL_TYPES",
        "POINT_DATA",
        "CELL_DATA",
        "LOOKUP_TABLE",
    ];
    for line in bytes.split(|&b| b == b'\n') {
        let Ok(line) = std::str::from_utf8(line) else {
            continue;
        };
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        if !KEYS.contains(&key) {
            continue;
        }
        for w in words {
            if let Ok(n) = w.parse::<u64>()
                && n > bytes.len() as u64
            {
                return Err(format!(
                    "{key} declares {n} entries, more than the {} bytes of the file hold",
                    bytes.len()
                ));
            }
        }
    }
    Ok(())
}

/// Bounds on an XML file (after raw appended data was moved inline): the piece sizes, and
/// the headers of every compressed data array (inline or appended base64).
pub fn check_xml(bytes: &[u8]) -> Result<(), String> {
    let limit = RATIO.saturating_mul(bytes.len()).saturating_add(1024);
    let (head, appended) = match find(bytes, b"<AppendedData") {
        Some(at) => {
            let rest = &bytes[at..];
            let data = find(rest, b"_").map_or(&b""[..], |u| &rest[u + 1..]);
            (&bytes[..at], data)
        }
        None => (bytes, &b""[..]),
    };
    let head = std::str::from_utf8(head).map_err(|_| "the XML is not UTF-8".to_string())?;
    let mut rest = head;
    while let Some(i) = rest.find("<Piece") {
        let end = rest[i..].find('>').map_or(rest.len(), |e| e + i);
        let tag = &rest[i..end];
        for key in ["NumberOfPoints", "NumberOfCells"] {
            if let Some(n) = attr(tag, key).and_then(|v| v.trim().parse::<u64>().ok())
                && n > limit as u64
            {
                return Err(format!("{key}=\"{n}\" is more than the file can hold"));
            }
        }
        rest = &rest[end..];
    }
    let Some(root_at) = head.find("<VTKFile") else {
        return Ok(());
    };
    let root = &head[root_at
        ..head[root_at..]
            .find('>')
            .map_or(head.len(), |e| e + root_at)];
    if attr(root, "compressor").is_none_or(|c| c.is_empty()) {
        return Ok(());
    }
    let hs = match attr(root, "header_type").as_deref() {
        Some("UInt64") => 8,
        _ => 4,
    };
    let big = attr(root, "byte_order").as_deref() == Some("BigEndian");
    let mut rest = head;
    while let Some(i) = rest.find("<DataArray") {
        let end = rest[i..]
            .find('>')
            .map_or(rest.len(), |e| e + i + 1)
            .min(rest.len());
        let tag = &rest[i..end];
        let name = attr(tag, "Name").unwrap_or_default();
        let what = |m: String| format!("DataArray {name:?}: {m}");
        match attr(tag, "format").as_deref() {
            Some("binary") if !tag.ends_with("/>") => {
                let body = &rest[end..];
                let text = body[..body.find('<').unwrap_or(body.len())].trim();
                check_compressed_b64(text.as_bytes(), hs, big, limit).map_err(what)?;
            }
            Some("appended") => {
                let off: usize = attr(tag, "offset")
                    .and_then(|o| o.trim().parse().ok())
                    .ok_or_else(|| what("missing or invalid offset".into()))?;
                let text = appended
                    .get(off..)
                    .ok_or_else(|| what(format!("offset {off} past the appended data")))?;
                check_compressed_b64(text, hs, big, limit).map_err(what)?;
            }
            _ => {}
        }
        rest = &rest[end..];
    }
    Ok(())
}

/// A compressed block's header `[nb][nu][np][nc_1..nc_nb]` read from `num(i)` (the i-th
/// header number): at least one block, the last one not larger than the others, the
/// uncompressed size within `limit` and `ratio` times the compressed size. Returns
/// (header length in numbers, total compressed bytes).
pub fn check_block_header(
    num: impl Fn(usize) -> Result<usize, String>,
    limit: usize,
    max_blocks: usize,
) -> Result<(usize, usize), String> {
    let nb = num(0)?;
    if nb == 0 || nb > max_blocks {
        return Err(format!("{nb} compressed blocks"));
    }
    let (nu, np) = (num(1)?, num(2)?);
    if np > nu {
        return Err(format!(
            "last block of {np} bytes, larger than the blocks ({nu})"
        ));
    }
    let mut nc = 0usize;
    for i in 0..nb {
        nc = nc.saturating_add(num(3 + i)?);
    }
    let total = nu.checked_mul(nb - 1).and_then(|t| t.checked_add(np));
    match total {
        Some(t) if t <= limit && t <= RATIO.saturating_mul(nc).saturating_add(1024) => {
            Ok((3 + nb, nc))
        }
        _ => Err(format!(
            "{nb} blocks of {nu} bytes uncompress to more than the file can hold"
        )),
    }
}

fn check_compressed_b64(text: &[u8], hs: usize, big: bool, limit: usize) -> Result<(), String> {
    let chars = |bytes: usize| bytes.div_ceil(3).saturating_mul(4);
    let decode = |nbytes: usize| -> Result<Vec<u8>, String> {
        let n = chars(nbytes);
        let t = text.get(..n).ok_or("the compressed header is cut off")?;
        b64_decode(t).ok_or_else(|| "invalid base64 in the compressed header".to_string())
    };
    let first = decode(hs)?;
    let read = |h: &[u8], i: usize| -> Result<usize, String> {
        let b = h
            .get(i * hs..(i + 1) * hs)
            .ok_or("the compressed header is cut off")?;
        let v = match (hs, big) {
            (8, false) => u64::from_le_bytes(b.try_into().unwrap_or_default()),
            (8, true) => u64::from_be_bytes(b.try_into().unwrap_or_default()),
            (_, false) => u32::from_le_bytes(b.try_into().unwrap_or_default()) as u64,
            (_, true) => u32::from_be_bytes(b.try_into().unwrap_or_default()) as u64,
        };
        usize::try_from(v).map_err(|_| "header number too large".to_string())
    };
    let nb = read(&first, 0)?;
    let max_blocks = text.len() / hs.max(1);
    if nb == 0 || nb > max_blocks {
        return Err(format!("{nb} compressed blocks"));
    }
    let header = decode(hs * (3 + nb))?;
    let (_, nc) = check_block_header(|i| read(&header, i), limit, max_blocks)?;
    if chars(hs * (3 + nb)).saturating_add(chars(nc)) > text.len() {
        return Err(format!("{nc} compressed bytes run past the data"));
    }
    Ok(())
}

/// Standard base64 decoding (padding allowed); `None` on any other character.
fn b64_decode(t: &[u8]) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let mut out = Vec::with_capacity(t.len() / 4 * 3);
    for chunk in t.chunks(4) {
        let pad = chunk.iter().rev().take_while(|&&c| c == b'=').count();
        let mut n = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            let v = if c == b'=' && k >= chunk.len() - pad {
                0
            } else {
                val(c)?
            };
            n |= v << (18 - 6 * k);
        }
        let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&bytes[..(chunk.len() * 3 / 4).saturating_sub(pad)]);
    }
    Some(out)
}

/// The first position of `needle` in `hay`.
pub(super) fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// The value of attribute `name` in a tag (`name="v"` or `name='v'`).
pub(super) fn attr(tag: &str, name: &str) -> Option<String> {
    let mut from = 0;
    while let Some(i) = tag[from..].find(name) {
        let at = from + i;
        from = at + name.len();
        let before_ok = at == 0 || tag.as_bytes()[at - 1].is_ascii_whitespace();
        let rest = tag[from..].trim_start();
        if before_ok && let Some(rest) = rest.strip_prefix('=') {
            let rest = rest.trim_start();
            let q = rest.chars().next()?;
            if q == '"' || q == '\'' {
                let end = rest[1..].find(q)?;
                return Some(rest[1..1 + end].to_string());
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decoding_inverts_rfc4648_vectors() {
        for (a, b) in [
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(b64_decode(b.as_bytes()).unwrap(), a.as_bytes());
        }
        assert!(b64_decode(b"Zm9v!").is_none());
    }

    #[test]
    fn block_headers() {
        let h = |v: Vec<usize>| move |i: usize| v.get(i).copied().ok_or("short".to_string());
        assert_eq!(
            check_block_header(h(vec![2, 100, 50, 30, 20]), 1000, 10),
            Ok((5, 50))
        );
        // No block, a last block larger than the others, sizes beyond the file.
        assert!(check_block_header(h(vec![0, 100, 0]), 1000, 10).is_err());
        assert!(check_block_header(h(vec![1, 10, 50, 5]), 1000, 10).is_err());
        assert!(check_block_header(h(vec![3, 1 << 40, 0, 1, 1, 1]), 1000, 10).is_err());
        assert!(check_block_header(h(vec![1, 0, usize::MAX, 1]), usize::MAX, 10).is_err());
    }

    #[test]
    fn legacy_counts() {
        assert!(check_legacy(b"POINTS 3 double\n0 0 0 1 0 0 0 1 0\n").is_ok());
        let e = check_legacy(b"POINTS 300000000000 double\n0 0 0\n").unwrap_err();
        assert!(e.contains("POINTS declares 300000000000"), "{e}");
    }
}

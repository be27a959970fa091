//! Raw appended data of VTK XML files, re-encoded as inline base64 data arrays.
//!
//! ParaView and VTK write `.vtu` files with `<AppendedData encoding="raw">_<bytes>`
//! by default (zlib-compressed blocks, UInt64 headers); vtkio 0.7 reads only base64
//! appended data. Each `<DataArray format="appended" offset="N"/>` gets its block, found
//! from its header, as `format="binary"` base64 text, which is what VTK writes for inline
//! binary data: header and data encoded together when uncompressed, separately when
//! compressed.

use super::guard::{attr, find};

/// The file with raw appended data moved inline, or the same bytes when there is none.
pub fn inline_raw_appended(bytes: &[u8]) -> Result<Vec<u8>, String> {
    let Some(start) = find(bytes, b"<AppendedData") else {
        return Ok(bytes.to_vec());
    };
    let tag_end = find(&bytes[start..], b">").ok_or("unterminated <AppendedData> tag")? + start;
    let tag = std::str::from_utf8(&bytes[start..=tag_end]).map_err(|_| "invalid tag")?;
    if attr(tag, "encoding").as_deref() != Some("raw") {
        return Ok(bytes.to_vec());
    }
    let underscore = find(&bytes[tag_end..], b"_").ok_or("no '_' before the raw data")? + tag_end;
    let raw = &bytes[underscore + 1..];
    let head = std::str::from_utf8(&bytes[..start])
        .map_err(|_| "the XML before the appended data is not UTF-8")?;
    let root_at = head.find("<VTKFile").ok_or("no <VTKFile> element")?;
    let root =
        &head[root_at..root_at + head[root_at..].find('>').ok_or("unterminated <VTKFile>")?];
    let header64 = match attr(root, "header_type").as_deref() {
        None | Some("UInt32") => false,
        Some("UInt64") => true,
        Some(t) => return Err(format!("header_type {t} is not supported")),
    };
    let big = attr(root, "byte_order").as_deref() == Some("BigEndian");
    let compressed = attr(root, "compressor").is_some_and(|c| !c.is_empty());
    let hs = if header64 { 8 } else { 4 };
    let num = |at: usize| -> Result<usize, String> {
        let b = at
            .checked_add(hs)
            .and_then(|end| raw.get(at..end))
            .ok_or("a block header runs past the end of the appended data")?;
        let v = match (header64, big) {
            (true, false) => u64::from_le_bytes(b.try_into().unwrap_or_default()),
            (true, true) => u64::from_be_bytes(b.try_into().unwrap_or_default()),
            (false, false) => u32::from_le_bytes(b.try_into().unwrap_or_default()) as u64,
            (false, true) => u32::from_be_bytes(b.try_into().unwrap_or_default()) as u64,
        };
        usize::try_from(v).map_err(|_| "block size too large".to_string())
    };
    let block = |off: usize| -> Result<String, String> {
        let slice = |a: usize, n: usize| {
            a.checked_add(n)
                .and_then(|e| raw.get(a..e))
                .ok_or_else(|| format!("the block at offset {off} runs past the end of the data"))
        };
        if compressed {
            let limit = 10_000usize.saturating_mul(bytes.len()).saturating_add(1024);
            let (n_head, total) = super::guard::check_block_header(
                |i| num(off.saturating_add(hs.saturating_mul(i))),
                limit,
                raw.len() / hs,
            )
            .map_err(|m| format!("the block at offset {off}: {m}"))?;
            let header_len = hs * n_head;
            let header = slice(off, header_len)?;
            let data = slice(off.saturating_add(header_len), total)?;
            Ok(format!("{}{}", base64(header), base64(data)))
        } else {
            let n = num(off)?;
            Ok(base64(slice(off, hs.saturating_add(n))?))
        }
    };
    let mut out = String::with_capacity(head.len() + raw.len() * 4 / 3);
    let mut rest = head;
    while let Some(i) = rest.find("<DataArray") {
        let end = rest[i..].find('>').ok_or("unterminated <DataArray> tag")? + i;
        let tag = &rest[i..=end];
        out.push_str(&rest[..i]);
        if attr(tag, "format").as_deref() == Some("appended") {
            let off: usize = attr(tag, "offset")
                .and_then(|o| o.trim().parse().ok())
                .ok_or_else(|| format!("{tag}: missing or invalid offset"))?;
            let text = block(off)?;
            let self_closing = tag.ends_with("/>");
            let body = tag
                .trim_end_matches('>')
                .trim_end_matches('/')
                .replacen("format=\"appended\"", "format=\"binary\"", 1)
                .replacen("format='appended'", "format=\"binary\"", 1);
            out.push_str(&body);
            out.push('>');
            out.push_str(&text);
            if self_closing {
                out.push_str("</DataArray>");
            }
        } else {
            out.push_str(tag);
        }
        rest = &rest[end + 1..];
    }
    out.push_str(rest);
    out.push_str("</VTKFile>\n");
    Ok(out.into_bytes())
}

/// Standard base64 with padding (RFC 4648).
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            s.push(if k <= c.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        // RFC 4648 section 10 test vectors.
        for (a, b) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(a.as_bytes()), b);
        }
    }

    #[test]
    fn attributes() {
        let t = r#"<DataArray type="Float64" Name='U' format="appended" offset="16"/>"#;
        assert_eq!(attr(t, "offset").as_deref(), Some("16"));
        assert_eq!(attr(t, "Name").as_deref(), Some("U"));
        assert_eq!(attr(t, "type").as_deref(), Some("Float64"));
        assert_eq!(attr(t, "compressor"), None);
    }
}

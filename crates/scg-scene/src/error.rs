//! Scene errors that name the file, the key and the line.

use std::fmt;

use toml::de::{DeTable, DeValue};

/// Why a scene was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SceneError {
    /// The scene file (or `<embedded>` / `<string>`).
    pub file: String,
    /// Dotted key path, e.g. `groups[1].diameter`, when known.
    pub key: Option<String>,
    /// 1-based line of the key in the file, when known.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        write!(f, ": ")?;
        if let Some(k) = &self.key {
            write!(f, "key `{k}`: ")?;
        }
        write!(f, "{}", self.message)
    }
}

/// 1-based line of byte offset `pos` in `text`.
pub fn line_of(text: &str, pos: usize) -> usize {
    text.as_bytes()[..pos.min(text.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
        + 1
}

/// Find the line of a dotted key path (`a.b[2].c`) in a TOML document.
pub fn locate(text: &str, path: &str) -> Option<usize> {
    let doc = DeTable::parse(text).ok()?;
    let mut table: &DeTable = doc.get_ref();
    let mut line = None;
    let mut value: Option<&DeValue> = None;
    for part in path.split('.') {
        let (name, index) = match part.find('[') {
            Some(i) => (
                &part[..i],
                part[i + 1..].trim_end_matches(']').parse::<usize>().ok(),
            ),
            None => (part, None),
        };
        if let Some(v) = value {
            match v {
                DeValue::Table(t) => table = t,
                _ => return line,
            }
        }
        let (k, v) = table.get_key_value(name)?;
        line = Some(line_of(text, k.span().start));
        let mut v: &DeValue = v.get_ref();
        if let Some(i) = index {
            if let DeValue::Array(a) = v {
                let item = a.get(i)?;
                line = Some(line_of(text, item.span().start));
                v = item.get_ref();
            } else {
                return line;
            }
        }
        value = Some(v);
    }
    line
}

/// The dotted key path whose entry contains byte offset `pos` (deepest match).
///
/// Tables opened by headers (`[drag]`, `[[groups]]`) do not span their bodies, so every
/// entry of the document is visited, not only those inside a matching parent.
pub fn key_at(text: &str, pos: usize) -> Option<String> {
    let doc = DeTable::parse(text).ok()?;
    let mut best: Option<(usize, String)> = None;
    walk(doc.get_ref(), pos, "", 0, &mut best);
    best.map(|(_, p)| p)
}

fn contains(span: std::ops::Range<usize>, pos: usize) -> bool {
    span.start <= pos && pos < span.end.max(span.start + 1)
}

fn walk(
    table: &DeTable,
    pos: usize,
    prefix: &str,
    depth: usize,
    best: &mut Option<(usize, String)>,
) {
    for (k, v) in table.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        if (contains(k.span(), pos) || contains(v.span(), pos))
            && best.as_ref().is_none_or(|(d, _)| depth >= *d)
        {
            *best = Some((depth, path.clone()));
        }
        match v.get_ref() {
            DeValue::Table(t) => walk(t, pos, &path, depth + 1, best),
            DeValue::Array(a) => {
                for (i, item) in a.iter().enumerate() {
                    let ip = format!("{path}[{i}]");
                    if contains(item.span(), pos)
                        && best.as_ref().is_none_or(|(d, _)| depth + 1 >= *d)
                    {
                        *best = Some((depth + 1, ip.clone()));
                    }
                    if let DeValue::Table(t) = item.get_ref() {
                        walk(t, pos, &ip, depth + 2, best);
                    }
                }
            }
            _ => {}
        }
    }
}

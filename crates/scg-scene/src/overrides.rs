//! `--set key=value` overrides: edit the scene's TOML text before it is parsed.

use crate::error::{self, SceneError};

/// Apply `key=value` overrides (TOML values, dotted keys, `groups.0.alpha=2`) to `text`.
pub fn apply_overrides(text: &str, file: &str, overrides: &[String]) -> Result<String, SceneError> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let bad = |key: &str, message: String| SceneError {
        file: format!("{file} (--set)"),
        key: Some(key.to_string()),
        line: None,
        message,
    };
    let doc: toml::Table = toml::from_str(text).map_err(|e| SceneError {
        file: file.to_string(),
        key: None,
        line: e.span().map(|s| error::line_of(text, s.start)),
        message: e.message().to_string(),
    })?;
    let mut root = toml::Value::Table(doc);
    for o in overrides {
        let Some((key, value)) = o.split_once('=') else {
            return Err(bad(o, "expected key=value".into()));
        };
        let key = key.trim();
        let value: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {value}")) {
            Ok(mut t) => t
                .remove("v")
                .unwrap_or(toml::Value::String(value.to_string())),
            // Bare words (e.g. `law=none`) are strings.
            Err(_) => toml::Value::String(value.trim().to_string()),
        };
        let parts: Vec<&str> = key.split('.').collect();
        let mut cur: &mut toml::Value = &mut root;
        for (i, p) in parts.iter().enumerate() {
            let last = i + 1 == parts.len();
            cur = match cur {
                toml::Value::Table(t) => {
                    if last {
                        t.insert(p.to_string(), value.clone());
                        break;
                    }
                    t.entry(p.to_string())
                        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                }
                toml::Value::Array(a) => {
                    let idx: usize = p
                        .parse()
                        .map_err(|_| bad(key, format!("`{p}` is not an index")))?;
                    let len = a.len();
                    let slot = a
                        .get_mut(idx)
                        .ok_or_else(|| bad(key, format!("index {idx} out of range (len {len})")))?;
                    if last {
                        *slot = value.clone();
                        break;
                    }
                    slot
                }
                _ => return Err(bad(key, format!("`{p}` is inside a plain value"))),
            };
        }
    }
    toml::to_string(&root).map_err(|e| bad("", e.to_string()))
}

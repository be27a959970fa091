//! `--set key=value` overrides: edit the scene's TOML text before it is parsed.
//!
//! The text is edited in place (`toml_edit`): comments, layout and line numbers stay as
//! written, so errors name the lines of the file and recordings store the scene as the
//! user wrote it, with the overridden values. A key that is not in the file yet is added:
//! a new table goes at the end (no line moves), a new key of an inline table stays on its
//! line, and a new key of a table written with a header (or of the top level, which TOML
//! puts before the first header) goes after that table's last key, moving the lines below
//! it down by one.

use toml_edit::{DocumentMut, InlineTable, Item, Table, Value};

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
    let mut doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| SceneError {
        file: file.to_string(),
        key: None,
        line: e.span().map(|s| error::line_of(text, s.start)),
        message: e.message().to_string(),
    })?;
    for o in overrides {
        let Some((key, value)) = o.split_once('=') else {
            return Err(bad(o, "expected key=value".into()));
        };
        let key = key.trim();
        let parts: Vec<&str> = key.split('.').collect();
        set_in_table(doc.as_table_mut(), &parts, parse_value(value)).map_err(|m| bad(key, m))?;
    }
    Ok(doc.to_string())
}

/// A TOML value; bare words (e.g. `law=none`) are strings.
fn parse_value(value: &str) -> Value {
    format!("v = {value}")
        .parse::<DocumentMut>()
        .ok()
        .and_then(|d| d.get("v").and_then(Item::as_value).cloned())
        .map(|mut v| {
            v.decor_mut().clear();
            v
        })
        .unwrap_or_else(|| Value::from(value.trim()))
}

/// Replace `slot` by `value`, keeping the slot's surrounding whitespace and comments.
fn replace(slot: &mut Value, mut value: Value) {
    *value.decor_mut() = slot.decor().clone();
    *slot = value;
}

fn index(p: &str, len: usize) -> Result<usize, String> {
    let idx: usize = p.parse().map_err(|_| format!("`{p}` is not an index"))?;
    if idx >= len {
        return Err(format!("index {idx} out of range (len {len})"));
    }
    Ok(idx)
}

fn set_in_table(t: &mut Table, parts: &[&str], value: Value) -> Result<(), String> {
    let (p, rest) = (parts[0], &parts[1..]);
    if rest.is_empty() {
        match t.get_mut(p) {
            Some(Item::Value(slot)) => replace(slot, value),
            _ => {
                t.insert(p, Item::Value(value));
            }
        }
        return Ok(());
    }
    if !t.contains_key(p) {
        let mut child = Table::new();
        child.set_implicit(true);
        t.insert(p, Item::Table(child));
    }
    match t.get_mut(p) {
        Some(Item::Table(child)) => set_in_table(child, rest, value),
        Some(Item::ArrayOfTables(a)) => {
            let idx = index(rest[0], a.len())?;
            let child = a.get_mut(idx).ok_or("index out of range")?;
            if rest.len() == 1 {
                return Err(format!("`{}` is a table, not a value", rest[0]));
            }
            set_in_table(child, &rest[1..], value)
        }
        Some(Item::Value(v)) => set_in_value(v, p, rest, value),
        _ => Err(format!("`{p}` is inside a plain value")),
    }
}

fn set_in_value(v: &mut Value, name: &str, parts: &[&str], value: Value) -> Result<(), String> {
    let (p, rest) = (parts[0], &parts[1..]);
    match v {
        Value::InlineTable(t) => set_in_inline(t, parts, value),
        Value::Array(a) => {
            let idx = index(p, a.len())?;
            let slot = a.get_mut(idx).ok_or("index out of range")?;
            if rest.is_empty() {
                replace(slot, value);
                Ok(())
            } else {
                set_in_value(slot, p, rest, value)
            }
        }
        _ => Err(format!("`{name}` is inside a plain value")),
    }
}

fn set_in_inline(t: &mut InlineTable, parts: &[&str], value: Value) -> Result<(), String> {
    let (p, rest) = (parts[0], &parts[1..]);
    if rest.is_empty() {
        match t.get_mut(p) {
            Some(slot) => replace(slot, value),
            None => {
                t.insert(p, value);
            }
        }
        return Ok(());
    }
    if !t.contains_key(p) {
        t.insert(p, Value::InlineTable(InlineTable::new()));
    }
    let child = t.get_mut(p).ok_or("missing key")?;
    set_in_value(child, p, rest, value)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "# a comment\nname = \"x\" # trailing\ndt = 1e-5\n\n[[groups]]\nname = \"a\"\ndiameter = 1e-3 # m\nregion = { kind = \"box\", min = [0.0, 0.0, 0.0] }\n";

    fn set(sets: &[&str]) -> Result<String, SceneError> {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        apply_overrides(TEXT, "t.toml", &sets)
    }

    #[test]
    fn edits_in_place_keeping_comments_and_lines() {
        let out = set(&[
            "dt=2e-5",
            "groups.0.diameter=2e-3",
            "groups.0.region.min.1=0.5",
        ])
        .unwrap();
        assert!(out.contains("# a comment\n"), "{out}");
        assert!(out.contains("name = \"x\" # trailing\n"), "{out}");
        assert!(out.contains("dt = 2e-5\n"), "{out}");
        assert!(out.contains("diameter = 2e-3 # m\n"), "{out}");
        assert!(out.contains("min = [0.0, 0.5, 0.0]"), "{out}");
        // Every line keeps its number.
        for (a, b) in TEXT.lines().zip(out.lines()) {
            assert_eq!(a.split('=').next(), b.split('=').next());
        }
        assert_eq!(TEXT.lines().count(), out.lines().count());
    }

    #[test]
    fn new_keys_and_tables_are_added_and_bare_words_are_strings() {
        let out = set(&["coarse_grain.law=none", "groups.0.region.max=[1, 1, 1]"]).unwrap();
        let doc: toml::Table = toml::from_str(&out).unwrap();
        assert_eq!(doc["coarse_grain"]["law"].as_str(), Some("none"));
        assert_eq!(
            doc["groups"][0]["region"]["max"].as_array().map(Vec::len),
            Some(3)
        );
        // A new table at the end and a new key of an inline table move no line.
        for (i, (a, b)) in TEXT.lines().zip(out.lines()).enumerate() {
            if !a.starts_with("region") {
                assert_eq!(a, b, "line {}", i + 1);
            }
        }
        // A new top-level key goes before the first table: the lines below move by one,
        // in order and unchanged.
        let out = set(&["seed=3"]).unwrap();
        let doc: toml::Table = toml::from_str(&out).unwrap();
        assert_eq!(doc["seed"].as_integer(), Some(3));
        let kept: Vec<&str> = out.lines().filter(|l| *l != "seed = 3").collect();
        assert_eq!(kept, TEXT.lines().collect::<Vec<_>>());
    }

    #[test]
    fn bad_paths_name_the_key() {
        for (s, want) in [
            ("noequals", "expected key=value"),
            ("groups.9.diameter=1", "index 9 out of range (len 1)"),
            ("groups.x.diameter=1", "`x` is not an index"),
            ("dt.x=1", "`dt` is inside a plain value"),
        ] {
            let e = set(&[s]).unwrap_err();
            assert!(e.message.contains(want), "{s}: {e}");
            assert!(e.key.is_some() && e.file.ends_with("(--set)"), "{s}: {e:?}");
        }
    }
}

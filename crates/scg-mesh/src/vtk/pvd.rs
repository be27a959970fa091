//! ParaView's collection files (`.pvd`): the time steps of a VTK series and their files.
//!
//! A `.pvd` is an XML `VTKFile` of type `Collection` whose `Collection` lists one
//! `<DataSet timestep="t" file="name.vtu"/>` per file (ParaView's own writer adds `group`
//! and `part`). Each data set is one time step here: a collection whose steps are split
//! into several parts (`part` other than 0, or two data sets at one time) is refused, as is
//! any data set without a finite `timestep` or a `file`.

use std::path::{Path, PathBuf};

use crate::MeshError;

/// The time steps of the collection `path` and their files (relative names resolved
/// against the collection's folder), in increasing time.
pub fn read_pvd(path: impl AsRef<Path>) -> Result<Vec<(f64, PathBuf)>, MeshError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| MeshError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    let bad = |entry: &str, m: String| MeshError::invalid(path, entry, m);
    if !text.contains("Collection") {
        return Err(bad(
            "VTKFile",
            "not a collection (no `Collection` element): a .pvd lists a series' files".into(),
        ));
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut steps: Vec<(f64, PathBuf)> = Vec::new();
    let mut rest = text.as_str();
    let mut k = 0;
    while let Some(at) = rest.find("<DataSet") {
        let tail = &rest[at + "<DataSet".len()..];
        let end = tail
            .find('>')
            .ok_or_else(|| bad(&format!("DataSet[{k}]"), "the element is not closed".into()))?;
        let tag = &tail[..end];
        let entry = format!("DataSet[{k}]");
        let time = attribute(tag, "timestep")
            .ok_or_else(|| bad(&entry, "no `timestep` attribute".into()))?;
        let t: f64 = time
            .trim()
            .parse()
            .ok()
            .filter(|t: &f64| t.is_finite())
            .ok_or_else(|| {
                bad(
                    &entry,
                    format!("timestep \"{time}\" is not a finite number"),
                )
            })?;
        let file =
            attribute(tag, "file").ok_or_else(|| bad(&entry, "no `file` attribute".into()))?;
        if let Some(part) = attribute(tag, "part")
            && part.trim() != "0"
        {
            return Err(bad(
                &entry,
                format!(
                    "part \"{part}\": a time step split into parts is not read (write one \
                     file per time step)"
                ),
            ));
        }
        steps.push((t, dir.join(file)));
        rest = &tail[end..];
        k += 1;
    }
    if steps.is_empty() {
        return Err(bad("Collection", "no DataSet".into()));
    }
    steps.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(w) = steps.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(bad(
            "Collection",
            format!(
                "two data sets at timestep {} ({} and {}): one file per time step",
                w[0].0,
                w[0].1.display(),
                w[1].1.display()
            ),
        ));
    }
    Ok(steps)
}

/// The value of attribute `name` in the inside of a start tag (`key="v"` or `key='v'`).
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let mut rest = tag;
    while let Some(i) = rest.find(name) {
        let before = rest[..i].chars().next_back();
        let after = rest[i + name.len()..].trim_start();
        rest = &rest[i + name.len()..];
        if before.is_some_and(|c| !c.is_whitespace()) {
            continue;
        }
        let Some(v) = after.strip_prefix('=') else {
            continue;
        };
        let v = v.trim_start();
        let q = v.chars().next()?;
        if q != '"' && q != '\'' {
            return None;
        }
        let v = &v[1..];
        return v.find(q).map(|e| &v[..e]);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pvd(body: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("u.pvd");
        let text = format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n\
             <Collection>\n{body}</Collection>\n</VTKFile>\n"
        );
        std::fs::write(&p, text).unwrap();
        (dir, p)
    }

    #[test]
    fn a_collection_gives_its_steps_in_time_order() {
        let (d, p) = pvd(
            "<DataSet timestep=\"0.5\" group=\"\" part=\"0\" file=\"b/u_1.vtu\"/>\n\
             <DataSet file='u_0.vtu' timestep='0'/>\n\
             <DataSet timestep=\"1e0\" part=\"0\" file=\"u_2.vtu\"/>\n",
        );
        let s = read_pvd(&p).unwrap();
        assert_eq!(
            s,
            vec![
                (0.0, d.path().join("u_0.vtu")),
                (0.5, d.path().join("b/u_1.vtu")),
                (1.0, d.path().join("u_2.vtu")),
            ]
        );
    }

    #[test]
    fn a_bad_collection_is_refused_naming_the_data_set() {
        for (body, want) in [
            ("<DataSet file=\"a.vtu\"/>\n", "DataSet[0]: no `timestep`"),
            (
                "<DataSet timestep=\"x\" file=\"a.vtu\"/>\n",
                "not a finite number",
            ),
            ("<DataSet timestep=\"0\"/>\n", "no `file`"),
            (
                "<DataSet timestep=\"0\" part=\"1\" file=\"a.vtu\"/>\n",
                "split into parts",
            ),
            (
                "<DataSet timestep=\"0\" file=\"a.vtu\"/><DataSet timestep=\"0\" file=\"b.vtu\"/>\n",
                "two data sets at timestep 0",
            ),
            ("", "no DataSet"),
        ] {
            let (_d, p) = pvd(body);
            let e = read_pvd(&p).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains("u.pvd"), "{body}: {e}");
        }
    }
}

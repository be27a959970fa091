//! `volVectorField` files → [`CellField`].

use std::path::Path;

use glam::DVec3;

use super::parse::{Dict, ListData, Parser, Token, Value};
use super::{TimeSel, boundary, read_maybe_gz, select_time};
use crate::{CellField, MeshError, Patch, PolyMesh};

/// Read the volVectorField `name` (e.g. `U`, in its own units: m/s for a velocity) of the
/// time directory `time` picks, on `mesh`.
///
/// `internalField` gives the cell values (`uniform (x y z)` or `nonuniform List<vector>`
/// with one value per cell); each patch of the mesh must have a `boundaryField` entry (of
/// its name, of its group such as `wall`, or a quoted regular expression such as `".*"`),
/// whose `type` decides the face values [`CellField::patches`]`[i]` as OpenFOAM means
/// them ([`super::boundary::TABLE`]: `noSlip` zero, `fixedValue`, `inletOutlet`, … their
/// `value`, `slip` and `symmetry` the owner's tangential part, `zeroGradient` and `empty`
/// the owner's value, stored as `None`). A type not in the table, or one scg cannot honour
/// (`cyclic`, `processor`), is an error naming the patch and the type. Every value must be
/// finite.
pub fn read_vector_field(
    case_dir: impl AsRef<Path>,
    mesh: &PolyMesh,
    time: TimeSel,
    name: &str,
) -> Result<CellField, MeshError> {
    let dir = select_time(case_dir, time)?;
    let (file, bytes) = read_maybe_gz(&dir.join(name))?;
    parse_vector_field(&file, &bytes, mesh)
}

/// Parse the bytes of a volVectorField file (`file` names it in errors).
pub(crate) fn parse_vector_field(
    file: &Path,
    bytes: &[u8],
    mesh: &PolyMesh,
) -> Result<CellField, MeshError> {
    let (cells, patches) = parse_field(
        file,
        bytes,
        mesh,
        "volVectorField",
        values,
        |kind, written, patch, cells| boundary::face_values(kind, written, mesh, patch, cells),
    )?;
    Ok(CellField { cells, patches })
}

/// Reads the values of an entry: `(file, entry, tokens, count)` → `count` finite values.
pub(super) type ReadValues<T> = fn(&Path, &str, &[Token], usize) -> Result<Vec<T>, MeshError>;

/// A parsed field: the cell values and, per patch, the face values (`None`: the owners').
pub(super) type Parsed<T> = (Vec<T>, Vec<Option<Vec<T>>>);

/// Parse a field file of `class`: the cell values and, per patch of `mesh`, the face values
/// `face` makes of the patch's `type`, its `value` (if written) and the cell values.
pub(super) fn parse_field<T>(
    file: &Path,
    bytes: &[u8],
    mesh: &PolyMesh,
    class: &str,
    values: ReadValues<T>,
    face: impl Fn(&str, Option<Vec<T>>, &Patch, &[T]) -> Result<Option<Vec<T>>, String>,
) -> Result<Parsed<T>, MeshError> {
    let mut p = Parser::new(file, bytes);
    let h = p.header()?;
    let found = h.word("class").unwrap_or("");
    if found != class {
        return Err(p.err(
            "FoamFile/class",
            format!("class '{found}' where {class} was expected"),
        ));
    }
    let body = p.dict_body("", false)?;
    let bad = |entry: &str, message: String| MeshError::invalid(file, entry, message);
    if body.get("dimensions").is_none() {
        return Err(bad("dimensions", "missing".into()));
    }
    let internal = match body.get("internalField") {
        Some(Value::Tokens(t)) => t,
        Some(_) => {
            return Err(bad(
                "internalField",
                "expected a value, not a dictionary".into(),
            ));
        }
        None => return Err(bad("internalField", "missing".into())),
    };
    let cells = values(file, "internalField", internal, mesh.n_cells)?;
    let Some(Value::Dict(bf)) = body.get("boundaryField") else {
        return Err(bad("boundaryField", "missing or not a dictionary".into()));
    };
    let mut patches = Vec::with_capacity(mesh.patches.len());
    for patch in &mesh.patches {
        let entry = format!("boundaryField/{}", patch.name);
        let d = match patch_entry(bf, patch).map_err(|m| bad("boundaryField", m))? {
            Some(Value::Dict(d)) => d,
            Some(_) => return Err(bad(&entry, "expected a dictionary { ... }".into())),
            None => {
                return Err(bad(
                    &entry,
                    "missing: no entry of this name, of its group or matching a pattern".into(),
                ));
            }
        };
        let Some(kind) = d.word("type") else {
            return Err(bad(&format!("{entry}/type"), "missing".into()));
        };
        let written = match d.get("value") {
            None => None,
            Some(Value::Tokens(t)) => Some(values(file, &format!("{entry}/value"), t, patch.size)?),
            Some(Value::Dict(_)) => {
                return Err(bad(
                    &format!("{entry}/value"),
                    "expected a value, not a dictionary".into(),
                ));
            }
        };
        let v = face(kind, written, patch, &cells).map_err(|m| bad(&format!("{entry}/type"), m))?;
        patches.push(v);
    }
    Ok((cells, patches))
}

/// The boundaryField entry of `patch`, found as OpenFOAM finds it: by the patch's name,
/// else by its group (the patch type for types other than plain `patch`, e.g. `wall`), else
/// by the last quoted keyword whose regular expression matches the whole name.
fn patch_entry<'a>(bf: &'a Dict, patch: &Patch) -> Result<Option<&'a Value>, String> {
    let plain = |key: &str| {
        bf.entries
            .iter()
            .zip(&bf.quoted)
            .rev()
            .find(|((k, _), q)| !**q && k == key)
            .map(|((_, v), _)| v)
    };
    if let Some(v) = plain(&patch.name) {
        return Ok(Some(v));
    }
    if patch.kind != "patch"
        && let Some(v) = plain(&patch.kind)
    {
        return Ok(Some(v));
    }
    for ((key, v), _) in bf.entries.iter().zip(&bf.quoted).rev().filter(|(_, q)| **q) {
        let re = regex::Regex::new(&format!("^(?:{key})$"))
            .map_err(|e| format!("\"{key}\" is not a regular expression: {e}"))?;
        if re.is_match(&patch.name) {
            return Ok(Some(v));
        }
    }
    Ok(None)
}

/// `uniform (x y z)` or `nonuniform List<vector> N (...)`, as `n` finite values.
fn values(file: &Path, entry: &str, t: &[Token], n: usize) -> Result<Vec<DVec3>, MeshError> {
    let bad = |message: String| MeshError::invalid(file, entry, message);
    let out = match t {
        [
            Token::Word(u),
            Token::Punct(b'('),
            Token::Num(x),
            Token::Num(y),
            Token::Num(z),
            Token::Punct(b')'),
        ] if u == "uniform" => {
            vec![DVec3::new(*x, *y, *z); n]
        }
        [Token::Word(u), Token::List(ListData::Vectors(v))] if u == "nonuniform" => {
            if v.len() != n {
                return Err(bad(format!("{} values where {n} are needed", v.len())));
            }
            v.clone()
        }
        // `nonuniform List<vector> 0()` may also be written `nonuniform 0()`.
        [
            Token::Word(u),
            Token::Num(z),
            Token::Punct(b'('),
            Token::Punct(b')'),
        ] if u == "nonuniform" && *z == 0.0 => {
            if n != 0 {
                return Err(bad(format!("0 values where {n} are needed")));
            }
            Vec::new()
        }
        [Token::Word(u), Token::List(_)] if u == "nonuniform" => {
            return Err(bad("a list of vectors (List<vector>) was expected".into()));
        }
        [Token::Word(u), Token::Num(_)] if u == "uniform" => {
            return Err(bad("a scalar where a vector (x y z) was expected".into()));
        }
        _ => {
            return Err(bad(
                "expected 'uniform (x y z)' or 'nonuniform List<vector> N (...)'".into(),
            ));
        }
    };
    if let Some((i, v)) = out.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(MeshError::invalid(
            file,
            format!("{entry}[{i}]"),
            format!("not finite: {v}"),
        ));
    }
    Ok(out)
}

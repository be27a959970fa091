//! `volScalarField` files → [`ScalarField`] (turbulence `k`, `epsilon`, `omega`, `nut`, …).

use std::path::Path;

use super::field::parse_field;
use super::parse::{ListData, Token};
use super::{TimeSel, boundary, read_maybe_gz, select_time};
use crate::{MeshError, PolyMesh, ScalarField};

/// Read the volScalarField `name` (e.g. `k` in m²/s², `epsilon` m²/s³, `omega` 1/s, `nut`
/// m²/s) of the time directory `time` picks, on `mesh`; `name.gz` when `name` is absent.
///
/// As [`super::read_vector_field`] for a vector: `internalField` gives the cell values
/// (`uniform x` or `nonuniform List<scalar>` with one value per cell, ASCII or binary);
/// each patch of the mesh must have a `boundaryField` entry (of its name, of its group, or
/// a quoted regular expression), whose `type` decides the face values
/// [`ScalarField::patches`]`[i]` as OpenFOAM means them ([`super::boundary::SCALAR_TABLE`]:
/// `fixedValue`, the wall functions of `epsilon`, `omega` and `nut`, `inletOutlet`, the
/// turbulence inlets, `calculated`, … their `value`; `zeroGradient`, `kqRWallFunction`,
/// `slip`, `symmetry`, `wedge` and `empty` the owner's value, stored as `None`). A type not
/// in the table, or a refused one (`cyclic`, `processor`), is an error naming the patch and
/// the type. Every value must be finite; negative values are accepted (call
/// [`ScalarField::check_non_negative`] for `k`, `epsilon`, `omega`, `nut`).
pub fn read_scalar_field(
    case_dir: impl AsRef<Path>,
    mesh: &PolyMesh,
    time: TimeSel,
    name: &str,
) -> Result<ScalarField, MeshError> {
    let dir = select_time(case_dir, time)?;
    let (file, bytes) = read_maybe_gz(&dir.join(name))?;
    parse_scalar_field(&file, &bytes, mesh)
}

/// Parse the bytes of a volScalarField file (`file` names it in errors).
pub(crate) fn parse_scalar_field(
    file: &Path,
    bytes: &[u8],
    mesh: &PolyMesh,
) -> Result<ScalarField, MeshError> {
    let (cells, patches) = parse_field(
        file,
        bytes,
        mesh,
        "volScalarField",
        values,
        |kind, written, _, _| boundary::scalar_face_values(kind, written),
    )?;
    Ok(ScalarField { cells, patches })
}

/// `uniform x` or `nonuniform List<scalar> N (...)`, as `n` finite values.
fn values(file: &Path, entry: &str, t: &[Token], n: usize) -> Result<Vec<f64>, MeshError> {
    let bad = |message: String| MeshError::invalid(file, entry, message);
    let out = match t {
        [Token::Word(u), Token::Num(x)] if u == "uniform" => vec![*x; n],
        [Token::Word(u), Token::List(ListData::Scalars(v))] if u == "nonuniform" => {
            if v.len() != n {
                return Err(bad(format!("{} values where {n} are needed", v.len())));
            }
            v.clone()
        }
        // `nonuniform List<scalar> 0()` may also be written `nonuniform 0()`.
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
            return Err(bad("a list of scalars (List<scalar>) was expected".into()));
        }
        [Token::Word(u), Token::Punct(b'('), ..] if u == "uniform" => {
            return Err(bad("a vector where a scalar was expected".into()));
        }
        _ => {
            return Err(bad(
                "expected 'uniform x' or 'nonuniform List<scalar> N (...)'".into(),
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

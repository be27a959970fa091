//! Rotating-frame solutions: `constant/SRFProperties` (a single rotating frame, whose
//! `Urel` is the velocity relative to the frame) and `constant/MRFProperties` (frozen-rotor
//! zones, whose `U` is absolute).
//!
//! `SRFProperties` as `SRFSimpleFoam` and `SRFPimpleFoam` read it:
//!
//! ```text
//! SRFModel  rpm;          // the only model OpenFOAM has
//! origin    (0 0 0);      // a point on the axis, in the mesh's units
//! axis      (0 0 1);      // normalised by OpenFOAM, right-handed
//! rpmCoeffs { rpm 1000; } // rev/min
//! ```

use std::path::Path;

use glam::DVec3;

use super::parse::{Dict, Parser, Token, Value};
use super::read_maybe_gz;
use crate::MeshError;

/// A single rotating frame (`constant/SRFProperties`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Srf {
    /// A point on the axis, in the mesh's units (before any scene `scale`/`translate`).
    pub origin: DVec3,
    /// The unit axis (right-handed rotation).
    pub axis: DVec3,
    /// Rotation rate, rev/min.
    pub rpm: f64,
}

impl Srf {
    /// The angular velocity vector, rad/s.
    pub fn omega(&self) -> DVec3 {
        self.axis * self.rpm * std::f64::consts::TAU / 60.0
    }
}

/// One frozen-rotor zone of `constant/MRFProperties`.
#[derive(Clone, Debug, PartialEq)]
pub struct MrfZone {
    /// The zone's name (its dictionary keyword).
    pub name: String,
    /// The cell zone that rotates.
    pub cell_zone: String,
    /// `active` (default yes).
    pub active: bool,
    /// Patches in the zone that do not rotate.
    pub non_rotating_patches: Vec<String>,
    /// A point on the axis, in the mesh's units.
    pub origin: DVec3,
    /// The unit axis.
    pub axis: DVec3,
    /// Angular speed about the axis, rad/s.
    pub omega: f64,
}

/// The case's `constant/SRFProperties`, if it has one.
pub fn read_srf(case_dir: impl AsRef<Path>) -> Result<Option<Srf>, MeshError> {
    let base = case_dir.as_ref().join("constant").join("SRFProperties");
    let Some((file, d)) = read_dict(&base)? else {
        return Ok(None);
    };
    let bad = |entry: &str, message: String| MeshError::invalid(&file, entry, message);
    match d.word("SRFModel") {
        Some("rpm") => {}
        Some(other) => {
            return Err(bad(
                "SRFModel",
                format!("unknown SRF model '{other}' (OpenFOAM's is `rpm`)"),
            ));
        }
        None => return Err(bad("SRFModel", "missing".into())),
    }
    let origin = vector(&d, "origin").map_err(|m| bad("origin", m))?;
    let axis = unit(vector(&d, "axis").map_err(|m| bad("axis", m))?).map_err(|m| bad("axis", m))?;
    let rpm = match d.get("rpmCoeffs") {
        Some(Value::Dict(c)) => c.number("rpm"),
        _ => None,
    }
    .filter(|r| r.is_finite())
    .ok_or_else(|| bad("rpmCoeffs/rpm", "missing or not a finite number".into()))?;
    Ok(Some(Srf { origin, axis, rpm }))
}

/// The zones of the case's `constant/MRFProperties`, if it has one.
///
/// `omega` is read as OpenFOAM v1912 reads it (a number, or `constant <number>`) or from
/// `rpm` (newer releases); a zone with neither is an error naming the entry.
pub fn read_mrf(case_dir: impl AsRef<Path>) -> Result<Option<Vec<MrfZone>>, MeshError> {
    let base = case_dir.as_ref().join("constant").join("MRFProperties");
    let Some((file, d)) = read_dict(&base)? else {
        return Ok(None);
    };
    let mut out = Vec::new();
    for (name, value) in &d.entries {
        let Value::Dict(z) = value else { continue };
        let bad = |key: &str, message: String| {
            MeshError::invalid(&file, format!("{name}/{key}"), message)
        };
        let cell_zone = z
            .word("cellZone")
            .ok_or_else(|| bad("cellZone", "missing".into()))?
            .to_string();
        let active = match z.word("active") {
            None | Some("yes" | "on" | "true") => true,
            Some("no" | "off" | "false") => false,
            Some(w) => return Err(bad("active", format!("'{w}' is not yes or no"))),
        };
        let non_rotating_patches = match z.get("nonRotatingPatches") {
            None => Vec::new(),
            Some(Value::Tokens(t)) => t
                .iter()
                .filter_map(|k| match k {
                    Token::Word(w) | Token::Str(w) => Some(w.clone()),
                    _ => None,
                })
                .collect(),
            Some(Value::Dict(_)) => {
                return Err(bad("nonRotatingPatches", "a list of patch names".into()));
            }
        };
        let origin = vector(z, "origin").map_err(|m| bad("origin", m))?;
        let axis =
            unit(vector(z, "axis").map_err(|m| bad("axis", m))?).map_err(|m| bad("axis", m))?;
        let omega = match (z.get("omega"), z.number("rpm")) {
            (Some(Value::Tokens(t)), _) => match t.as_slice() {
                [Token::Num(w)] => Some(*w),
                [Token::Word(k), Token::Num(w)] if k == "constant" => Some(*w),
                _ => {
                    return Err(bad(
                        "omega",
                        "only a constant rate is read (`omega 104.7;` or `omega constant 104.7;`)"
                            .into(),
                    ));
                }
            },
            (None, Some(rpm)) => Some(rpm * std::f64::consts::TAU / 60.0),
            _ => None,
        }
        .filter(|w| w.is_finite())
        .ok_or_else(|| bad("omega", "missing (or `rpm`), or not a finite number".into()))?;
        out.push(MrfZone {
            name: name.clone(),
            cell_zone,
            active,
            non_rotating_patches,
            origin,
            axis,
            omega,
        });
    }
    Ok(Some(out))
}

/// The dictionary in `base` (or `base.gz`), `None` when neither exists.
fn read_dict(base: &Path) -> Result<Option<(std::path::PathBuf, Dict)>, MeshError> {
    let mut gz = base.as_os_str().to_owned();
    gz.push(".gz");
    if !base.exists() && !Path::new(&gz).exists() {
        return Ok(None);
    }
    let (file, bytes) = read_maybe_gz(base)?;
    let mut p = Parser::new(&file, &bytes);
    p.header()?;
    let d = p.dict_body("", false)?;
    Ok(Some((file, d)))
}

/// `key (x y z);` of `d`.
fn vector(d: &Dict, key: &str) -> Result<DVec3, String> {
    match d.get(key) {
        Some(Value::Tokens(t)) => match t.as_slice() {
            [
                Token::Punct(b'('),
                Token::Num(x),
                Token::Num(y),
                Token::Num(z),
                Token::Punct(b')'),
            ] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(DVec3::new(*x, *y, *z)),
            _ => Err("must be a vector (x y z) of finite numbers".into()),
        },
        Some(Value::Dict(_)) => Err("must be a vector (x y z), not a dictionary".into()),
        None => Err("missing".into()),
    }
}

/// `v` normalised; an error for a zero vector.
fn unit(v: DVec3) -> Result<DVec3, String> {
    let l = v.length();
    if l > 0.0 {
        Ok(v / l)
    } else {
        Err("must not be the zero vector".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "FoamFile\n{\n version 2.0;\n format ascii;\n class dictionary;\n \
                          object X;\n}\n";

    fn case_with(name: &str, body: &str) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("constant")).unwrap();
        std::fs::write(
            dir.path().join("constant").join(name),
            format!("{HEADER}{body}"),
        )
        .unwrap();
        dir
    }

    #[test]
    fn reads_the_mixer_tutorials_srf_properties() {
        let c = case_with(
            "SRFProperties",
            "SRFModel rpm;\norigin (0 0 0);\naxis (0 0 2);\nrpmCoeffs\n{\n rpm 1000;\n}\n",
        );
        let s = read_srf(c.path()).unwrap().unwrap();
        assert_eq!(s.axis, DVec3::Z);
        assert_eq!(s.rpm, 1000.0);
        assert!((s.omega().z - 104.719_755_119_659_77).abs() < 1e-12);
        assert_eq!(read_mrf(c.path()).unwrap(), None);
        assert_eq!(read_srf(tempfile::tempdir().unwrap().path()).unwrap(), None);
    }

    #[test]
    fn srf_errors_name_the_entry() {
        for (body, entry) in [
            (
                "SRFModel spin;\norigin (0 0 0);\naxis (0 0 1);\nrpmCoeffs { rpm 1; }\n",
                "SRFModel",
            ),
            (
                "SRFModel rpm;\naxis (0 0 1);\nrpmCoeffs { rpm 1; }\n",
                "origin",
            ),
            (
                "SRFModel rpm;\norigin (0 0 0);\naxis (0 0 0);\nrpmCoeffs { rpm 1; }\n",
                "axis",
            ),
            (
                "SRFModel rpm;\norigin (0 0 0);\naxis (0 0 1);\n",
                "rpmCoeffs/rpm",
            ),
        ] {
            let c = case_with("SRFProperties", body);
            let e = read_srf(c.path()).unwrap_err().to_string();
            assert!(e.contains("SRFProperties") && e.contains(entry), "{e}");
        }
    }

    #[test]
    fn reads_mrf_zones() {
        let c = case_with(
            "MRFProperties",
            "MRF1\n{\n cellZone rotor;\n active yes;\n nonRotatingPatches (shaft hub);\n \
             origin (0 0 0.1);\n axis (0 0 1);\n omega constant 10;\n}\n\
             MRF2 { cellZone r2; active no; origin (0 0 0); axis (1 0 0); rpm 60; }\n",
        );
        let z = read_mrf(c.path()).unwrap().unwrap();
        assert_eq!(z.len(), 2);
        assert_eq!(z[0].cell_zone, "rotor");
        assert_eq!(z[0].non_rotating_patches, ["shaft", "hub"]);
        assert_eq!(z[0].omega, 10.0);
        assert!(!z[1].active);
        assert!((z[1].omega - std::f64::consts::TAU).abs() < 1e-12);
        let c = case_with(
            "MRFProperties",
            "MRF1 { cellZone rotor; origin (0 0 0); axis (0 0 1); omega table ((0 1)); }\n",
        );
        let e = read_mrf(c.path()).unwrap_err().to_string();
        assert!(e.contains("MRF1/omega"), "{e}");
    }
}

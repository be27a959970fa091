//! Writing a [`PolyMesh`], a [`CellField`] and a [`ScalarField`] as an OpenFOAM case.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use crate::{CellField, MeshError, PolyMesh, ScalarField};

/// How lists are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Text; faces as `faceList`. Numbers are written in Rust's shortest round-trip form,
    /// so they read back bit for bit.
    Ascii,
    /// Raw little-endian bytes (`arch "LSB;label=32;scalar=64"`); faces as
    /// `faceCompactList`, as OpenFOAM writes them in binary.
    Binary,
}

/// Write `mesh` as the case `dir` (`constant/polyMesh/{points, faces, owner, neighbour,
/// boundary}`, plus a minimal `system/` with controlDict, fvSchemes and fvSolution so that
/// OpenFOAM utilities such as `checkMesh` run on it) and, when given, the field
/// `(name, field)` as the volVectorField `0/<name>`. Directories are created as needed.
pub fn write_case(
    dir: impl AsRef<Path>,
    mesh: &PolyMesh,
    field: Option<(&str, &CellField)>,
    format: Format,
) -> Result<(), MeshError> {
    let dir = dir.as_ref();
    let pm = dir.join("constant").join("polyMesh");
    mesh.check(&pm)?;
    let io = |file: &Path| {
        let file = file.to_path_buf();
        move |source| MeshError::Io { file, source }
    };
    std::fs::create_dir_all(&pm).map_err(io(&pm))?;
    let w = Writer { format };

    let file = pm.join("points");
    let mut out = w.header("vectorField", "constant/polyMesh", "points", None);
    w.vectors(&mut out, &mesh.points);
    put(&file, out)?;

    let file = pm.join("faces");
    let n_faces = mesh.n_faces();
    let mut out;
    match format {
        Format::Ascii => {
            out = w.header("faceList", "constant/polyMesh", "faces", None);
            out.extend(format!("\n{n_faces}\n(\n").bytes());
            for f in 0..n_faces {
                let face = mesh.face(f);
                out.extend(format!("{}(", face.len()).bytes());
                for (i, p) in face.iter().enumerate() {
                    if i > 0 {
                        out.push(b' ');
                    }
                    out.extend(p.to_string().bytes());
                }
                out.extend(b")\n");
            }
            out.extend(b")\n");
        }
        Format::Binary => {
            out = w.header("faceCompactList", "constant/polyMesh", "faces", None);
            w.labels(&mut out, &mesh.face_offsets);
            w.labels(&mut out, &mesh.face_points);
        }
    }
    put(&file, out)?;

    let note = format!(
        "nPoints:{} nCells:{} nFaces:{} nInternalFaces:{}",
        mesh.points.len(),
        mesh.n_cells,
        n_faces,
        mesh.n_internal_faces()
    );
    for (name, list) in [("owner", &mesh.owner), ("neighbour", &mesh.neighbour)] {
        let mut out = w.header("labelList", "constant/polyMesh", name, Some(&note));
        w.labels(&mut out, list);
        put(&pm.join(name), out)?;
    }

    let mut out = w.header("polyBoundaryMesh", "constant/polyMesh", "boundary", None);
    out.extend(format!("\n{}\n(\n", mesh.patches.len()).bytes());
    for p in &mesh.patches {
        let groups = if p.kind == "wall" {
            "        inGroups        1(wall);\n"
        } else {
            ""
        };
        out.extend(
            format!(
                "    {}\n    {{\n        type            {};\n{groups}        nFaces          {};\n        startFace       {};\n    }}\n",
                p.name, p.kind, p.size, p.start
            )
            .bytes(),
        );
    }
    out.extend(b")\n");
    put(&pm.join("boundary"), out)?;

    let sys = dir.join("system");
    std::fs::create_dir_all(&sys).map_err(io(&sys))?;
    let fmt = match format {
        Format::Ascii => "ascii",
        Format::Binary => "binary",
    };
    let dict = |object: &str, body: &str| {
        format!(
            "FoamFile\n{{\n    version     2.0;\n    format      ascii;\n    class       dictionary;\n    object      {object};\n}}\n\n{body}"
        )
        .into_bytes()
    };
    put(
        &sys.join("controlDict"),
        dict(
            "controlDict",
            &format!(
                "application     none;\nstartFrom       latestTime;\nstartTime       0;\nstopAt          endTime;\nendTime         0;\ndeltaT          1;\nwriteControl    timeStep;\nwriteInterval   1;\nwriteFormat     {fmt};\nwritePrecision  17;\nwriteCompression off;\ntimeFormat      general;\ntimePrecision   6;\nrunTimeModifiable false;\n"
            ),
        ),
    )?;
    put(
        &sys.join("fvSchemes"),
        dict(
            "fvSchemes",
            "ddtSchemes { default steadyState; }\ngradSchemes { default Gauss linear; }\ndivSchemes { default none; }\nlaplacianSchemes { default Gauss linear corrected; }\ninterpolationSchemes { default linear; }\nsnGradSchemes { default corrected; }\n",
        ),
    )?;
    put(&sys.join("fvSolution"), dict("fvSolution", "solvers {}\n"))?;

    if let Some((name, field)) = field {
        write_vector_field(dir, "0", name, mesh, field, format)?;
    }
    Ok(())
}

/// Write `field` as the volVectorField `dir/<time>/<name>` on `mesh`. Patches with values
/// are written `type calculated; value nonuniform List<vector> ...`, the others
/// `type zeroGradient` (`type empty` on empty patches).
pub fn write_vector_field(
    dir: impl AsRef<Path>,
    time: &str,
    name: &str,
    mesh: &PolyMesh,
    field: &CellField,
    format: Format,
) -> Result<(), MeshError> {
    let w = Writer { format };
    let file = FieldFile {
        dir: dir.as_ref(),
        time,
        name,
        class: "volVectorField",
        dimensions: "[0 1 -1 0 0 0 0]",
        list: "List<vector>",
    };
    file.write(
        mesh,
        &field.cells,
        &field.patches,
        |out, v| w.vectors(out, v),
        &w,
    )
}

/// Write `field` as the volScalarField `dir/<time>/<name>` on `mesh`, as
/// [`write_vector_field`] writes a vector: the cells as `nonuniform List<scalar>`, patches
/// with values `type calculated; value nonuniform List<scalar> ...`, the others
/// `type zeroGradient` (`type empty` on empty patches). The `dimensions` are those of
/// `k`, `epsilon`, `omega`, `nut`, `nuTilda` or kinematic `p` when `name` is one of them,
/// else dimensionless.
pub fn write_scalar_field(
    dir: impl AsRef<Path>,
    time: &str,
    name: &str,
    mesh: &PolyMesh,
    field: &ScalarField,
    format: Format,
) -> Result<(), MeshError> {
    let w = Writer { format };
    let file = FieldFile {
        dir: dir.as_ref(),
        time,
        name,
        class: "volScalarField",
        dimensions: match name {
            "k" | "p" => "[0 2 -2 0 0 0 0]",
            "epsilon" => "[0 2 -3 0 0 0 0]",
            "omega" => "[0 0 -1 0 0 0 0]",
            "nut" | "nuTilda" => "[0 2 -1 0 0 0 0]",
            _ => "[0 0 0 0 0 0 0]",
        },
        list: "List<scalar>",
    };
    file.write(
        mesh,
        &field.cells,
        &field.patches,
        |out, v| w.scalars(out, v),
        &w,
    )
}

/// A field file to write.
struct FieldFile<'a> {
    dir: &'a Path,
    time: &'a str,
    name: &'a str,
    class: &'a str,
    dimensions: &'a str,
    /// The list type (`List<vector>`).
    list: &'a str,
}

impl FieldFile<'_> {
    fn write<T>(
        &self,
        mesh: &PolyMesh,
        cells: &[T],
        patches: &[Option<Vec<T>>],
        values: impl Fn(&mut Vec<u8>, &[T]),
        w: &Writer,
    ) -> Result<(), MeshError> {
        let tdir = self.dir.join(self.time);
        let file = tdir.join(self.name);
        if cells.len() != mesh.n_cells {
            return Err(MeshError::invalid(
                &file,
                "internalField",
                format!("{} values for {} cells", cells.len(), mesh.n_cells),
            ));
        }
        if patches.len() != mesh.patches.len() {
            return Err(MeshError::invalid(
                &file,
                "boundaryField",
                format!(
                    "{} patch entries for {} patches",
                    patches.len(),
                    mesh.patches.len()
                ),
            ));
        }
        std::fs::create_dir_all(&tdir).map_err(|source| MeshError::Io {
            file: tdir.clone(),
            source,
        })?;
        let mut out = w.header(self.class, self.time, self.name, None);
        out.extend(
            format!(
                "\ndimensions      {};\n\ninternalField   nonuniform {} ",
                self.dimensions, self.list
            )
            .bytes(),
        );
        values(&mut out, cells);
        out.extend(b";\n\nboundaryField\n{\n");
        for (p, vals) in mesh.patches.iter().zip(patches) {
            out.extend(format!("    {}\n    {{\n", p.name).bytes());
            match vals {
                Some(v) => {
                    if v.len() != p.size {
                        return Err(MeshError::invalid(
                            &file,
                            format!("boundaryField/{}/value", p.name),
                            format!("{} values for {} faces", v.len(), p.size),
                        ));
                    }
                    out.extend(
                        format!(
                            "        type            calculated;\n        value           nonuniform {} ",
                            self.list
                        )
                        .bytes(),
                    );
                    values(&mut out, v);
                    out.extend(b";\n");
                }
                None if p.kind == "empty" => out.extend(b"        type            empty;\n"),
                None => out.extend(b"        type            zeroGradient;\n"),
            }
            out.extend(b"    }\n");
        }
        out.extend(b"}\n");
        put(&file, out)
    }
}

fn put(file: &Path, bytes: Vec<u8>) -> Result<(), MeshError> {
    let mut f = std::fs::File::create(file).map_err(|source| MeshError::Io {
        file: file.to_path_buf(),
        source,
    })?;
    f.write_all(&bytes)
        .and_then(|_| f.write_all(b"\n// ************************************************************************* //\n"))
        .map_err(|source| MeshError::Io {
            file: file.to_path_buf(),
            source,
        })
}

struct Writer {
    format: Format,
}

impl Writer {
    fn header(&self, class: &str, location: &str, object: &str, note: Option<&str>) -> Vec<u8> {
        let format = match self.format {
            Format::Ascii => "ascii",
            Format::Binary => "binary",
        };
        let note = note.map_or(String::new(), |n| format!("    note        \"{n}\";\n"));
        format!(
            "/*--------------------------------*- C++ -*----------------------------------*\\\n  Written by scg-mesh\n\\*---------------------------------------------------------------------------*/\nFoamFile\n{{\n    version     2.0;\n    format      {format};\n    arch        \"LSB;label=32;scalar=64\";\n    class       {class};\n{note}    location    \"{location}\";\n    object      {object};\n}}\n// * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * //\n\n"
        )
        .into_bytes()
    }

    fn vectors(&self, out: &mut Vec<u8>, v: &[DVec3]) {
        out.extend(format!("\n{}\n(", v.len()).bytes());
        match self.format {
            Format::Ascii => {
                out.push(b'\n');
                for x in v {
                    out.extend(format!("({} {} {})\n", x.x, x.y, x.z).bytes());
                }
            }
            Format::Binary => {
                for x in v {
                    for c in x.to_array() {
                        out.extend(c.to_le_bytes());
                    }
                }
            }
        }
        out.extend(b")\n");
    }

    fn scalars(&self, out: &mut Vec<u8>, v: &[f64]) {
        out.extend(format!("\n{}\n(", v.len()).bytes());
        match self.format {
            Format::Ascii => {
                out.push(b'\n');
                for x in v {
                    out.extend(format!("{x}\n").bytes());
                }
            }
            Format::Binary => {
                for x in v {
                    out.extend(x.to_le_bytes());
                }
            }
        }
        out.extend(b")\n");
    }

    fn labels(&self, out: &mut Vec<u8>, v: &[u32]) {
        out.extend(format!("\n{}\n(", v.len()).bytes());
        match self.format {
            Format::Ascii => {
                out.push(b'\n');
                for x in v {
                    out.extend(x.to_string().bytes());
                    out.push(b'\n');
                }
            }
            Format::Binary => {
                for &x in v {
                    // PolyMesh::check bounds every index by a length; lengths fit 31 bits.
                    out.extend((x as i32).to_le_bytes());
                }
            }
        }
        out.extend(b")\n");
    }
}

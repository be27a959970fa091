//! `constant/polyMesh` → [`PolyMesh`].

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::parse::{Dict, Elem, LABEL, Parser, VECTOR};
use super::read_maybe_gz;
use crate::{MeshError, Patch, PolyMesh};

/// Read the mesh of an OpenFOAM case from `case_dir/constant/polyMesh/{points, faces,
/// owner, neighbour, boundary}` (each plain or `.gz`). Points are in metres, as OpenFOAM
/// stores them. The number of cells is max(owner, neighbour) + 1, checked against the
/// `nCells` of the owner file's `note` when there is one; the result passes
/// [`PolyMesh::check`].
pub fn read_mesh(case_dir: impl AsRef<Path>) -> Result<PolyMesh, MeshError> {
    let dir = case_dir.as_ref().join("constant").join("polyMesh");
    let files = ["points", "faces", "owner", "neighbour", "boundary"]
        .map(|name| read_maybe_gz(&dir.join(name)));
    let [points, faces, owner, neighbour, boundary] = files;
    let (points, faces, owner, neighbour, boundary) =
        (points?, faces?, owner?, neighbour?, boundary?);
    parse_mesh(
        &dir,
        [
            view(&points),
            view(&faces),
            view(&owner),
            view(&neighbour),
            view(&boundary),
        ],
    )
}

fn view(x: &(PathBuf, Vec<u8>)) -> (&Path, &[u8]) {
    (x.0.as_path(), x.1.as_slice())
}

/// The mesh from the bytes of its five files (points, faces, owner, neighbour, boundary),
/// each with the path that names it in errors; `dir` names the mesh as a whole.
pub(crate) fn parse_mesh(dir: &Path, files: [(&Path, &[u8]); 5]) -> Result<PolyMesh, MeshError> {
    let [points, faces, owner_f, neighbour_f, boundary] = files;
    let points = parse_points(points.0, points.1)?;
    let (face_offsets, face_points) = parse_faces(faces.0, faces.1)?;
    let (owner, owner_note) = parse_labels(owner_f.0, owner_f.1, "owner")?;
    let (neighbour, _) = parse_labels(neighbour_f.0, neighbour_f.1, "neighbour")?;
    let patches = parse_boundary(boundary.0, boundary.1)?;

    let n_faces = face_offsets.len().saturating_sub(1);
    if owner.len() != n_faces {
        return Err(MeshError::invalid(
            owner_f.0,
            "owner",
            format!("{} owners for {n_faces} faces", owner.len()),
        ));
    }
    if neighbour.len() > n_faces {
        return Err(MeshError::invalid(
            neighbour_f.0,
            "neighbour",
            format!("{} neighbours for {n_faces} faces", neighbour.len()),
        ));
    }
    let n_cells = owner
        .iter()
        .chain(&neighbour)
        .max()
        .map_or(0, |&c| c as usize + 1);
    if let Some(note) = owner_note
        && let Some(nc) = note_count(&note, "nCells")
        && nc != n_cells
    {
        return Err(MeshError::invalid(
            owner_f.0,
            "FoamFile/note",
            format!("nCells:{nc} but the owner and neighbour lists address {n_cells} cells"),
        ));
    }
    let mesh = PolyMesh {
        points,
        face_offsets,
        face_points,
        owner,
        neighbour,
        patches,
        n_cells,
    };
    mesh.check(dir)?;
    Ok(mesh)
}

/// The count `key:N` in a `note "nPoints:.. nCells:.. ..."`.
fn note_count(note: &str, key: &str) -> Option<usize> {
    note.split_whitespace()
        .find_map(|kv| kv.strip_prefix(key)?.strip_prefix(':')?.parse().ok())
}

fn header_class(p: &mut Parser, classes: &[&str]) -> Result<(Dict, String), MeshError> {
    let h = p.header()?;
    let class = h.word("class").unwrap_or("").to_string();
    if !classes.contains(&class.as_str()) {
        return Err(p.err(
            "FoamFile/class",
            format!(
                "class '{class}' where {} was expected",
                classes.join(" or ")
            ),
        ));
    }
    Ok((h, class))
}

fn end(p: &mut Parser, entry: &str) -> Result<(), MeshError> {
    if p.at_end() {
        Ok(())
    } else {
        Err(p.err(entry, "unexpected data after the list"))
    }
}

fn parse_points(file: &Path, bytes: &[u8]) -> Result<Vec<DVec3>, MeshError> {
    let mut p = Parser::new(file, bytes);
    header_class(&mut p, &["vectorField"])?;
    let points = p.list("points", VECTOR)?;
    end(&mut p, "points")?;
    if let Some((i, x)) = points.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(MeshError::invalid(
            file,
            format!("points[{i}]"),
            format!("not finite: {x}"),
        ));
    }
    Ok(points)
}

/// A label as a `u32` index, or an error naming `entry`.
fn index(file: &Path, entry: impl FnOnce() -> String, v: i64) -> Result<u32, MeshError> {
    u32::try_from(v).map_err(|_| MeshError::invalid(file, entry(), format!("invalid index {v}")))
}

fn parse_faces(file: &Path, bytes: &[u8]) -> Result<(Vec<u32>, Vec<u32>), MeshError> {
    let mut p = Parser::new(file, bytes);
    let (_, class) = header_class(&mut p, &["faceList", "faceCompactList"])?;
    if class == "faceList" {
        let faces: Vec<Vec<i64>> = p.list("faces", Elem::Face(|v| v))?;
        end(&mut p, "faces")?;
        let mut offsets = Vec::with_capacity(faces.len() + 1);
        offsets.push(0u32);
        let mut pts = Vec::with_capacity(faces.iter().map(Vec::len).sum());
        for (f, face) in faces.iter().enumerate() {
            for &v in face {
                pts.push(index(file, || format!("faces[{f}]"), v)?);
            }
            offsets.push(index(file, || format!("faces[{f}]"), pts.len() as i64)?);
        }
        Ok((offsets, pts))
    } else {
        let offs = p.list("faces/offsets", LABEL)?;
        let pts = p.list("faces/points", LABEL)?;
        end(&mut p, "faces")?;
        if offs.first().is_some_and(|&o| o != 0) {
            return Err(MeshError::invalid(
                file,
                "faces/offsets[0]",
                format!("{} where 0 was expected", offs[0]),
            ));
        }
        let mut offsets = Vec::with_capacity(offs.len().max(1));
        let mut prev = 0;
        for (i, &o) in offs.iter().enumerate() {
            if o < prev || o as usize > pts.len() {
                return Err(MeshError::invalid(
                    file,
                    format!("faces/offsets[{i}]"),
                    format!(
                        "offset {o} out of order or past the {} point indices",
                        pts.len()
                    ),
                ));
            }
            prev = o;
            offsets.push(o as u32);
        }
        if offsets.is_empty() {
            offsets.push(0);
        }
        if *offsets.last().unwrap_or(&0) as usize != pts.len() {
            return Err(MeshError::invalid(
                file,
                "faces/offsets",
                format!(
                    "the last offset is {} but there are {} point indices",
                    offsets.last().unwrap_or(&0),
                    pts.len()
                ),
            ));
        }
        let pts = pts
            .iter()
            .enumerate()
            .map(|(i, &v)| index(file, || format!("faces/points[{i}]"), v))
            .collect::<Result<Vec<u32>, _>>()?;
        Ok((offsets, pts))
    }
}

/// A labelList (owner or neighbour), with the header's `note` if any.
fn parse_labels(
    file: &Path,
    bytes: &[u8],
    name: &str,
) -> Result<(Vec<u32>, Option<String>), MeshError> {
    let mut p = Parser::new(file, bytes);
    let (h, _) = header_class(&mut p, &["labelList"])?;
    let raw = p.list(name, LABEL)?;
    end(&mut p, name)?;
    let list = raw
        .iter()
        .enumerate()
        .map(|(i, &v)| index(file, || format!("{name}[{i}]"), v))
        .collect::<Result<Vec<u32>, _>>()?;
    Ok((list, h.word("note").map(str::to_owned)))
}

fn parse_boundary(file: &Path, bytes: &[u8]) -> Result<Vec<Patch>, MeshError> {
    let mut p = Parser::new(file, bytes);
    header_class(&mut p, &["polyBoundaryMesh"])?;
    // The patch list is read as text even in binary files (OpenFOAM writes it so).
    p.enc.binary = false;
    let n = p.label("boundary")?;
    if n < 0 {
        return Err(p.err("boundary", format!("invalid number of patches {n}")));
    }
    p.expect(b'(', "boundary")?;
    let mut patches = Vec::new();
    for i in 0..n {
        let (name, dict) = p.named_dict(&format!("boundary[{i}]"))?;
        let entry = format!("boundary/{name}");
        let kind = dict
            .word("type")
            .ok_or_else(|| MeshError::invalid(file, format!("{entry}/type"), "missing"))?
            .to_string();
        let count = |key: &str| -> Result<usize, MeshError> {
            match dict.number(key) {
                Some(x) if x >= 0.0 && x.fract() == 0.0 && x < u32::MAX as f64 => Ok(x as usize),
                Some(x) => Err(MeshError::invalid(
                    file,
                    format!("{entry}/{key}"),
                    format!("{x} is not a face count"),
                )),
                None => Err(MeshError::invalid(
                    file,
                    format!("{entry}/{key}"),
                    "missing or not a number",
                )),
            }
        };
        patches.push(Patch {
            name,
            kind,
            start: count("startFace")?,
            size: count("nFaces")?,
        });
    }
    p.expect(b')', "boundary")?;
    end(&mut p, "boundary")?;
    Ok(patches)
}

/// The cell zones of a case (`constant/polyMesh/cellZones`, plain or `.gz`): per zone its
/// name and cell labels; empty when the file does not exist. Every label must be a cell
/// of a mesh of `cells` cells.
pub fn read_cell_zones(
    case_dir: impl AsRef<Path>,
    cells: usize,
) -> Result<Vec<(String, Vec<u32>)>, MeshError> {
    let base = case_dir.as_ref().join("constant/polyMesh/cellZones");
    let mut gz = base.as_os_str().to_owned();
    gz.push(".gz");
    if !base.exists() && !Path::new(&gz).exists() {
        return Ok(Vec::new());
    }
    let (file, bytes) = read_maybe_gz(&base)?;
    parse_cell_zones(&file, &bytes, cells)
}

/// The zones of a `cellZones` file's bytes.
pub(crate) fn parse_cell_zones(
    file: &Path,
    bytes: &[u8],
    cells: usize,
) -> Result<Vec<(String, Vec<u32>)>, MeshError> {
    use super::parse::{ListData, Token, Value};
    let mut p = Parser::new(file, bytes);
    header_class(&mut p, &["regIOobject", "cellZoneMesh"])?;
    let n = p.label("cellZones")?;
    if n < 0 {
        return Err(p.err("cellZones", format!("invalid number of zones {n}")));
    }
    p.expect(b'(', "cellZones")?;
    let mut zones = Vec::new();
    for i in 0..n {
        let (name, dict) = p.named_dict(&format!("cellZones[{i}]"))?;
        let entry = format!("cellZones/{name}/cellLabels");
        let labels = match dict.get("cellLabels") {
            Some(Value::Tokens(t)) => match t.as_slice() {
                [Token::List(ListData::Labels(l))] => l.clone(),
                [Token::Word(w), Token::Num(x)] if w == "uniform" && *x == 0.0 => Vec::new(),
                _ => {
                    return Err(MeshError::invalid(
                        file,
                        entry,
                        "must be a List<label> of cell labels",
                    ));
                }
            },
            _ => return Err(MeshError::invalid(file, entry, "missing")),
        };
        let mut out = Vec::with_capacity(labels.len());
        for (k, l) in labels.into_iter().enumerate() {
            if l < 0 || l as usize >= cells {
                return Err(MeshError::invalid(
                    file,
                    format!("{entry}[{k}]"),
                    format!("{l} is not a cell of the mesh ({cells} cells)"),
                ));
            }
            out.push(l as u32);
        }
        zones.push((name, out));
    }
    p.expect(b')', "cellZones")?;
    end(&mut p, "cellZones")?;
    Ok(zones)
}

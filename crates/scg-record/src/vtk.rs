//! VTK files for ParaView (and any VTK reader): one XML UnstructuredGrid (`.vtu`) per
//! frame, the particles as vertex cells with their velocity, diameter, density, id and
//! group (and, with dispersion, the fluctuation |u′|) as point data; a ParaView
//! collection (`<case>.pvd`) that puts the frames on the simulation time; the scene
//! geometry as line cells in `<case>_geometry.vtu`; and a mesh flow's boundary patches as
//! triangles in `<case>_patches.vtu` (cell data `patch`, `role`); moving walls per frame
//! where they are, `<case>_walls_<step>.vtu` indexed by `<case>_walls.pvd`; with `[erosion]`, the
//! wear of the walls per face in `<case>_erosion.vtu`, written when the run finishes.
//!
//! A frame without particles is a grid of no points and no cells, which VTK's reader and
//! ParaView load; meshio 5.3 reads no grid without cells (not even one it writes itself).
//!
//! The files are ASCII, floats written in shortest round-trip exponent form, so a reader
//! gets back every recorded value bit for bit. [`VtkSink`] writes them while a run goes
//! (`scg run --vtk DIR`) or from a recording (`scg replay REC.mcap --vtk DIR`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use scg_core::frame::{Frame, FrameSink, Outline, PatchSurface, RunMeta, WearMap};

use crate::RecordError;

/// Writes a run as VTK files into a folder (see the module documentation).
pub struct VtkSink {
    dir: PathBuf,
    case: String,
    /// (file name, time in s) of every frame written.
    written: Vec<(String, f64)>,
    /// The moving walls' outlines (drawn per frame where they are).
    moving: Vec<Outline>,
    /// (file name, time in s) of every moving-wall geometry file written.
    moved: Vec<(String, f64)>,
}

impl VtkSink {
    /// A sink writing into `dir` (created if missing), with the geometry of `meta` written
    /// at once.
    pub fn create(dir: &Path, meta: &RunMeta) -> Result<Self, RecordError> {
        std::fs::create_dir_all(dir).map_err(|source| RecordError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let (moving, still): (Vec<Outline>, Vec<Outline>) = meta
            .outlines
            .iter()
            .cloned()
            .partition(|o| !o.motion.is_fixed());
        let sink = VtkSink {
            dir: dir.to_path_buf(),
            case: meta.case.clone(),
            written: Vec::new(),
            moving,
            moved: Vec::new(),
        };
        if !still.is_empty() {
            let path = dir.join(format!("{}_geometry.vtu", meta.case));
            write_file(&path, &geometry_vtu(&still))?;
        }
        if !meta.patches.is_empty() {
            let path = dir.join(format!("{}_patches.vtu", meta.case));
            write_file(&path, &patches_vtu(&meta.patches))?;
        }
        Ok(sink)
    }

    /// The collection file that indexes the frames by time.
    pub fn pvd_path(&self) -> PathBuf {
        self.dir.join(format!("{}.pvd", self.case))
    }
}

fn write_file(path: &Path, text: &str) -> Result<(), RecordError> {
    std::fs::write(path, text).map_err(|source| RecordError::Io {
        path: path.to_path_buf(),
        source,
    })
}

impl FrameSink for VtkSink {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        let name = format!("{}_{:09}.vtu", self.case, frame.step);
        write_file(&self.dir.join(&name), &frame_vtu(frame)).map_err(|e| e.to_string())?;
        self.written.push((name, frame.time));
        if !self.moving.is_empty() {
            // the moving walls where they are at this frame's time
            let posed: Vec<Outline> = self
                .moving
                .iter()
                .map(|o| {
                    let p = o.motion.pose(frame.time);
                    let at = |v: [f64; 3]| p.to_world(glam::DVec3::from_array(v)).to_array();
                    Outline {
                        strips: o
                            .strips
                            .iter()
                            .map(|s| s.iter().map(|&v| at(v)).collect())
                            .collect(),
                        ..Default::default()
                    }
                })
                .collect();
            let name = format!("{}_walls_{:09}.vtu", self.case, frame.step);
            write_file(&self.dir.join(&name), &geometry_vtu(&posed)).map_err(|e| e.to_string())?;
            self.moved.push((name, frame.time));
        }
        Ok(())
    }

    fn write_wear(&mut self, wear: &WearMap) -> Result<(), String> {
        let path = self.dir.join(format!("{}_erosion.vtu", self.case));
        write_file(&path, &wear_vtu(wear)).map_err(|e| e.to_string())
    }

    fn finish(&mut self) -> Result<(), String> {
        write_file(&self.pvd_path(), &pvd(&self.written)).map_err(|e| e.to_string())?;
        if !self.moved.is_empty() {
            let path = self.dir.join(format!("{}_walls.pvd", self.case));
            write_file(&path, &pvd(&self.moved)).map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}

/// A ParaView collection of the files `written` (name, time in s), one per time step.
fn pvd(written: &[(String, f64)]) -> String {
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
    );
    for (name, t) in written {
        let _ = writeln!(
            pvd,
            "<DataSet timestep=\"{t}\" part=\"0\" file=\"{name}\"/>"
        );
    }
    pvd.push_str("</Collection>\n</VTKFile>\n");
    pvd
}

/// VTK cell types used here.
const VTK_VERTEX: u8 = 1;
const VTK_LINE: u8 = 3;
const VTK_TRIANGLE: u8 = 5;

/// A number as an ASCII `DataArray` writes it: floats in shortest round-trip exponent
/// form (`1.5e-5`), integers plain.
trait Ascii {
    fn put(&self, out: &mut String);
}

impl Ascii for f64 {
    fn put(&self, out: &mut String) {
        let _ = write!(out, "{self:e}");
    }
}

macro_rules! ascii_int {
    ($($t:ty),*) => {$(
        impl Ascii for $t {
            fn put(&self, out: &mut String) {
                let _ = write!(out, "{self}");
            }
        }
    )*};
}
ascii_int!(u8, u32, u64, usize);

impl<T: Ascii> Ascii for &T {
    fn put(&self, out: &mut String) {
        (*self).put(out)
    }
}

/// One `DataArray` of ASCII numbers.
fn data_array<T: Ascii>(
    out: &mut String,
    ty: &str,
    name: &str,
    components: usize,
    values: impl IntoIterator<Item = T>,
) {
    let comps = if components > 1 {
        format!(" NumberOfComponents=\"{components}\"")
    } else {
        String::new()
    };
    let _ = write!(
        out,
        "<DataArray type=\"{ty}\" Name=\"{name}\"{comps} format=\"ascii\">"
    );
    let mut any = false;
    for (k, v) in values.into_iter().enumerate() {
        if k > 0 {
            out.push(' ');
        }
        v.put(out);
        any = true;
    }
    // an empty array holds a line break, not nothing: readers that take the element's
    // text (meshio) find a string to split
    if !any {
        out.push('\n');
    }
    out.push_str("</DataArray>\n");
}

/// An UnstructuredGrid of `points` with the cells given by (connectivity, offsets, type).
fn grid(
    points: &[[f64; 3]],
    cells: (&[usize], &[usize], u8),
    point_data: impl FnOnce(&mut String),
) -> String {
    let (conn, offsets, ty) = cells;
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n",
    );
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        points.len(),
        offsets.len()
    );
    s.push_str("<PointData>\n");
    point_data(&mut s);
    s.push_str("</PointData>\n<Points>\n");
    data_array(&mut s, "Float64", "Points", 3, points.iter().flatten());
    s.push_str("</Points>\n<Cells>\n");
    data_array(&mut s, "Int64", "connectivity", 1, conn.iter());
    data_array(&mut s, "Int64", "offsets", 1, offsets.iter());
    data_array(&mut s, "UInt8", "types", 1, offsets.iter().map(|_| ty));
    s.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    s
}

/// The `.vtu` text of one frame.
pub fn frame_vtu(frame: &Frame) -> String {
    let n = frame.len();
    let conn: Vec<usize> = (0..n).collect();
    let offsets: Vec<usize> = (1..=n).collect();
    grid(&frame.position, (&conn, &offsets, VTK_VERTEX), |s| {
        data_array(s, "Float64", "velocity", 3, frame.velocity.iter().flatten());
        data_array(s, "Float64", "diameter", 1, &frame.diameter);
        data_array(s, "Float64", "density", 1, &frame.density);
        data_array(s, "UInt32", "id", 1, &frame.id);
        data_array(s, "UInt32", "group", 1, &frame.group);
        if !frame.fluctuation.is_empty() {
            data_array(s, "Float64", "fluctuation", 1, &frame.fluctuation);
        }
    })
}

/// The `.vtu` text of a mesh flow's boundary patches: their triangles, with the cell data
/// `patch` (the patch's index in the mesh) and `role` (0 wall, 1 outlet, 2 inlet, 3 other).
pub fn patches_vtu(patches: &[PatchSurface]) -> String {
    let mut points: Vec<[f64; 3]> = Vec::new();
    let (mut conn, mut offsets, mut patch, mut role) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, p) in patches.iter().enumerate() {
        let base = points.len();
        points.extend_from_slice(&p.vertices);
        let r: u32 = match p.role.as_str() {
            "wall" => 0,
            "outlet" => 1,
            "inlet" => 2,
            _ => 3,
        };
        for t in &p.triangles {
            conn.extend(t.iter().map(|&v| base + v as usize));
            offsets.push(conn.len());
            patch.push(i as u32);
            role.push(r);
        }
    }
    let mut s = grid(&points, (&conn, &offsets, VTK_TRIANGLE), |_| {});
    let mut cd = String::from("<CellData>\n");
    data_array(&mut cd, "UInt32", "patch", 1, &patch);
    data_array(&mut cd, "UInt32", "role", 1, &role);
    cd.push_str("</CellData>\n");
    let at = s.find("<Points>").unwrap_or(s.len());
    s.insert_str(at, &cd);
    s
}

/// The `.vtu` text of a run's wear (`[erosion]`): the logged patches' faces as triangles
/// (each face fanned from its first point), with cell data `patch` (index in the map),
/// `face` (the mesh's face index), `volume_m3`, `depth_rate_m_per_s`, `impacts` and the
/// impacts' mass-weighted `angle_deg`, `normal_speed_m_per_s` and
/// `tangential_speed_m_per_s` (0 where none struck) of the face each triangle belongs to.
pub fn wear_vtu(wear: &WearMap) -> String {
    let mut points: Vec<[f64; 3]> = Vec::new();
    let (mut conn, mut offsets) = (Vec::new(), Vec::new());
    let (mut patch, mut face, mut volume, mut rate, mut impacts) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut angle, mut normal, mut tangential) = (Vec::new(), Vec::new(), Vec::new());
    for (i, p) in wear.patches.iter().enumerate() {
        let base = points.len();
        points.extend_from_slice(&p.vertices);
        for (t, &f) in p.triangles.iter().zip(&p.triangle_face) {
            conn.extend(t.iter().map(|&v| base + v as usize));
            offsets.push(conn.len());
            let f = f as usize;
            patch.push(i as u32);
            face.push(p.faces[f]);
            volume.push(p.volume[f]);
            rate.push(p.depth_rate[f]);
            impacts.push(p.impacts[f]);
            angle.push(p.angle[f].to_degrees());
            normal.push(p.normal_speed[f]);
            tangential.push(p.tangential_speed[f]);
        }
    }
    let mut s = grid(&points, (&conn, &offsets, VTK_TRIANGLE), |_| {});
    let mut cd = String::from("<CellData>\n");
    data_array(&mut cd, "UInt32", "patch", 1, &patch);
    data_array(&mut cd, "UInt32", "face", 1, &face);
    data_array(&mut cd, "Float64", "volume_m3", 1, &volume);
    data_array(&mut cd, "Float64", "depth_rate_m_per_s", 1, &rate);
    data_array(&mut cd, "UInt64", "impacts", 1, &impacts);
    data_array(&mut cd, "Float64", "angle_deg", 1, &angle);
    data_array(&mut cd, "Float64", "normal_speed_m_per_s", 1, &normal);
    data_array(
        &mut cd,
        "Float64",
        "tangential_speed_m_per_s",
        1,
        &tangential,
    );
    cd.push_str("</CellData>\n");
    let at = s.find("<Points>").unwrap_or(s.len());
    s.insert_str(at, &cd);
    s
}

/// The `.vtu` text of the scene geometry: every strip as consecutive line segments.
pub fn geometry_vtu(outlines: &[Outline]) -> String {
    let mut points: Vec<[f64; 3]> = Vec::new();
    let (mut conn, mut offsets) = (Vec::new(), Vec::new());
    for strip in outlines.iter().flat_map(|o| &o.strips) {
        let base = points.len();
        points.extend_from_slice(strip);
        for k in 1..strip.len() {
            conn.extend([base + k - 1, base + k]);
            offsets.push(conn.len());
        }
    }
    grid(&points, (&conn, &offsets, VTK_LINE), |_| {})
}

/// The rows of a frame as CSV (`id,group,x,y,z,vx,vy,vz,diameter,density`, SI units),
/// floats in shortest round-trip exponent form.
pub fn frame_csv(frame: &Frame) -> String {
    let mut s = String::from("id,group,x,y,z,vx,vy,vz,diameter,density\n");
    for k in 0..frame.len() {
        let ([x, y, z], [vx, vy, vz]) = (frame.position[k], frame.velocity[k]);
        let (d, rho) = (frame.diameter[k], frame.density[k]);
        let _ = writeln!(
            s,
            "{},{},{x:e},{y:e},{z:e},{vx:e},{vy:e},{vz:e},{d:e},{rho:e}",
            frame.id[k], frame.group[k]
        );
    }
    s
}

/// Writes one CSV file per frame into a folder (`<case>_<step>.csv`).
pub struct CsvSink {
    dir: PathBuf,
    case: String,
}

impl CsvSink {
    /// A sink writing into `dir` (created if missing).
    pub fn create(dir: &Path, meta: &RunMeta) -> Result<Self, RecordError> {
        std::fs::create_dir_all(dir).map_err(|source| RecordError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        Ok(CsvSink {
            dir: dir.to_path_buf(),
            case: meta.case.clone(),
        })
    }
}

impl FrameSink for CsvSink {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        let path = self
            .dir
            .join(format!("{}_{:09}.csv", self.case, frame.step));
        write_file(&path, &frame_csv(frame)).map_err(|e| e.to_string())
    }

    fn finish(&mut self) -> Result<(), String> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patches_are_triangles_with_their_patch_and_role() {
        let p = |name: &str, role: &str, z: f64| PatchSurface {
            name: name.into(),
            role: role.into(),
            vertices: vec![[0.0, 0.0, z], [1.0, 0.0, z], [1.0, 1.0, z], [0.0, 1.0, z]],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let s = patches_vtu(&[p("walls", "wall", 0.0), p("out", "outlet", 1.0)]);
        assert!(
            s.contains("NumberOfPoints=\"8\" NumberOfCells=\"4\""),
            "{s}"
        );
        assert!(s.contains("Name=\"connectivity\" format=\"ascii\">0 1 2 0 2 3 4 5 6 4 6 7<"));
        assert!(
            s.contains("Name=\"patch\" format=\"ascii\">0 0 1 1<"),
            "{s}"
        );
        assert!(s.contains("Name=\"role\" format=\"ascii\">0 0 1 1<"), "{s}");
        assert!(s.contains("Name=\"types\" format=\"ascii\">5 5 5 5<"));
        // an empty frame's arrays hold a line break
        let empty = frame_vtu(&Frame::default());
        assert!(empty.contains("NumberOfPoints=\"0\" NumberOfCells=\"0\""));
        assert!(!empty.contains("\"ascii\"></DataArray>"), "{empty}");
    }
}

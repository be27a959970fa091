//! The erosion log of a run (`[erosion]`): per patch or wall and per face, and where the
//! wear is deepest.

use scg_core::physics::wall_shape::WallShape;
use scg_core::sim::Simulation;
use scg_core::stages::erosion::{ErosionLog, FaceWear};
use scg_scene::Scene;

/// One face's wear with where it is.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceRow {
    /// Patch name (a `[[walls]]` entry's name for its faces).
    pub patch: String,
    /// The mesh's face index (an STL wall's triangle; 0 for an analytic wall).
    pub face: u32,
    /// Face centre, m.
    pub centre: [f64; 3],
    /// Face area, m².
    pub area: f64,
    /// Impacts (simulated particles).
    pub impacts: u64,
    /// Original powder's mass of the impacts, kg.
    pub mass: f64,
    /// Volume removed, m³.
    pub volume: f64,
    /// Mean depth rate, m/s: volume / (area · time).
    pub depth_rate: f64,
    /// Mean impact angle to the wall plane over the powder mass that struck, degrees.
    pub angle_deg: f64,
    /// Mean normal impact speed (mass-weighted), m/s.
    pub normal_speed: f64,
    /// Mean tangential impact speed (mass-weighted), m/s.
    pub tangential_speed: f64,
}

/// A face's row: where it is and its wear over `t` s.
fn row(patch: &str, face: u32, centre: [f64; 3], area: f64, w: &FaceWear, t: f64) -> FaceRow {
    FaceRow {
        patch: patch.to_string(),
        face,
        centre,
        area,
        impacts: w.impacts,
        mass: w.mass,
        volume: w.volume,
        depth_rate: w.volume / (area * t),
        angle_deg: w.mean_angle().to_degrees(),
        normal_speed: w.mean_normal_speed(),
        tangential_speed: w.mean_tangential_speed(),
    }
}

/// A `[[walls]]` face: an STL wall's triangle (centroid, area), an analytic wall's one
/// face (no centre, no area: NaN).
fn wall_face(scene: &Scene, wall: u32, tri: u32) -> (String, [f64; 3], f64) {
    let Some(w) = scene.impulse_walls.get(wall as usize) else {
        return (String::new(), [f64::NAN; 3], f64::NAN);
    };
    match &w.wall.shape {
        WallShape::Mesh(m) => {
            let [a, b, c] = m.triangles()[tri as usize].map(|i| m.vertices()[i as usize]);
            let centre = ((a + b + c) / 3.0).to_array();
            (
                w.wall.name.clone(),
                centre,
                0.5 * (b - a).cross(c - a).length(),
            )
        }
        _ => (w.wall.name.clone(), [f64::NAN; 3], f64::NAN),
    }
}

/// Every face hit (`None` without `[erosion]`): the mesh flow's faces in face order,
/// then the `[[walls]]` faces (STL triangles; an analytic wall as one face without centre
/// or area, NaN) in wall order.
pub fn rows(scene: &Scene, sim: &Simulation) -> Option<Vec<FaceRow>> {
    let log = sim.world.get_resource::<ErosionLog>()?;
    let t = sim.time().max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    if let Some(m) = scene.mesh_flow.as_ref() {
        let (mesh, g) = (m.flow.mesh(), m.flow.geometry());
        for (&f, w) in &log.faces {
            let p = m.flow.patch_of(f) as usize;
            let name = mesh.patches.get(p).map_or("", |p| p.name.as_str());
            let (c, a) = (
                g.face_centres[f as usize],
                g.face_areas[f as usize].length(),
            );
            out.push(row(name, f, c.to_array(), a, w, t));
        }
    }
    for (&(wall, tri), w) in &log.wall_faces {
        let (name, centre, area) = wall_face(scene, wall, tri);
        out.push(row(&name, tri, centre, area, w, t));
    }
    Some(out)
}

/// Seconds in a year (365.25 days), for the mm/year the summary prints.
const YEAR: f64 = 365.25 * 86_400.0;

/// The console summary: the model, per patch the impacts, mass and volume, and the face
/// whose depth rate is largest.
pub fn render(scene: &Scene, sim: &Simulation, rows: &[FaceRow]) -> String {
    let Some(log) = sim.world.get_resource::<ErosionLog>() else {
        return String::new();
    };
    let mut s = format!(
        "erosion ({}; impacts on rebound and stick wall patches, α³ originals each), over {:.4} s:\n",
        log.model.name(),
        sim.time()
    );
    let entered = scene.initial_count()
        + sim
            .world
            .get_resource::<scg_core::state::Tally>()
            .map_or(0, |t| t.fed.iter().sum::<u64>());
    let (total, lo, hi) = log.total_interval(entered);
    s += &format!(
        "  total {total:.4e} m³ [{lo:.4e}, {hi:.4e}] (95 %, over the {entered} particles that \
         entered)\n"
    );
    let names = scene
        .mesh_flow
        .iter()
        .flat_map(|m| m.flow.mesh().patches.iter().map(|p| ("", p.name.as_str())))
        .zip(log.patches.iter().copied())
        .chain(
            scene
                .impulse_walls
                .iter()
                .map(|w| ("wall ", w.wall.name.as_str()))
                .zip(log.walls.iter().copied()),
        );
    {
        for ((kind, name), on) in names {
            if !on {
                continue;
            }
            let of = rows.iter().filter(|r| r.patch == name);
            let (n, mass, vol, faces) = of.fold((0, 0.0, 0.0, 0), |a, r| {
                (a.0 + r.impacts, a.1 + r.mass, a.2 + r.volume, a.3 + 1)
            });
            s += &format!(
                "  {kind}`{name}`: {n} impacts on {faces} faces, {mass:.4e} kg of powder, \
                 {vol:.4e} m³ removed\n"
            );
        }
    }
    if let Some(r) = rows
        .iter()
        .filter(|r| r.depth_rate.is_finite())
        .max_by(|a, b| a.depth_rate.total_cmp(&b.depth_rate))
    {
        s += &format!(
            "  deepest: face {} of `{}` at [{:.4}, {:.4}, {:.4}] m ({:.3e} m²): {} impacts, \
             {:.4e} m³, {:.4e} m/s ({:.4e} mm/year at this feed); struck at {:.1}° on \
             average, normal {:.2} m/s, tangential {:.2} m/s (mass-weighted)\n",
            r.face,
            r.patch,
            r.centre[0],
            r.centre[1],
            r.centre[2],
            r.area,
            r.impacts,
            r.volume,
            r.depth_rate,
            r.depth_rate * YEAR * 1e3,
            r.angle_deg,
            r.normal_speed,
            r.tangential_speed
        );
    }
    s
}

/// CSV: `patch,face,x,y,z,area_m2,impacts,mass_kg,volume_m3,depth_rate_m_per_s,
/// angle_deg,normal_speed_m_per_s,tangential_speed_m_per_s` (the last three mass-weighted
/// means of the impacts).
pub fn csv(rows: &[FaceRow]) -> String {
    let mut s = String::from(
        "patch,face,x,y,z,area_m2,impacts,mass_kg,volume_m3,depth_rate_m_per_s,angle_deg,\
         normal_speed_m_per_s,tangential_speed_m_per_s\n",
    );
    for r in rows {
        s += &format!(
            "{},{},{:e},{:e},{:e},{:e},{},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            r.patch,
            r.face,
            r.centre[0],
            r.centre[1],
            r.centre[2],
            r.area,
            r.impacts,
            r.mass,
            r.volume,
            r.depth_rate,
            r.angle_deg,
            r.normal_speed,
            r.tangential_speed
        );
    }
    s
}

/// The logged patches and STL walls as a legacy-VTK surface (an unstructured grid of
/// polygons, ASCII, which ParaView and meshio read: each mesh face a polygon, each STL
/// triangle a triangle) with the wear per face as cell data: `volume_m3`,
/// `depth_rate_m_per_s`, `impacts`, and the impacts' mass-weighted `angle_deg`,
/// `normal_speed_m_per_s`, `tangential_speed_m_per_s` (zero on faces not hit), to open
/// in ParaView (`None` without `[erosion]`). Analytic walls have no faces to draw.
pub fn vtk(scene: &Scene, sim: &Simulation) -> Option<String> {
    let log = sim.world.get_resource::<ErosionLog>()?;
    let t = sim.time().max(f64::MIN_POSITIVE);
    // every face: its corners, its wear, its area
    let mut faces: Vec<(Vec<glam::DVec3>, FaceWear, f64)> = Vec::new();
    if let Some(m) = scene.mesh_flow.as_ref() {
        let (mesh, g) = (m.flow.mesh(), m.flow.geometry());
        for (p, _) in mesh.patches.iter().zip(&log.patches).filter(|(_, on)| **on) {
            for f in p.start..p.start + p.size {
                let corners = mesh
                    .face(f)
                    .iter()
                    .map(|&q| mesh.points[q as usize])
                    .collect();
                let w = log.faces.get(&(f as u32)).copied().unwrap_or_default();
                faces.push((corners, w, g.face_areas[f].length()));
            }
        }
    }
    for (k, iw) in scene.impulse_walls.iter().enumerate() {
        let WallShape::Mesh(m) = &iw.wall.shape else {
            continue;
        };
        if !log.wants_wall(k) {
            continue;
        }
        for (j, tri) in m.triangles().iter().enumerate() {
            let [a, b, c] = tri.map(|i| m.vertices()[i as usize]);
            let w = log.wall_faces.get(&(k as u32, j as u32)).copied();
            faces.push((
                vec![a, b, c],
                w.unwrap_or_default(),
                0.5 * (b - a).cross(c - a).length(),
            ));
        }
    }
    let n: usize = faces.iter().map(|f| f.0.len()).sum();
    let mut s = format!(
        "# vtk DataFile Version 3.0\nscg erosion ({}) of {} over {t} s\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {n} double\n",
        log.model.name(),
        scene.name,
    );
    for p in faces.iter().flat_map(|f| &f.0) {
        s += &format!("{:e} {:e} {:e}\n", p.x, p.y, p.z);
    }
    s += &format!("CELLS {} {}\n", faces.len(), n + faces.len());
    let mut next = 0;
    for f in &faces {
        let ids: Vec<String> = (next..next + f.0.len()).map(|i| i.to_string()).collect();
        next += f.0.len();
        s += &format!("{} {}\n", ids.len(), ids.join(" "));
    }
    // VTK_TRIANGLE, VTK_QUAD, else VTK_POLYGON
    s += &format!("CELL_TYPES {}\n", faces.len());
    for f in &faces {
        s += match f.0.len() {
            3 => "5\n",
            4 => "9\n",
            _ => "7\n",
        };
    }
    // the impacts' mass-weighted means, 0 on faces not hit
    let mean = |w: &FaceWear, x: f64| if w.mass > 0.0 { x / w.mass } else { 0.0 };
    type Get = fn(&FaceWear, f64, f64) -> f64;
    let columns: [(&str, Get); 6] = [
        ("volume_m3", |w, _, _| w.volume),
        ("depth_rate_m_per_s", |w, a, t| w.volume / (a * t)),
        ("impacts", |w, _, _| w.impacts as f64),
        ("angle_deg", |w, _, _| w.angle_mass.to_degrees()),
        ("normal_speed_m_per_s", |w, _, _| w.normal_mass),
        ("tangential_speed_m_per_s", |w, _, _| w.tangential_mass),
    ];
    s += &format!("CELL_DATA {}\n", faces.len());
    for (k, (name, get)) in columns.iter().enumerate() {
        s += &format!("SCALARS {name} double 1\nLOOKUP_TABLE default\n");
        for (_, w, a) in &faces {
            let x = get(w, *a, t);
            let x = if k >= 3 { mean(w, x) } else { x };
            s += &if k == 2 {
                format!("{x}\n")
            } else {
                format!("{x:e}\n")
            };
        }
    }
    Some(s)
}

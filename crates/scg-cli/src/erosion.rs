//! The erosion log of a run (`[erosion]`): per patch or wall and per face, and where the
//! wear is deepest.

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
        let Some(iw) = scene.impulse_walls.get(wall as usize) else {
            continue;
        };
        // an analytic wall: one face without centre or area
        let (centre, area) = iw
            .wall
            .shape
            .face(tri)
            .map_or(([f64::NAN; 3], f64::NAN), |(c, a)| (c.to_array(), a));
        out.push(row(&iw.wall.name, tri, centre, area, w, t));
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
/// in ParaView (`None` without `[erosion]`). Written from the run's wear map (the one the
/// recordings get); analytic walls have no faces to draw.
pub fn vtk(scene: &Scene, sim: &Simulation) -> Option<String> {
    let map = scg_core::stages::erosion::wear_map(&sim.world, sim.step_count(), sim.time())?;
    let n_points: usize = map.patches.iter().map(|p| p.vertices.len()).sum();
    let mut s = format!(
        "# vtk DataFile Version 3.0\nscg erosion ({}) of {} over {} s\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {n_points} double\n",
        map.model,
        scene.name,
        sim.time().max(f64::MIN_POSITIVE),
    );
    for v in map.patches.iter().flat_map(|p| &p.vertices) {
        s += &format!("{:e} {:e} {:e}\n", v[0], v[1], v[2]);
    }
    // every face's polygon, its points numbered over all patches
    let mut cells: Vec<Vec<usize>> = Vec::new();
    let mut base = 0;
    for p in &map.patches {
        cells.extend(
            p.polygons()
                .into_iter()
                .map(|c| c.iter().map(|&v| base + v as usize).collect()),
        );
        base += p.vertices.len();
    }
    let size: usize = cells.iter().map(|c| c.len() + 1).sum();
    s += &format!("CELLS {} {size}\n", cells.len());
    for c in &cells {
        let ids: Vec<String> = c.iter().map(|i| i.to_string()).collect();
        s += &format!("{} {}\n", ids.len(), ids.join(" "));
    }
    // VTK_TRIANGLE, VTK_QUAD, else VTK_POLYGON
    s += &format!("CELL_TYPES {}\n", cells.len());
    for c in &cells {
        s += match c.len() {
            3 => "5\n",
            4 => "9\n",
            _ => "7\n",
        };
    }
    type Column = fn(&scg_core::frame::WearPatch, usize) -> f64;
    let columns: [(&str, Column); 6] = [
        ("volume_m3", |p, f| p.volume[f]),
        ("depth_rate_m_per_s", |p, f| p.depth_rate[f]),
        ("impacts", |p, f| p.impacts[f] as f64),
        ("angle_deg", |p, f| p.angle[f].to_degrees()),
        ("normal_speed_m_per_s", |p, f| p.normal_speed[f]),
        ("tangential_speed_m_per_s", |p, f| p.tangential_speed[f]),
    ];
    s += &format!("CELL_DATA {}\n", cells.len());
    for (name, get) in columns {
        s += &format!("SCALARS {name} double 1\nLOOKUP_TABLE default\n");
        for p in &map.patches {
            for f in 0..p.faces.len() {
                let x = get(p, f);
                s += &if name == "impacts" {
                    format!("{x}\n")
                } else {
                    format!("{x:e}\n")
                };
            }
        }
    }
    Some(s)
}

//! The erosion log of a run (`[erosion]`): per patch and per face, and where the wear is
//! deepest.

use scg_core::sim::Simulation;
use scg_core::stages::erosion::{ErosionLog, FaceWear};
use scg_scene::Scene;

/// One face's wear with where it is.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceRow {
    /// Patch name.
    pub patch: String,
    /// The mesh's face index.
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

/// Every face hit, in face order (`None` without `[erosion]`).
pub fn rows(scene: &Scene, sim: &Simulation) -> Option<Vec<FaceRow>> {
    let log = sim.world.get_resource::<ErosionLog>()?;
    let m = scene.mesh_flow.as_ref()?;
    let (mesh, g) = (m.flow.mesh(), m.flow.geometry());
    let t = sim.time().max(f64::MIN_POSITIVE);
    Some(
        log.faces
            .iter()
            .map(|(&f, w)| {
                let p = m.flow.patch_of(f) as usize;
                let area = g.face_areas[f as usize].length();
                FaceRow {
                    patch: mesh
                        .patches
                        .get(p)
                        .map_or(String::new(), |p| p.name.clone()),
                    face: f,
                    centre: g.face_centres[f as usize].to_array(),
                    area,
                    impacts: w.impacts,
                    mass: w.mass,
                    volume: w.volume,
                    depth_rate: w.volume / (area * t),
                    angle_deg: w.mean_angle().to_degrees(),
                    normal_speed: w.mean_normal_speed(),
                    tangential_speed: w.mean_tangential_speed(),
                }
            })
            .collect(),
    )
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
    if let Some(m) = &scene.mesh_flow {
        for (p, on) in m.flow.mesh().patches.iter().zip(&log.patches) {
            if !on {
                continue;
            }
            let of = rows.iter().filter(|r| r.patch == p.name);
            let (n, mass, vol, faces) = of.fold((0, 0.0, 0.0, 0), |a, r| {
                (a.0 + r.impacts, a.1 + r.mass, a.2 + r.volume, a.3 + 1)
            });
            s += &format!(
                "  `{}`: {n} impacts on {faces} faces, {mass:.4e} kg of powder, {vol:.4e} m³ removed\n",
                p.name
            );
        }
    }
    if let Some(r) = rows
        .iter()
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

/// The logged patches as a legacy-VTK surface (an unstructured grid of polygons, ASCII,
/// which ParaView and meshio read) with the wear per face
/// as cell data: `volume_m3`, `depth_rate_m_per_s`, `impacts`, and the impacts'
/// mass-weighted `angle_deg`, `normal_speed_m_per_s`, `tangential_speed_m_per_s` (zero
/// on faces not hit), to open in ParaView (`None` without `[erosion]`).
pub fn vtk(scene: &Scene, sim: &Simulation) -> Option<String> {
    let log = sim.world.get_resource::<ErosionLog>()?;
    let m = scene.mesh_flow.as_ref()?;
    let (mesh, g) = (m.flow.mesh(), m.flow.geometry());
    let t = sim.time().max(f64::MIN_POSITIVE);
    let faces: Vec<usize> = mesh
        .patches
        .iter()
        .zip(&log.patches)
        .filter(|(_, on)| **on)
        .flat_map(|(p, _)| p.start..p.start + p.size)
        .collect();
    // the points the faces use, renumbered in order of first use
    let mut index = std::collections::HashMap::new();
    let mut points = Vec::new();
    for &f in &faces {
        for &p in mesh.face(f) {
            index.entry(p).or_insert_with(|| {
                points.push(mesh.points[p as usize]);
                points.len() - 1
            });
        }
    }
    let mut s = format!(
        "# vtk DataFile Version 3.0\nscg erosion ({}) of {} over {t} s\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {} double\n",
        log.model.name(),
        scene.name,
        points.len()
    );
    for p in &points {
        s += &format!("{:e} {:e} {:e}\n", p.x, p.y, p.z);
    }
    let size: usize = faces.iter().map(|&f| mesh.face(f).len() + 1).sum();
    s += &format!("CELLS {} {size}\n", faces.len());
    for &f in &faces {
        let ids: Vec<String> = mesh.face(f).iter().map(|p| index[p].to_string()).collect();
        s += &format!("{} {}\n", ids.len(), ids.join(" "));
    }
    // VTK_TRIANGLE, VTK_QUAD, else VTK_POLYGON
    s += &format!("CELL_TYPES {}\n", faces.len());
    for &f in &faces {
        s += match mesh.face(f).len() {
            3 => "5\n",
            4 => "9\n",
            _ => "7\n",
        };
    }
    let wear = |f: usize| log.faces.get(&(f as u32)).copied().unwrap_or_default();
    s += &format!(
        "CELL_DATA {}\nSCALARS volume_m3 double 1\nLOOKUP_TABLE default\n",
        faces.len()
    );
    for &f in &faces {
        s += &format!("{:e}\n", wear(f).volume);
    }
    s += "SCALARS depth_rate_m_per_s double 1\nLOOKUP_TABLE default\n";
    for &f in &faces {
        let area = g.face_areas[f].length();
        s += &format!("{:e}\n", wear(f).volume / (area * t));
    }
    s += "SCALARS impacts double 1\nLOOKUP_TABLE default\n";
    for &f in &faces {
        s += &format!("{}\n", wear(f).impacts);
    }
    // the impacts' mass-weighted means, 0 on faces not hit
    let mean = |w: FaceWear, x: f64| if w.mass > 0.0 { x / w.mass } else { 0.0 };
    for (name, get) in [
        ("angle_deg", (|w: FaceWear| w.angle_mass.to_degrees()) as fn(FaceWear) -> f64),
        ("normal_speed_m_per_s", |w| w.normal_mass),
        ("tangential_speed_m_per_s", |w| w.tangential_mass),
    ] {
        s += &format!("SCALARS {name} double 1\nLOOKUP_TABLE default\n");
        for &f in &faces {
            let w = wear(f);
            s += &format!("{:e}\n", mean(w, get(w)));
        }
    }
    Some(s)
}

//! What became of each group's particles at the end of a run: fed, escaped per patch (or
//! drained and lost through an analytic outlet), stuck per patch, airborne; counts of
//! simulated particles and the original powder's mass they stand for.
//!
//! Conservation holds exactly: initial + fed = escaped + stuck + lost + airborne, per group.

use scg_core::physics::mesh_flow::PatchRole;
use scg_core::physics::scaling::sphere_mass;
use scg_core::sim::Simulation;
use scg_core::stages::collect::CollectLog;
use scg_core::stages::impulse_walls::WallLog;
use scg_core::stages::mesh_flow::PatchLog;
use scg_scene::Scene;

/// The fates of one group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GroupFates {
    /// Group name.
    pub group: String,
    /// Original particle mass each simulated particle stands for, kg (α³ originals).
    pub represented_mass: f64,
    /// Particles placed at the start.
    pub initial: u64,
    /// Particles fed.
    pub fed: u64,
    /// (patch, role, escaped, stuck) for every patch of a mesh flow a particle reached.
    pub patches: Vec<(String, &'static str, u64, u64)>,
    /// Drained through an analytic outlet (no mesh flow).
    pub drained: u64,
    /// Lost: left the domain other than through a patch (outside the mesh, or out of an
    /// analytic domain).
    pub lost: u64,
    /// Per declared zone (`[[zones]]`, in their order): (zone, collects, count). A
    /// collecting zone counts the particles that entered it (removed then); any other
    /// zone the particles still in the domain at the end, in the first such zone holding
    /// the centre.
    pub zones: Vec<(String, bool, u64)>,
    /// Still in the domain (moving or resting on a contact wall), in no zone.
    pub airborne: u64,
    /// A size distribution's report bin: its original sizes, m.
    pub size_range: Option<(f64, f64)>,
}

impl GroupFates {
    /// Particles accounted for at the end.
    pub fn accounted(&self) -> u64 {
        let through: u64 = self.patches.iter().map(|p| p.2 + p.3).sum();
        let zoned: u64 = self.zones.iter().map(|z| z.2).sum();
        through + self.drained + self.lost + zoned + self.airborne
    }

    /// Collected: entered a collecting zone (`[[zones]] collects = true`).
    pub fn collected(&self) -> u64 {
        self.zones.iter().filter(|z| z.1).map(|z| z.2).sum()
    }

    /// Particles that entered the run.
    pub fn entered(&self) -> u64 {
        self.initial + self.fed
    }
}

/// The fates of every group of `scene` in `sim` at its end.
pub fn fates(scene: &Scene, sim: &mut Simulation) -> Vec<GroupFates> {
    let counts = GroupCounts::of(sim);
    // per group and zone: the collected (removed on entering a collecting zone, from
    // its log), and the particles still in a zone that does not collect (the first
    // such zone holding the centre)
    let mut zoned = vec![vec![0u64; scene.zones.len()]; scene.groups.len()];
    if !scene.zones.is_empty() {
        let collect = sim.world.get_resource::<CollectLog>().cloned();
        let collecting: Vec<usize> = (0..scene.zones.len())
            .filter(|&z| scene.zones[z].collects)
            .collect();
        for (k, &z) in collecting.iter().enumerate() {
            for (g, row) in zoned.iter_mut().enumerate() {
                row[z] = collect
                    .as_ref()
                    .and_then(|l| l.collected.get(k))
                    .and_then(|v| v.get(g))
                    .map_or(0, |t| t.len() as u64);
            }
        }
        let mut q = sim.world.query::<(
            &scg_core::components::GroupId,
            &scg_core::components::Position,
        )>();
        for (g, x) in q.iter(&sim.world) {
            if let (Some(row), Some(z)) = (
                zoned.get_mut(g.0 as usize),
                scene
                    .zones
                    .iter()
                    .position(|z| !z.collects && z.region.contains(x.0)),
            ) {
                row[z] += 1;
            }
        }
    }
    let log = sim.world.get_resource::<PatchLog>().cloned();
    let walls = sim.world.get_resource::<WallLog>().cloned();
    let mesh = scene.mesh_flow.as_ref().map(|m| m.flow.clone());
    scene
        .groups
        .iter()
        .enumerate()
        .map(|(g, grp)| {
            let get = |v: &Vec<u64>| v.get(g).copied().unwrap_or(0);
            let times = |v: &Vec<Vec<f64>>| v.get(g).map_or(0, |t| t.len() as u64);
            let mut f = GroupFates {
                group: grp.name.clone(),
                represented_mass: grp.alpha.powi(3) * sphere_mass(grp.diameter, grp.density),
                initial: grp.count() as u64,
                fed: get(&counts.fed),
                airborne: get(&counts.held),
                size_range: grp.size.as_ref().map(|s| s.range()),
                ..Default::default()
            };
            let drained = times(&counts.drained);
            let lost = times(&counts.lost);
            for (z, zone) in scene.zones.iter().enumerate() {
                let k = zoned[g][z];
                f.zones.push((zone.name.clone(), zone.collects, k));
                if !zone.collects {
                    f.airborne -= k;
                }
            }
            match (&log, &mesh) {
                (Some(log), Some(flow)) => {
                    let m = flow.mesh();
                    let (mut out, mut inl) = (0, 0);
                    for (p, patch) in m.patches.iter().enumerate() {
                        let esc = log.escaped.get(p).map_or(0, get);
                        let stuck = log.stuck.get(p).map_or(0, get);
                        let role = flow.role(p as u32);
                        if esc > 0 || stuck > 0 || role != PatchRole::Lost {
                            f.patches
                                .push((patch.name.clone(), role.name(), esc, stuck));
                        }
                        if role == PatchRole::Outlet {
                            out += esc;
                        } else {
                            inl += esc;
                        }
                    }
                    // escapes through outlets are the drained ones, through other patches
                    // a part of the lost ones; the rest of the lost left the mesh elsewhere
                    debug_assert_eq!(out, drained);
                    f.lost = lost.saturating_sub(inl);
                }
                _ => {
                    f.drained = drained;
                    f.lost = lost;
                }
            }
            if let Some(w) = &walls {
                for (k, iw) in scene.impulse_walls.iter().enumerate() {
                    let esc = w.escaped.get(k).map_or(0, get);
                    let stuck = w.stuck.get(k).map_or(0, get);
                    f.patches
                        .push((format!("wall {}", iw.wall.name), "wall", esc, stuck));
                }
            }
            f
        })
        .collect()
}

fn share(n: u64, of: u64) -> String {
    if of == 0 {
        "-".into()
    } else {
        format!("{:.1} %", 100.0 * n as f64 / of as f64)
    }
}

/// A group's fates as the console table names them, (fate, count), in its order: per
/// patch escaped (outlets and inlets always, walls when some did) and stuck (walls
/// always, other patches when some did), drained without an outlet patch, lost, per zone,
/// airborne.
pub fn lines(f: &GroupFates) -> Vec<(String, u64)> {
    let mut v = Vec::new();
    for (patch, role, esc, stuck) in &f.patches {
        if *esc > 0 || *role != "wall" {
            v.push((format!("escaped through `{patch}` ({role})"), *esc));
        }
        if *stuck > 0 || *role == "wall" {
            v.push((format!("stuck on `{patch}` ({role})"), *stuck));
        }
    }
    if !f.patches.iter().any(|p| p.1 == "outlet") {
        v.push(("drained (outlet)".into(), f.drained));
    }
    v.push(("lost (left the domain elsewhere)".into(), f.lost));
    for (zone, collects, k) in &f.zones {
        let what = if *collects {
            format!("collected in zone `{zone}`")
        } else {
            format!("in zone `{zone}` at the end")
        };
        v.push((what, *k));
    }
    let what = if f.zones.is_empty() {
        "airborne (in the domain)"
    } else {
        "airborne (in the domain, no zone)"
    };
    v.push((what.into(), f.airborne));
    v
}

/// The console table: one line per group and fate, with the share of what entered and the
/// original-powder mass.
pub fn render(fates: &[GroupFates]) -> String {
    let mut s = String::from(
        "fates (simulated particles; share of those that entered; original-powder mass):\n",
    );
    for f in fates {
        let n = f.entered();
        let mass = |k: u64| k as f64 * f.represented_mass;
        let range = f.size_range.map_or(String::new(), |(lo, hi)| {
            format!(" ({:.3}–{:.3} µm)", lo * 1e6, hi * 1e6)
        });
        s += &format!(
            "  {}{range}: entered {} ({} placed + {} fed, {:.4e} kg)\n",
            f.group,
            n,
            f.initial,
            f.fed,
            mass(n)
        );
        for (what, k) in lines(f) {
            s += &format!(
                "    {what:<34} {k:>9}  {:>7}  {:.4e} kg\n",
                share(k, n),
                mass(k)
            );
        }
        if f.accounted() != n {
            s += &format!(
                "    warning: {} accounted for, {n} entered\n",
                f.accounted()
            );
        }
    }
    s
}

/// The fates as CSV rows `group,fate,patch,count,share,mass_kg` (fate: `entered`,
/// `escaped`, `stuck`, `drained`, `lost`, `collected` and `zone` (the zone's name in the
/// patch column),
/// `airborne`; share of the entered; mass of the
/// original powder), one row per group and fate (per patch for escaped and stuck).
pub fn csv(fates: &[GroupFates]) -> String {
    let mut s = String::from("group,fate,patch,count,share,mass_kg\n");
    for f in fates {
        let n = f.entered();
        let mut row = |fate: &str, patch: &str, k: u64| {
            let share = if n == 0 { 0.0 } else { k as f64 / n as f64 };
            s += &format!(
                "{},{fate},{patch},{k},{share:e},{:e}\n",
                f.group,
                k as f64 * f.represented_mass
            );
        };
        row("entered", "", n);
        for (patch, _, esc, stuck) in &f.patches {
            row("escaped", patch, *esc);
            row("stuck", patch, *stuck);
        }
        row("drained", "", f.drained);
        row("lost", "", f.lost);
        for (zone, collects, k) in &f.zones {
            row(if *collects { "collected" } else { "zone" }, zone, *k);
        }
        row("airborne", "", f.airborne);
    }
    s
}

/// The fates as JSON (for `summary.json`): per group, counts and masses.
pub fn json(f: &GroupFates) -> serde_json::Value {
    let m = |k: u64| k as f64 * f.represented_mass;
    let patches: Vec<serde_json::Value> = f
        .patches
        .iter()
        .map(|(p, role, esc, stuck)| {
            serde_json::json!({
                "patch": p, "role": role,
                "escaped": esc, "escaped_mass": m(*esc),
                "stuck": stuck, "stuck_mass": m(*stuck),
            })
        })
        .collect();
    serde_json::json!({
        "represented_mass": f.represented_mass,
        "initial": f.initial,
        "fed": f.fed,
        "fed_mass": m(f.fed),
        "patches": patches,
        "drained": f.drained,
        "lost": f.lost,
        "lost_mass": m(f.lost),
        "zones": f.zones.iter().map(|(z, c, k)| serde_json::json!({
            "zone": z, "collects": c, "count": k, "mass": m(*k),
        })).collect::<Vec<_>>(),
        "collected": f.collected(),
        "collected_mass": m(f.collected()),
        "airborne": f.airborne,
        "airborne_mass": m(f.airborne),
        "conserved": f.accounted() == f.entered(),
    })
}

/// Per-group counts at the end of a run, index = group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GroupCounts {
    /// Particles fed.
    pub fed: Vec<u64>,
    /// Times (s) at which particles drained through an outlet.
    pub drained: Vec<Vec<f64>>,
    /// Times (s) at which particles were lost (left the domain other than by an outlet).
    pub lost: Vec<Vec<f64>>,
    /// Particles still in the domain.
    pub held: Vec<u64>,
}

impl GroupCounts {
    /// Read from the simulation's `Tally`, `OutletLog` and particles.
    pub fn of(sim: &mut scg_core::sim::Simulation) -> Self {
        let world = &mut sim.world;
        let mut c = GroupCounts::default();
        if let Some(t) = world.get_resource::<scg_core::state::Tally>() {
            c.fed.clone_from(&t.fed);
        }
        if let Some(l) = world.get_resource::<scg_core::stages::outlet::OutletLog>() {
            c.drained.clone_from(&l.drained);
            c.lost.clone_from(&l.lost);
        }
        let mut q = world.query::<&scg_core::components::GroupId>();
        for g in q.iter(world) {
            let i = g.0 as usize;
            if c.held.len() <= i {
                c.held.resize(i + 1, 0);
            }
            c.held[i] += 1;
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_adds_up_and_flags_a_gap() {
        let mut f = GroupFates {
            group: "d5".into(),
            represented_mass: 2e-12,
            initial: 0,
            fed: 10,
            patches: vec![
                ("outlet".into(), "outlet", 6, 0),
                ("walls".into(), "wall", 0, 3),
            ],
            drained: 0,
            lost: 0,
            zones: Vec::new(),
            airborne: 1,
            size_range: None,
        };
        assert_eq!(f.accounted(), 10);
        let t = render(std::slice::from_ref(&f));
        assert!(t.contains("escaped through `outlet` (outlet)"), "{t}");
        assert!(t.contains("stuck on `walls` (wall)"), "{t}");
        assert!(t.contains("60.0 %") && !t.contains("warning"), "{t}");
        let j = json(&f);
        assert_eq!(j["patches"][1]["stuck"], 3);
        let c = csv(std::slice::from_ref(&f));
        assert!(
            c.starts_with("group,fate,patch,count,share,mass_kg\n"),
            "{c}"
        );
        assert!(c.contains("d5,escaped,outlet,6,6e-1,1.2e-11\n"), "{c}");
        assert!(c.contains("d5,stuck,walls,3,3e-1,6e-12\n"), "{c}");
        assert_eq!(j["conserved"], true);
        // a collecting zone and one counted at the end add to the books
        let mut z = f.clone();
        z.patches.pop();
        z.zones = vec![("bin".into(), true, 2), ("pipe".into(), false, 1)];
        assert_eq!((z.accounted(), z.collected()), (10, 2));
        let t = render(std::slice::from_ref(&z));
        assert!(
            t.contains("collected in zone `bin`") && t.contains("in zone `pipe` at the end"),
            "{t}"
        );
        assert!(!t.contains("warning"), "{t}");
        let c = csv(std::slice::from_ref(&z));
        assert!(
            c.contains("d5,collected,bin,2,") && c.contains("d5,zone,pipe,1,"),
            "{c}"
        );
        assert_eq!(
            (
                json(&z)["collected"].as_u64(),
                json(&z)["zones"][1]["collects"].as_bool()
            ),
            (Some(2), Some(false))
        );
        f.airborne = 0;
        assert!(render(&[f]).contains("warning: 9 accounted for, 10 entered"));
    }
}

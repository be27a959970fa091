//! Cut sizes of a tangential-inlet cyclone from cyclone theory, beside the simulated d50:
//! Lapple's (1951) and Barth–Muschelknautz's (Hoffmann & Stein, *Gas Cyclones and Swirl
//! Tubes*, 2nd ed., ch. 6, clean-gas version). The numbers of `cases/cyclone/README.md`
//! ("Cut size") are these functions on [`Cyclone::OPENFOAM_TUTORIAL`].

use std::f64::consts::PI;

/// The dimensions of a cyclone with a cylindrical barrel, a conical lower part and a
/// rectangular tangential inlet, and its gas, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cyclone {
    /// Barrel radius R, m.
    pub radius: f64,
    /// Barrel height h, m.
    pub barrel_height: f64,
    /// Total height H (roof to the bottom of the cone), m.
    pub total_height: f64,
    /// Diameter of the cone at its bottom B, m.
    pub cone_bottom: f64,
    /// Inlet height a (along the axis), m.
    pub inlet_height: f64,
    /// Inlet width b (radial), m.
    pub inlet_width: f64,
    /// Radius of the inlet's centre line R_in, m.
    pub inlet_radius: f64,
    /// Inner radius of the vortex finder R_x, m.
    pub vortex_finder_radius: f64,
    /// Outer radius of the vortex finder, m.
    pub vortex_finder_outer: f64,
    /// Vortex finder length below the roof S, m.
    pub vortex_finder_length: f64,
    /// Inlet gas velocity v_in, m/s.
    pub inlet_velocity: f64,
    /// Gas density, kg/m³.
    pub gas_density: f64,
    /// Gas dynamic viscosity, Pa·s.
    pub gas_viscosity: f64,
    /// Wall friction factor f of Barth–Muschelknautz (0.005 for clean gas).
    pub friction: f64,
    /// The CFD field's own velocities on the control surface, (tangential, inward radial)
    /// m/s, where measured ([`Cyclone::control_surface`]).
    pub field_swirl: Option<(f64, f64)>,
}

impl Cyclone {
    /// `cases/cyclone.toml`: OpenFOAM's MPPICFoam/cyclone geometry with air at 10 m/s.
    pub const OPENFOAM_TUTORIAL: Cyclone = Cyclone {
        radius: 0.5,
        barrel_height: 1.0,
        total_height: 2.0,
        cone_bottom: 0.3,
        inlet_height: 0.4,
        inlet_width: 0.2,
        inlet_radius: 0.35,
        vortex_finder_radius: 0.15,
        vortex_finder_outer: 0.2,
        vortex_finder_length: 0.4,
        inlet_velocity: 10.0,
        gas_density: 1.2,
        gas_viscosity: 1.8e-5,
        friction: 0.005,
        field_swirl: None,
    };

    /// Gas flow rate Q = a·b·v_in, m³/s.
    pub fn flow_rate(&self) -> f64 {
        self.inlet_height * self.inlet_width * self.inlet_velocity
    }

    /// Lapple's number of effective turns N_e = (h + (H − h)/2) / a.
    pub fn lapple_turns(&self) -> f64 {
        (self.barrel_height + 0.5 * (self.total_height - self.barrel_height)) / self.inlet_height
    }

    /// Lapple's cut size d50 = √(9 μ b / (2π N_e v_in (ρ_p − ρ))) for particles of density
    /// `particle_density`, m.
    pub fn lapple_d50(&self, particle_density: f64) -> f64 {
        (9.0 * self.gas_viscosity * self.inlet_width
            / (2.0
                * PI
                * self.lapple_turns()
                * self.inlet_velocity
                * (particle_density - self.gas_density)))
            .sqrt()
    }

    /// Barth–Muschelknautz's inlet constriction coefficient α of a slot inlet, from
    /// ξ = b / R: α = (1/ξ)·{1 − √(1 + 4[(ξ/2)² − ξ/2]·√(1 − (1 − ξ²)(2ξ − ξ²)))}
    /// (Hoffmann & Stein eq. 6.1.2, clean gas).
    pub fn constriction(&self) -> f64 {
        let xi = self.inlet_width / self.radius;
        let inner = (1.0 - (1.0 - xi * xi) * (2.0 * xi - xi * xi)).sqrt();
        (1.0 - (1.0 + 4.0 * ((0.5 * xi).powi(2) - 0.5 * xi) * inner).sqrt()) / xi
    }

    /// Inner friction area A_R: roof annulus, barrel, cone and the vortex finder's outside, m².
    pub fn friction_area(&self) -> f64 {
        let r = self.radius;
        let rb = 0.5 * self.cone_bottom;
        let cone_height = self.total_height - self.barrel_height;
        PI * (r * r - self.vortex_finder_outer.powi(2))
            + 2.0 * PI * r * self.barrel_height
            + PI * (r + rb) * ((r - rb).powi(2) + cone_height.powi(2)).sqrt()
            + 2.0 * PI * self.vortex_finder_outer * self.vortex_finder_length
    }

    /// Barth–Muschelknautz's tangential velocity at the control surface (the cylinder
    /// below the vortex finder, radius R_x) v_θCS, m/s.
    pub fn bm_tangential_velocity(&self) -> f64 {
        let r = self.radius;
        let rx = self.vortex_finder_radius;
        let v_wall = self.inlet_velocity * self.inlet_radius / (self.constriction() * r);
        v_wall * (r / rx)
            / (1.0
                + self.friction * self.friction_area() * v_wall * (r / rx).sqrt()
                    / (2.0 * self.flow_rate()))
    }

    /// Barth–Muschelknautz's radial (inward) velocity through the control surface, v_rCS =
    /// Q / (2π R_x (H − S)), m/s.
    pub fn bm_radial_velocity(&self) -> f64 {
        self.flow_rate()
            / (2.0
                * PI
                * self.vortex_finder_radius
                * (self.total_height - self.vortex_finder_length))
    }

    /// Barth–Muschelknautz's cut size: the particle whose centrifugal force at the control
    /// surface balances the Stokes drag of the inward flow,
    /// x50 = √(18 μ v_rCS R_x / ((ρ_p − ρ) v_θCS²)), m.
    pub fn barth_muschelknautz_d50(&self, particle_density: f64) -> f64 {
        self.bm_d50_with_swirl(particle_density, self.bm_tangential_velocity())
    }

    /// Barth–Muschelknautz's cut size with the tangential velocity at the control surface
    /// given (`v_theta`, m/s: e.g. the CFD field's own), the radial one from the flow rate, m.
    pub fn bm_d50_with_swirl(&self, particle_density: f64, v_theta: f64) -> f64 {
        (18.0 * self.gas_viscosity * self.bm_radial_velocity() * self.vortex_finder_radius
            / ((particle_density - self.gas_density) * v_theta * v_theta))
            .sqrt()
    }

    /// Shepherd–Lapple's pressure drop Δp = K·(a·b/D_x²)·ρ·v_in²/2 with K = 16 (a
    /// tangential slot inlet), D_x = 2·R_x the vortex finder's diameter, Pa.
    pub fn shepherd_lapple_pressure_drop(&self) -> f64 {
        let d_x = 2.0 * self.vortex_finder_radius;
        16.0 * self.inlet_height * self.inlet_width / (d_x * d_x)
            * 0.5
            * self.gas_density
            * self.inlet_velocity.powi(2)
    }

    /// Barth–Muschelknautz's pressure drop (Hoffmann & Stein eqs. 6.2.1–6.2.3, clean gas)
    /// with the tangential velocity at the control surface `v_theta` (m/s; the model's is
    /// [`Cyclone::bm_tangential_velocity`]): the body's wall friction f·A_R·ρ·(v_θw·v_θCS)^1.5
    /// / (2·0.9·Q) plus the vortex finder's ½ρv_x²·[2 + (v_θCS/v_x)² + 3·(v_θCS/v_x)^(4/3)],
    /// v_x = Q/(π·R_x²) and v_θw = v_in·R_in/(α·R); (body, vortex finder), Pa.
    pub fn bm_pressure_drop(&self, v_theta: f64) -> (f64, f64) {
        let q = self.flow_rate();
        let v_wall = self.inlet_velocity * self.inlet_radius / (self.constriction() * self.radius);
        let body =
            self.friction * self.friction_area() * self.gas_density * (v_wall * v_theta).powf(1.5)
                / (2.0 * 0.9 * q);
        let v_x = q / (PI * self.vortex_finder_radius.powi(2));
        let ratio = v_theta / v_x;
        let finder = 0.5
            * self.gas_density
            * v_x
            * v_x
            * (2.0 + ratio * ratio + 3.0 * ratio.powf(4.0 / 3.0));
        (body, finder)
    }

    /// One line of the study's report: Shepherd–Lapple's pressure drop and
    /// Barth–Muschelknautz's with its own swirl and, when measured, the field's.
    pub fn pressure_drops(&self) -> String {
        let (body, finder) = self.bm_pressure_drop(self.bm_tangential_velocity());
        let field = self.field_swirl.map_or(String::new(), |(vt, _)| {
            let (b, f) = self.bm_pressure_drop(vt);
            format!(", {:.0} Pa with the field's", b + f)
        });
        format!(
            "pressure drop: Shepherd–Lapple {:.0} Pa; Barth–Muschelknautz {:.0} Pa (body \
             {body:.0}, vortex finder {finder:.0}) with its swirl{field} (the CFD's own: \
             cases/cyclone/build.sh's summary.txt)",
            self.shepherd_lapple_pressure_drop(),
            body + finder
        )
    }

    /// A flow's mean velocities on Barth–Muschelknautz's control surface, the cylinder of
    /// radius R_x from the vortex finder's bottom down to the cone's bottom, for a cyclone
    /// on the z axis with its roof at `roof_z`: (|mean tangential|, mean inward radial), m/s,
    /// from `n` × `n` points evenly over its height and angle where `velocity` knows the
    /// flow (`None` when it knows it nowhere).
    pub fn control_surface(
        &self,
        roof_z: f64,
        n: usize,
        velocity: impl Fn(glam::DVec3) -> Option<glam::DVec3>,
    ) -> Option<(f64, f64)> {
        let rx = self.vortex_finder_radius;
        let top = roof_z - self.vortex_finder_length;
        let bottom = roof_z - self.total_height;
        let (mut vt, mut vr, mut k) = (0.0, 0.0, 0usize);
        for i in 0..n {
            let z = bottom + (i as f64 + 0.5) / n as f64 * (top - bottom);
            for j in 0..n {
                let a = 2.0 * PI * (j as f64 + 0.5) / n as f64;
                let (sn, cs) = a.sin_cos();
                if let Some(u) = velocity(glam::DVec3::new(rx * cs, rx * sn, z)) {
                    vt += -sn * u.x + cs * u.y;
                    vr -= cs * u.x + sn * u.y;
                    k += 1;
                }
            }
        }
        (k > 0).then(|| ((vt / k as f64).abs(), vr / k as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cut_sizes_of_the_readme() {
        // cases/cyclone/README.md, "Cut size": N_e = 3.75, Lapple 8.3 µm (9.6 / 7.4 at
        // 1500 / 2500 kg/m³); α = 0.62, A_R = 6.47 m², v_θCS = 26.5 m/s, v_rCS = 0.53 m/s,
        // Barth–Muschelknautz 4.3 µm (4.9 / 3.8). Tolerance: the README's last digit.
        let c = Cyclone::OPENFOAM_TUTORIAL;
        assert!((c.lapple_turns() - 3.75).abs() < 1e-12);
        assert!((c.flow_rate() - 0.8).abs() < 1e-12);
        let um = |x: f64| x * 1e6;
        for (rho, lapple, bm) in [(2000.0, 8.3, 4.3), (1500.0, 9.6, 4.9), (2500.0, 7.4, 3.8)] {
            assert!((um(c.lapple_d50(rho)) - lapple).abs() < 0.05, "{rho}");
            assert!(
                (um(c.barth_muschelknautz_d50(rho)) - bm).abs() < 0.05,
                "{rho}: {}",
                um(c.barth_muschelknautz_d50(rho))
            );
        }
        assert!((c.constriction() - 0.62).abs() < 0.005);
        assert!((c.friction_area() - 6.47).abs() < 0.005);
        assert!((c.bm_tangential_velocity() - 26.5).abs() < 0.05);
        assert!((c.bm_radial_velocity() - 0.53).abs() < 0.005);
        // With half the swirl, twice the cut size.
        let half = c.bm_d50_with_swirl(2000.0, 0.5 * c.bm_tangential_velocity());
        assert!((half / c.barth_muschelknautz_d50(2000.0) - 2.0).abs() < 1e-12);
        // A forced vortex Ω = 10 rad/s with a sink flow of 1 m/s at R_x, roof at z = 1:
        // v_θ = Ω·R_x, v_r = 1 (inward), sampled everywhere; nothing known: None.
        let (vt, vr) = c
            .control_surface(1.0, 16, |x| {
                assert!(x.z > -1.0 && x.z < 0.6 && (x.truncate().length() - 0.15).abs() < 1e-12);
                let r = x.truncate().length();
                Some(glam::DVec3::new(
                    -10.0 * x.y - x.x / r,
                    10.0 * x.x - x.y / r,
                    3.0,
                ))
            })
            .unwrap();
        assert!(
            (vt - 1.5).abs() < 1e-12 && (vr - 1.0).abs() < 1e-12,
            "{vt} {vr}"
        );
        assert!(c.control_surface(1.0, 4, |_| None).is_none());
        // Pressure drops: Shepherd–Lapple 16·(0.4·0.2/0.3²)·½·1.2·10² = 853.3 Pa;
        // Barth–Muschelknautz with its own swirl: v_θw = 10·0.35/(0.62·0.5) = 11.29 m/s,
        // body 0.005·6.47·1.2·(11.29·26.5)^1.5/(1.8·0.8) = 139.4 Pa; v_x = 11.32 m/s, vortex
        // finder 1291 Pa (by hand from the formulas above).
        assert!((c.shepherd_lapple_pressure_drop() - 853.33).abs() < 0.01);
        let (body, finder) = c.bm_pressure_drop(c.bm_tangential_velocity());
        assert!((body - 139.4).abs() < 0.5, "{body}");
        assert!((finder - 1291.0).abs() < 5.0, "{finder}");
        // no swirl: the vortex finder's loss is 2 dynamic heads
        let (b0, f0) = c.bm_pressure_drop(0.0);
        let v_x = 0.8 / (PI * 0.15f64.powi(2));
        assert!(b0 == 0.0 && (f0 - 1.2 * v_x * v_x).abs() < 1e-9);
        // Lapple: d50 ∝ √(1/(ρ_p − ρ)) exactly.
        let r = c.lapple_d50(1000.0) / c.lapple_d50(4000.0);
        assert!((r - ((4000.0 - 1.2) / (1000.0 - 1.2f64)).sqrt()).abs() < 1e-12);
    }
}

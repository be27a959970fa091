//! The forces against their formulas, written out again here from the papers.

use super::*;
use std::f64::consts::PI;

const AIR: Fluid = Fluid {
    density: 1.2,
    viscosity: 1.8e-5,
};

fn rel(a: DVec3, b: DVec3) -> f64 {
    (a - b).length() / b.length()
}

/// u = (γ·y, 0, 0): J has ∂u_x/∂y = γ in its second column.
fn shear(gamma: f64) -> DMat3 {
    DMat3::from_cols(DVec3::ZERO, DVec3::new(gamma, 0.0, 0.0), DVec3::ZERO)
}

#[test]
fn vorticity_of_a_shear_and_a_rotation() {
    assert_eq!(vorticity(shear(3.0)), DVec3::new(0.0, 0.0, -3.0));
    // solid-body rotation Ω about z: u = (−Ω·y, Ω·x, 0), ∇×u = 2Ω
    let w = 5.0;
    let j = DMat3::from_cols(
        DVec3::new(0.0, w, 0.0),
        DVec3::new(-w, 0.0, 0.0),
        DVec3::ZERO,
    );
    assert_eq!(vorticity(j), DVec3::new(0.0, 0.0, 2.0 * w));
}

#[test]
fn saffman_mei_in_a_linear_shear_against_mei_1992() {
    // 50 µm in air, slip 0.3 m/s along x, shear 200 1/s
    let (d, gamma) = (50e-6, 200.0);
    let slip = DVec3::new(0.3, 0.0, 0.0);
    let omega = vorticity(shear(gamma));
    let f = saffman_mei(d, AIR, slip, omega);
    // Mei (1992) as OpenFOAM writes it, term by term
    let re = 1.2 * 0.3 * d / 1.8e-5;
    let re_w = 1.2 * gamma * d * d / 1.8e-5;
    let beta = re_w / (2.0 * re);
    let a = 0.3314 * beta.sqrt();
    let fm = (1.0 - a) * (-0.1 * re).exp() + a;
    let cl = 3.0 / (2.0 * PI * re_w.sqrt()) * 6.46 * fm;
    let want = PI * d * d * d / 6.0 * 1.2 * cl * slip.cross(omega);
    assert!(rel(f, want) < 1e-12, "{f} vs {want}");
    // a particle lagging the flow (slip along +x) is lifted toward the faster fluid (+y)
    assert!(f.y > 0.0 && f.x == 0.0 && f.z == 0.0);
    // Re ≥ 40: the other branch, 6.46·0.0524·√(β·Re)
    let fast = DVec3::new(20.0, 0.0, 0.0);
    let re2 = 1.2 * 20.0 * d / 1.8e-5;
    assert!(re2 >= 40.0);
    let b2 = re_w / (2.0 * re2);
    let cl2 = 3.0 / (2.0 * PI * re_w.sqrt()) * 6.46 * 0.0524 * (b2 * re2).sqrt();
    let want2 = PI * d * d * d / 6.0 * 1.2 * cl2 * fast.cross(omega);
    assert!(rel(saffman_mei(d, AIR, fast, omega), want2) < 1e-12);
    // no shear or no slip: no lift
    assert_eq!(saffman_mei(d, AIR, slip, DVec3::ZERO), DVec3::ZERO);
    assert_eq!(saffman_mei(d, AIR, DVec3::ZERO, omega), DVec3::ZERO);
}

#[test]
fn saffman_mei_is_saffmans_lift_times_meis_f() {
    // Saffman (1965): F = 1.615·d²·√(ρ_f·μ·|ω|)·|u − v|; Mei's factor f → 1 at small Re, β
    let (d, gamma) = (10e-6, 10.0);
    let slip = DVec3::new(0.1, 0.0, 0.0);
    let f = saffman_mei(d, AIR, slip, vorticity(shear(gamma)));
    let saffman = 1.615 * d * d * (1.2 * 1.8e-5 * gamma).sqrt() * 0.1;
    let re = 1.2 * 0.1 * d / 1.8e-5;
    let beta = 1.2 * gamma * d * d / 1.8e-5 / (2.0 * re);
    let a = 0.3314 * beta.sqrt();
    let fm = (1.0 - a) * (-0.1 * re).exp() + a;
    // 1.615 = 6.46/4 exactly
    assert!((f.length() / (saffman * fm) - 1.0).abs() < 1e-12);
    assert!((fm - 1.0).abs() < 0.01);
}

#[test]
fn rubinow_keller_is_magnus_on_a_spinning_sphere() {
    // a 1 mm sphere moving at 2 m/s along +x through still air, spinning 100 rad/s about +z
    let (d, spin) = (1e-3, DVec3::new(0.0, 0.0, 100.0));
    let slip = DVec3::new(-2.0, 0.0, 0.0); // u − v
    let f = rubinow_keller(d, 1.2, spin, DVec3::ZERO, slip);
    let want = PI / 8.0 * 1.2 * d * d * d * 100.0 * 2.0;
    assert!(
        (f.y - want).abs() < 1e-12 * want && f.x == 0.0 && f.z == 0.0,
        "{f}"
    );
    // spinning with the fluid's rotation (ω_p = ω_f/2): no rotational lift
    let w = DVec3::new(0.0, 0.0, 200.0);
    assert_eq!(rubinow_keller(d, 1.2, 0.5 * w, w, slip), DVec3::ZERO);
}

fn coupling(d: f64, rho: f64) -> FluidCoupling {
    FluidCoupling {
        drag_diameter: d,
        reynolds_diameter: d,
        force_density: rho,
        force_scale: 1.0,
        tau: 1e-3,
    }
}

#[test]
fn pressure_gradient_and_added_mass_make_a_neutral_particle_move_with_the_fluid() {
    // solid-body rotation Ω about z: Du/Dt = J·u = −Ω²·r
    let w = 3.0;
    let j = DMat3::from_cols(
        DVec3::new(0.0, w, 0.0),
        DVec3::new(-w, 0.0, 0.0),
        DVec3::ZERO,
    );
    let x = DVec3::new(0.2, -0.1, 0.4);
    let u = j * x;
    let f = StepForces {
        fluid: Fluid {
            density: 1000.0,
            viscosity: 1e-3,
        },
        added_mass: 0.5,
        pressure_gradient: true,
        saffman_mei: false,
        frame: None,
    };
    // ρ_p = ρ_f: (1 + 0.5)·1·Du/Dt / (1 + 0.5) = Du/Dt, the fluid's own acceleration
    let a = f.acceleration(&coupling(1e-3, 1000.0), DVec3::ZERO, u, j, u);
    let want = -w * w * DVec3::new(x.x, x.y, 0.0);
    assert!(rel(a, want) < 1e-15, "{a} vs {want}");
    // a heavy particle (ρ_p = 2500 in water) gets (1 + C_A)·(ρ_f/ρ_p)/k of it
    let heavy = f.acceleration(&coupling(1e-3, 2500.0), DVec3::ZERO, u, j, u);
    let r = 1000.0 / 2500.0;
    assert!(rel(heavy, want * (1.5 * r / (1.0 + 0.5 * r))) < 1e-15);
    // pressure gradient alone: (ρ_f/ρ_p)·Du/Dt
    let pg = StepForces {
        added_mass: 0.0,
        ..f
    };
    assert!(
        rel(
            pg.acceleration(&coupling(1e-3, 2500.0), DVec3::ZERO, u, j, u),
            want * r
        ) < 1e-15
    );
    // k for the spawn
    let forces = ExtraForces {
        added_mass: Some(0.5),
        ..Default::default()
    };
    assert_eq!(forces.inertia(Some(&f.fluid), 1000.0), 1.5);
    assert_eq!(ExtraForces::default().inertia(Some(&f.fluid), 1000.0), 1.0);
}

/// One step of the spinning sphere: the spin relaxes exactly toward ω/2, and the kick is
/// the Rubinow–Keller force on the step's mean relative spin over the (added-mass) inertia,
/// (3/4)·(ρ_f/ρ_p)·Ω̄ × (v − u)·dt/k in closed form.
#[test]
fn rotational_lift_step_relaxes_the_spin_and_kicks_by_the_lift() {
    let fluid = Fluid {
        density: 1.2,
        viscosity: 1.8e-5,
    };
    let (d, rho, dt, k) = (50e-6, 2500.0, 2e-5, 1.0 + 0.5 * 1.2 / 2500.0);
    let fc = coupling(d, rho);
    let tau = spin_relaxation_time(d, rho, fluid.viscosity);
    assert!((tau - rho * d * d / (60.0 * 1.8e-5)).abs() <= 1e-15 * tau);
    let (spin, omega, slip) = (
        DVec3::new(300.0, -50.0, 1000.0),
        DVec3::new(0.0, 0.0, 400.0),
        DVec3::new(2.0, -1.0, 0.5),
    );
    let (dv, s1) = rotational_lift_step(spin, omega, slip, &fc, fluid, 0.5, dt);
    let half = 0.5 * omega;
    let want_spin = half + (spin - half) * (-dt / tau).exp();
    assert!((s1 - want_spin).length() <= 1e-12 * want_spin.length());
    let mean = (spin - half) * (tau / dt * (1.0 - (-dt / tau).exp()));
    let want = 0.75 * (fluid.density / rho) * mean.cross(-slip) * dt / k;
    assert!(
        (dv - want).length() <= 1e-12 * want.length(),
        "{dv} vs {want}"
    );
    // a spin that turns with the fluid feels no lift and keeps turning with it
    let (dv, s1) = rotational_lift_step(half, omega, slip, &fc, fluid, 0.5, dt);
    assert_eq!(dv, DVec3::ZERO);
    assert!((s1 - half).length() <= 1e-15 * half.length());
}

/// The rotating frame's fictitious acceleration: Coriolis −2·Ω × v and centrifugal
/// −Ω × (Ω × (x − c)) = Ω²·r outward for Ω along z.
#[test]
fn a_rotating_frames_centrifugal_and_coriolis() {
    let f = RotatingFrame {
        omega: DVec3::new(0.0, 0.0, 3.0),
        centre: DVec3::new(1.0, 0.0, 0.0),
    };
    let a = f.acceleration(DVec3::new(1.5, 0.0, 7.0), DVec3::ZERO);
    assert!((a - DVec3::new(4.5, 0.0, 0.0)).length() < 1e-15, "{a}");
    let c = f.acceleration(DVec3::new(1.0, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0));
    assert!((c - DVec3::new(0.0, -12.0, 0.0)).length() < 1e-15, "{c}");
}

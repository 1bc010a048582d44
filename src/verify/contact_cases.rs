//! The cases of `magdem verify contacts` — the Chung & Ooi (2011) single-contact benchmark types
//! with the paper's material — as scenes with their Hertz closed forms, what one run of a case
//! measures, and how two measurements compare. The runner (`contacts`) and the report
//! (`contacts_report`) both use them.

use std::f64::consts::PI;

/// Material of every case (the paper's case 1) and the time step.
pub const DIAMETER: f64 = 11.0e-6;
pub const DENSITY: f64 = 1087.0;
pub const YOUNGS: f64 = 1.0e9;
pub const POISSON: f64 = 0.5;
pub const FRICTION: f64 = 0.5;
pub const DT: f64 = 1.0e-10;
/// A frame every this many steps.
pub const FRAME_STEPS: u64 = 5;
/// The benchmark's source.
pub const SOURCE: &str = "Chung & Ooi (2011)";
/// The restitution cases' coefficients (pairs at [`PAIR_SPEED`] each).
pub const RESTITUTIONS: [f64; 4] = [0.3, 0.5, 0.7, 0.9];
/// Approach speed of each sphere in the pair cases (m/s).
pub const PAIR_SPEED: f64 = 0.05;
/// Impact speed of the wall cases (m/s), and the restitution of the oblique and spin cases.
pub const WALL_SPEED: f64 = 0.1;
pub const OBLIQUE_RESTITUTION: f64 = 0.5;
/// Incident angles of the oblique cases (degrees from the wall normal).
pub const OBLIQUE_ANGLES: [f64; 9] = [5.0, 15.0, 25.0, 35.0, 45.0, 55.0, 65.0, 75.0, 85.0];

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Geometry {
    /// Two spheres of diameters d1, d2 approaching along x, each at `speed`.
    Pair { d1: f64, d2: f64 },
    /// One sphere hitting the z-lo wall.
    Wall,
}

#[derive(Debug, Clone)]
pub struct Case {
    pub name: String,
    pub group: &'static str,
    pub geometry: Geometry,
    pub restitution: f64,
    /// Normal approach speed (pair: each sphere; wall: the sphere) and tangential speed (m/s).
    pub normal_speed: f64,
    pub tangential_speed: f64,
    /// Initial spin about y (rad/s).
    pub spin: f64,
}

impl Case {
    /// Incident angle from the wall normal (degrees).
    pub fn incident_angle(&self) -> f64 {
        self.tangential_speed.atan2(self.normal_speed).to_degrees()
    }

    /// Radii of the two bodies (the wall's is infinite).
    pub fn radii(&self) -> (f64, f64) {
        match self.geometry {
            Geometry::Pair { d1, d2 } => (0.5 * d1, 0.5 * d2),
            Geometry::Wall => (0.5 * DIAMETER, f64::INFINITY),
        }
    }

    /// Hertz closed forms (max overlap, duration) for an elastic normal impact, DESIGN.md §5,
    /// with E* = 1/Σ(1 − ν²)/E (the wall has the sphere's material) and the relative speed.
    pub fn hertz(&self) -> (f64, f64) {
        let (a1, a2) = self.radii();
        let m = |a: f64| DENSITY * 4.0 / 3.0 * PI * a.powi(3);
        let (r_eff, m_eff, v) = match self.geometry {
            Geometry::Pair { .. } => (a1 * a2 / (a1 + a2), m(a1) * m(a2) / (m(a1) + m(a2)), 2.0 * self.normal_speed),
            Geometry::Wall => (a1, m(a1), self.normal_speed),
        };
        let e_star = YOUNGS / (2.0 * (1.0 - POISSON * POISSON));
        let delta = (15.0 * m_eff * v * v / (16.0 * e_star * r_eff.sqrt())).powf(0.4);
        let t_c = 2.87 * (m_eff * m_eff / (r_eff * e_star * e_star * v)).powf(0.2);
        (delta, t_c)
    }

    /// The case as a scene: contact only, walls on every face, a gap of 1 nm at the start.
    pub fn scene_text(&self) -> String {
        let (a1, a2) = self.radii();
        let gap = 1e-9;
        let box_half = 4.0 * DIAMETER;
        let (species, particles) = match self.geometry {
            Geometry::Pair { d1, d2 } => {
                let mut sp = species_block("s1", d1, self.restitution);
                let mut parts = format!(
                    "[[particles]]\nspecies = \"s1\"\npositions = [[{:e}, 0.0, 0.0]]\nvelocities = [[{:e}, {:e}, 0.0]]\n",
                    -a1 - 0.5 * gap,
                    self.normal_speed,
                    self.tangential_speed
                );
                let second = if d2 == d1 { "s1" } else { "s2" };
                if d2 != d1 {
                    sp += &species_block("s2", d2, self.restitution);
                }
                parts += &format!(
                    "[[particles]]\nspecies = \"{second}\"\npositions = [[{:e}, 0.0, 0.0]]\nvelocities = [[{:e}, 0.0, 0.0]]\n",
                    a2 + 0.5 * gap,
                    -self.normal_speed
                );
                (sp, parts)
            }
            Geometry::Wall => (
                species_block("s1", DIAMETER, self.restitution),
                format!(
                    "[[particles]]\nspecies = \"s1\"\npositions = [[0.0, 0.0, {:e}]]\nvelocities = [[{:e}, 0.0, {:e}]]\nangular_velocities = [[0.0, {:e}, 0.0]]\n",
                    -box_half + a1 + gap,
                    self.tangential_speed,
                    -self.normal_speed,
                    self.spin
                ),
            ),
        };
        let (_, t_c) = self.hertz();
        let end = (3.0 * t_c / (DT * FRAME_STEPS as f64)).ceil() * DT * FRAME_STEPS as f64;
        format!(
            "# magdem verify contacts: {} ({})\nversion = 1\nname = \"{}\"\n[domain]\nlo = [{lo:e}, {lo:e}, {lo:e}]\nhi = [{hi:e}, {hi:e}, {hi:e}]\n\
             {species}{particles}[forces.contact]\n[integration]\nscheme = \"velocity-verlet\"\ndt = {DT:e}\nend_time = {end:e}\n\
             [output]\ninterval = {:e}\nforces = true\n",
            self.name,
            self.group,
            self.name,
            DT * FRAME_STEPS as f64,
            lo = -box_half,
            hi = box_half
        )
    }
}

fn species_block(name: &str, d: f64, e: f64) -> String {
    format!(
        "[[species]]\nname = \"{name}\"\ndiameter = {d:e}\ndensity = {DENSITY:e}\nyoungs_modulus = {YOUNGS:e}\npoisson_ratio = {POISSON}\nfriction = {FRICTION}\nrestitution = {e}\n"
    )
}

/// The benchmark cases.
pub fn cases() -> Vec<Case> {
    let pair = Geometry::Pair { d1: DIAMETER, d2: DIAMETER };
    let base = |name: String, group, geometry, restitution, vn, vt, spin| Case {
        name,
        group,
        geometry,
        restitution,
        normal_speed: vn,
        tangential_speed: vt,
        spin,
    };
    let mut v = vec![
        base("elastic pair".into(), "1 normal, equal spheres", pair, 1.0, PAIR_SPEED, 0.0, 0.0),
        base("elastic wall".into(), "2 normal, sphere-wall", Geometry::Wall, 1.0, WALL_SPEED, 0.0, 0.0),
    ];
    for e in RESTITUTIONS {
        v.push(base(format!("pair e = {e}"), "3 restitution", pair, e, PAIR_SPEED, 0.0, 0.0));
    }
    for angle in OBLIQUE_ANGLES {
        let (vn, vt) = (WALL_SPEED * angle.to_radians().cos(), WALL_SPEED * angle.to_radians().sin());
        v.push(base(
            format!("oblique {angle:.0}°"),
            "4 oblique, sphere-wall",
            Geometry::Wall,
            OBLIQUE_RESTITUTION,
            vn,
            vt,
            0.0,
        ));
    }
    let a = 0.5 * DIAMETER;
    v.push(base("spin, normal".into(), "5 spin, sphere-wall", Geometry::Wall, 0.5, 0.1, 0.0, 0.5 * 0.1 / a));
    v.push(base("spin, oblique 45°".into(), "5 spin, sphere-wall", Geometry::Wall, 0.5, 0.0707, 0.0707, -0.0707 / a));
    v.push(base(
        "unequal 1:2, elastic".into(),
        "6 unequal sizes",
        Geometry::Pair { d1: DIAMETER, d2: 2.0 * DIAMETER },
        1.0,
        0.05,
        0.0,
        0.0,
    ));
    v
}

/// What one run of one case measured.
#[derive(Debug, Clone, Copy, Default)]
pub struct Metrics {
    pub restitution: f64,
    pub duration: f64,
    pub max_overlap: f64,
    /// Rebound tangential velocity of the (first) sphere's centre (m/s).
    pub rebound_tangential: f64,
    /// Rebound angular velocity about y of the first sphere (rad/s).
    pub rebound_spin: f64,
    /// Rebound angle from the normal (degrees).
    pub rebound_angle: f64,
}

/// One case run by one engine.
pub struct Outcome {
    pub case: Case,
    pub engine: &'static str,
    pub metrics: Metrics,
    pub force_overlap: Vec<(f64, f64)>,
}

/// Relative difference a/b − 1, or the absolute difference when b is ~0.
pub fn relative(a: f64, b: f64, scale: f64) -> f64 {
    if b.abs() > 1e-9 * scale.abs() {
        a / b - 1.0
    } else {
        (a - b) / scale
    }
}

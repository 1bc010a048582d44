//! Particle state in struct-of-arrays form, plus the contact history that belongs to it.
//!
//! Everything a run needs to continue bit for bit lives here, so a checkpoint is this struct.

/// Three-vector of f64 used throughout the core (SI units).
pub type Vec3 = nalgebra::Vector3<f64>;

/// Material, magnetic and geometric properties shared by the particles of one species.
#[derive(Debug, Clone, PartialEq)]
pub struct Species {
    pub name: String,
    /// Sphere radius a (m).
    pub radius: f64,
    /// Particle density ρ_p (kg/m³).
    pub density: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson ratio ν.
    pub poisson_ratio: f64,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// Normal coefficient of restitution e (sets the contact damping, LIGGGHTS' formula).
    pub restitution: f64,
    /// Effective susceptibility of a sphere, χ_eff = 3(μr − 1)/(μr + 2) (Clausius–Mossotti).
    pub susceptibility: f64,
    /// Saturation magnetisation Ms (A/m): |M_induced| ≤ Ms.
    pub saturation_magnetisation: Option<f64>,
    /// Permanent moment (A·m²) each particle of the species carries, in its body frame at t = 0.
    pub permanent_moment: Option<Vec3>,
}

impl Species {
    pub fn volume(&self) -> f64 {
        4.0 / 3.0 * std::f64::consts::PI * self.radius.powi(3)
    }
    pub fn mass(&self) -> f64 {
        self.density * self.volume()
    }
    /// Moment of inertia of a solid sphere, I = 2/5 m a².
    pub fn inertia(&self) -> f64 {
        0.4 * self.mass() * self.radius * self.radius
    }
    /// Shear modulus G = E / (2(1 + ν)).
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))
    }
}

/// Per-particle arrays (struct of arrays). Index i is the particle id.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Particles {
    pub species: Vec<u16>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inertia: Vec<f64>,
    /// 1/m and 1/I, kept beside `mass` and `inertia` (a kick multiplies rather than divides).
    pub inv_mass: Vec<f64>,
    pub inv_inertia: Vec<f64>,
    pub position: Vec<Vec3>,
    pub velocity: Vec<Vec3>,
    pub angular_velocity: Vec<Vec3>,
    /// Force and torque at the current state (the integrators keep this invariant). With
    /// multiple time stepping these hold the fast part and `slow_*` the slow (magnetic) part.
    pub force: Vec<Vec3>,
    pub torque: Vec<Vec3>,
    pub slow_force: Vec<Vec3>,
    pub slow_torque: Vec<Vec3>,
    /// Total magnetic moment m_i (A·m²): induced plus permanent.
    pub moment: Vec<Vec3>,
    /// Permanent moment, rotated with the particle (zero for purely induced particles).
    pub permanent_moment: Vec<Vec3>,
    /// Whether any particle carries a permanent moment (otherwise the drift need not turn them).
    pub has_permanent_moments: bool,
}

impl Particles {
    pub fn len(&self) -> usize {
        self.position.len()
    }
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Adds one particle of `species` (index `species_index`) at rest.
    pub fn push(&mut self, species_index: u16, species: &Species, position: Vec3, velocity: Vec3) {
        self.species.push(species_index);
        self.radius.push(species.radius);
        self.mass.push(species.mass());
        self.inertia.push(species.inertia());
        self.inv_mass.push(1.0 / species.mass());
        self.inv_inertia.push(1.0 / species.inertia());
        self.position.push(position);
        self.velocity.push(velocity);
        self.angular_velocity.push(Vec3::zeros());
        self.force.push(Vec3::zeros());
        self.torque.push(Vec3::zeros());
        self.slow_force.push(Vec3::zeros());
        self.slow_torque.push(Vec3::zeros());
        self.moment.push(Vec3::zeros());
        let permanent = species.permanent_moment.unwrap_or_else(Vec3::zeros);
        self.has_permanent_moments |= permanent != Vec3::zeros();
        self.permanent_moment.push(permanent);
    }

    /// Sets the masses, and from them and the radii the inertias (solid spheres) and inverses.
    pub fn set_masses(&mut self, mass: Vec<f64>) {
        self.inertia = mass.iter().zip(&self.radius).map(|(m, a)| 0.4 * m * a * a).collect();
        self.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
        self.inv_inertia = self.inertia.iter().map(|i| 1.0 / i).collect();
        self.mass = mass;
    }

    pub fn kinetic_energy(&self) -> f64 {
        (0..self.len())
            .map(|i| {
                0.5 * self.mass[i] * self.velocity[i].norm_squared()
                    + 0.5 * self.inertia[i] * self.angular_velocity[i].norm_squared()
            })
            .sum()
    }
}

/// Wall faces of the box: 0..6 = x-lo, x-hi, y-lo, y-hi, z-lo, z-hi.
pub type WallFace = u8;

/// Tangential spring (shear history) of every active contact, sorted by key: the order in which
/// the contact term visits contacts, so it finds each spring by a merge rather than a hash, and a
/// checkpoint stores them in a deterministic order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ContactHistory {
    pub pairs: Vec<((u32, u32), Vec3)>,
    pub walls: Vec<((u32, WallFace), Vec3)>,
}

/// What the last force evaluation saw that the stability monitor needs.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactDiagnostics {
    /// Largest overlap δ divided by the smaller diameter of the pair (or the particle's for a wall).
    pub max_overlap_ratio: f64,
    /// The particles of that contact (`j = None` for a wall).
    pub max_overlap_pair: (u32, Option<u32>),
}

/// Full simulation state: particles, contact history, clock.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct State {
    pub particles: Particles,
    pub contacts: ContactHistory,
    pub diagnostics: ContactDiagnostics,
    /// Number of steps taken since t = 0.
    pub step: u64,
    /// Simulated time (s); `step × dt` between steps.
    pub time: f64,
    /// The substep an adaptive integrator proposes to try next (its controller's memory, kept
    /// here so that a checkpoint carries it and a resumed run repeats the uninterrupted one).
    pub next_substep: Option<f64>,
}

//! Particle state in struct-of-arrays form, plus the contact history that belongs to it.
//!
//! Everything a run needs to continue bit for bit lives here, so a checkpoint is this struct.

use super::renumber::{Renumbering, GONE};
pub use super::vector::Vec3;

/// Saturation of the induced magnetisation at Ms (A/m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Saturation {
    pub ms: f64,
    pub law: SaturationLaw,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SaturationLaw {
    /// |M| = min(χ_eff |H|, Ms).
    Cap,
    /// Fröhlich–Kennelly: |M| = χ_eff |H| · Ms / (Ms + χ_eff |H|) (Jiles 1998, §1.5): linear at
    /// low field, Ms at infinite field, smooth in between.
    FrohlichKennelly,
    /// Langevin: |M| = Ms L(3 χ_eff |H| / Ms), L(ξ) = coth ξ − 1/ξ: a superparamagnetic core's
    /// thermal average, whose initial susceptibility is χ_eff (Rosensweig, Ferrohydrodynamics,
    /// 1985, §2.5). With χ_eff = μ0 m_c²/(3kT V) it is m_c L(μ0 m_c H/kT) per particle.
    Langevin,
}

/// The Langevin function L(ξ) = coth ξ − 1/ξ, ≥ 0 for ξ ≥ 0; below ξ = 1e-2 its series
/// ξ/3 − ξ³/45 + 2ξ⁵/945 (the closed form cancels there), error below 1e-16 of it.
pub fn langevin(xi: f64) -> f64 {
    if xi < 1e-2 {
        let x2 = xi * xi;
        xi * (1.0 / 3.0 - x2 / 45.0 + 2.0 * x2 * x2 / 945.0)
    } else {
        1.0 / xi.tanh() - 1.0 / xi
    }
}

impl Saturation {
    /// The saturated magnitude of a magnetisation whose linear value is `linear` (A/m, ≥ 0).
    pub fn magnetisation(&self, linear: f64) -> f64 {
        match self.law {
            SaturationLaw::Cap => linear.min(self.ms),
            SaturationLaw::FrohlichKennelly => linear * self.ms / (self.ms + linear),
            SaturationLaw::Langevin => self.ms * langevin(3.0 * linear / self.ms),
        }
    }

    /// The largest moment (A·m²) a sphere of `volume` whose linear magnetisation is `linear`
    /// may carry: Ms·V for the cap, the law's moment otherwise.
    pub fn moment(&self, linear: f64, volume: f64) -> f64 {
        match self.law {
            SaturationLaw::Cap => self.ms * volume,
            SaturationLaw::FrohlichKennelly | SaturationLaw::Langevin => self.magnetisation(linear) * volume,
        }
    }
}

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
    /// How the induced magnetisation saturates (none: linear at any field).
    pub saturation: Option<Saturation>,
    /// Permanent moment (A·m²) each particle of the species carries, in its body frame at t = 0.
    pub permanent_moment: Option<Vec3>,
    /// Radii drawn per particle from a distribution (polydisperse), or all `radius`.
    pub size: Option<SizeDistribution>,
}

/// The law of a polydisperse species' radii.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SizeLaw {
    Normal,
    /// ln a normal, with the mean and standard deviation of a itself.
    LogNormal,
}

/// Radii a ~ `law` with mean `mean` and standard deviation `std` before truncation, drawn again
/// until they fall in [`min`, `max`] (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizeDistribution {
    pub law: SizeLaw,
    pub mean: f64,
    pub std: f64,
    pub min: f64,
    pub max: f64,
}

impl SizeDistribution {
    /// The untruncated density at radius `a`.
    fn density(&self, a: f64) -> f64 {
        use statrs::distribution::Continuous;
        match self.law {
            SizeLaw::Normal => statrs::distribution::Normal::new(self.mean, self.std).map_or(0.0, |d| d.pdf(a)),
            SizeLaw::LogNormal => {
                let (mu, sigma) = self.log_parameters();
                statrs::distribution::LogNormal::new(mu, sigma).map_or(0.0, |d| d.pdf(a))
            }
        }
    }

    /// μ and σ of ln a for the log-normal law: σ² = ln(1 + (std/mean)²), μ = ln mean − σ²/2.
    fn log_parameters(&self) -> (f64, f64) {
        let s2 = (1.0 + (self.std / self.mean).powi(2)).ln();
        (self.mean.ln() - 0.5 * s2, s2.sqrt())
    }

    /// One radius, by rejection from the untruncated law (Box–Muller from two uniforms).
    pub fn draw(&self, rng: &mut impl rand::Rng) -> f64 {
        use rand::RngExt;
        loop {
            let (u, v): (f64, f64) = (rng.random(), rng.random());
            let z = (-2.0 * (1.0 - u).ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos();
            let a = match self.law {
                SizeLaw::Normal => self.mean + self.std * z,
                SizeLaw::LogNormal => {
                    let (mu, sigma) = self.log_parameters();
                    (mu + sigma * z).exp()
                }
            };
            if (self.min..=self.max).contains(&a) {
                return a;
            }
        }
    }

    /// E[a³] over the truncated law (Simpson's rule, 4 000 intervals).
    pub fn mean_cube(&self) -> f64 {
        let n = 4000;
        let h = (self.max - self.min) / n as f64;
        let (mut z, mut m3) = (0.0, 0.0);
        for k in 0..=n {
            let a = self.min + k as f64 * h;
            let w = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let p = w * self.density(a);
            z += p;
            m3 += p * a * a * a;
        }
        m3 / z
    }
}

/// I = 2/5 m a², a solid sphere's moment of inertia.
pub fn sphere_inertia(mass: f64, radius: f64) -> f64 {
    0.4 * mass * radius * radius
}

/// V = 4/3 π a³.
pub fn sphere_volume(radius: f64) -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
}

/// The largest diameter of `species` (0 for none): the scale of every range given in diameters.
pub fn largest_diameter(species: &[Species]) -> f64 {
    species.iter().map(|s| 2.0 * s.largest_radius()).fold(0.0, f64::max)
}

impl Species {
    /// The mean particle volume (over the size distribution, if any).
    pub fn volume(&self) -> f64 {
        match &self.size {
            None => sphere_volume(self.radius),
            Some(d) => 4.0 / 3.0 * std::f64::consts::PI * d.mean_cube(),
        }
    }
    /// The largest radius a particle of the species can have.
    pub fn largest_radius(&self) -> f64 {
        self.size.map_or(self.radius, |d| d.max)
    }
    /// The species with every particle at its smallest radius: the stiffest contacts, the
    /// fastest drag relaxation, so the stable-step estimate's case.
    pub fn smallest(&self) -> Species {
        Species { radius: self.size.map_or(self.radius, |d| d.min), size: None, ..self.clone() }
    }
    pub fn mass(&self) -> f64 {
        self.density * self.volume()
    }
    /// Shear modulus G = E / (2(1 + ν)).
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))
    }
}

/// Every particle's 1/m and 1/I: one pair for all while the particles are alike (a one-species
/// scene), so the integrators' passes read two arrays fewer (12% of a one-thread contact step at
/// 30 000 particles, reports/performance-history.md).
#[derive(Debug, Clone, PartialEq)]
pub enum InverseMasses {
    Uniform { mass: f64, inertia: f64 },
    PerParticle { mass: Vec<f64>, inertia: Vec<f64> },
}

impl Default for InverseMasses {
    fn default() -> Self {
        InverseMasses::PerParticle { mass: Vec::new(), inertia: Vec::new() }
    }
}

impl InverseMasses {
    /// Records particle `k`'s inverses, given those of particles 0..k already.
    fn push(&mut self, k: usize, inv_mass: f64, inv_inertia: f64) {
        match self {
            InverseMasses::Uniform { mass, inertia } if (*mass, *inertia) == (inv_mass, inv_inertia) => {}
            InverseMasses::Uniform { mass, inertia } => {
                let (mut masses, mut inertias) = (vec![*mass; k], vec![*inertia; k]);
                masses.push(inv_mass);
                inertias.push(inv_inertia);
                *self = InverseMasses::PerParticle { mass: masses, inertia: inertias };
            }
            InverseMasses::PerParticle { mass, .. } if mass.is_empty() => {
                *self = InverseMasses::Uniform { mass: inv_mass, inertia: inv_inertia };
            }
            InverseMasses::PerParticle { mass, inertia } => {
                mass.push(inv_mass);
                inertia.push(inv_inertia);
            }
        }
    }
}

/// Whether every particle has one radius and one mass: kept beside the arrays by
/// [`Particles::push`] and [`Particles::set_masses`], so that the contact law may set its
/// reduced radius and mass once for all pairs instead of per contact.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Sizes {
    #[default]
    NoParticles,
    One {
        radius: f64,
        mass: f64,
    },
    Several,
}

impl Sizes {
    fn push(&mut self, radius: f64, mass: f64) {
        *self = match *self {
            Sizes::NoParticles => Sizes::One { radius, mass },
            Sizes::One { radius: a, mass: m } if (a, m) == (radius, mass) => Sizes::One { radius, mass },
            _ => Sizes::Several,
        };
    }
}

/// The particles' positions, read as a slice. They change in one of two ways: a drift, which
/// states a bound on how far it moved any particle, or any other write (placing, restoring,
/// reading back from a reference code, renumbering), which is counted. From the [`Motion`] a
/// neighbour list then knows, without looking at the particles, when none can have moved far
/// enough since its build to need a rebuild. There is no other way to change them: code that
/// moves particles must say which of the two it does. Each set of positions (a new one, a clone)
/// has its own identity, so that a motion is never compared with another set's.
#[derive(Debug)]
pub struct Positions {
    x: Vec<Vec3>,
    motion: Motion,
}

/// What a set of positions went through so far: the sum of the drifts' bounds and the count of
/// other writes (see [`Positions`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Motion {
    /// The set's identity (0: none, the motion of no set).
    set: u64,
    travelled: f64,
    writes: u64,
}

impl Motion {
    /// The motion of a new set of positions.
    fn new() -> Self {
        static SETS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        Motion { set: SETS.fetch_add(1, std::sync::atomic::Ordering::Relaxed), travelled: 0.0, writes: 0 }
    }

    /// A bound on how far (m, minimum image) any particle has moved since `earlier` was taken
    /// from the same set of positions; `None` if it was taken from another set, or the
    /// positions were written otherwise since.
    pub fn since(&self, earlier: Motion) -> Option<f64> {
        (self.set != 0 && self.set == earlier.set && self.writes == earlier.writes)
            .then_some(self.travelled - earlier.travelled)
    }
}

impl Default for Positions {
    fn default() -> Self {
        Vec::new().into()
    }
}

/// A clone is another set of positions: a list built from one examines the other's particles.
impl Clone for Positions {
    fn clone(&self) -> Self {
        self.x.clone().into()
    }
}

/// Equal positions are equal whatever their motion (a restored state equals the one stored).
impl PartialEq for Positions {
    fn eq(&self, other: &Self) -> bool {
        self.x == other.x
    }
}

impl std::ops::Deref for Positions {
    type Target = [Vec3];
    fn deref(&self) -> &[Vec3] {
        &self.x
    }
}

impl<'a> IntoIterator for &'a Positions {
    type Item = &'a Vec3;
    type IntoIter = std::slice::Iter<'a, Vec3>;
    fn into_iter(self) -> Self::IntoIter {
        self.x.iter()
    }
}

impl From<Vec<Vec3>> for Positions {
    fn from(x: Vec<Vec3>) -> Self {
        Positions { x, motion: Motion::new() }
    }
}

impl Positions {
    pub fn motion(&self) -> Motion {
        self.motion
    }

    /// The positions as their vector.
    pub fn as_vec(&self) -> &Vec<Vec3> {
        &self.x
    }

    /// The positions, to be changed otherwise than by a drift: counted as a write, so that every
    /// neighbour list examines every particle at its next update.
    pub fn write(&mut self) -> &mut Vec<Vec3> {
        self.motion.writes += 1;
        &mut self.x
    }

    /// A drift: `f` moves the particles and returns a bound on the distance (m, minimum image)
    /// it moved any of them. The sum of the bounds is rounded up at each addition, so it never
    /// falls below the true sum (a bound of 0 adds nothing); a bound that is not a finite number
    /// ≥ 0 counts as a write.
    pub fn drift(&mut self, f: impl FnOnce(&mut [Vec3]) -> f64) {
        match f(&mut self.x) {
            0.0 => {}
            bound if bound > 0.0 && bound.is_finite() => {
                self.motion.travelled = (self.motion.travelled + bound).next_up()
            }
            _ => self.motion.writes += 1,
        }
    }
}

/// Per-particle arrays (struct of arrays), one slot per particle. Slot k holds the particle whose
/// id is [`State::ids`]`[k]`: its id until the particles are renumbered.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Particles {
    pub species: Vec<u16>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inertia: Vec<f64>,
    /// 1/m and 1/I, kept beside `mass` and `inertia` by [`Particles::push`] and
    /// [`Particles::set_masses`] (a kick multiplies rather than divides).
    pub inverse_masses: InverseMasses,
    /// One radius and mass for all, or several (kept by [`Particles::push`] and
    /// [`Particles::set_masses`]).
    pub sizes: Sizes,
    pub position: Positions,
    pub velocity: Vec<Vec3>,
    pub angular_velocity: Vec<Vec3>,
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

    /// Adds one particle of `species` (index `species_index`) at rest, of the species' radius.
    pub fn push(&mut self, species_index: u16, species: &Species, position: Vec3, velocity: Vec3) {
        self.push_sized(species_index, species, species.radius, position, velocity);
    }

    /// [`Particles::push`] with the particle's own `radius` (a polydisperse species): its mass,
    /// inertia and (through the volume) moment follow it.
    pub fn push_sized(&mut self, species_index: u16, species: &Species, radius: f64, position: Vec3, velocity: Vec3) {
        let mass = species.density * sphere_volume(radius);
        let inertia = sphere_inertia(mass, radius);
        self.species.push(species_index);
        self.radius.push(radius);
        self.mass.push(mass);
        self.inertia.push(inertia);
        self.inverse_masses.push(self.species.len() - 1, 1.0 / mass, 1.0 / inertia);
        self.sizes.push(radius, mass);
        self.position.write().push(position);
        self.velocity.push(velocity);
        self.angular_velocity.push(Vec3::zeros());
        let permanent = species.permanent_moment.unwrap_or_else(Vec3::zeros);
        self.has_permanent_moments |= permanent != Vec3::zeros();
        self.permanent_moment.push(permanent);
    }

    /// Sets the masses, and from them and the radii the inertias (solid spheres) and inverses.
    pub fn set_masses(&mut self, mass: Vec<f64>) {
        self.inertia = mass.iter().zip(&self.radius).map(|(&m, &a)| sphere_inertia(m, a)).collect();
        (self.inverse_masses, self.sizes) = Default::default();
        for (k, (m, i)) in mass.iter().zip(&self.inertia).enumerate() {
            self.inverse_masses.push(k, 1.0 / m, 1.0 / i);
            self.sizes.push(self.radius[k], *m);
        }
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

/// Per-contact history, as LAMMPS' `fix neigh/history` keeps `size_history` values per pair: a
/// 3-vector per touching pair and per wall contact, kept across steps for the one force term that
/// declares it ([`crate::core::forces::ForceTerm::keeps_history`]; the contact's tangential
/// springs). The framework holds it here, renumbers it, checkpoints it and negates a pair's value
/// when its ends swap; the term reads and rewrites it through
/// [`crate::core::forces::Forces::history`]. Sorted by key: the order in which the term visits
/// contacts, so it finds each value by a merge rather than a hash, and a checkpoint stores them
/// in a deterministic order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PairHistory {
    pub pairs: PairSprings,
    pub walls: Vec<WallSpring>,
}

/// A pair contact's key (i < j) and tangential spring.
pub type PairSpring = ((u32, u32), Vec3);

/// A wall contact's key (particle, face) and tangential spring.
pub type WallSpring = ((u32, WallFace), Vec3);

/// The pair contacts' springs, sorted by key, held in consecutive pieces: the contact pass writes
/// one piece per share of particles, in parallel, and the pieces are never joined (a join would
/// copy every spring on one thread each step). Read as one sequence.
#[derive(Debug, Clone, Default)]
pub struct PairSprings {
    pieces: Vec<Vec<PairSpring>>,
}

impl PairSprings {
    /// Pieces each sorted by key, every key of a piece below those of the pieces after it.
    pub fn from_pieces(pieces: Vec<Vec<PairSpring>>) -> Self {
        debug_assert!(
            pieces.iter().flatten().zip(pieces.iter().flatten().skip(1)).all(|(a, b)| a.0 < b.0),
            "springs sorted by key"
        );
        Self { pieces }
    }

    pub fn pieces(&self) -> &[Vec<PairSpring>] {
        &self.pieces
    }

    pub fn into_pieces(self) -> Vec<Vec<PairSpring>> {
        self.pieces
    }

    pub fn iter(&self) -> impl Iterator<Item = &PairSpring> + Clone + '_ {
        self.pieces.iter().flatten()
    }

    pub fn len(&self) -> usize {
        self.pieces.iter().map(Vec::len).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.pieces.iter().all(Vec::is_empty)
    }
}

/// Springs in any order, sorted by key.
impl From<Vec<PairSpring>> for PairSprings {
    fn from(mut springs: Vec<PairSpring>) -> Self {
        springs.sort_unstable_by_key(|(key, _)| *key);
        Self { pieces: vec![springs] }
    }
}

/// The same springs in the same order, however they are split into pieces.
impl PartialEq for PairSprings {
    fn eq(&self, other: &Self) -> bool {
        self.iter().eq(other.iter())
    }
}

impl<'a> IntoIterator for &'a PairSprings {
    type Item = &'a PairSpring;
    type IntoIter = std::iter::Flatten<std::slice::Iter<'a, Vec<PairSpring>>>;
    fn into_iter(self) -> Self::IntoIter {
        self.pieces.iter().flatten()
    }
}

/// What the last force evaluation saw that the stability monitor needs.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactDiagnostics {
    /// Largest overlap δ divided by the smaller diameter of the pair (or the particle's for a wall).
    pub max_overlap_ratio: f64,
    /// The particles of that contact (`j = None` for a wall).
    pub max_overlap_pair: (u32, Option<u32>),
}

/// What the force evaluations compute from the particles, per particle: read by the
/// integrators, written only through [`crate::core::forces::Forces`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Fields {
    /// Force and torque at the current state (the integrators keep this invariant). With
    /// multiple time stepping these hold the fast part and `slow_*` the slow (magnetic) part.
    pub force: Vec<Vec3>,
    pub torque: Vec<Vec3>,
    pub slow_force: Vec<Vec3>,
    pub slow_torque: Vec<Vec3>,
    /// Total magnetic moment m_i (A·m²): induced plus permanent (the paper's induction starts
    /// each evaluation from the previous one's).
    pub moment: Vec<Vec3>,
}

impl Fields {
    /// Zero fields for `n` particles, unless they already have that length.
    pub fn fit(&mut self, n: usize) {
        for v in [&mut self.force, &mut self.torque, &mut self.slow_force, &mut self.slow_torque, &mut self.moment] {
            if v.len() != n {
                v.resize(n, Vec3::zeros());
            }
        }
    }
}

/// Where a particle went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Way {
    /// Through outlet k of `ExitRules::outlets` ([`crate::core::exits`]).
    Outlet(u16),
    /// Held by the vessel's wall.
    Captured,
}

/// One particle's exit: its id, the step and time after which it left, and its centre then.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exit {
    pub id: u32,
    pub step: u64,
    pub time: f64,
    pub position: Vec3,
    pub way: Way,
}

/// What the rules carry between steps: since when each particle touching the vessel's wall has
/// touched it, by id (sorted).
pub type Touching = Vec<(u32, f64)>;

/// Full simulation state: particles, what the forces computed from them, contact history, clock.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct State {
    pub particles: Particles,
    pub fields: Fields,
    pub history: PairHistory,
    pub diagnostics: ContactDiagnostics,
    /// Number of steps taken since t = 0.
    pub step: u64,
    /// Simulated time (s); `step × dt` between steps.
    pub time: f64,
    /// The substep an adaptive integrator proposes to try next (its controller's memory, kept
    /// here so that a checkpoint carries it and a resumed run repeats the uninterrupted one).
    pub next_substep: Option<f64>,
    /// `ids[k]`: the id of the particle in slot k, its index in the scene's particles (and in the
    /// trajectory's frames, which are written in id order); 0, 1, … until a renumbering.
    pub ids: Vec<u32>,
    /// The particles that left the run so far, in order ([`crate::core::exits`]).
    pub exits: Vec<Exit>,
    /// Since when each particle touching the vessel's wall has touched it, by id.
    pub touching: Touching,
}

/// The per-particle vectors of a state by name (see [`State::vectors`]); one body for the shared
/// and the mutable listing (match ergonomics give `&` or `&mut` bindings).
macro_rules! state_vectors {
    ($state:expr, $position:ident => $access:expr) => {{
        // `ids` are stored as the checkpoint's `id` (and index the fixed properties).
        // `exits` and `touching` are stored with the trajectory's exits.
        let State {
            particles,
            fields,
            history: _,
            diagnostics: _,
            step: _,
            time: _,
            next_substep: _,
            ids: _,
            exits: _,
            touching: _,
        } = $state;
        let Particles {
            position: $position,
            velocity,
            angular_velocity,
            permanent_moment,
            // Stored as fixed properties, or rebuilt from them (`set_masses`, the moments' norm).
            species: _,
            radius: _,
            mass: _,
            inertia: _,
            inverse_masses: _,
            sizes: _,
            has_permanent_moments: _,
        } = particles;
        let Fields { force, torque, slow_force, slow_torque, moment } = fields;
        [
            ("position", $access),
            ("velocity", velocity),
            ("angular_velocity", angular_velocity),
            ("force", force),
            ("torque", torque),
            ("slow_force", slow_force),
            ("slow_torque", slow_torque),
            ("moment", moment),
            ("permanent_moment", permanent_moment),
        ]
    }};
}

impl State {
    /// Every per-particle vector a run needs to continue bit for bit, by name: what a checkpoint
    /// stores besides the fixed properties (species, radius, mass, from which inertia and the
    /// inverse masses are rebuilt), the contact history and the clock. Every field of the state
    /// is named in the destructuring (none is skipped with `..`), so a field added to
    /// [`Particles`], [`Fields`] or [`State`] does not compile until it is listed here or said
    /// to be stored or rebuilt elsewhere.
    pub fn vectors(&self) -> [(&'static str, &Vec<Vec3>); 9] {
        state_vectors!(self, position => position.as_vec())
    }

    /// [`State::vectors`], writable (a checkpoint restore).
    pub fn vectors_mut(&mut self) -> [(&'static str, &mut Vec<Vec3>); 9] {
        state_vectors!(self, position => position.write())
    }

    /// The names of [`State::vectors`], in order.
    pub fn vector_names() -> [&'static str; 9] {
        State::default().vectors().map(|(name, _)| name)
    }

    /// `particles` at rest at t = 0, with zero fields (forces not yet evaluated).
    pub fn new(particles: Particles) -> Self {
        let mut fields = Fields::default();
        fields.fit(particles.len());
        let ids = (0..particles.len() as u32).collect();
        State { particles, fields, ids, ..State::default() }
    }

    /// The id of the particle in slot `k` (what messages name).
    pub fn id(&self, k: usize) -> usize {
        self.ids.get(k).map_or(k, |&id| id as usize)
    }

    /// `v` (one value per slot) in id order: what an output writes.
    pub fn in_id_order<T: Copy + Default>(&self, v: &[T]) -> Vec<T> {
        let mut out = vec![T::default(); v.len()];
        for (&id, x) in self.ids.iter().zip(v) {
            out[id as usize] = *x;
        }
        out
    }

    /// Moves every particle to its slot under `r`: the per-particle arrays, fixed properties,
    /// fields and ids are permuted and the contact history renamed. Every field is named (none
    /// skipped with `..`), so a field added to [`State`], [`Particles`] or [`Fields`] does not
    /// compile until it says what a renumbering does to it.
    pub fn renumber(&mut self, r: &Renumbering) {
        // The exits and the wall-contact times are kept by id.
        let State {
            particles,
            fields,
            history,
            diagnostics,
            step: _,
            time: _,
            next_substep: _,
            ids,
            exits: _,
            touching: _,
        } = self;
        let Particles {
            species,
            radius,
            mass,
            inertia,
            inverse_masses,
            sizes: _,
            position,
            velocity,
            angular_velocity,
            permanent_moment,
            has_permanent_moments: _,
        } = particles;
        r.permute(species);
        r.permute(ids);
        for v in [radius, mass, inertia] {
            r.permute(v);
        }
        if let InverseMasses::PerParticle { mass, inertia } = inverse_masses {
            r.permute(mass);
            r.permute(inertia);
        }
        let Fields { force, torque, slow_force, slow_torque, moment } = fields;
        for v in [
            position.write(),
            velocity,
            angular_velocity,
            permanent_moment,
            force,
            torque,
            slow_force,
            slow_torque,
            moment,
        ] {
            r.permute(v);
        }
        history.renumber(r);
        // The diagnostics name the pair of the last evaluation (none if it left).
        if !r.is_empty() {
            let (i, j) = diagnostics.max_overlap_pair;
            let (i, j) = (r.to(i), j.map(|j| r.to(j)));
            *diagnostics = match i == GONE || j == Some(GONE) {
                true => ContactDiagnostics::default(),
                false => ContactDiagnostics { max_overlap_pair: (i, j), ..*diagnostics },
            };
        }
    }
}

impl PairHistory {
    /// The history with old slot i renamed `r.to(i)`, sorted again. A pair whose ends swap
    /// stores the spring of j against i: the relative tangential displacement, negated.
    /// The springs of a particle removed are dropped.
    pub fn renumber(&mut self, r: &Renumbering) {
        let renamed = |&(key, spring): &PairSpring| {
            let (key, swapped) = r.pair(key);
            (key.1 != GONE).then_some((key, if swapped { -spring } else { spring }))
        };
        self.pairs = self.pairs.iter().filter_map(renamed).collect::<Vec<_>>().into();
        for ((i, _), _) in &mut self.walls {
            *i = r.to(*i);
        }
        self.walls.retain(|((i, _), _)| *i != GONE);
        self.walls.sort_unstable_by_key(|(key, _)| *key);
    }
}

/// A non-magnetic test sphere of `radius` (ρ = 5000 kg/m³, E = 1 GPa, ν = 0.3, μ = e = 0.5).
#[cfg(test)]
pub(crate) fn test_sphere(radius: f64) -> Species {
    Species {
        name: "s".into(),
        radius,
        density: 5000.0,
        youngs_modulus: 1e9,
        poisson_ratio: 0.3,
        friction: 0.5,
        restitution: 0.5,
        susceptibility: 0.0,
        saturation: None,
        permanent_moment: None,
        size: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A motion bounds the drifts since an earlier one of the same set of positions, never below
    /// their sum (many small bounds on a large one are not rounded away); a write, a bound that is
    /// not a number ≥ 0, or another set (a clone) gives no bound.
    #[test]
    fn a_motion_bounds_the_drifts_of_its_own_positions_only() {
        let mut x = Positions::from(vec![Vec3::zeros(); 3]);
        let start = x.motion();
        x.drift(|_| 1e6);
        let after_large = x.motion();
        for _ in 0..1000 {
            x.drift(|x| {
                x[1].y += 1e-12;
                1e-12
            });
        }
        let since = x.motion().since(after_large).expect("drifts only");
        assert!(since >= 1000.0 * 1e-12, "{since}");
        assert!(x.motion().since(start).unwrap() >= 1e6 + 1e-9);
        assert_eq!(x.clone().motion().since(start), None, "a clone is another set");
        let before = x.motion();
        x.drift(|_| 0.0);
        assert_eq!(x.motion().since(before), Some(0.0), "a drift bounded by 0 moved nothing");
        for bad in [f64::NAN, f64::INFINITY, -1.0] {
            let before = x.motion();
            x.drift(|_| bad);
            assert_eq!(x.motion().since(before), None, "a bound of {bad}");
        }
        let before = x.motion();
        x.write()[0].x = 1.0;
        assert_eq!(x.motion().since(before), None, "a write");
        assert_eq!(x[0].x, 1.0);
    }

    /// A renumbering followed by its inverse gives the state back bit for bit; in between, each
    /// particle's values moved with it, the springs of swapped pairs are negated and the history
    /// stays sorted.
    #[test]
    fn a_renumbering_moves_every_value_with_its_particle_and_its_inverse_undoes_it() {
        let (small, large) = (test_sphere(1e-6), test_sphere(2e-6));
        let mut p = Particles::default();
        for k in 0..5 {
            let x = Vec3::new(k as f64, 0.0, 0.0);
            p.push(k as u16 % 2, if k % 2 == 0 { &small } else { &large }, x, Vec3::new(0.0, k as f64, 0.0));
        }
        let mut state = State::new(p);
        state.fields.moment.iter_mut().enumerate().for_each(|(k, m)| m.z = k as f64);
        let spring = Vec3::new(1.0, 2.0, 3.0);
        state.history.pairs = vec![((0, 3), spring), ((1, 2), -spring)].into();
        state.history.walls = vec![((4, 0), spring)];
        let original = state.clone();
        let r = Renumbering::new(vec![3, 4, 0, 2, 1]);
        state.renumber(&r);
        assert_eq!(state.ids, [3, 4, 0, 2, 1]);
        for (k, &id) in state.ids.iter().enumerate() {
            let i = id as usize;
            assert_eq!(state.particles.position[k], original.particles.position[i]);
            assert_eq!(state.particles.radius[k], original.particles.radius[i]);
            assert_eq!(state.fields.moment[k], original.fields.moment[i]);
        }
        // (0, 3) → (2, 0) and (1, 2) → (4, 3): both swapped, so stored as (0, 2) and (3, 4) with
        // their springs negated.
        assert_eq!(state.history.pairs.iter().copied().collect::<Vec<_>>(), [((0, 2), -spring), ((3, 4), spring)]);
        assert_eq!(state.history.walls, [((1, 0), spring)]);
        assert_eq!(state.in_id_order(&state.particles.position), *original.particles.position);
        let inverse = Renumbering::new((0..5).map(|i| r.to(i)).collect());
        state.renumber(&inverse);
        assert_eq!(state, original);
    }

    /// Alike particles share one 1/m, 1/I; the first unlike one spreads the shared pair over
    /// the particles before it; a checkpoint's masses rebuild the same inverses.
    #[test]
    fn inverse_masses_stay_shared_only_while_particles_are_alike() {
        let (small, large) = (test_sphere(1e-6), test_sphere(2e-6));
        let mut p = Particles::default();
        p.push(0, &small, Vec3::zeros(), Vec3::zeros());
        p.push(0, &small, Vec3::zeros(), Vec3::zeros());
        assert_eq!(
            p.inverse_masses,
            InverseMasses::Uniform {
                mass: 1.0 / small.mass(),
                inertia: 1.0 / sphere_inertia(small.mass(), small.radius)
            }
        );
        p.push(1, &large, Vec3::zeros(), Vec3::zeros());
        let InverseMasses::PerParticle { mass, inertia } = &p.inverse_masses else { panic!("{:?}", p.inverse_masses) };
        assert_eq!(mass, &[1.0 / small.mass(), 1.0 / small.mass(), 1.0 / large.mass()]);
        let (i_small, i_large) =
            (sphere_inertia(small.mass(), small.radius), sphere_inertia(large.mass(), large.radius));
        assert_eq!(inertia, &[1.0 / i_small, 1.0 / i_small, 1.0 / i_large]);
        let mut restored = Particles { radius: p.radius.clone(), ..Particles::default() };
        restored.set_masses(p.mass.clone());
        assert_eq!(restored.inverse_masses, p.inverse_masses);
        assert_eq!((p.sizes, restored.sizes), (Sizes::Several, Sizes::Several));
        let mut alike = Particles::default();
        assert_eq!(alike.sizes, Sizes::NoParticles);
        alike.push(0, &small, Vec3::zeros(), Vec3::zeros());
        alike.push(0, &small, Vec3::zeros(), Vec3::zeros());
        assert_eq!(alike.sizes, Sizes::One { radius: small.radius, mass: small.mass() });
        let mut restored = Particles { radius: alike.radius.clone(), ..Particles::default() };
        restored.set_masses(alike.mass.clone());
        assert_eq!(restored.sizes, alike.sizes);
    }
}

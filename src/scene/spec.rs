//! The scene file format (TOML, SI units throughout). Every table denies unknown keys, so a
//! misspelt key or an unknown force term is an error, never silently ignored.

use crate::core::integrators::Scheme;
use serde::Deserialize;

pub use super::exits::{ExitsSpec, OutletSpec};
pub use super::field::{CoilSpec, FieldSpec, WaveformSpec};
pub use super::fluid::{FluidSpec, VesselSpec};
pub use crate::core::forces::contact::{ContactSpec, NormalSpec, TangentialSpec};
pub use crate::core::forces::dipole::{DipoleSpec, InductionSpec};
pub use crate::core::forces::drag::{DragLawSpec, DragSpec, ShieldingSpec};
pub use crate::core::forces::gradient::GradientSpec;
pub use crate::core::forces::gravity::GravitySpec;
pub use crate::core::forces::wall_drag::{FaceSpec, WallDragSpec};
pub use crate::core::forces::ForcesSpec;

fn default_true() -> bool {
    true
}

/// Top level of a scene file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Scene format version; this magdem reads 1.
    pub version: u32,
    pub name: Option<String>,
    pub description: Option<String>,
    /// Seed of random particle placement (default 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    pub domain: DomainSpec,
    pub fluid: Option<FluidSpec>,
    pub field: Option<FieldSpec>,
    pub species: Vec<SpeciesSpec>,
    /// Placed particles; absent when the scene starts from a trajectory (`[start]`).
    #[serde(default)]
    pub particles: Vec<ParticleGroupSpec>,
    /// Start from the state a trajectory ends with, instead of placing `[[particles]]`.
    pub start: Option<StartSpec>,
    #[serde(default)]
    pub forces: ForcesSpec,
    pub integration: IntegrationSpec,
    #[serde(default)]
    pub output: OutputSpec,
    #[serde(default)]
    pub stability: StabilitySpec,
    /// How particles leave the run: outlets and capture (none by default).
    pub exits: Option<ExitsSpec>,
}

/// `[start]`: the particles, their velocities and spins, and the contact history (tangential
/// springs of touching pairs and wall contacts) of the state a magdem trajectory ends with (its
/// checkpoint: the last frame written). The run's clock starts again at t = 0, step 0. Each
/// particle keeps its radius and takes its species (matched by name) from this scene: its mass,
/// inertia and moment follow this scene's density and magnetic properties. Wall springs are kept
/// only where this scene's box equals the trajectory's. The first forces are evaluated anew, with
/// the stored (full-step) velocities and springs not advanced, so the started run is a new run
/// from that state, not a continuation to the bit (that is `magdem run --resume`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// The trajectory (HDF5), relative to this scene file.
    pub trajectory: std::path::PathBuf,
    /// How the started particles are numbered: as the trajectory numbers them (`placement`, the
    /// default) or along a Morton curve through cells of the smallest diameter (`spatial`), the
    /// contact history renamed with them.
    #[serde(default)]
    pub order: ParticleOrder,
}

fn default_seed() -> u64 {
    1
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Boundary {
    Wall,
    Periodic,
}

/// `[domain]`: an axis-aligned box (m).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    /// Per axis `"wall"` (default) or `"periodic"`.
    #[serde(default)]
    pub boundary: BoundarySpec,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    pub x: Boundary,
    pub y: Boundary,
    pub z: Boundary,
}

impl Default for BoundarySpec {
    fn default() -> Self {
        Self { x: Boundary::Wall, y: Boundary::Wall, z: Boundary::Wall }
    }
}

impl BoundarySpec {
    /// The boundary of axis 0, 1 or 2.
    pub fn axis(&self, k: usize) -> Boundary {
        [self.x, self.y, self.z][k]
    }
}

/// `[[species]]`: one kind of particle.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeciesSpec {
    pub name: String,
    /// m
    pub diameter: f64,
    /// kg/m³
    pub density: f64,
    /// Pa
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub friction: f64,
    /// Normal coefficient of restitution, 0 < e ≤ 1.
    pub restitution: f64,
    /// Relative permeability μr of the material (χ_eff = 3(μr − 1)/(μr + 2)).
    pub relative_permeability: Option<f64>,
    /// Or the material susceptibility χ = μr − 1.
    pub susceptibility: Option<f64>,
    /// Saturation magnetisation Ms (A/m).
    pub saturation_magnetisation: Option<f64>,
    /// How the induced magnetisation reaches Ms: `cap` (default, |M| = min(χ_eff H, Ms)),
    /// `frohlich-kennelly` (M = χ_eff H · Ms / (Ms + χ_eff H)) or `langevin` (a superparamagnetic
    /// core: m = m_c L(μ0 m_c H/kT), m_c = Ms π d_c³/6, with `core_diameter` and `temperature`,
    /// and no permeability or susceptibility). Needs `saturation_magnetisation`.
    pub saturation_law: Option<SaturationLawSpec>,
    /// The magnetic core's diameter d_c (m), `langevin` only (default `diameter`): one
    /// single-domain core whose Néel relaxation is fast, inside the particle.
    pub core_diameter: Option<f64>,
    /// The cores' temperature T (K), `langevin` only; equal to `[forces.thermal]`'s if listed.
    pub temperature: Option<f64>,
    /// Permanent moment (A·m²), turning with the particle.
    pub permanent_moment: Option<[f64; 3]>,
    /// Diameters drawn per particle (polydisperse); `diameter` is then their mean.
    pub size: Option<SizeSpec>,
}

/// `size = { law = "normal", cv = 0.1 }`: each randomly placed particle's diameter is drawn from
/// the scene seed, from `law` with mean `diameter` and standard deviation `cv` × `diameter` (or
/// `std`), drawn again while outside [`min_diameter`, `max_diameter`] (default `diameter` ×
/// (1 ∓ 3 cv), the lower at least a tenth of `diameter`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SizeSpec {
    /// `normal` | `log-normal` (of the diameter, with its mean and standard deviation).
    pub law: SizeLawSpec,
    /// Coefficient of variation: the standard deviation over the mean.
    pub cv: Option<f64>,
    /// Or the standard deviation itself (m).
    pub std: Option<f64>,
    /// Truncation (m).
    pub min_diameter: Option<f64>,
    pub max_diameter: Option<f64>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SizeLawSpec {
    Normal,
    LogNormal,
}

/// `species.saturation_law`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SaturationLawSpec {
    Cap,
    FrohlichKennelly,
    Langevin,
}

/// `[[particles]]`: a group of particles of one species, given by exactly one of `positions`,
/// `count`, `concentration` or `lattice`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleGroupSpec {
    pub species: String,
    /// Explicit centres (m).
    pub positions: Option<Vec<[f64; 3]>>,
    /// Initial velocities of explicit particles (m/s), default at rest.
    pub velocities: Option<Vec<[f64; 3]>>,
    /// Initial angular velocities of explicit particles (rad/s), default zero.
    pub angular_velocities: Option<Vec<[f64; 3]>>,
    /// Number of randomly placed particles.
    pub count: Option<usize>,
    /// Mass concentration (mg/ml = kg/m³) of randomly placed particles over the region's volume;
    /// the count is rounded down.
    pub concentration: Option<f64>,
    /// Particles on every site of a lattice that fits in the region (a packed bed).
    pub lattice: Option<LatticeSpec>,
    /// Placement region (default: the whole box).
    pub region: Option<RegionSpec>,
    /// How randomly placed particles are numbered (default: in the order they were placed).
    #[serde(default)]
    pub order: ParticleOrder,
    /// Randomly placed particles inside the `[fluid.vessel]` only (within the region), at a
    /// uniform density or weighted by the flow.
    pub in_vessel: Option<VesselPlacement>,
}

/// `in_vessel`: where in the vessel's cross-section random particles go.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VesselPlacement {
    /// A uniform density over the part of the region inside the vessel.
    Uniform,
    /// A density proportional to the steady flow's speed, 1 − r²/R²: the particles a uniform
    /// concentration carries through a cross-section (a flux-weighted inlet).
    Flux,
}

/// The numbering of randomly placed or started particles. The physics does not depend on it; the
/// speed of large scenes does, since particles near in space are then near in memory.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ParticleOrder {
    /// In the order they were placed (random in space).
    #[default]
    Placement,
    /// Along a Morton (Z-order) curve through cells of one diameter.
    Spatial,
}

/// `lattice = { kind = "fcc", spacing = … }`: a crystal filling the group's region, its cubic axes
/// along x, y, z and a site at the region's low corner (a radius in from a wall). On a walled
/// axis the sites stop a radius short of the wall; a periodic axis must be spanned by the region
/// and hold a whole number of cubic cells.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeSpec {
    pub kind: LatticeKind,
    /// Nearest-neighbour distance between centres (m); default one diameter (touching spheres).
    /// Less than a diameter starts the bed pre-compressed, by at most `stability.max_overlap`.
    pub spacing: Option<f64>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum LatticeKind {
    /// Face-centred cubic: cubic cell √2 × spacing, 4 sites per cell, 12 nearest neighbours.
    Fcc,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

/// `[integration]`: the scheme, with its own keys beside it in the same table (see each
/// scheme's spec in `core::integrators`), and the keys every scheme shares.
#[derive(Debug, Clone)]
pub struct IntegrationSpec {
    /// `integration.scheme` (default `velocity-verlet`) and the scheme's own keys: `slow_every`
    /// of `respa` and `subcycled-euler`, `tolerance` of `adaptive-verlet`.
    pub scheme: Scheme,
    /// Renumber the particles along a Morton curve through their positions every this many
    /// steps (0, the default: never), so that particles close in space sit close in memory as
    /// they move (LAMMPS' `atom_modify sort`): faster per-step passes in large scenes. It changes
    /// the order of force sums, so a run is the same to round-off, not to the bit, as one without
    /// it; outputs are in particle id order either way. Under multiple time stepping a multiple
    /// of `slow_every`. magdem's own solver only (the reference engines keep their order).
    pub renumber_every: u64,
    /// s
    pub dt: f64,
    /// s
    pub end_time: f64,
}

impl IntegrationSpec {
    /// K: steps over which the magnetic forces are held (1 unless the scheme steps them apart).
    pub fn slow_every(&self) -> u64 {
        self.scheme.spec().slow_every()
    }
}

/// `scheme = "<name>"` and the scheme's own keys, as lines of an `[integration]` table.
pub fn scheme_lines(scheme: &Scheme) -> String {
    struct Keys<'a>(&'a Scheme);
    impl serde::Serialize for Keys<'_> {
        fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            self.0.keys(s)
        }
    }
    let own = toml::Table::try_from(Keys(scheme)).expect("a scheme's keys are plain numbers");
    let mut lines = format!("scheme = \"{scheme}\"\n");
    for (key, value) in own {
        lines += &format!("{key} = {value}\n");
    }
    lines
}

/// The `[integration]` keys every scheme shares.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Shared {
    #[serde(default)]
    renumber_every: u64,
    dt: f64,
    end_time: f64,
}

/// A scheme's keys that did not read, by key: a key the scheme does not take names the schemes
/// that take it.
fn scheme_error(name: &str, own: &toml::Table, message: &str) -> String {
    let read = |scheme: &str, key: &String, value: &toml::Value| {
        let keys = toml::Value::Table([(key.clone(), value.clone())].into_iter().collect());
        Scheme::deserialize_named(scheme, keys).err().map(|e| e.message().to_string())
    };
    let unknown = |why: &str| why.starts_with("unknown field");
    let Some((key, value, why)) = own.iter().find_map(|(k, v)| read(name, k, v).map(|why| (k, v, why))) else {
        return format!("scheme \"{name}\": {message}");
    };
    if !unknown(&why) {
        return format!("{key} = {value}: {why}");
    }
    let takes = |other: &str| !read(other, key, value).is_some_and(|why| unknown(&why));
    let takers: Vec<&str> = Scheme::NAMES.iter().copied().filter(|&other| takes(other)).collect();
    let takers = if takers.is_empty() { "none".to_string() } else { takers.join(", ") };
    format!("{key} = {value} is not a key of scheme \"{name}\" (schemes that take {key}: {takers})")
}

const SHARED: [&str; 3] = ["renumber_every", "dt", "end_time"];

/// The table read as the shared keys, `scheme`, and the named scheme's own keys from the rest.
impl<'de> Deserialize<'de> for IntegrationSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut own = toml::Table::deserialize(d)?;
        let names = Scheme::NAMES.join(", ");
        let name = match own.remove("scheme") {
            None => Scheme::default().name().to_string(),
            Some(toml::Value::String(name)) => name,
            Some(other) => return Err(D::Error::custom(format!("scheme = {other}: expected one of {names}"))),
        };
        let shared: toml::Table = SHARED.iter().filter_map(|&k| own.remove(k).map(|v| (k.to_string(), v))).collect();
        let Shared { renumber_every, dt, end_time } =
            Shared::deserialize(toml::Value::Table(shared)).map_err(|e| D::Error::custom(e.message()))?;
        let scheme = |keys: toml::Table| Scheme::deserialize_named(&name, toml::Value::Table(keys));
        let scheme = match scheme(own.clone()) {
            Ok(Some(scheme)) => scheme,
            Ok(None) => {
                return Err(D::Error::custom(format!("scheme = \"{name}\": unknown scheme, expected one of {names}")))
            }
            Err(e) => return Err(D::Error::custom(scheme_error(&name, &own, e.message()))),
        };
        Ok(Self { scheme, renumber_every, dt, end_time })
    }
}

/// `[output]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Simulated time between frames (s); default: 100 frames over the run.
    pub interval: Option<f64>,
    /// Also store per-particle force and torque (default false).
    #[serde(default)]
    pub forces: bool,
    /// Also store the contact list of each frame (default true).
    #[serde(default = "default_true")]
    pub contacts: bool,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { interval: None, forces: false, contacts: true }
    }
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum OnUnstable {
    Warn,
    Refuse,
}

/// `[stability]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StabilitySpec {
    /// What to do when dt exceeds the estimated stable step: `warn` (default) | `refuse`.
    #[serde(default = "default_on_unstable")]
    pub on_unstable_dt: OnUnstable,
    /// Stop when an overlap exceeds this fraction of the smaller diameter (default 0.1).
    #[serde(default = "default_max_overlap")]
    pub max_overlap: f64,
    /// Stop when a particle moves more than this fraction of its radius in one step (default 0.25).
    #[serde(default = "default_max_step_fraction")]
    pub max_step_fraction: f64,
}

fn default_on_unstable() -> OnUnstable {
    OnUnstable::Warn
}
fn default_max_overlap() -> f64 {
    0.1
}
fn default_max_step_fraction() -> f64 {
    0.25
}

impl Default for StabilitySpec {
    fn default() -> Self {
        Self {
            on_unstable_dt: default_on_unstable(),
            max_overlap: default_max_overlap(),
            max_step_fraction: default_max_step_fraction(),
        }
    }
}

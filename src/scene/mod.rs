//! The scene layer: the only code that reads TOML. It parses a scene, checks every value (errors
//! name the key, the value and why), places particles and builds a [`Simulation`].

pub mod exits;
pub mod experiment;
pub mod field;
pub mod fluid;
pub mod placement;
pub mod spec;
mod start;

use crate::core::domain::Domain;
use crate::core::forces::drag::Drag;
use crate::core::forces::magnetisation::{held_bound, impact_speed, isolated_moment, Induction, Magnetisation, MU0};
use crate::core::forces::setup::{self, Invalid, Pairs, SceneContext, StepBound, StepContext, TermSpec};
use crate::core::forces::thermal::BOLTZMANN;
use crate::core::forces::ForceTerm;
use crate::core::integrators;
use crate::core::neighbours::{PairRange, Skins};
use crate::core::simulation::{ForceField, RenumberSchedule, Simulation};
use crate::core::stability::{Monitor, StepEstimate};
use crate::core::state::{
    largest_diameter, PairHistory, Particles, Saturation, SaturationLaw, SizeDistribution, SizeLaw, Species, State,
    Vec3,
};
use rand::{RngExt, SeedableRng};
use sha2::{Digest, Sha256};
pub use spec::*;
use std::f64::consts::PI;
use std::path::Path;

/// A scene that cannot be used. Shown as one line; the CLI exits with code 2.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene {path}: {source}")]
    Read { path: String, source: std::io::Error },
    #[error("{origin}:{line}: {message}")]
    Syntax { origin: String, line: usize, message: String },
    #[error("{key} = {value}: {reason}")]
    Invalid { key: String, value: String, reason: String },
}

impl From<Invalid> for SceneError {
    fn from(Invalid { key, value, reason }: Invalid) -> Self {
        SceneError::Invalid { key, value, reason }
    }
}

fn invalid(key: impl Into<String>, value: impl std::fmt::Display, reason: impl Into<String>) -> SceneError {
    setup::invalid(key, value, reason).into()
}

fn fmt3(v: &[f64; 3]) -> String {
    format!("[{:e}, {:e}, {:e}]", v[0], v[1], v[2])
}

/// A parsed, checked scene with its particles placed.
#[derive(Debug, Clone)]
pub struct Scene {
    pub spec: SceneSpec,
    /// The TOML text as read (stored in every trajectory).
    pub text: String,
    /// SHA-256 of `text` (and of the started state, with `[start]`), hex.
    pub hash: String,
    pub domain: Domain,
    pub species: Vec<Species>,
    pub initial: Particles,
    /// The contact history the run starts with (from `[start]`; else empty).
    pub initial_history: PairHistory,
    pub estimate: StepEstimate,
    /// Non-fatal findings (e.g. a gradient that is not divergence-free, dt above the estimate).
    pub warnings: Vec<String>,
}

impl Scene {
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| SceneError::Read { path: path.display().to_string(), source })?;
        Self::parse_in(&text, &path.display().to_string(), path.parent().unwrap_or(Path::new(".")))
    }

    /// Parses and checks `text`; `origin` names it in messages. A `[start]` trajectory is found
    /// relative to the current directory.
    pub fn parse(text: &str, origin: &str) -> Result<Self, SceneError> {
        Self::parse_in(text, origin, Path::new("."))
    }

    /// The box and the spec of a stored scene, without placing or loading its particles: what
    /// reading a trajectory needs (its frames hold the particles; a `[start]` file need not be
    /// on this machine).
    pub fn layout(text: &str, origin: &str) -> Result<(SceneSpec, Domain), SceneError> {
        let spec: SceneSpec = toml::from_str(text).map_err(|e| syntax_error(text, origin, &e))?;
        let domain = check_domain(&spec.domain)?;
        Ok((spec, domain))
    }

    /// [`Scene::parse`] with a `[start]` trajectory relative to `dir` (the scene file's).
    pub fn parse_in(text: &str, origin: &str, dir: &Path) -> Result<Self, SceneError> {
        // Every float anywhere in the scene must be finite (TOML allows nan and inf), and every
        // vector has three components (serde would drop a fourth silently).
        if let Ok(table) = toml::from_str::<toml::Table>(text) {
            let table = toml::Value::Table(table);
            if let Some((key, value)) = first_non_finite(&table, String::new()) {
                return Err(invalid(key, value, "must be a finite number"));
            }
            check_shapes(&table, "", "")?;
        }
        let spec: SceneSpec = toml::from_str(text).map_err(|e| syntax_error(text, origin, &e))?;
        let mut hasher = Sha256::new();
        hasher.update(text.as_bytes());
        Self::build(spec, text.to_string(), hasher, dir)
    }

    fn build(mut spec: SceneSpec, text: String, mut hasher: Sha256, dir: &Path) -> Result<Self, SceneError> {
        let mut warnings = vec![];
        if spec.version != 1 {
            return Err(invalid("version", spec.version, "this magdem reads scene version 1"));
        }
        let domain = check_domain(&spec.domain)?;
        let end_time = spec.integration.end_time;
        if let Some(f) = &mut spec.fluid {
            fluid::check(f)?;
            hasher.update(fluid::load_grid(f, dir, (domain.lo, domain.hi), end_time)?);
        }
        if let Some(f) = &spec.field {
            field::check(f)?;
        }
        let species =
            spec.species.iter().enumerate().map(|(k, s)| check_species(k, s)).collect::<Result<Vec<_>, _>>()?;
        if species.is_empty() {
            return Err(invalid("species", "[]", "at least one [[species]] is needed"));
        }
        for (k, s) in species.iter().enumerate() {
            if species[..k].iter().any(|o| o.name == s.name) {
                return Err(invalid(format!("species[{k}].name"), &s.name, "the name is used twice"));
            }
        }
        if let Some(thermal) = &spec.forces.thermal {
            for (k, s) in spec.species.iter().enumerate() {
                if let Some(t) = s.temperature.filter(|&t| t != thermal.temperature) {
                    return Err(invalid(
                        format!("species[{k}].temperature"),
                        t,
                        format!("differs from forces.thermal.temperature = {}", thermal.temperature),
                    ));
                }
            }
        }
        check_forces(&spec, &domain, &species, &mut warnings)?;
        if let Some(e) = &spec.exits {
            let vessel = spec.fluid.as_ref().is_some_and(|f| f.vessel.is_some());
            exits::check(e, vessel, spec.forces.contact.as_ref().is_some_and(|c| c.walls))?;
        }
        let (initial, initial_history) = match &spec.start {
            Some(start) => {
                let started = start::load(&spec, start, dir, &domain, &species, &mut warnings)?;
                hasher.update(&started.digest);
                (started.particles, started.history)
            }
            None => (place_particles(&spec, &domain, &species)?, PairHistory::default()),
        };
        if initial.is_empty() {
            return Err(invalid("particles", 0, NO_PARTICLES));
        }
        if let Some(f) = &spec.fluid {
            fluid::check_particles(f, &initial)?;
        }
        exits::check_particles(spec.exits.as_ref(), &initial)?;
        if let Some(f) = &spec.field {
            field::check_particles(f, &initial)?;
        }
        let hash = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
        check_integration(&spec)?;

        let estimate = estimate(&spec, &domain, &species, &initial);
        let dt = spec.integration.dt;
        // The adaptive integrator's dt is only its largest step.
        if dt > estimate.stable_dt && !spec.integration.scheme.spec().dt_is_a_cap() {
            let why = format!("exceeds the estimated stable step: {}", estimate.summary(dt));
            match spec.stability.on_unstable_dt {
                OnUnstable::Refuse => {
                    return Err(invalid(
                        "integration.dt",
                        dt,
                        format!("{why} (set stability.on_unstable_dt = \"warn\" to run anyway)"),
                    ))
                }
                OnUnstable::Warn => warnings.push(format!("integration.dt = {dt:e} {why}")),
            }
        }
        let scene = Self { spec, text, hash, domain, species, initial, initial_history, estimate, warnings };
        let k = scene.spec.integration.slow_every();
        if !scene.steps_per_frame().is_multiple_of(k) || !scene.total_steps().is_multiple_of(k) {
            return Err(invalid(
                "integration.slow_every",
                k,
                format!(
                    "must divide the steps per frame ({}) and the run ({})",
                    scene.steps_per_frame(),
                    scene.total_steps()
                ),
            ));
        }
        Ok(scene)
    }

    pub fn dt(&self) -> f64 {
        self.spec.integration.dt
    }

    /// Total number of steps, end_time / dt rounded to the nearest integer.
    pub fn total_steps(&self) -> u64 {
        (self.spec.integration.end_time / self.dt()).round() as u64
    }

    /// Steps between output frames (≥ 1).
    pub fn steps_per_frame(&self) -> u64 {
        steps_per_frame(&self.spec)
    }

    /// Steps whose multiples a run checkpoints at when interrupted, so that the resumed run is
    /// bitwise equal: the drag's renewal interval (`forces.drag.refactor_every`), else 1.
    pub fn checkpoint_multiple(&self) -> u64 {
        self.spec.forces.drag.as_ref().map_or(1, |d| d.refactor_every)
    }

    /// Runs the scene in memory from t = 0 to its end (no trajectory file): the finished
    /// simulation, or where it went unstable.
    pub fn run_to_end(&self) -> Result<Simulation, crate::core::simulation::RunError> {
        let mut sim = self.simulation(None);
        sim.initialise()?;
        while sim.state.step < self.total_steps() {
            sim.step()?;
        }
        Ok(sim)
    }

    /// The initial state (forces not yet evaluated).
    pub fn initial_state(&self) -> State {
        State { history: self.initial_history.clone(), ..State::new(self.initial.clone()) }
    }

    /// The initial state with the magnetic forces evaluated once (the moments at t = 0 in
    /// `fields.moment`), or `None` without a magnetic term.
    pub fn initial_magnetic_state(&self) -> Option<State> {
        let mut field = self.magnetic_force_field()?;
        let mut state = self.initial_state();
        field.evaluate(&mut state, self.dt());
        Some(state)
    }

    /// The scene's integrator, given each particle's linear and rotational drag coefficients.
    fn integrator(&self) -> Box<dyn integrators::Integrator> {
        let drag = self.spec.forces.drag.as_ref();
        let fluid = self.spec.fluid.as_ref();
        let mu = drag.and(fluid).map_or(0.0, |f| f.viscosity);
        let rotational = drag.is_some_and(|d| d.rotational);
        let radius = &self.initial.radius;
        let linear_drag: Vec<f64> = radius.iter().map(|&a| Drag::stokes_coefficient(mu, a)).collect();
        let rotational_drag: Vec<f64> = radius
            .iter()
            .map(|&a| if rotational { 8.0 * std::f64::consts::PI * mu * a.powi(3) } else { 0.0 })
            .collect();
        self.spec.integration.scheme.spec().build(&integrators::IntegratorContext {
            linear_drag: &linear_drag,
            rotational_drag: &rotational_drag,
            // A flow that is not uniform is refused with this scheme (the drag's check).
            fluid_velocity: fluid.map_or(Vec3::zeros(), |f| fluid::flow(f).uniform().unwrap_or_default()),
            viscosity: mu,
            temperature: self.spec.forces.thermal.as_ref().map_or(0.0, |t| t.temperature),
            seed: self.spec.seed,
        })
    }

    /// Only the magnetic forces (the moments and the terms that read them): what magdem supplies
    /// to a reference code in lock step. `None` when the scene has no magnetic term.
    pub fn magnetic_force_field(&self) -> Option<ForceField> {
        let ctx = term_context(&self.spec, &self.domain, &self.species, Skins::default());
        let magnetic: Vec<_> = self.spec.forces.terms().into_iter().filter(|t| t.moments(&ctx).is_some()).collect();
        let terms = build_terms(&magnetic, &ctx);
        (!terms.is_empty()).then(|| ForceField::new(self.domain.clone(), terms))
    }

    /// A simulation at t = 0 (call `initialise` before stepping), or around `state` if given.
    pub fn simulation(&self, state: Option<State>) -> Simulation {
        let spec = &self.spec;
        // One near-pair search for contact and shielding (see `term_context`).
        let range = near_range(spec, &self.species);
        let volume: f64 = self.domain.length().iter().product();
        let skins = Skins::for_density(self.initial.len() as f64 / volume, range);
        let ctx = term_context(spec, &self.domain, &self.species, skins);
        let terms = build_terms(&spec.forces.terms(), &ctx);
        let field = ForceField::new(self.domain.clone(), terms);
        Simulation {
            state: state.unwrap_or_else(|| self.initial_state()),
            field,
            integrator: self.integrator(),
            dt: spec.integration.dt,
            monitor: Monitor {
                max_overlap: spec.stability.max_overlap,
                max_step_fraction: spec.stability.max_step_fraction,
            },
            estimate: self.estimate.clone(),
            balance: Default::default(),
            exits: exits::rules(spec.exits.as_ref()),
            renumber: (spec.integration.renumber_every > 0).then(|| RenumberSchedule {
                every: spec.integration.renumber_every,
                cell: 2.0 * self.initial.radius.iter().copied().fold(f64::INFINITY, f64::min),
            }),
        }
    }
}

/// Steps between output frames of `spec` (≥ 1).
fn steps_per_frame(spec: &SceneSpec) -> u64 {
    let interval = spec.output.interval.unwrap_or(spec.integration.end_time / 100.0);
    ((interval / spec.integration.dt).round() as u64).max(1)
}

/// The near pair range: the largest diameter times 1 + the largest gap a term counts as near
/// (the shielding's touch tolerance), at least 1e-9.
fn near_range(spec: &SceneSpec, species: &[Species]) -> f64 {
    let tolerance = spec.forces.terms().iter().map(|t| t.near_tolerance()).fold(0.0, f64::max);
    largest_diameter(species) * (1.0 + tolerance.max(1e-9))
}

/// What the terms' specs see of the scene, their pair ranges padded by `skins`.
fn term_context<'a>(spec: &'a SceneSpec, domain: &'a Domain, species: &'a [Species], skins: Skins) -> SceneContext<'a> {
    let range = near_range(spec, species);
    SceneContext {
        domain,
        species,
        fluid: spec.fluid.as_ref().map(fluid::fluid),
        field: spec.field.as_ref().map(FieldSpec::applied),
        scheme: spec.integration.scheme,
        steps_per_frame: steps_per_frame(spec),
        pairs: Pairs { near: PairRange::Within { range, skin: skins.near * range }, skins },
        forces: &spec.forces,
        seed: spec.seed,
    }
}

/// The stable-step estimate: each term's bound, with the species at their smallest radius (the
/// strictest for every bound) and the moment of an isolated particle in the largest applied field
/// ([`crate::core::field::AppliedField::largest_field`]: at the box centre for a linear field, the
/// largest over the centre and the corners for coils, the gradient on).
fn estimate(spec: &SceneSpec, domain: &Domain, species: &[Species], initial: &Particles) -> StepEstimate {
    let terms = spec.forces.terms();
    let ctx = term_context(spec, domain, species, Skins::default());
    let induction = induction(&terms, &ctx);
    let b = ctx.field().largest_field(domain.lo, domain.hi);
    let smallest: Vec<Species> = species.iter().map(Species::smallest).collect();
    let moments: Vec<f64> = smallest.iter().map(|s| isolated_moment(induction, b, s)).collect();
    let drag_viscosity = spec.forces.drag.as_ref().and(spec.fluid.as_ref()).map(|f| f.viscosity);
    let max_initial_speed = initial.velocity.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let step = StepContext {
        species: &smallest,
        scheme: spec.integration.scheme,
        impact_speeds: smallest
            .iter()
            .zip(&moments)
            .map(|(s, &m)| {
                // A term's agitation (thermal motion) adds its closing speed to the field's. Without
                // inertia (overdamped dynamics) the noise is a displacement, which the contact's
                // overdamped bound takes itself.
                let agitation = if spec.integration.scheme.spec().overdamped() {
                    0.0
                } else {
                    terms.iter().map(|t| t.agitation_speed(s)).fold(0.0, f64::max)
                };
                impact_speed(s, m, drag_viscosity, max_initial_speed) + agitation
            })
            .collect(),
        moments,
        drag_viscosity,
        temperature: spec.forces.thermal.as_ref().map(|t| t.temperature),
        max_initial_speed,
    };
    // The moments' bound (held over several steps), then each term's.
    let bounds: Vec<StepBound> =
        held_bound(&step).into_iter().chain(terms.iter().filter_map(|t| t.stable_dt(&step))).collect();
    StepEstimate::new(&step, bounds)
}

/// The induction of the moments the terms read: the first asked for other than none, or `None`
/// when no term reads moments.
fn induction(terms: &[&dyn TermSpec], ctx: &SceneContext) -> Option<Induction> {
    terms.iter().filter_map(|t| t.moments(ctx)).reduce(|a, b| if a == Induction::None { b } else { a })
}

/// The force terms in registry order, after the moments term when any of them reads moments.
fn build_terms(terms: &[&dyn TermSpec], ctx: &SceneContext) -> Vec<Box<dyn ForceTerm>> {
    let moments = induction(terms, ctx).map(|induction| {
        Box::new(Magnetisation::new(induction, ctx.field(), ctx.species, ctx.pairs.skins)) as Box<dyn ForceTerm>
    });
    moments.into_iter().chain(terms.iter().map(|t| t.build(ctx))).collect()
}

fn positive(key: &str, v: f64) -> Result<(), SceneError> {
    Ok(setup::positive(key, v)?)
}

fn non_negative(key: &str, v: f64) -> Result<(), SceneError> {
    Ok(setup::non_negative(key, v)?)
}

fn check_domain(d: &DomainSpec) -> Result<Domain, SceneError> {
    for k in 0..3 {
        if d.hi[k].partial_cmp(&d.lo[k]) != Some(std::cmp::Ordering::Greater)
            || !d.lo[k].is_finite()
            || !d.hi[k].is_finite()
        {
            return Err(invalid(
                "domain.hi",
                fmt3(&d.hi),
                format!("must exceed domain.lo = {} on every axis", fmt3(&d.lo)),
            ));
        }
    }
    let b = &d.boundary;
    Ok(Domain {
        lo: Vec3::from(d.lo),
        hi: Vec3::from(d.hi),
        periodic: [b.x == Boundary::Periodic, b.y == Boundary::Periodic, b.z == Boundary::Periodic],
    })
}

fn check_species(k: usize, s: &SpeciesSpec) -> Result<Species, SceneError> {
    let key = |name: &str| format!("species[{k}].{name}");
    positive(&key("diameter"), s.diameter)?;
    positive(&key("density"), s.density)?;
    positive(&key("youngs_modulus"), s.youngs_modulus)?;
    if !(0.0..=0.5).contains(&s.poisson_ratio) {
        return Err(invalid(key("poisson_ratio"), s.poisson_ratio, "must lie in [0, 0.5]"));
    }
    non_negative(&key("friction"), s.friction)?;
    if !(s.restitution > 0.0 && s.restitution <= 1.0) {
        return Err(invalid(key("restitution"), s.restitution, "must lie in (0, 1]"));
    }
    let chi = match (s.relative_permeability, s.susceptibility) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                key("susceptibility"),
                s.susceptibility.unwrap(),
                "give relative_permeability or susceptibility, not both",
            ))
        }
        (Some(mu_r), None) if mu_r >= 1.0 && mu_r.is_finite() => mu_r - 1.0,
        (Some(mu_r), None) => return Err(invalid(key("relative_permeability"), mu_r, "must be ≥ 1 (paramagnetic)")),
        (None, Some(chi)) => {
            non_negative(&key("susceptibility"), chi)?;
            chi
        }
        (None, None) => 0.0,
    };
    if let Some(ms) = s.saturation_magnetisation {
        positive(&key("saturation_magnetisation"), ms)?;
    }
    let law_name = |law| match law {
        SaturationLawSpec::Cap => "cap",
        SaturationLawSpec::FrohlichKennelly => "frohlich-kennelly",
        SaturationLawSpec::Langevin => "langevin",
    };
    if let (Some(law), None) = (s.saturation_law, s.saturation_magnetisation) {
        return Err(invalid(key("saturation_law"), law_name(law), "needs saturation_magnetisation"));
    }
    let law = match s.saturation_law {
        Some(SaturationLawSpec::FrohlichKennelly) => SaturationLaw::FrohlichKennelly,
        Some(SaturationLawSpec::Langevin) => SaturationLaw::Langevin,
        Some(SaturationLawSpec::Cap) | None => SaturationLaw::Cap,
    };
    // A superparamagnetic core: its moment m_c = Ms V_c, its susceptibility μ0 m_c²/(3kT V) and
    // the particle's saturation m_c/V (docs/model.md §4.4).
    let mut saturation = s.saturation_magnetisation.map(|ms| Saturation { ms, law });
    let mut chi_eff = 3.0 * chi / (chi + 3.0);
    match (law, s.core_diameter, s.temperature) {
        (SaturationLaw::Langevin, core, Some(t)) => {
            positive(&key("temperature"), t)?;
            if s.relative_permeability.is_some() || s.susceptibility.is_some() {
                return Err(invalid(
                    key("saturation_law"),
                    "langevin",
                    "the cores' susceptibility follows from their moment and temperature: leave out relative_permeability and susceptibility",
                ));
            }
            let d_c = core.unwrap_or(s.diameter);
            positive(&key("core_diameter"), d_c)?;
            if d_c > s.diameter {
                return Err(invalid(key("core_diameter"), d_c, format!("exceeds the diameter {:e} m", s.diameter)));
            }
            let ms = s.saturation_magnetisation.unwrap_or_default();
            let (volume, core_moment) = ((s.diameter / 2.0).powi(3), ms * (d_c / 2.0).powi(3));
            let (volume, core_moment) = (4.0 / 3.0 * PI * volume, 4.0 / 3.0 * PI * core_moment);
            chi_eff = MU0 * core_moment * core_moment / (3.0 * BOLTZMANN * t * volume);
            saturation = Some(Saturation { ms: core_moment / volume, law });
        }
        (SaturationLaw::Langevin, _, None) => {
            return Err(invalid(key("saturation_law"), "langevin", "needs the cores' temperature (K)"));
        }
        (_, Some(d_c), _) => {
            return Err(invalid(key("core_diameter"), d_c, "applies to saturation_law = \"langevin\""))
        }
        (_, _, Some(t)) => return Err(invalid(key("temperature"), t, "applies to saturation_law = \"langevin\"")),
        (_, None, None) => {}
    }
    let size = s.size.as_ref().map(|size| check_size(&key("size"), s.diameter, size)).transpose()?;
    Ok(Species {
        name: s.name.clone(),
        radius: 0.5 * s.diameter,
        density: s.density,
        youngs_modulus: s.youngs_modulus,
        poisson_ratio: s.poisson_ratio,
        friction: s.friction,
        restitution: s.restitution,
        // Clausius–Mossotti: χ_eff = 3(μr − 1)/(μr + 2) = 3χ/(χ + 3); a Langevin core's above.
        susceptibility: chi_eff,
        saturation,
        permanent_moment: s.permanent_moment.map(Vec3::from),
        size,
    })
}

/// A species' size distribution, in radii, checked (`key` is `species[k].size`).
fn check_size(key: &str, diameter: f64, size: &SizeSpec) -> Result<SizeDistribution, SceneError> {
    let std = match (size.cv, size.std) {
        (Some(cv), None) => {
            positive(&format!("{key}.cv"), cv)?;
            cv * diameter
        }
        (None, Some(std)) => {
            positive(&format!("{key}.std"), std)?;
            std
        }
        (Some(cv), Some(_)) => return Err(invalid(format!("{key}.cv"), cv, "give cv or std, not both")),
        (None, None) => return Err(invalid(key, "{ ... }", "needs cv or std")),
    };
    let min = size.min_diameter.unwrap_or((diameter - 3.0 * std).max(0.1 * diameter));
    let max = size.max_diameter.unwrap_or(diameter + 3.0 * std);
    positive(&format!("{key}.min_diameter"), min)?;
    if !(min < diameter && diameter < max) {
        return Err(invalid(
            format!("{key}.max_diameter"),
            max,
            format!("the truncation [{min:e}, {max:e}] m must hold the mean diameter {diameter:e} m inside it"),
        ));
    }
    let law = match size.law {
        SizeLawSpec::Normal => SizeLaw::Normal,
        SizeLawSpec::LogNormal => SizeLaw::LogNormal,
    };
    Ok(SizeDistribution { law, mean: 0.5 * diameter, std: 0.5 * std, min: 0.5 * min, max: 0.5 * max })
}

/// Checks every force term's keys, and warns of an applied field that is not divergence- or
/// curl-free.
fn check_forces(
    spec: &SceneSpec,
    domain: &Domain,
    species: &[Species],
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let ctx = term_context(spec, domain, species, Skins::default());
    // An overdamped scheme takes the temperature from the thermal term (which checks the drag).
    if spec.integration.scheme.spec().overdamped() && spec.forces.thermal.is_none() {
        return Err(invalid(
            "integration.scheme",
            spec.integration.scheme,
            "overdamped Brownian dynamics takes its temperature from [forces.thermal]: add it",
        ));
    }
    for term in spec.forces.terms() {
        term.check(&ctx)?;
    }
    if let Some(field) = spec.field.as_ref().filter(|f| f.coils.is_empty()) {
        let g: [[f64; 3]; 3] = field.linear_gradient().transpose().into();
        let div = g[0][0] + g[1][1] + g[2][2];
        let scale = g.iter().flatten().fold(0.0_f64, |a, v| a.max(v.abs()));
        if scale > 0.0 && div.abs() > 1e-12 * scale {
            warnings
                .push(format!("field.gradient has divergence {div:e} T/m: the applied field does not satisfy ∇·B = 0"));
        }
        if (0..3).any(|a| (0..3).any(|b| (g[a][b] - g[b][a]).abs() > 1e-12 * scale)) {
            warnings.push("field.gradient is not symmetric: the applied field is not curl-free".into());
        }
    }
    Ok(())
}

/// The most steps a run may take: 2^53, below which every step number is exact in an f64.
pub const MAX_STEPS: u64 = 1 << 53;

fn check_integration(spec: &SceneSpec) -> Result<(), SceneError> {
    let i = &spec.integration;
    i.scheme.spec().check()?;
    positive("integration.dt", i.dt)?;
    positive("integration.end_time", i.end_time)?;
    let k = i.slow_every();
    if !i.renumber_every.is_multiple_of(k) {
        return Err(invalid(
            "integration.renumber_every",
            i.renumber_every,
            format!(
                "must be a multiple of integration.slow_every = {k}: particles are renumbered at the start of an outer step"
            ),
        ));
    }
    // A step's time is `step as f64 * dt`: exact only while the step count fits in 53 bits.
    let steps = (i.end_time / i.dt).round();
    if steps > MAX_STEPS as f64 {
        return Err(invalid(
            "integration.end_time",
            format!("{:e}", i.end_time),
            format!(
                "gives {steps:.3e} steps of integration.dt = {:e}; magdem counts at most 2^53 = {:.3e} steps",
                i.dt, MAX_STEPS as f64
            ),
        ));
    }
    if i.dt > i.end_time {
        return Err(invalid("integration.dt", i.dt, format!("is longer than integration.end_time = {:e}", i.end_time)));
    }
    if let Some(iv) = spec.output.interval {
        positive("output.interval", iv)?;
        if iv < i.dt {
            return Err(invalid("output.interval", iv, format!("is shorter than integration.dt = {:e}", i.dt)));
        }
    }
    let s = &spec.stability;
    if !(s.max_overlap > 0.0 && s.max_overlap < 1.0) {
        return Err(invalid("stability.max_overlap", s.max_overlap, "must lie in (0, 1)"));
    }
    if !(s.max_step_fraction > 0.0 && s.max_step_fraction <= 1.0) {
        return Err(invalid("stability.max_step_fraction", s.max_step_fraction, "must lie in (0, 1]"));
    }
    Ok(())
}

/// How many particles group `g` places at random in its region `lo..hi` (after `existing`
/// others), checked before anything is allocated: 32-bit indices, the random-placement packing
/// limit, and the run's memory against the machine's.
fn random_count(
    spec: &SceneSpec,
    domain: &Domain,
    s: &Species,
    g: usize,
    group: &ParticleGroupSpec,
    (lo, hi): (Vec3, Vec3),
    existing: usize,
) -> Result<usize, SceneError> {
    let key = |name: &str| format!("particles[{g}].{name}");
    let count = match (group.count, group.concentration) {
        (Some(n), _) => n as f64,
        (_, Some(c)) => {
            positive(&key("concentration"), c)?;
            let l = hi - lo;
            (c * l.x * l.y * l.z / s.mass()).floor()
        }
        _ => unreachable!(),
    };
    // A count refused names the key that set it.
    let refuse_count = |why: String| match (group.count, group.concentration) {
        (Some(n), _) => invalid(key("count"), n, why),
        (None, c) => {
            let c = c.unwrap_or_default();
            invalid(
                key("concentration"),
                if (1e-3..1e6).contains(&c.abs()) { c.to_string() } else { format!("{c:e}") },
                why,
            )
        }
    };
    // Checked before anything is allocated: what the region can hold at random (a count beyond
    // 32-bit indices is refused for that instead, below).
    let l = hi - lo;
    let fraction = count * s.volume() / (l.x * l.y * l.z);
    if fraction > MAX_RANDOM_SOLID_FRACTION && count <= u32::MAX as f64 {
        return Err(refuse_count(
            format!(
                "{count} particles fill {fraction:.3e} of their region; random placement holds at most {MAX_RANDOM_SOLID_FRACTION} \
                 (random sequential addition jams near 0.38); give explicit positions or a lattice for denser packings"
            ),
        ));
    }
    checked_count(spec, domain, s, existing, count, refuse_count)
}

/// `count` new particles after `existing` others, checked before anything is allocated: 32-bit
/// indices and the run's memory against the machine's (`refuse` names the key that set it).
fn checked_count(
    spec: &SceneSpec,
    domain: &Domain,
    s: &Species,
    existing: usize,
    count: f64,
    refuse: impl Fn(String) -> SceneError,
) -> Result<usize, SceneError> {
    // Pairs index particles with 32 bits.
    if existing as f64 + count > u32::MAX as f64 {
        return Err(refuse(format!(
            "gives {count:.3e} particles; magdem holds at most {} (32-bit particle indices)",
            u32::MAX
        )));
    }
    let count = count as usize;
    let needed = memory_estimate(spec, domain, existing + count, s.radius);
    if let Some(available) = available_memory().filter(|&a| needed > a) {
        return Err(refuse(format!(
            "{} particles need about {:.2} GB (state, neighbour and dipole lists), more than the {:.2} GB of memory available",
            existing + count,
            needed as f64 / 1e9,
            available as f64 / 1e9
        )));
    }
    Ok(count)
}

/// The largest sphere the group's species can have fits its region between the walls on every
/// walled axis (a thin monolayer box and a spread of diameters can disagree).
fn check_fits_between_walls(
    spec: &SceneSpec,
    domain: &Domain,
    s: &Species,
    group: &ParticleGroupSpec,
    (lo, hi): (Vec3, Vec3),
) -> Result<(), SceneError> {
    let largest = s.largest_radius();
    let (lo_c, hi_c) = placement::centre_range(largest, lo, hi, domain);
    let Some(axis) = (0..3).find(|&k| lo_c[k] > hi_c[k]) else {
        return Ok(());
    };
    let k = spec.species.iter().position(|x| x.name == group.species).unwrap_or_default();
    let (key, what) = match s.size {
        Some(_) => (format!("species[{k}].size"), "its size law draws diameters up to"),
        None => (format!("species[{k}].diameter"), "its diameter is"),
    };
    Err(invalid(
        key,
        format!("{:.3e}", 2.0 * largest),
        format!(
            "{what} {:.3e} m, more than the {:.3e} m between the walls along {} where its particles are placed: such a sphere \
             cannot be placed without overlapping a wall (widen the box or truncate the law with max_diameter)",
            2.0 * largest,
            hi[axis].min(domain.hi[axis]) - lo[axis].max(domain.lo[axis]),
            ["x", "y", "z"][axis]
        ),
    ))
}

/// Group `g`'s particles placed at random in its region `lo..hi`, clear of the `existing`
/// particles of earlier groups, from the scene's seed: their centres and radii (drawn from a
/// second stream of the seed for a polydisperse species).
fn random_sites(
    spec: &SceneSpec,
    domain: &Domain,
    s: &Species,
    g: usize,
    group: &ParticleGroupSpec,
    (lo, hi): (Vec3, Vec3),
    existing: &[(Vec3, f64)],
) -> Result<(Vec<Vec3>, Vec<f64>), SceneError> {
    let key = |name: &str| format!("particles[{g}].{name}");
    check_fits_between_walls(spec, domain, s, group, (lo, hi))?;
    let count = random_count(spec, domain, s, g, group, (lo, hi), existing.len())?;
    let seed = spec.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(g as u64);
    let radii: Vec<f64> = match &s.size {
        None => vec![s.radius; count],
        Some(size) => {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5349_5a45_5349_5a45);
            (0..count).map(|_| size.draw(&mut rng)).collect()
        }
    };
    let vessel = match (group.in_vessel, spec.fluid.as_ref().and_then(|f| f.vessel.as_ref())) {
        (None, _) => None,
        (Some(how), Some(v)) => Some((how, fluid::vessel(v))),
        (Some(how), None) => {
            return Err(invalid(key("in_vessel"), format!("{how:?}").to_lowercase(), "needs a [fluid.vessel]"))
        }
    };
    // Inside the vessel, wholly (r + a ≤ R); flux-weighted by rejection, 1 − r²/R² ≥ a uniform draw.
    let inside = |x: &Vec3, a: f64, rng: &mut rand_chacha::ChaCha8Rng| match &vessel {
        None => true,
        Some((how, v)) => {
            let r = v.radial(*x);
            r + a <= v.radius
                && (*how == VesselPlacement::Uniform || rng.random::<f64>() <= 1.0 - (r / v.radius).powi(2))
        }
    };
    let placed = placement::place_random(&radii, lo, hi, domain, existing, seed, inside).map_err(|k| {
        let l = hi - lo;
        let fraction = count as f64 * s.volume() / (l.x * l.y * l.z);
        invalid(
            key(if group.count.is_some() { "count" } else { "concentration" }),
            group.count.map_or_else(|| group.concentration.unwrap().to_string(), |n| n.to_string()),
            format!(
                "could not place particle {k} of {count} without overlap after {} attempts (solid fraction {fraction:.3})",
                placement::MAX_ATTEMPTS
            ),
        )
    })?;
    Ok((placed, radii))
}

/// The sites of group `g`'s lattice in its region `lo..hi`, checked: the spacing against the
/// overlap the run accepts, periodic axes, the count (before allocating) and the `existing`
/// particles of earlier groups.
fn lattice_sites(
    spec: &SceneSpec,
    domain: &Domain,
    s: &Species,
    g: usize,
    lattice: &LatticeSpec,
    (lo, hi): (Vec3, Vec3),
    existing: &[(Vec3, f64)],
) -> Result<Vec<Vec3>, SceneError> {
    let key = |name: &str| format!("particles[{g}].lattice.{name}");
    let diameter = 2.0 * s.radius;
    let spacing = lattice.spacing.unwrap_or(diameter);
    let least = diameter * (1.0 - spec.stability.max_overlap);
    if spacing.is_nan() || spacing < least {
        return Err(invalid(
            key("spacing"),
            spacing,
            format!(
                "must be at least {least:e} m: neighbours would overlap by more than stability.max_overlap = {} of the diameter",
                spec.stability.max_overlap
            ),
        ));
    }
    let LatticeKind::Fcc = lattice.kind;
    let grid =
        placement::FccGrid::new(spacing, s.radius, lo, hi, domain).map_err(|why| invalid(key("kind"), "fcc", why))?;
    let count = grid.count();
    if count == 0 {
        return Err(invalid(key("spacing"), spacing, "no lattice site fits in the region"));
    }
    checked_count(spec, domain, s, existing.len(), count as f64, |why| invalid(key("spacing"), spacing, why))?;
    let sites = grid.sites();
    if let Some(k) = placement::first_overlap(&sites, s.radius, existing, domain) {
        return Err(invalid(
            key("kind"),
            "fcc",
            format!("site {k} at {} overlaps a particle of an earlier group", fmt3(&sites[k].into())),
        ));
    }
    Ok(sites)
}

/// Group `g`'s explicit positions (with their velocities and spins), checked inside the box and
/// against the particles placed so far.
fn place_explicit(
    spec: &SceneSpec,
    domain: &Domain,
    (si, s): (usize, &Species),
    g: usize,
    group: &ParticleGroupSpec,
    positions: &[[f64; 3]],
    particles: &mut Particles,
) -> Result<(), SceneError> {
    let key = |name: &str| format!("particles[{g}].{name}");
    if group.order != ParticleOrder::Placement {
        return Err(invalid(
            key("order"),
            "spatial",
            "explicit positions keep their given order; order applies to count or concentration",
        ));
    }
    let velocities = group.velocities.clone().unwrap_or_else(|| vec![[0.0; 3]; positions.len()]);
    let spins = group.angular_velocities.clone().unwrap_or_else(|| vec![[0.0; 3]; positions.len()]);
    for (name, len) in [("velocities", velocities.len()), ("angular_velocities", spins.len())] {
        if len != positions.len() {
            return Err(invalid(
                key(name),
                format!("{len} entries"),
                format!("must match the {} positions", positions.len()),
            ));
        }
    }
    for (k, (x, v)) in positions.iter().zip(&velocities).enumerate() {
        let at = Vec3::from(*x);
        check_inside(&key(&format!("positions[{k}]")), x, at, s.radius, domain)?;
        for j in 0..particles.len() {
            let gap = domain.displacement(&at, &particles.position[j]).norm() - s.radius - particles.radius[j];
            // Overlaps the run monitor accepts are allowed (a pre-compressed start).
            let limit = spec.stability.max_overlap * 2.0 * s.radius.min(particles.radius[j]);
            if -gap > limit {
                return Err(invalid(
                    key(&format!("positions[{k}]")),
                    fmt3(x),
                    format!(
                        "overlaps particle {j} by {:e} m, more than stability.max_overlap = {} of the smaller diameter",
                        -gap, spec.stability.max_overlap
                    ),
                ));
            }
        }
        particles.push(si as u16, s, at, Vec3::from(*v));
        *particles.angular_velocity.last_mut().expect("just pushed") = Vec3::from(spins[k]);
    }
    Ok(())
}

/// Why a scene without particles is refused.
const NO_PARTICLES: &str = "the scene places no particles: a run needs at least one";

fn place_particles(spec: &SceneSpec, domain: &Domain, species: &[Species]) -> Result<Particles, SceneError> {
    let mut particles = Particles::default();
    if spec.particles.is_empty() {
        return Err(invalid("particles", "[]", "at least one [[particles]] group is needed"));
    }
    for (g, group) in spec.particles.iter().enumerate() {
        let key = |name: &str| format!("particles[{g}].{name}");
        let Some(si) = species.iter().position(|s| s.name == group.species) else {
            let names: Vec<_> = species.iter().map(|s| s.name.as_str()).collect();
            return Err(invalid(
                key("species"),
                &group.species,
                format!("no such species; defined: {}", names.join(", ")),
            ));
        };
        let s = &species[si];
        if group.count == Some(0) {
            return Err(invalid(key("count"), 0, NO_PARTICLES));
        }
        let given =
            [group.positions.is_some(), group.count.is_some(), group.concentration.is_some(), group.lattice.is_some()];
        if given.iter().filter(|&&b| b).count() != 1 {
            return Err(invalid(
                format!("particles[{g}]"),
                &group.species,
                "give exactly one of positions, count, concentration, lattice",
            ));
        }
        if let Some(positions) = &group.positions {
            if s.size.is_some() {
                return Err(invalid(
                    key("positions"),
                    "[...]",
                    "a species with `size` draws its diameters; explicit positions take the species' one diameter",
                ));
            }
            place_explicit(spec, domain, (si, s), g, group, positions, &mut particles)?;
            continue;
        }
        if group.velocities.is_some() || group.angular_velocities.is_some() {
            return Err(invalid(key("velocities"), "[...]", "only explicit positions take velocities"));
        }
        let (lo, hi) = match &group.region {
            Some(r) => {
                for k in 0..3 {
                    if r.hi[k].partial_cmp(&r.lo[k]) != Some(std::cmp::Ordering::Greater)
                        || r.lo[k] < domain.lo[k]
                        || r.hi[k] > domain.hi[k]
                    {
                        return Err(invalid(
                            key("region"),
                            format!("{} .. {}", fmt3(&r.lo), fmt3(&r.hi)),
                            "must be a non-empty box inside the domain",
                        ));
                    }
                }
                (Vec3::from(r.lo), Vec3::from(r.hi))
            }
            None => (domain.lo, domain.hi),
        };
        let existing: Vec<(Vec3, f64)> =
            (0..particles.len()).map(|j| (particles.position[j], particles.radius[j])).collect();
        let (placed, radii) =
            match &group.lattice {
                Some(_) if s.size.is_some() => return Err(invalid(
                    key("lattice"),
                    &group.species,
                    "a lattice holds spheres of one size; a species with `size` is placed by count or concentration",
                )),
                Some(lattice) => {
                    let sites = lattice_sites(spec, domain, s, g, lattice, (lo, hi), &existing)?;
                    let radii = vec![s.radius; sites.len()];
                    (sites, radii)
                }
                None => random_sites(spec, domain, s, g, group, (lo, hi), &existing)?,
            };
        let order: Vec<usize> = match group.order {
            ParticleOrder::Placement => (0..placed.len()).collect(),
            ParticleOrder::Spatial => crate::core::renumber::morton_order(&placed, 2.0 * s.radius, domain),
        };
        for i in order {
            particles.push_sized(si as u16, s, radii[i], placed[i], Vec3::zeros());
        }
    }
    Ok(particles)
}

/// A TOML or type error, located: the line, and the table and key it is in.
fn syntax_error(text: &str, origin: &str, e: &toml::de::Error) -> SceneError {
    let message = e.message().trim().replace('\n', " ");
    let Some(start) = e.span().map(|s| s.start.min(text.len())) else {
        return SceneError::Syntax { origin: origin.to_string(), line: 0, message };
    };
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_text = text[line_start..].lines().next().unwrap_or("").trim();
    let line = text[..start].matches('\n').count() + 1;
    let (header, key) = if line_text.starts_with('[') {
        (Some(line_text), None)
    } else {
        let header = text[..line_start].lines().rev().map(str::trim).find(|l| l.starts_with('['));
        (header, line_text.split_once('=').map(|(k, _)| k.trim()).filter(|k| !k.is_empty()))
    };
    let message = match (header, key) {
        (Some(h), Some(k)) => format!("in {h}, key {k}: {message}"),
        (Some(h), None) => format!("in {h}: {message}"),
        (None, Some(k)) => format!("key {k}: {message}"),
        (None, None) => message,
    };
    SceneError::Syntax { origin: origin.to_string(), line, message }
}

/// Keys whose values are 3-vectors, lists of 3-vectors, or 3 × 3 matrices.
const VECTOR_KEYS: [&str; 11] =
    ["lo", "hi", "b0", "g", "velocity", "permanent_moment", "gradient_mri", "centre", "axis", "from", "to"];
const VECTOR_LIST_KEYS: [&str; 4] = ["positions", "velocities", "angular_velocities", "gradient"];

/// Refuses a vector of `VECTOR_KEYS` (or an entry of `VECTOR_LIST_KEYS`) that has more or fewer
/// than three components, naming the dotted key.
fn check_shapes(value: &toml::Value, key: &str, name: &str) -> Result<(), SceneError> {
    let three = |key: &str, v: &toml::Value| match v {
        toml::Value::Array(a) if a.len() != 3 => {
            Err(invalid(key, v.to_string(), format!("must have 3 components, not {}", a.len())))
        }
        _ => Ok(()),
    };
    match value {
        toml::Value::Table(table) => {
            for (child, v) in table {
                check_shapes(v, &if key.is_empty() { child.clone() } else { format!("{key}.{child}") }, child)?;
            }
        }
        toml::Value::Array(items) if VECTOR_KEYS.contains(&name) => three(key, value)?,
        toml::Value::Array(items) if VECTOR_LIST_KEYS.contains(&name) => {
            if name == "gradient" {
                three(key, value)?;
            }
            for (k, v) in items.iter().enumerate() {
                three(&format!("{key}[{k}]"), v)?;
            }
        }
        toml::Value::Array(items) => {
            for (k, v) in items.iter().enumerate() {
                check_shapes(v, &format!("{key}[{k}]"), name)?;
            }
        }
        _ => {}
    }
    Ok(())
}

/// The dotted key (`species[0].permanent_moment[1]`) and value of the first NaN or infinite
/// float in `value` (keys of a table in alphabetical order).
fn first_non_finite(value: &toml::Value, key: String) -> Option<(String, f64)> {
    match value {
        toml::Value::Float(f) if !f.is_finite() => Some((key, *f)),
        toml::Value::Array(items) => {
            items.iter().enumerate().find_map(|(k, v)| first_non_finite(v, format!("{key}[{k}]")))
        }
        toml::Value::Table(table) => table.iter().find_map(|(name, v)| {
            first_non_finite(v, if key.is_empty() { name.clone() } else { format!("{key}.{name}") })
        }),
        _ => None,
    }
}

/// Bytes a run of `n` particles of radius `radius` is expected to hold: the particle state
/// (about 30 vectors and scalars per particle with the checkpoint and output buffers, 600 B),
/// the contact list (up to 13 neighbours within the skin, 48 B each), and the dipole and
/// induction neighbourhoods (every pair within the larger cut-off plus the wider of their skins,
/// 88 B each: the pair and its two fields; all pairs without a cut-off are summed directly and
/// stored only by the dense solve of exact induction, (3n)² × 8 B for n ≤ dense_max). An estimate to refuse
/// what cannot fit, not an exact account.
pub fn memory_estimate(spec: &SceneSpec, domain: &Domain, n: usize, radius: f64) -> u64 {
    let n_f = n as f64;
    let mut bytes = n_f * (600.0 + 13.0 * 48.0);
    if let Some(d) = &spec.forces.dipole {
        let diameters = match d.induction {
            InductionSpec::Paper => d.cutoff_diameters.unwrap_or(0.0).max(d.paper_radius_diameters),
            _ => d.cutoff_diameters.unwrap_or(0.0),
        };
        if diameters > 0.0 {
            let skins = Skins::default();
            let range = diameters * 2.0 * radius * (1.0 + skins.induction.max(skins.magnetic));
            let l = domain.length();
            let density = n_f / (l.x * l.y * l.z);
            let neighbours = (density * 4.0 / 3.0 * std::f64::consts::PI * range.powi(3)).min(n_f);
            bytes += n_f * neighbours / 2.0 * 88.0;
        }
        if matches!(d.induction, InductionSpec::Exact) && n <= d.dense_max {
            bytes += (3.0 * n_f).powi(2) * 8.0;
        }
    }
    if spec.forces.drag.as_ref().is_some_and(|d| d.law == DragLawSpec::Rpy) {
        // The dense 3N × 3N mobility and its Cholesky factor.
        bytes += 2.0 * (3.0 * n_f).powi(2) * 8.0;
    }
    bytes.min(u64::MAX as f64) as u64
}

/// MemAvailable of this machine (bytes), where the system says.
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Random sequential addition of equal spheres jams near a solid fraction of 0.38 in 3-D (Feder
/// 1980; Torquato, Uche & Stillinger 2006) and slows sharply well before; placement refuses
/// more than this fraction of a region.
pub const MAX_RANDOM_SOLID_FRACTION: f64 = 0.35;

fn check_inside(key: &str, raw: &[f64; 3], x: Vec3, radius: f64, domain: &Domain) -> Result<(), SceneError> {
    inside(x, radius, 0.0, domain).map_err(|why| invalid(key, fmt3(raw), why))
}

/// Why a sphere of `radius` at `x` does not fit `domain`: its centre outside the box, or a wall
/// overlap beyond `allowed` (m).
fn inside(x: Vec3, radius: f64, allowed: f64, domain: &Domain) -> Result<(), String> {
    for k in 0..3 {
        let axis = ["x", "y", "z"][k];
        if !(x[k] >= domain.lo[k] && x[k] <= domain.hi[k]) {
            return Err(format!("{axis} is outside the box [{:e}, {:e}]", domain.lo[k], domain.hi[k]));
        }
        let overlap = radius - (x[k] - domain.lo[k]).min(domain.hi[k] - x[k]);
        if !domain.periodic[k] && overlap > allowed {
            return Err(format!("the sphere (radius {radius:e} m) overlaps a wall normal to {axis} by {overlap:e} m"));
        }
    }
    Ok(())
}

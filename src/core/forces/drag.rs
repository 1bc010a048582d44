//! Hydrodynamic drag F = −½ ρ_f |u| u C_d A with u = v_i − u_f (paper eqs. 6–7), and the
//! rotational drag M = −8π μ a³ ω (assumption: the paper names M_drag without a formula).
//!
//! C_d = 24/Re (Stokes) or 24/Re (1 + 0.15 Re^0.687) (Schiller–Naumann), Re = ρ_f |u| d / μ.
//! Written as F = −12 μ u A/d · f(Re), which is exact Stokes (6π μ a u) for A = π a².
//! With shielding `paper`, A = A_eff of [`super::shielding`]. With a wall, the components of u
//! parallel to it are multiplied by the parallel-wall factor of [`super::wall_drag`].
//! Each particle's coefficient c_i = 12 μ A_i/d_i · f(Re_i) may be renewed every K steps
//! ([`Drag::renewed_every`]) and applied in between to each evaluation's velocity, F_i = −c_i u_i (as the RPY drag
//! holds its factor, [`super::hydrodynamics`]).

use super::hydrodynamics::RpyDrag;
pub use super::setup::Fluid;
use super::setup::{invalid, non_negative, positive, Invalid, SceneContext, StepBound, StepContext, TermSpec};
use super::shielding::shadow_area;
use super::wall_drag::{WallCorrection, WallDragSpec};
use super::{ConstantForce, Context, ForceTerm, Forces, Renewal, Renumbering};
use crate::core::flow::Flow;
use crate::core::neighbours::PairRange;
use crate::core::parallel;
use crate::core::state::{Particles, State, Vec3};
use std::f64::consts::PI;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DragLaw {
    Stokes,
    SchillerNaumann,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shielding {
    None,
    /// The paper's A_eff from the touching upstream neighbour: pairs count as touching when their
    /// gap is below `touch_tolerance` times the smaller radius, found among the `near` pairs
    /// (contact range times 1 + touch tolerance, the contact term's range).
    Paper {
        touch_tolerance: f64,
        near: PairRange,
    },
}

/// u_f at each particle in one evaluation: the uniform velocity, or a varying flow's samples.
#[derive(Clone, Copy)]
enum FluidAt<'a> {
    Uniform(Vec3),
    Sampled(&'a [Vec3]),
}

impl<'a> FluidAt<'a> {
    fn of(flow: &Flow, samples: &'a [Vec3]) -> Self {
        match flow {
            Flow::Uniform(u) => FluidAt::Uniform(*u),
            Flow::Vessel(_) | Flow::Grid(_) => FluidAt::Sampled(samples),
        }
    }

    #[inline(always)]
    fn at(self, i: usize) -> Vec3 {
        match self {
            FluidAt::Uniform(u) => u,
            FluidAt::Sampled(samples) => samples[i],
        }
    }
}

#[derive(Debug, Clone)]
pub struct Drag {
    pub law: DragLaw,
    pub shielding: Shielding,
    pub rotational: bool,
    pub fluid: Fluid,
    /// Leave out the linear Stokes parts −6π μ a (v − u_f) and −8π μ a³ ω, which an exponential
    /// integrator applies exactly; only the shielding and Schiller–Naumann corrections remain.
    pub exclude_linear: bool,
    /// Drag near a plane wall (parallel components), or none.
    pub wall: Option<WallCorrection>,
    /// When the coefficients c_i (shielded area and Schiller–Naumann factor) are renewed; every
    /// evaluation unless [`Drag::renewed_every`] says otherwise.
    renewal: Renewal,
    coefficient: Vec<f64>,
    shadow: Vec<f64>,
    flow_direction: Vec<Vec3>,
    /// u_f(x_i, t) of a flow that is not uniform, at the evaluation's positions and time.
    local_flow: Vec<Vec3>,
}

impl Drag {
    pub fn new(law: DragLaw, shielding: Shielding, rotational: bool, fluid: Fluid) -> Self {
        Self {
            law,
            shielding,
            rotational,
            fluid,
            exclude_linear: false,
            wall: None,
            renewal: Renewal::every(1),
            coefficient: vec![],
            shadow: vec![],
            flow_direction: vec![],
            local_flow: vec![],
        }
    }

    /// Samples a flow that varies in space or time at every particle, at the evaluation's time.
    fn sample_flow(&mut self, ctx: &Context, p: &Particles) {
        if self.fluid.flow.uniform().is_none() {
            let flow = &self.fluid.flow;
            self.local_flow.resize(p.len(), Vec3::zeros());
            parallel::for_each_share((&mut self.local_flow[..], &p.position[..]), |_, (u, x)| {
                u.iter_mut().zip(x).for_each(|(u, x)| *u = flow.velocity(*x, ctx.time));
            });
        }
    }

    /// The same drag with its coefficients renewed every `steps` steps ([`Renewal`]).
    pub fn renewed_every(mut self, steps: u64) -> Self {
        self.renewal = Renewal::every(steps);
        self
    }

    /// Linear drag coefficient 6π μ a (kg/s) of an unshielded sphere in Stokes flow.
    pub fn stokes_coefficient(viscosity: f64, radius: f64) -> f64 {
        6.0 * PI * viscosity * radius
    }

    /// Largest shadow each particle receives from a touching upstream neighbour, with each
    /// particle's flow direction computed once (not once per touching pair). In shares of
    /// particles: a share reads the near pairs with i below its end and keeps the shadows cast
    /// on its own particles (a maximum: the same bits in any order and on any split).
    fn compute_shadows(&mut self, ctx: &Context, p: &Particles, touch_tolerance: f64, near: PairRange) {
        let fluid = FluidAt::of(&self.fluid.flow, &self.local_flow);
        self.flow_direction.resize(p.len(), Vec3::zeros());
        parallel::for_each_share((&mut self.flow_direction[..], &p.velocity[..]), |first, (dirs, vs)| {
            for (k, (dir, v)) in dirs.iter_mut().zip(vs).enumerate() {
                let u = v - fluid.at(first + k);
                let speed = u.norm();
                *dir = if speed > 0.0 { u / speed } else { Vec3::zeros() };
            }
        });
        self.shadow.clear();
        self.shadow.resize(p.len(), 0.0);
        let pairs = ctx.neighbours.pairs(near);
        let flow = &self.flow_direction;
        parallel::for_each_share(&mut self.shadow[..], |lo, shadow| {
            let hi = lo + shadow.len();
            let rows = pairs.partition_point(|q| (q.i as usize) < hi);
            let mut cast = |me: usize, other: usize, offset: &Vec3| {
                if (lo..hi).contains(&me) {
                    let area = shadow_area(p.radius[me], p.radius[other], offset, &flow[me]);
                    if area > shadow[me - lo] {
                        shadow[me - lo] = area;
                    }
                }
            };
            for pair in pairs.range(0, rows) {
                let (i, j) = (pair.i as usize, pair.j as usize);
                if i < lo && !(lo..hi).contains(&j) {
                    continue;
                }
                let (a_i, a_j) = (p.radius[i], p.radius[j]);
                if pair.dist - a_i - a_j > touch_tolerance * a_i.min(a_j) {
                    continue;
                }
                // pair.r = x_i − x_j: offset of j seen from i is −r, of i seen from j is +r. A
                // zero flow direction (particle at rest in the fluid) casts no shadow.
                cast(i, j, &-pair.r);
                cast(j, i, &pair.r);
            }
        });
    }

    /// c_i = 12 μ A_i/(2 a_i) · f(Re_i) from the current positions (shadows) and velocities.
    fn renew_coefficients(&mut self, ctx: &Context, p: &Particles) {
        if let Shielding::Paper { touch_tolerance, near } = self.shielding {
            self.compute_shadows(ctx, p, touch_tolerance, near);
        }
        self.coefficient.resize(p.len(), 0.0);
        let (law, shielding, fluid, shadow) = (self.law, self.shielding, &self.fluid, &self.shadow);
        let fluid_at = FluidAt::of(&fluid.flow, &self.local_flow);
        parallel::for_each_share(&mut self.coefficient[..], |first, c| {
            for (k, c) in c.iter_mut().enumerate() {
                let i = first + k;
                let a = p.radius[i];
                let full = PI * a * a;
                let area = match shielding {
                    Shielding::None => full,
                    Shielding::Paper { .. } => full - shadow[i],
                };
                let correction = match law {
                    DragLaw::Stokes => 1.0,
                    DragLaw::SchillerNaumann => {
                        let u = p.velocity[i] - fluid_at.at(i);
                        schiller_naumann(fluid.density * u.norm() * 2.0 * a / fluid.viscosity)
                    }
                };
                *c = 12.0 * fluid.viscosity * area / (2.0 * a) * correction;
            }
        });
    }
}

/// Where [`Drag::pass`] writes: added to the forces and torques, or onto their start (the
/// constant force, zero if `None`, and zero torques).
#[derive(Clone, Copy)]
enum Onto<'a> {
    Add,
    Start(Option<&'a ConstantForce<'a>>),
}

impl Drag {
    fn renew_if_due(&mut self, ctx: &Context, p: &Particles) {
        self.sample_flow(ctx, p);
        if self.renewal.now(self.coefficient.len() == p.len()) {
            self.renew_coefficients(ctx, p);
        }
    }

    /// The drag on particle `i` with radius `a` and velocity `v` in fluid moving at `u_f`, to
    /// subtract from its force: c_i u (with a wall, c_i times u's scaled parallel parts), less
    /// 6π μ a u if the linear part is excluded.
    #[inline(always)]
    fn force_on(&self, p: &Particles, i: usize, a: f64, v: &Vec3, u_f: Vec3) -> Vec3 {
        let u = v - u_f;
        let linear = if self.exclude_linear { Self::stokes_coefficient(self.fluid.viscosity, a) } else { 0.0 };
        let coefficient = self.coefficient[i];
        match &self.wall {
            None => (coefficient - linear) * u,
            Some(w) => coefficient * w.scale_parallel(u, w.factor(&p.position[i], a)) - linear * u,
        }
    }

    /// The drag on every particle, in particle shares; the torque 8π μ a³ ω is subtracted where
    /// [`Drag::rotational`] (and the linear part is not excluded), the torques are otherwise left
    /// as they are (or zero).
    fn pass(&self, p: &Particles, out: &mut Forces, onto: Onto) {
        let rotational = self.rotational && !self.exclude_linear;
        let spin_drag = |a: f64, w: &Vec3| 8.0 * PI * self.fluid.viscosity * a.powi(3) * w;
        let fluid = FluidAt::of(&self.fluid.flow, &self.local_flow);
        parallel::for_each_share((&mut *out.force, &mut *out.torque), |first, (force, torque)| {
            let span = first..first + force.len();
            let each = force.iter_mut().zip(torque).zip(&p.radius[span.clone()]).zip(&p.velocity[span.clone()]);
            for (k, (((f, t), &a), v)) in each.enumerate() {
                let i = first + k;
                let drag = self.force_on(p, i, a, v, fluid.at(i));
                match onto {
                    Onto::Add => {
                        *f -= drag;
                        if rotational {
                            *t -= spin_drag(a, &p.angular_velocity[i]);
                        }
                    }
                    Onto::Start(start) => {
                        *f = start.map_or(Vec3::zeros(), |s| s.on(i)) - drag;
                        *t = match rotational {
                            // 0 − x, as the torque started at zero and then had x subtracted
                            // (not −x: the two differ in the sign of a zero).
                            true => Vec3::zeros() - spin_drag(a, &p.angular_velocity[i]),
                            false => Vec3::zeros(),
                        };
                    }
                }
            }
        });
    }
}

/// Schiller–Naumann correction 1 + 0.15 Re^0.687, with the power as exp(0.687 ln Re): two thirds
/// of `powf`'s time here (perf), relative error ≲ 1e-15 (|0.687 ln Re| ε), zero-safe (ln 0 = −∞).
#[inline]
fn schiller_naumann(re: f64) -> f64 {
    1.0 + 0.15 * (0.687 * re.ln()).exp()
}

impl ForceTerm for Drag {
    fn name(&self) -> &'static str {
        "drag"
    }
    fn pairs(&self) -> Option<PairRange> {
        match self.shielding {
            Shielding::None => None,
            // The contact's near range: one list serves both.
            Shielding::Paper { near, .. } => Some(near),
        }
    }
    fn begin_step(&mut self, state: &State) {
        self.renewal.begin_step(state.step);
    }
    fn apply(&mut self, ctx: &Context, p: &Particles, out: &mut Forces) {
        self.renew_if_due(ctx, p);
        self.pass(p, out, Onto::Add);
    }
    /// The drag written onto the starting force in the same pass (the drag is the first term
    /// after the constant one in the paper's scenes: a pass over the forces saved each step).
    fn apply_from(&mut self, ctx: &Context, p: &Particles, out: &mut Forces, start: Option<&ConstantForce>) -> bool {
        self.renew_if_due(ctx, p);
        self.pass(p, out, Onto::Start(start));
        true
    }
    /// The held coefficients follow their particles (the shadows and flow directions are
    /// working space of a renewal).
    fn renumber(&mut self, r: &Renumbering) {
        r.permute(&mut self.coefficient);
        self.shadow.clear();
        self.flow_direction.clear();
        self.local_flow.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::domain::Domain;
    use crate::core::forces::wall_drag::PlaneWall;
    use crate::core::neighbours::Neighbours;
    use crate::core::state::{ContactDiagnostics, PairHistory};

    /// Writing the drag onto the starting force and zero torques in one pass gives the bits of
    /// starting them and then adding the drag: for every start (none, uniform, per particle),
    /// with and without rotational drag, the linear part excluded or not, and a wall. Angular
    /// velocities include zeros of both signs (0 − x and −x differ there).
    #[test]
    fn drag_onto_the_start_gives_the_bits_of_start_then_add() {
        let value = |k: usize| (k as f64 * 0.618_033_988_749_895).fract() - 0.5;
        let species = crate::core::state::test_sphere(5.5e-6);
        let mut p = Particles::default();
        for k in 0..50 {
            let x = 1e-4 * Vec3::new(value(3 * k) + 0.5, value(3 * k + 1) + 0.5, value(3 * k + 2) + 0.5);
            p.push(0, &species, x, 1e-3 * Vec3::new(value(7 * k), value(7 * k + 1), value(7 * k + 2)));
        }
        for (k, w) in p.angular_velocity.iter_mut().enumerate() {
            *w = match k % 3 {
                0 => Vec3::new(0.0, -0.0, 1.0),
                _ => 1e2 * Vec3::new(value(11 * k), value(11 * k + 1), -0.0),
            };
        }
        let weights: Vec<Vec3> = (0..p.len()).map(|k| Vec3::new(value(k), -1e-9, value(k + 5))).collect();
        let starts = [
            None,
            Some(ConstantForce::Uniform(Vec3::new(0.0, 0.0, -1e-9))),
            Some(ConstantForce::PerParticle(&weights)),
        ];
        let domain = Domain { lo: Vec3::zeros(), hi: Vec3::repeat(1e-4), periodic: [false; 3] };
        let neighbours = Neighbours::new([]);
        let ctx = Context { domain: &domain, neighbours: &neighbours, dt: 1e-8, time: 0.0 };
        let wall = WallCorrection::new(PlaneWall { axis: 2, position: 0.0, side: 1.0, min_gap: 1e-3 });
        let fluid = Fluid { density: 1000.0, viscosity: 1e-3, flow: Flow::Uniform(Vec3::new(1e-4, 0.0, 0.0)) };
        let (mut cases, n) = (0, p.len());
        for rotational in [false, true] {
            for exclude_linear in [false, true] {
                for wall in [None, Some(wall)] {
                    for start in &starts {
                        let mut drag = Drag::new(DragLaw::SchillerNaumann, Shielding::None, rotational, fluid.clone());
                        (drag.exclude_linear, drag.wall) = (exclude_linear, wall);
                        let mut run = |fused: bool| {
                            let (mut force, mut torque) =
                                (vec![Vec3::repeat(f64::NAN); n], vec![Vec3::repeat(f64::NAN); n]);
                            let (mut moment, mut contacts, mut diagnostics) =
                                (vec![Vec3::zeros(); n], PairHistory::default(), ContactDiagnostics::default());
                            let mut out = Forces {
                                force: &mut force,
                                torque: &mut torque,
                                moment: &mut moment,
                                history: &mut contacts,
                                diagnostics: &mut diagnostics,
                            };
                            if !fused || !drag.apply_from(&ctx, &p, &mut out, start.as_ref()) {
                                for i in 0..n {
                                    out.force[i] = start.as_ref().map_or(Vec3::zeros(), |s| s.on(i));
                                    out.torque[i] = Vec3::zeros();
                                }
                                drag.apply(&ctx, &p, &mut out);
                            }
                            (force, torque)
                        };
                        let (separate, fused) = (run(false), run(true));
                        let bits =
                            |v: &[Vec3]| v.iter().flat_map(|x| x.iter().map(|c| c.to_bits())).collect::<Vec<_>>();
                        assert_eq!(bits(&separate.0), bits(&fused.0), "force: rotational {rotational}, wall {wall:?}");
                        assert_eq!(bits(&separate.1), bits(&fused.1), "torque: rotational {rotational}, wall {wall:?}");
                        assert!(separate.0.iter().all(|f| f.iter().all(|c| c.is_finite())), "every force written");
                        cases += 1;
                    }
                }
            }
        }
        assert_eq!(cases, 24);
    }

    /// The exp–ln form equals the power law to round-off from creeping flow (Re → 0, where the
    /// correction must vanish) to the top of the law's range (Re ≈ 800).
    #[test]
    fn schiller_naumann_matches_its_power_law() {
        assert_eq!(schiller_naumann(0.0), 1.0);
        for re in [1e-9, 1e-6, 1e-3, 0.1, 1.0, 10.0, 100.0, 800.0] {
            let power = 1.0 + 0.15 * f64::powf(re, 0.687);
            assert!(
                (schiller_naumann(re) - power).abs() <= 4e-15 * power,
                "Re = {re}: {} vs {power}",
                schiller_naumann(re)
            );
        }
    }
}

/// `[forces.drag]`: hydrodynamic drag (needs `[fluid]`).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DragSpec {
    /// `stokes` | `schiller-naumann` (default `schiller-naumann`, the paper's).
    #[serde(default = "default_drag_law")]
    pub law: DragLawSpec,
    /// `none` | `paper` (default `paper`, the paper's A_eff).
    #[serde(default = "default_shielding")]
    pub shielding: ShieldingSpec,
    /// Rotational drag −8π μ a³ ω (default true).
    #[serde(default = "default_true")]
    pub rotational: bool,
    /// Gap below which two particles count as touching for shielding, as a fraction of the
    /// smaller radius (default 1e-3).
    #[serde(default = "default_touch_tolerance")]
    pub touch_tolerance: f64,
    /// Steps between renewals of the drag's configuration-dependent part (default 1, every force
    /// evaluation): with `law = "rpy"` the mobility's factor, otherwise each particle's coefficient
    /// (shielded area and Schiller–Naumann factor). The drag uses each evaluation's velocities with
    /// the part renewed at the last step divisible by it. Must divide the steps per output frame
    /// (and be a multiple of `integration.slow_every` under multiple time stepping).
    #[serde(default = "default_refactor_every")]
    pub refactor_every: u64,
    /// Stokes drag near one plane wall of the box (with `law` stokes or schiller-naumann).
    pub wall: Option<WallDragSpec>,
}

#[derive(Debug, Clone, Copy, serde::Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum DragLawSpec {
    Stokes,
    SchillerNaumann,
    /// Stokes flow with hydrodynamic interactions: the Rotne–Prager–Yamakawa mobility of all
    /// spheres, factorised every `refactor_every` steps (dense, O(N³)).
    Rpy,
}

#[derive(Debug, Clone, Copy, serde::Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum ShieldingSpec {
    None,
    Paper,
}

fn default_drag_law() -> DragLawSpec {
    DragLawSpec::SchillerNaumann
}
fn default_shielding() -> ShieldingSpec {
    ShieldingSpec::Paper
}
fn default_true() -> bool {
    true
}
fn default_touch_tolerance() -> f64 {
    1e-3
}
fn default_refactor_every() -> u64 {
    1
}

impl DragSpec {
    /// What makes this drag other than a lone sphere's Stokes drag 6π μ a (Schiller–Naumann's at
    /// vanishing Re): the key, its value and why; `None` when it is that drag.
    pub fn unlike_stokes(&self) -> Option<(&'static str, String, &'static str)> {
        if self.law == DragLawSpec::Rpy {
            return Some(("forces.drag.law", "rpy".into(), "the RPY drag's correlated noise is not built yet"));
        }
        if self.shielding != ShieldingSpec::None {
            return Some((
                "forces.drag.shielding",
                "paper".into(),
                "the shielded coefficient changes with the neighbours",
            ));
        }
        if self.wall.is_some() {
            return Some(("forces.drag.wall", "{…}".into(), "a wall changes the drag near it"));
        }
        None
    }
}

impl TermSpec for DragSpec {
    fn check(&self, ctx: &SceneContext) -> Result<(), Invalid> {
        let Some(fluid) = &ctx.fluid else {
            return Err(invalid("forces.drag", "{}", "drag needs a [fluid] table"));
        };
        if fluid.flow.uniform().is_none() {
            if ctx.scheme.spec().integrates_linear_drag() {
                return Err(invalid(
                    "integration.scheme",
                    ctx.scheme,
                    "integrates the drag towards one uniform fluid velocity; the fluid's flow varies in space",
                ));
            }
            if self.wall.is_some() {
                return Err(invalid(
                    "forces.drag.wall",
                    "{…}",
                    "the wall correction is for a fluid at rest beside a plane; the fluid's flow is not",
                ));
            }
        }
        non_negative("forces.drag.touch_tolerance", self.touch_tolerance)?;
        let rpy = self.law == DragLawSpec::Rpy;
        if rpy && self.shielding != ShieldingSpec::None {
            return Err(invalid(
                "forces.drag.shielding",
                "paper",
                "the RPY mobility replaces the shielded area; use shielding = \"none\" with law = \"rpy\"",
            ));
        }
        if let Some(w) = &self.wall {
            positive("forces.drag.wall.min_gap", w.min_gap)?;
            if rpy {
                equal_spheres(ctx)?;
            }
            let (axis, _) = w.face.axis_and_side();
            if ctx.domain.periodic[axis] {
                return Err(invalid("forces.drag.wall.face", w.face, "that face is periodic, not a wall"));
            }
            if ctx.scheme.spec().integrates_linear_drag() {
                return Err(invalid(
                    "integration.scheme",
                    ctx.scheme,
                    "integrates a lone sphere's free-fluid Stokes drag exactly; a wall changes that drag",
                ));
            }
        }
        let every = self.refactor_every;
        if every != 1 && self.law == DragLawSpec::Stokes && self.shielding == ShieldingSpec::None {
            return Err(invalid(
                "forces.drag.refactor_every",
                every,
                "Stokes drag without shielding has a constant coefficient, nothing to renew; remove the key or set it to 1",
            ));
        }
        let per_call = ctx.scheme.spec().slow_every();
        if every > 1 && !every.is_multiple_of(per_call) {
            return Err(invalid(
                "forces.drag.refactor_every",
                every,
                format!(
                    "must be a multiple of integration.slow_every = {per_call}: the drag is renewed at the start of \
                     an outer step"
                ),
            ));
        }
        let per_frame = ctx.steps_per_frame;
        if every == 0 || !per_frame.is_multiple_of(every) {
            return Err(invalid(
                "forces.drag.refactor_every",
                every,
                format!(
                    "must be a positive divisor of the {per_frame} steps per output frame, so that every checkpoint \
                     falls on a renewal and a resumed run stays bitwise equal"
                ),
            ));
        }
        if rpy && ctx.scheme.spec().integrates_linear_drag() {
            return Err(invalid(
                "integration.scheme",
                ctx.scheme,
                "integrates a lone sphere's Stokes drag exactly; with law = \"rpy\" the drag couples all spheres",
            ));
        }
        Ok(())
    }

    fn near_tolerance(&self) -> f64 {
        self.touch_tolerance
    }

    /// The drag relaxation time τ = m/(6π μ a) of the fastest-relaxing species: explicit schemes
    /// are stable for dt < 2τ (a scheme that integrates the linear drag exactly has no bound).
    fn stable_dt(&self, ctx: &StepContext) -> Option<StepBound> {
        let mu = ctx.drag_viscosity?;
        let tau =
            ctx.species.iter().map(|s| s.mass() / Drag::stokes_coefficient(mu, s.radius)).fold(f64::INFINITY, f64::min);
        Some(StepBound {
            term: "drag",
            dt: (!ctx.scheme.spec().integrates_linear_drag()).then_some(2.0 * tau),
            limited_by: "drag relaxation",
            collision: None,
            summary: format!("; drag relaxation {tau:.3e} s"),
        })
    }

    fn build(&self, ctx: &SceneContext) -> Box<dyn ForceTerm> {
        let fluid = ctx.fluid.clone().expect("checked: drag has a [fluid] table");
        let wall = self.wall.as_ref().map(|w| w.wall(ctx.domain));
        let law = match self.law {
            DragLawSpec::Stokes => DragLaw::Stokes,
            DragLawSpec::SchillerNaumann => DragLaw::SchillerNaumann,
            DragLawSpec::Rpy => {
                let mut rpy = RpyDrag::new(fluid, self.rotational, self.refactor_every);
                rpy.wall = wall;
                return Box::new(rpy);
            }
        };
        let shielding = match self.shielding {
            ShieldingSpec::None => Shielding::None,
            ShieldingSpec::Paper => Shielding::Paper { touch_tolerance: self.touch_tolerance, near: ctx.pairs.near },
        };
        let mut drag = Drag::new(law, shielding, self.rotational, fluid).renewed_every(self.refactor_every);
        drag.exclude_linear = ctx.scheme.spec().integrates_linear_drag();
        drag.wall = wall.map(WallCorrection::new);
        Box::new(drag)
    }
}

/// The RPY mobility above a wall (Swan & Brady's) is that of equal spheres: one diameter, no size law.
fn equal_spheres(ctx: &SceneContext) -> Result<(), Invalid> {
    let why = "the RPY mobility above a wall (forces.drag.wall with law = \"rpy\") is written for equal spheres";
    let first = 2.0 * ctx.species[0].radius;
    for (k, s) in ctx.species.iter().enumerate() {
        if s.size.is_some() {
            return Err(invalid(format!("species[{k}].size"), s.name.as_str(), format!("{why}: give one diameter")));
        }
        if 2.0 * s.radius != first {
            return Err(invalid(
                format!("species[{k}].diameter"),
                2.0 * s.radius,
                format!("{why}: species[0] has {first:e} m"),
            ));
        }
    }
    Ok(())
}

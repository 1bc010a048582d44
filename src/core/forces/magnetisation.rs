//! Magnetic moments of linear, isotropic spheres in the applied field plus the field of the other
//! dipoles (mutual induction):
//!
//!   m_i = m_perm,i + sat(χ_eff V_i H_loc,i),  H_loc,i = H_ext(x_i) + Σ_j H_dip,j(x_i)
//!   H_ext(x, t) = B_ext(x, t) / μ0,  H_dip(r) = [3 (m·r̂) r̂ − m] / (4π r³)
//!
//! B_ext is the applied field ([`crate::core::field`]), B0 + G x or coils, at each particle's
//! position and the evaluated time. sat() saturates |M| at the species' Ms (a cap, or the Fröhlich–Kennelly law). The moments are
//! a force term of their own ("moments", slow): it adds no force, it writes the moments that the
//! dipole and gradient terms after it read. Levels (docs/model.md §4.3):
//! - `None`: H_loc = H_ext.
//! - `Paper`: the paper's neighbourhood scheme as magdem reads it: dipoles within 15 diameters
//!   contribute, using the moments stored at the previous step (one sweep per step; the
//!   self-consistent state is approached over successive steps).
//! - `Exact`: the self-consistent solution each step, all pairs: a dense LU solve (faer) of
//!   (I − D T) m = m_perm + D H_ext for N ≤ `dense_max` without saturation, otherwise fixed-point
//!   sweeps warm-started from the previous moments until max|Δm| ≤ tolerance · max|m|.

pub use super::setup::Induction;
use super::setup::{invalid, Invalid, SceneContext, StepBound, StepContext};
use super::{Context, ForceTerm, Forces, Renumbering, TermError};
use crate::core::field::{AppliedField, FieldAt};
use crate::core::lanes::{self, Vec3x4};
use crate::core::neighbours::{Pair, PairRange, RangePairs, Skins};
use crate::core::parallel;
use crate::core::parallel::Pieced;
use crate::core::state::{sphere_volume, Particles, Saturation, Species, State, Vec3};
use nalgebra::Matrix3;
use std::f64::consts::PI;
use wide::f64x4;

pub use crate::core::coils::MU0;

/// Fields of a pair's dipoles on each other, with r = x_i − x_j: on i from m_j and on j from m_i,
/// H = [3(m·r̂)r̂ − m]/(4π r³) (A/m; even in r̂, so both share r̂ and 1/(4π r³)).
#[inline]
pub fn pair_dipole_fields(m_i: &Vec3, m_j: &Vec3, pair: &Pair) -> (Vec3, Vec3) {
    (pair_dipole_field(m_j, pair), pair_dipole_field(m_i, pair))
}

/// The field of dipole `m` at the pair's other end (either: the field is even in r̂).
#[inline]
pub fn pair_dipole_field(m: &Vec3, pair: &Pair) -> Vec3 {
    let rhat = pair.r / pair.dist;
    let scale = 1.0 / (4.0 * PI * pair.dist.powi(3));
    (3.0 * m.dot(&rhat) * rhat - m) * scale
}

/// [`pair_dipole_fields`] of four pairs at once, `moment` indexed by particle: the same
/// operations in SIMD lanes, so the same bits. The sweep spent its time waiting on each pair's
/// chain of divisions and products; four pairs share one chain.
#[inline(always)]
pub fn pair_dipole_fields_four(moment: &[Vec3], q: [&Pair; 4]) -> [(Vec3, Vec3); 4] {
    let d = f64x4::new(q.map(|q| q.dist));
    let rhat = lanes::gather(q.map(|q| &q.r)).map(|c| c / d);
    // 4π r³ with r³ = (r r) r, as powi(3) multiplies.
    let scale = f64x4::ONE / (f64x4::splat(4.0 * PI) * (d * d * d));
    let field = |m: Vec3x4| {
        let t = f64x4::splat(3.0) * lanes::dot(&m, &rhat);
        lanes::scatter(&std::array::from_fn(|c| (t * rhat[c] - m[c]) * scale))
    };
    let on_i = field(lanes::gather(q.map(|q| &moment[q.j as usize])));
    let on_j = field(lanes::gather(q.map(|q| &moment[q.i as usize])));
    std::array::from_fn(|k| (on_i[k], on_j[k]))
}

/// Refuses a term that reads the moments in a scene without an applied field.
pub fn needs_field(ctx: &SceneContext) -> Result<(), Invalid> {
    match ctx.field {
        Some(_) => Ok(()),
        None => Err(invalid("forces", "dipole/gradient", "magnetic terms need a [field] table")),
    }
}

/// Moment magnitude of an isolated sphere of species `s` in the applied field `b` (T; zero
/// moment without moments), saturated, enhanced by mutual induction with one touching neighbour
/// along the field when induction is on: m/(1 − χ_eff/12); plus its permanent moment. For the
/// step estimate.
pub fn isolated_moment(induction: Option<Induction>, b: Vec3, s: &Species) -> f64 {
    let Some(induction) = induction else {
        return 0.0;
    };
    let h = (b / MU0).norm();
    let mut m = s.susceptibility * s.volume() * h;
    if let Some(sat) = s.saturation {
        m = m.min(sat.moment(s.susceptibility * h, s.volume()));
    }
    if induction != Induction::None && s.saturation.is_none() {
        m /= 1.0 - s.susceptibility / 12.0;
    }
    m + s.permanent_moment.map_or(0.0, |p| p.norm())
}

/// Fastest expected impact speed of two touching spheres of species `s` with moments `moment`:
/// all the magnetic energy μ0 m²/(2π d³) into motion, v = √(2E/m*), capped by the drag-limited
/// closing speed 2F/(6π μ a) under the contact attraction F = 3μ0 m²/(2π d⁴) in a fluid of
/// `drag_viscosity`; at least `least` (the fastest initial speed) and 1 µm/s.
pub fn impact_speed(s: &Species, moment: f64, drag_viscosity: Option<f64>, least: f64) -> f64 {
    let m_eff = 0.5 * s.mass();
    let d = 2.0 * s.radius;
    let magnetic_energy = MU0 * moment * moment / (2.0 * PI * d.powi(3));
    let mut v = (2.0 * magnetic_energy / m_eff).sqrt();
    if let Some(mu) = drag_viscosity {
        let attraction = 3.0 * MU0 * moment * moment / (2.0 * PI * d.powi(4));
        v = v.min(2.0 * attraction / (6.0 * PI * mu * s.radius));
    }
    v.max(least).max(1e-6)
}

/// The bound of magnetic forces held over K = `slow_every` steps (r-RESPA, sub-cycled Euler):
/// the dipole attraction at contact, F = 3μ0 m²/(2π d⁴), is a spring of stiffness |dF/dr| = 4F/d
/// between touching particles, integrated with the outer step K·dt: stable for K·dt < 2/ω_m,
/// ω_m = √(k_m/m*) (the Verlet bound on that spring, for r-RESPA; sub-cycled Euler holds the
/// force as forward Euler does and is bounded more tightly; the stability map measures r-RESPA).
pub fn held_bound(ctx: &StepContext) -> Option<StepBound> {
    let k = ctx.scheme.spec().slow_every();
    if k <= 1 {
        return None;
    }
    let bound = ctx
        .species
        .iter()
        .zip(&ctx.moments)
        .filter(|(_, &m)| m > 0.0)
        .map(|(s, &m)| {
            let d = 2.0 * s.radius;
            let stiffness = 4.0 * 3.0 * MU0 * m * m / (2.0 * PI * d.powi(5));
            let omega = (stiffness / (0.5 * s.mass())).sqrt();
            2.0 / (omega * k as f64)
        })
        .fold(f64::INFINITY, f64::min);
    bound.is_finite().then(|| StepBound {
        term: "moments",
        dt: Some(bound),
        limited_by: "magnetic contact spring held over slow_every steps",
        collision: None,
        summary: format!("; magnetic forces held over slow_every steps: bound {bound:.3e} s"),
    })
}

pub struct Magnetisation {
    pub induction: Induction,
    pub applied: AppliedField,
    /// χ_eff of each species.
    susceptibility: Vec<f64>,
    saturation: Vec<Option<Saturation>>,
    /// The pairs the local fields sum over (`None` for induction `none`).
    range: Option<PairRange>,
    field: Vec<Vec3>,
    moments: Vec<Vec3>,
    /// Sweeps used by the last `Exact` update (diagnostic).
    pub last_iterations: usize,
}

impl Magnetisation {
    pub fn new(induction: Induction, applied: AppliedField, species: &[Species], skins: Skins) -> Self {
        let range = match induction {
            Induction::None => None,
            Induction::Paper { radius } => Some(PairRange::Within { range: radius, skin: radius * skins.induction }),
            Induction::Exact { .. } => Some(PairRange::All),
        };
        Self {
            induction,
            applied,
            susceptibility: species.iter().map(|s| s.susceptibility).collect(),
            saturation: species.iter().map(|s| s.saturation).collect(),
            range,
            field: vec![],
            moments: vec![],
            last_iterations: 0,
        }
    }

    /// The applied field H_ext(x_i, t) = B_ext(x_i, t)/μ0 at every particle into `field` (in
    /// parallel for many particles); a linear field computes (B0 + G x)/μ0.
    fn external_fields(&self, p: &Particles, t: f64, field: &mut Vec<Vec3>) {
        let x = &p.position;
        match self.applied.at(t) {
            FieldAt::Linear { b0, g } => parallel::map_ordered(p.len(), field, |i| (b0 + g * x[i]) / MU0),
            applied => parallel::map_ordered(p.len(), field, |i| applied.field(&x[i]) / MU0),
        }
    }

    /// Induced plus permanent moment of particle i in local field `h`.
    fn moment_in(&self, p: &Particles, i: usize, h: &Vec3) -> Vec3 {
        let s = p.species[i] as usize;
        let volume = sphere_volume(p.radius[i]);
        let mut m = self.susceptibility[s] * volume * h;
        if let Some(sat) = self.saturation[s] {
            let norm = m.norm();
            let cap = sat.moment(norm / volume, volume);
            if norm > cap {
                m *= cap / norm;
            }
        }
        m + p.permanent_moment[i]
    }

    /// Sets every moment from the local fields in `self.field` (in parallel for many particles).
    fn set_moments(&mut self, p: &Particles) {
        let mut moments = std::mem::take(&mut self.moments);
        parallel::map_ordered(p.len(), &mut moments, |i| self.moment_in(p, i, &self.field[i]));
        self.moments = moments;
    }

    /// Local fields from the applied field and the moments `moment` over `pairs`.
    fn sweep_fields(&mut self, p: &Particles, t: f64, moment: &[Vec3], pairs: &RangePairs) {
        let mut field = std::mem::take(&mut self.field);
        self.external_fields(p, t, &mut field);
        pairs.add_in_order_by_four(
            &mut field,
            |q| pair_dipole_fields(&moment[q.i as usize], &moment[q.j as usize], q),
            |q| pair_dipole_field(&moment[q.i as usize], q),
            |q| pair_dipole_fields_four(moment, q),
        );
        self.field = field;
    }

    /// Computes the moments for the current positions and time `t` into `self.moments`;
    /// `previous` are the last evaluation's (the paper's lagged sweep reads them, the iteration
    /// starts from them).
    fn update(&mut self, p: &Particles, t: f64, previous: &[Vec3], pairs: &RangePairs) -> Result<(), TermError> {
        match self.induction {
            Induction::None => {
                let mut field = std::mem::take(&mut self.field);
                self.external_fields(p, t, &mut field);
                self.field = field;
                self.set_moments(p);
            }
            Induction::Paper { .. } => {
                self.sweep_fields(p, t, previous, pairs);
                self.set_moments(p);
            }
            Induction::Exact { tolerance, max_iterations, dense_max } => {
                if p.len() <= dense_max && self.saturation.iter().all(Option::is_none) {
                    self.solve_dense(p, t, pairs.pairs);
                    self.last_iterations = 1;
                } else {
                    self.moments.clear();
                    self.moments.extend_from_slice(previous);
                    self.iterate(p, t, pairs, tolerance, max_iterations)?;
                }
            }
        }
        Ok(())
    }

    /// Fixed-point sweeps on `self.moments` (the current iterate).
    fn iterate(
        &mut self,
        p: &Particles,
        t: f64,
        pairs: &RangePairs,
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<(), TermError> {
        let mut residual = f64::INFINITY;
        let mut moments = std::mem::take(&mut self.moments);
        for iteration in 1..=max_iterations {
            self.sweep_fields(p, t, &moments, pairs);
            let (mut change, mut largest) = (0.0_f64, 0.0_f64);
            for (i, moment) in moments.iter_mut().enumerate() {
                let m = self.moment_in(p, i, &self.field[i]);
                change = change.max((m - *moment).norm());
                largest = largest.max(m.norm());
                *moment = m;
            }
            residual = if largest > 0.0 { change / largest } else { 0.0 };
            if residual <= tolerance {
                self.last_iterations = iteration;
                self.moments = moments;
                return Ok(());
            }
        }
        self.moments = moments;
        Err(TermError::Induction { residual, iterations: max_iterations, tolerance })
    }

    /// Dense solve of (I − D T) m = m_perm + D H_ext (no saturation).
    fn solve_dense(&mut self, p: &Particles, t: f64, pairs: Pieced<Pair>) {
        let n = p.len();
        let chi_v = |i: usize| self.susceptibility[p.species[i] as usize] * 4.0 / 3.0 * PI * p.radius[i].powi(3);
        let mut a = faer::Mat::<f64>::identity(3 * n, 3 * n);
        let mut rhs = faer::Mat::<f64>::zeros(3 * n, 1);
        let applied = self.applied.at(t);
        for i in 0..n {
            let h = applied.field(&p.position[i]) / MU0;
            for k in 0..3 {
                rhs[(3 * i + k, 0)] = chi_v(i) * h[k] + p.permanent_moment[i][k];
            }
        }
        for pair in pairs.iter() {
            let (i, j) = (pair.i as usize, pair.j as usize);
            let rhat = pair.r / pair.dist;
            // T_ij = (3 r̂ r̂ᵀ − I) / (4π r³), symmetric and equal for (i, j) and (j, i).
            let t = (3.0 * rhat * rhat.transpose() - Matrix3::identity()) / (4.0 * PI * pair.dist.powi(3));
            for r in 0..3 {
                for c in 0..3 {
                    a[(3 * i + r, 3 * j + c)] = -chi_v(i) * t[(r, c)];
                    a[(3 * j + r, 3 * i + c)] = -chi_v(j) * t[(r, c)];
                }
            }
        }
        use faer::linalg::solvers::Solve;
        let m = a.partial_piv_lu().solve(&rhs);
        self.moments.clear();
        self.moments.extend((0..n).map(|i| Vec3::new(m[(3 * i, 0)], m[(3 * i + 1, 0)], m[(3 * i + 2, 0)])));
    }
}

impl ForceTerm for Magnetisation {
    fn name(&self) -> &'static str {
        "moments"
    }
    fn is_slow(&self) -> bool {
        true
    }
    fn pairs(&self) -> Option<PairRange> {
        self.range
    }
    fn prepare(&mut self, ctx: &Context, state: &State) -> Result<(), TermError> {
        // Without induction no pairs are read (and none declared).
        let pairs = ctx.neighbours.range_pairs(self.range.unwrap_or(PairRange::All));
        self.update(&state.particles, ctx.time, &state.fields.moment, &pairs)
    }
    fn apply(&mut self, _ctx: &Context, _p: &Particles, out: &mut Forces) {
        parallel::for_each_share((&mut *out.moment, &self.moments[..]), |_, (out, m)| out.copy_from_slice(m));
    }
    /// The previous moments are the state's; the local fields and moments held here follow
    /// their particles.
    fn renumber(&mut self, r: &Renumbering) {
        r.permute(&mut self.field);
        r.permute(&mut self.moments);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four pairs in lanes give each pair's scalar fields bit for bit, over separations from
    /// touching to the 15-diameter neighbourhood in every direction and moments of any orientation.
    #[test]
    fn fields_in_lanes_are_the_scalar_fields_bit_for_bit() {
        let (moment, quads) = lanes::testing::random_quads(11, 4000);
        for pairs in &quads {
            let lanes = pair_dipole_fields_four(&moment, [&pairs[0], &pairs[1], &pairs[2], &pairs[3]]);
            for (q, (on_i, on_j)) in pairs.iter().zip(lanes) {
                let (m_i, m_j) = (&moment[q.i as usize], &moment[q.j as usize]);
                let (scalar_i, scalar_j) = pair_dipole_fields(m_i, m_j, q);
                assert_eq!(on_i.map(f64::to_bits), scalar_i.map(f64::to_bits), "pair {q:?}");
                assert_eq!(on_j.map(f64::to_bits), scalar_j.map(f64::to_bits), "pair {q:?}");
            }
        }
    }
}

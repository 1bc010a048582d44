//! Weight minus buoyancy, F = V (ρ_p − ρ_f) g (paper eq. 11).

use super::setup::{Invalid, SceneContext, TermSpec};
use super::{ConstantForce, Context, ForceTerm, Forces, Renumbering};
use crate::core::parallel;
use crate::core::state::{sphere_volume, Particles, Vec3};

#[derive(Debug, Clone)]
pub struct GravityBuoyancy {
    pub gravity: Vec3,
    pub fluid_density: f64,
    /// Each particle's force, computed once (masses and radii do not change).
    weights: Vec<Vec3>,
    /// The weight, when it is the same for every particle.
    uniform: Option<Vec3>,
}

impl GravityBuoyancy {
    pub fn new(gravity: Vec3, fluid_density: f64) -> Self {
        Self { gravity, fluid_density, weights: vec![], uniform: None }
    }

    /// Computes the weights once per particle set (masses and radii do not change).
    fn weigh(&mut self, p: &Particles) {
        if self.weights.len() != p.len() {
            self.weights = (0..p.len())
                .map(|i| {
                    let volume = sphere_volume(p.radius[i]);
                    (p.mass[i] - volume * self.fluid_density) * self.gravity
                })
                .collect();
            self.uniform = self.weights.split_first().filter(|(w, rest)| rest.iter().all(|r| r == *w)).map(|(w, _)| *w);
        }
    }
}

impl ForceTerm for GravityBuoyancy {
    fn name(&self) -> &'static str {
        "gravity"
    }
    fn is_constant(&self) -> bool {
        true
    }
    fn constant_force(&mut self, p: &Particles) -> Option<ConstantForce<'_>> {
        self.weigh(p);
        Some(match self.uniform {
            Some(weight) => ConstantForce::Uniform(weight),
            None => ConstantForce::PerParticle(&self.weights),
        })
    }
    fn apply(&mut self, _ctx: &Context, p: &Particles, out: &mut Forces) {
        self.weigh(p);
        parallel::for_each_share((&mut *out.force, &self.weights[..]), |_, (f, w)| {
            f.iter_mut().zip(w).for_each(|(f, w)| *f += w)
        });
    }
    fn renumber(&mut self, r: &Renumbering) {
        r.permute(&mut self.weights);
    }
}

/// `[forces.gravity]`: weight minus buoyancy.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravitySpec {
    /// m/s² (default [0, 0, −9.81]).
    #[serde(default = "default_g")]
    pub g: [f64; 3],
}

fn default_g() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

impl TermSpec for GravitySpec {
    fn check(&self, _ctx: &SceneContext) -> Result<(), Invalid> {
        Ok(())
    }
    /// Buoyancy in the `[fluid]` table's density, none without one.
    fn build(&self, ctx: &SceneContext) -> Box<dyn ForceTerm> {
        Box::new(GravityBuoyancy::new(Vec3::from(self.g), ctx.fluid.as_ref().map_or(0.0, |f| f.density)))
    }
}

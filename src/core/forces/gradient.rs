//! Force of the applied field gradient on a point dipole, F = (m·∇) B_ext = G m, with
//! G_ab = ∂B_a/∂x_b (paper eq. 4, written for the moment m = V M).

use super::magnetisation::{needs_field, Induction};
use super::setup::{Invalid, SceneContext, TermSpec};
use super::{Context, ForceTerm, Forces, Renumbering};
use crate::core::state::Particles;
use nalgebra::Matrix3;

#[derive(Debug, Clone)]
pub struct GradientForce {
    /// G_ab = ∂B_a/∂x_b (T/m).
    pub gradient: Matrix3<f64>,
}

impl ForceTerm for GradientForce {
    fn name(&self) -> &'static str {
        "gradient"
    }
    fn is_slow(&self) -> bool {
        true
    }
    fn apply(&mut self, _ctx: &Context, _p: &Particles, out: &mut Forces) {
        for (f, m) in out.force.iter_mut().zip(out.moment.iter()) {
            *f += self.gradient * m;
        }
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `[forces.gradient]`: force of the applied gradient on each moment (needs `[field]`).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GradientSpec {}

impl TermSpec for GradientSpec {
    fn check(&self, ctx: &SceneContext) -> Result<(), Invalid> {
        needs_field(ctx)
    }
    /// The moments in the applied field alone, unless the dipole term asks for induction.
    fn moments(&self, _ctx: &SceneContext) -> Option<Induction> {
        Some(Induction::None)
    }
    fn build(&self, ctx: &SceneContext) -> Box<dyn ForceTerm> {
        Box::new(GradientForce { gradient: ctx.field().1 })
    }
}

//! Force of the applied field gradient on a point dipole, F = (m·∇) B_ext = G(x, t) m, with
//! G_ab = ∂B_a/∂x_b at the particle (paper eq. 4, written for the moment m = V M; the Jacobian of
//! coils in [`crate::core::field`]).

use super::magnetisation::{needs_field, Induction};
use super::setup::{Invalid, SceneContext, TermSpec};
use super::{Context, ForceTerm, Forces, Renumbering};
use crate::core::field::{AppliedField, FieldAt};
use crate::core::parallel;
use crate::core::state::Particles;

#[derive(Debug, Clone)]
pub struct GradientForce {
    /// The applied field whose Jacobian pulls on the moments.
    pub field: AppliedField,
}

impl ForceTerm for GradientForce {
    fn name(&self) -> &'static str {
        "gradient"
    }
    fn is_slow(&self) -> bool {
        true
    }
    /// One constant G for every particle when the field is linear; the Jacobian at each particle
    /// (in parallel for many) for coils.
    fn apply(&mut self, ctx: &Context, p: &Particles, out: &mut Forces) {
        match self.field.at(ctx.time) {
            FieldAt::Linear { g, .. } => {
                for (f, m) in out.force.iter_mut().zip(out.moment.iter()) {
                    *f += g * m;
                }
            }
            field => parallel::for_each_share((&mut *out.force, &*out.moment, &p.position[..]), |_, (f, m, x)| {
                for ((f, m), x) in f.iter_mut().zip(m).zip(x) {
                    *f += field.jacobian(x) * m;
                }
            }),
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
        Box::new(GradientForce { field: ctx.field() })
    }
}

//! Force of the applied field gradient on a point dipole, F = (m·∇) B_ext = G m, with
//! G_ab = ∂B_a/∂x_b (paper eq. 4, written for the moment m = V M).

use super::{ForceContext, ForceTerm};
use crate::core::state::State;
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
    fn apply(&mut self, _ctx: &ForceContext, state: &mut State) {
        let p = &mut state.particles;
        for i in 0..p.len() {
            p.force[i] += self.gradient * p.moment[i];
        }
    }
}

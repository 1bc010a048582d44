//! Weight minus buoyancy, F = V (ρ_p − ρ_f) g (paper eq. 11).

use super::{ForceContext, ForceTerm};
use crate::core::state::{State, Vec3};

#[derive(Debug, Clone)]
pub struct GravityBuoyancy {
    pub gravity: Vec3,
    pub fluid_density: f64,
}

impl ForceTerm for GravityBuoyancy {
    fn name(&self) -> &'static str {
        "gravity"
    }
    fn apply(&mut self, _ctx: &ForceContext, state: &mut State) {
        let p = &mut state.particles;
        for i in 0..p.len() {
            let volume = 4.0 / 3.0 * std::f64::consts::PI * p.radius[i].powi(3);
            let particle_density = p.mass[i] / volume;
            p.force[i] += volume * (particle_density - self.fluid_density) * self.gravity;
        }
    }
}

//! Weight minus buoyancy, F = V (ρ_p − ρ_f) g (paper eq. 11).

use super::{ForceContext, ForceTerm};
use crate::core::parallel;
use crate::core::state::{State, Vec3};
use rayon::prelude::*;

#[derive(Debug, Clone)]
pub struct GravityBuoyancy {
    pub gravity: Vec3,
    pub fluid_density: f64,
    /// Each particle's force, computed once (masses and radii do not change).
    weights: Vec<Vec3>,
}

impl GravityBuoyancy {
    pub fn new(gravity: Vec3, fluid_density: f64) -> Self {
        Self { gravity, fluid_density, weights: vec![] }
    }
}

impl ForceTerm for GravityBuoyancy {
    fn name(&self) -> &'static str {
        "gravity"
    }
    fn apply(&mut self, _ctx: &ForceContext, state: &mut State) {
        let p = &mut state.particles;
        if self.weights.len() != p.len() {
            self.weights = (0..p.len())
                .map(|i| {
                    let volume = 4.0 / 3.0 * std::f64::consts::PI * p.radius[i].powi(3);
                    (p.mass[i] - volume * self.fluid_density) * self.gravity
                })
                .collect();
        }
        let add = |(f, w): (&mut Vec3, &Vec3)| *f += w;
        if parallel::worth_it(p.len()) {
            p.force.par_iter_mut().zip(&self.weights).with_min_len(parallel::CHUNK).for_each(add);
        } else {
            p.force.iter_mut().zip(&self.weights).for_each(add);
        }
    }
}

//! The paper's effective drag area A_eff = π a_i² − E_overlap (its eqs. 8–10): the part of sphere
//! i's cross-section hidden behind a touching upstream neighbour j, both projected onto the plane
//! normal to the relative velocity.
//!
//! magdem's rule where the paper assumes a straight chain: with several touching upstream
//! neighbours, the one hiding the largest area counts (areas are not added, so A_eff ≥ 0 always).

use crate::core::state::Vec3;
use std::f64::consts::PI;

/// Area of the lens common to two circles of radii `r1`, `r2` whose centres are `s` apart.
pub fn lens_area(r1: f64, r2: f64, s: f64) -> f64 {
    if s >= r1 + r2 {
        return 0.0;
    }
    if s <= (r1 - r2).abs() {
        return PI * r1.min(r2).powi(2);
    }
    if r1 == r2 {
        // Equal circles (one species): A = 2 r² acos(s/2r) − (s/2) √(4r² − s²), one acos.
        return 2.0 * r1 * r1 * (s / (2.0 * r1)).acos() - 0.5 * s * (4.0 * r1 * r1 - s * s).sqrt();
    }
    let alpha = ((s * s + r1 * r1 - r2 * r2) / (2.0 * s * r1)).clamp(-1.0, 1.0).acos();
    let beta = ((s * s + r2 * r2 - r1 * r1) / (2.0 * s * r2)).clamp(-1.0, 1.0).acos();
    let k = (-s + r1 + r2) * (s + r1 - r2) * (s - r1 + r2) * (s + r1 + r2);
    r1 * r1 * alpha + r2 * r2 * beta - 0.5 * k.max(0.0).sqrt()
}

/// Shadow that neighbour j (at `offset = x_j − x_i`, radius `a_j`) casts on sphere i (radius
/// `a_i`) moving with relative velocity along the unit vector `dir`; zero unless j is upstream,
/// i.e. `offset · dir > 0`.
pub fn shadow_area(a_i: f64, a_j: f64, offset: &Vec3, dir: &Vec3) -> f64 {
    let along = offset.dot(dir);
    if along <= 0.0 {
        return 0.0;
    }
    let lateral = (offset - along * dir).norm();
    lens_area(a_i, a_j, lateral)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lens_area_limits() {
        assert_eq!(lens_area(1.0, 1.0, 2.0), 0.0);
        assert!((lens_area(1.0, 1.0, 0.0) - PI).abs() < 1e-15);
        assert!((lens_area(1.0, 0.5, 0.2) - PI * 0.25).abs() < 1e-15);
        // Equal circles: A = 2 r² acos(s/2r) − (s/2) √(4r² − s²)
        for s in [0.1, 0.5, 1.0, 1.5, 1.9] {
            let exact = 2.0 * (s / 2.0_f64).acos() - 0.5 * s * (4.0 - s * s).sqrt();
            assert!((lens_area(1.0, 1.0, s) - exact).abs() < 1e-14, "s = {s}");
        }
    }
}

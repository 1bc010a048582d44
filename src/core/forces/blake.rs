//! The RPY mobility of equal spheres above a no-slip plane wall (the Rotne–Prager–Blake tensor),
//! a sub-model of the RPY drag: Swan & Brady, Phys. Fluids 19, 113306 (2007), appendix C, built
//! on Blake's image system (Proc. Camb. Phil. Soc. 70, 303, 1971). In the wall's frame (wall at
//! z = 0, fluid at z > 0), in units of 1/(6π μ a):
//!
//! - self, h = z_i/a: M_ii = RPY_ii − (1/16)(9/h − 2/h³ + 1/h⁵)(I − ẑẑ) − (1/8)(9/h − 4/h³ + 1/h⁵) ẑẑ,
//!   i.e. f_∥ = 1/(1 − 9/16 λ + 1/8 λ³ − 1/16 λ⁵), λ = 1/h (Faxén's series without its λ⁴ term);
//! - pair i ≠ j, with j's image x̄_j = x_j − 2 z_j ẑ: R = (x_i − x̄_j)/a, e = R/|R|, e_z = e·ẑ,
//!   ĥ = z_j/(a R_z): M_ij = RPY_ij + C(R, ĥ), the five-tensor correction of appendix C
//!   ([`pair_correction`]); M_ji = M_ijᵀ.
//!
//! Heights are taken no lower than a (1 + `min_gap`), the same rule as the free-fluid drag's wall
//! factor ([`super::wall_drag`]). Positive definite for spheres that do not overlap each other or
//! the wall (Swan & Brady); the Cholesky factor reports the configurations where it is not.

use super::wall_drag::PlaneWall;
use crate::core::state::Vec3;
use nalgebra::Matrix3;

impl PlaneWall {
    /// `x` in the wall's frame: the wall-normal component last, measured from the wall into the
    /// fluid (a reflection where the fluid lies below it: Stokes flow is reflection invariant).
    fn local(&self, x: &Vec3) -> Vec3 {
        let (t1, t2) = ((self.axis + 1) % 3, (self.axis + 2) % 3);
        Vec3::new(x[t1], x[t2], self.height(x))
    }

    /// A block from the wall's frame back to the box's (the inverse of [`Self::local`]).
    fn global(&self, m: &Matrix3<f64>) -> Matrix3<f64> {
        let (t1, t2) = ((self.axis + 1) % 3, (self.axis + 2) % 3);
        let mut q = Matrix3::zeros();
        q[(t1, 0)] = 1.0;
        q[(t2, 1)] = 1.0;
        q[(self.axis, 2)] = self.side;
        q * m * q.transpose()
    }

    /// The wall's corrections to the 3 × 3 blocks of the unbounded mobility (m/(N s)) of spheres
    /// of radius `a` at `positions`, as (i, j, block) with i ≤ j; block(j, i) is the transpose.
    pub fn corrections(&self, positions: &[Vec3], a: f64, viscosity: f64) -> Vec<(usize, usize, Matrix3<f64>)> {
        let unit = 1.0 / (6.0 * std::f64::consts::PI * viscosity * a);
        let floor = a * (1.0 + self.min_gap);
        let local: Vec<Vec3> = positions
            .iter()
            .map(|x| {
                let mut l = self.local(x);
                l.z = l.z.max(floor);
                l / a
            })
            .collect();
        let n = positions.len();
        let mut out = Vec::with_capacity(n * (n + 1) / 2);
        for i in 0..n {
            out.push((i, i, self.global(&self_correction(local[i].z)) * unit));
            for j in i + 1..n {
                out.push((i, j, self.global(&pair_correction(&local[i], &local[j])) * unit));
            }
        }
        out
    }
}

/// The wall's self-mobility correction (units 1/(6π μ a)) at height h = z/a.
pub fn self_correction(h: f64) -> Matrix3<f64> {
    let parallel = -(9.0 / h - 2.0 / h.powi(3) + 1.0 / h.powi(5)) / 16.0;
    let normal = -(9.0 / h - 4.0 / h.powi(3) + 1.0 / h.powi(5)) / 8.0;
    Matrix3::from_diagonal(&Vec3::new(parallel, parallel, normal))
}

/// The wall's correction C to the pair block M_ij (units 1/(6π μ a)) for spheres at `xi`, `xj`
/// (in radii, wall frame), from the image of j: Swan & Brady (2007), appendix C.
pub fn pair_correction(xi: &Vec3, xj: &Vec3) -> Matrix3<f64> {
    let image = Vec3::new(xj.x, xj.y, -xj.z);
    let r_vec = xi - image;
    let r = r_vec.norm();
    let e = r_vec / r;
    let ez = e.z;
    let ez2 = ez * ez;
    let h = xj.z / r_vec.z;
    let (r3, r5) = (r.powi(3), r.powi(5));
    let z = Vec3::z();
    let ee = e * e.transpose();
    let ez_col = e * (z * ez).transpose();
    let z_e = (z * ez) * e.transpose();
    let zz = z * z.transpose();
    let c_ee = -0.25
        * (3.0 * (1.0 - 6.0 * h * (1.0 - h) * ez2) / r - 6.0 * (1.0 - 5.0 * ez2) / r3 + 10.0 * (1.0 - 7.0 * ez2) / r5);
    let c_id = -0.25
        * (3.0 * (1.0 + 2.0 * h * (1.0 - h) * ez2) / r + 2.0 * (1.0 - 3.0 * ez2) / r3 - 2.0 * (2.0 - 5.0 * ez2) / r5);
    let c_ez = 0.5
        * (3.0 * h * (1.0 - 6.0 * (1.0 - h) * ez2) / r - 6.0 * (1.0 - 5.0 * ez2) / r3 + 10.0 * (2.0 - 7.0 * ez2) / r5);
    let c_ze = 0.5 * (3.0 * h / r - 10.0 / r5);
    let c_zz = -(3.0 * h * h * ez2 / r + 3.0 * ez2 / r3 + (2.0 - 15.0 * ez2) / r5);
    ee * c_ee + Matrix3::identity() * c_id + ez_col * c_ez + z_e * c_ze + zz * c_zz
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pair correction is the image of j seen from i; computed the other way round it is the
    /// transpose (the mobility's symmetry), for spheres at different heights and offsets.
    #[test]
    fn the_pair_correction_seen_from_either_sphere_is_the_transpose() {
        for (xi, xj) in [
            (Vec3::new(0.0, 0.0, 1.2), Vec3::new(2.1, 0.0, 1.2)),
            (Vec3::new(0.3, -1.0, 1.5), Vec3::new(2.0, 1.7, 4.0)),
            (Vec3::new(-3.0, 2.0, 7.0), Vec3::new(1.0, 0.5, 1.01)),
        ] {
            let (ij, ji) = (pair_correction(&xi, &xj), pair_correction(&xj, &xi));
            assert!((ij - ji.transpose()).norm() < 1e-14 * ij.norm(), "{xi:?} {xj:?}: {ij:?} vs {ji:?}");
        }
    }
}

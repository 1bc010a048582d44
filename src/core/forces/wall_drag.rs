//! Stokes drag of a sphere translating parallel to a plane wall, a sub-model of the drag term:
//! the factor f_∥ = F / (6π μ a U) at a centre–wall distance h, applied to the components of the
//! relative velocity parallel to the wall (the normal component keeps the free-fluid drag).
//!
//! - h/a ≥ 3.7622: Faxén's series, f_∥ = 1 / (1 − 9/16 λ + 1/8 λ³ − 45/256 λ⁴ − 1/16 λ⁵),
//!   λ = a/h (Faxén 1923; as in Happel & Brenner 1965, §7.4), within 0.01 % of the exact values
//!   there;
//! - 1.005 ≤ h/a < 3.7622: the exact bispherical-coordinate values of O'Neill (1964) as tabulated
//!   by Goldman, Cox & Brenner (Chem. Eng. Sci. 22, 637, 1967) for a translating, non-rotating
//!   sphere, interpolated linearly in (ln δ/a, ln f) with δ = h − a the gap;
//! - δ/a < 0.005: Goldman, Cox & Brenner's lubrication limit f_∥ = −(8/15) ln(δ/a) + 0.9588.
//!
//! The gap is never taken below `min_gap` × a: a sphere resting on a real substrate keeps a gap
//! set by its roughness, and f_∥ diverges (logarithmically) at contact. docs/model.md §7.

use crate::core::state::Vec3;
use std::sync::LazyLock;

/// (h/a, f_∥) of O'Neill (1964) / Goldman, Cox & Brenner (1967), for the interpolated range.
const EXACT: [(f64, f64); 6] =
    [(1.0050, 3.7863), (1.0453, 2.6475), (1.1276, 2.1514), (1.5431, 1.5675), (2.3524, 1.3079), (3.7622, 1.1738)];

/// [`EXACT`] on the interpolation's axes, (ln(h/a − 1), ln f_∥), computed once.
static KNOTS: LazyLock<[(f64, f64); 6]> = LazyLock::new(|| EXACT.map(|(h, f)| ((h - 1.0).ln(), f.ln())));

/// Faxén's series for f_∥ at `h_over_a` = h/a.
pub fn faxen(h_over_a: f64) -> f64 {
    let l = 1.0 / h_over_a;
    1.0 / (1.0 - 9.0 / 16.0 * l + l.powi(3) / 8.0 - 45.0 / 256.0 * l.powi(4) - l.powi(5) / 16.0)
}

/// Goldman, Cox & Brenner's near-contact limit of f_∥ at gap `gap_over_a` = δ/a.
pub fn lubrication(gap_over_a: f64) -> f64 {
    -8.0 / 15.0 * gap_over_a.ln() + 0.9588
}

/// f_∥ at `h_over_a` = h/a (> 1) from the published values and limits above.
pub fn parallel_factor(h_over_a: f64) -> f64 {
    let (first, last) = (EXACT[0], EXACT[EXACT.len() - 1]);
    if h_over_a >= last.0 {
        return faxen(h_over_a);
    }
    if h_over_a < first.0 {
        return lubrication(h_over_a - 1.0);
    }
    let k = EXACT.windows(2).position(|w| h_over_a < w[1].0).unwrap_or(EXACT.len() - 2);
    let ((x0, y0), (x1, y1)) = (KNOTS[k], KNOTS[k + 1]);
    let t = ((h_over_a - 1.0).ln() - x0) / (x1 - x0);
    (y0 + t * (y1 - y0)).exp()
}

/// A plane wall of the box as the drag sees it (this factor, and the RPY mobility above a wall of
/// [`super::blake`]): normal to `axis` at coordinate `position`, the fluid on one side of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneWall {
    /// Axis normal to the wall (0, 1, 2).
    pub axis: usize,
    /// The wall's coordinate along `axis` (m).
    pub position: f64,
    /// +1 when the fluid lies on the wall's positive side (a low face of the box), −1 otherwise.
    pub side: f64,
    /// Smallest sphere–wall gap used, as a fraction of the radius.
    pub min_gap: f64,
}

impl PlaneWall {
    /// The distance from the wall into the fluid of a point at `x` (m).
    pub fn height(&self, x: &Vec3) -> f64 {
        self.side * (x[self.axis] - self.position)
    }
}

/// The parallel-wall factor of one wall of the box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallCorrection {
    pub wall: PlaneWall,
    /// f_∥ at the smallest gap, where a sphere resting on the wall sits.
    at_min_gap: f64,
}

impl WallCorrection {
    pub fn new(wall: PlaneWall) -> Self {
        Self { wall, at_min_gap: parallel_factor(1.0 + wall.min_gap) }
    }

    /// f_∥ of a sphere of radius `a` centred at `x`.
    pub fn factor(&self, x: &Vec3, a: f64) -> f64 {
        let h_over_a = self.wall.height(x) / a;
        if h_over_a <= 1.0 + self.wall.min_gap {
            self.at_min_gap
        } else {
            parallel_factor(h_over_a)
        }
    }

    /// `u` with its components parallel to the wall multiplied by `f`.
    pub fn scale_parallel(&self, u: Vec3, f: f64) -> Vec3 {
        let mut v = u * f;
        v[self.wall.axis] = u[self.wall.axis];
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Faxén's series reproduces the exact values where the model switches to it (0.01 %), and
    /// the lubrication limit the smallest tabulated gap (0.05 %): the pieces meet.
    #[test]
    fn the_pieces_meet_the_published_values_at_their_junctions() {
        let (first, last) = (EXACT[0], EXACT[EXACT.len() - 1]);
        assert!((faxen(last.0) / last.1 - 1.0).abs() < 1e-4, "Faxén {} vs {}", faxen(last.0), last.1);
        assert!((lubrication(first.0 - 1.0) / first.1 - 1.0).abs() < 5e-4);
        for &(h, f) in &EXACT[..EXACT.len() - 1] {
            assert!((parallel_factor(h) / f - 1.0).abs() < 1e-12, "h/a = {h}");
        }
        // Far from the wall the drag is the free one.
        assert!((parallel_factor(1e4) - 1.0).abs() < 1e-4);
    }

    /// The interpolation between published values: leaving out h/a = 1.1276 and interpolating it
    /// from its neighbours misses the exact 2.1514 by 1.1 %, so between the denser actual nodes the
    /// error is below that; and f_∥ falls monotonically with h.
    #[test]
    fn interpolation_error_is_about_one_percent_and_the_factor_is_monotone() {
        let ((h0, f0), (h, f), (h1, f1)) = (EXACT[1], EXACT[2], EXACT[3]);
        let t = ((h - 1.0).ln() - (h0 - 1.0).ln()) / ((h1 - 1.0).ln() - (h0 - 1.0).ln());
        let left_out = (f0.ln() + t * (f1.ln() - f0.ln())).exp();
        assert!((left_out / f - 1.0).abs() < 0.015, "leave-one-out {left_out} vs {f}");
        let mut previous = f64::INFINITY;
        for k in 0..2600 {
            let h = 1.0 + 1e-4 * 1.005_f64.powi(k);
            let f = parallel_factor(h);
            assert!(f < previous, "not monotone at h/a = {h}");
            previous = f;
        }
    }
}

/// `[forces.drag.wall]`: the parallel-wall drag factor (Faxén; Goldman, Cox & Brenner) on the
/// velocity components parallel to one face of the box.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallDragSpec {
    /// The face that is the wall (case 2's substrate: `z-`).
    pub face: FaceSpec,
    /// Smallest sphere–wall gap used, as a fraction of the radius (default 0.01): a sphere
    /// resting on the wall keeps a gap set by its roughness; the factor diverges at contact.
    #[serde(default = "default_min_gap")]
    pub min_gap: f64,
}

fn default_min_gap() -> f64 {
    1e-2
}

impl WallDragSpec {
    /// The wall in `domain`.
    pub fn wall(&self, domain: &crate::core::domain::Domain) -> PlaneWall {
        let (axis, high) = self.face.axis_and_side();
        let position = if high { domain.hi[axis] } else { domain.lo[axis] };
        PlaneWall { axis, position, side: if high { -1.0 } else { 1.0 }, min_gap: self.min_gap }
    }
}

/// A face of the box.
#[derive(Debug, Clone, Copy, serde::Deserialize, PartialEq, Eq)]
pub enum FaceSpec {
    #[serde(rename = "x-")]
    XLow,
    #[serde(rename = "x+")]
    XHigh,
    #[serde(rename = "y-")]
    YLow,
    #[serde(rename = "y+")]
    YHigh,
    #[serde(rename = "z-")]
    ZLow,
    #[serde(rename = "z+")]
    ZHigh,
}

impl FaceSpec {
    /// The face's axis and whether it is the high one.
    pub fn axis_and_side(self) -> (usize, bool) {
        match self {
            FaceSpec::XLow => (0, false),
            FaceSpec::XHigh => (0, true),
            FaceSpec::YLow => (1, false),
            FaceSpec::YHigh => (1, true),
            FaceSpec::ZLow => (2, false),
            FaceSpec::ZHigh => (2, true),
        }
    }
}

impl std::fmt::Display for FaceSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (axis, high) = self.axis_and_side();
        write!(f, "{}{}", ["x", "y", "z"][axis], if high { "+" } else { "-" })
    }
}

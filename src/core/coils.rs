//! Magnetic fields of real coils in free space: circular loops in closed form, straight segments
//! by Biot–Savart, the gradient pairs built from them (Maxwell, Golay), and the gradient tensor
//! of an ideal MRI gradient with the concomitant terms ∇·B = 0 and ∇×B = 0 impose.
//!
//! A coil here is a set of current paths; its field is their sum. Each value returns B (T) at a
//! point (m); [`Coil::jacobian`] gives G_ab = ∂B_a/∂x_b by central differences.

use super::vector::Vec3;
use nalgebra::{Matrix3, Rotation3, Unit};
use std::f64::consts::PI;

/// Vacuum permeability μ0 (T·m/A).
pub const MU0: f64 = 4.0e-7 * PI;

/// Complete elliptic integrals of the first and second kind, K(m) and E(m), of parameter
/// m = k² in [0, 1), by the arithmetic–geometric mean (Abramowitz & Stegun 17.6).
pub fn elliptic_ke(m: f64) -> (f64, f64) {
    let (mut a, mut b, mut c) = (1.0, (1.0 - m).sqrt(), m.sqrt());
    let mut sum = 0.5 * c * c;
    let mut power = 0.5;
    while c.abs() > 1e-16 * a {
        let next = (0.5 * (a + b), (a * b).sqrt(), 0.5 * (a - b));
        (a, b, c) = next;
        power *= 2.0;
        sum += power * c * c;
    }
    let k = PI / (2.0 * a);
    (k, k * (1.0 - sum))
}

/// S(m) = Σ_{n≥2} d_n m^{n−2}, with (1 − m/2) E(m) − (1 − m) K(m) = (π/2) m² S(m) (see
/// [`Loop::field`]); every d_n is positive, so the sum does not cancel. For m < 0.1 it takes at
/// most 17 terms.
fn near_axis_series(m: f64) -> f64 {
    // c_n = ((2n)!/(2^{2n} n!²))², e_n = −c_n/(2n − 1); from n = 1.
    let (mut c_prev, mut e_prev) = (0.25, -0.25);
    let (mut sum, mut power) = (0.0, 1.0);
    for n in 2..64 {
        let ratio = (2 * n - 1) as f64 / (2 * n) as f64;
        let c = c_prev * ratio * ratio;
        let e = -c / (2 * n - 1) as f64;
        let term = (e - 0.5 * e_prev - c + c_prev) * power;
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
        (c_prev, e_prev, power) = (c, e, power * m);
    }
    sum
}

/// A circular loop of radius `radius` about `centre`, its normal `axis`, carrying `current`
/// (A, positive counter-clockwise about the axis).
#[derive(Debug, Clone, Copy)]
pub struct Loop {
    pub centre: Vec3,
    pub axis: Unit<Vec3>,
    pub radius: f64,
    pub current: f64,
}

impl Loop {
    /// B of the loop (Smythe, Static and Dynamic Electricity, §7.10): with ρ, z about the axis,
    /// α² = (a − ρ)² + z², β² = (a + ρ)² + z², m = 1 − α²/β² = 4aρ/β²,
    /// B_z = μ0 I / (2π α² β) [(a² − r²) E + α² K],
    /// B_ρ = μ0 I z / (2π α² β ρ) [(a² + r²) E − α² K], r² = ρ² + z².
    /// The bracket of B_ρ is β² [(1 − m/2) E − (1 − m) K], which cancels to (π/2)(3/16) m² near
    /// the axis and far away (small m): there (m < 0.1) it is summed as its power series
    /// (π/2) Σ_{n≥2} d_n mⁿ, d_n = e_n − e_{n−1}/2 − c_n + c_{n−1} from K = (π/2) Σ c_n mⁿ and
    /// E = (π/2) Σ e_n mⁿ (A & S 17.3.11–12), which keeps B_ρ to round-off (the closed form
    /// loses a factor 1/m² of it, 1e-6 at ρ = 1e-5 a).
    pub fn field(&self, at: Vec3) -> Vec3 {
        let d = at - self.centre;
        let z = d.dot(&self.axis);
        let radial = d - z * self.axis.into_inner();
        let rho = radial.norm();
        let a = self.radius;
        let (alpha2, beta2) = ((a - rho).powi(2) + z * z, (a + rho).powi(2) + z * z);
        let m = 4.0 * a * rho / beta2;
        let (k, e) = elliptic_ke(m);
        let r2 = rho * rho + z * z;
        let scale = MU0 * self.current / (2.0 * PI * alpha2 * beta2.sqrt());
        let bz = scale * ((a * a - r2) * e + alpha2 * k);
        // B_ρ r̂ = b · (x − centre)_⊥, without dividing by ρ: B_ρ/ρ stays finite on the axis.
        let b = if m < 0.1 {
            // scale z β² (π/2) m² S / ρ with m²/ρ = 16 a² ρ / β⁴.
            scale * z * 8.0 * PI * a * a / beta2 * near_axis_series(m)
        } else {
            scale * z / (rho * rho) * ((a * a + r2) * e - alpha2 * k)
        };
        bz * self.axis.into_inner() + b * radial
    }

    /// Distance from `at` to the wire: √((a − ρ)² + z²).
    pub fn distance(&self, at: Vec3) -> f64 {
        let d = at - self.centre;
        let z = d.dot(&self.axis);
        let rho = (d - z * self.axis.into_inner()).norm();
        (self.radius - rho).hypot(z)
    }
}

/// A straight wire from `from` to `to` carrying `current` (A) in that direction.
#[derive(Debug, Clone, Copy)]
pub struct Segment {
    pub from: Vec3,
    pub to: Vec3,
    pub current: f64,
}

impl Segment {
    /// Biot–Savart for a finite segment: with a = from − x, b = to − x,
    /// B = μ0 I / 4π · (a × b)(|a| + |b|) / (|a||b| (|a||b| + a·b)).
    pub fn field(&self, at: Vec3) -> Vec3 {
        let (a, b) = (self.from - at, self.to - at);
        let (la, lb) = (a.norm(), b.norm());
        let (ab, cross) = (a.dot(&b), a.cross(&b));
        // |a||b| + a·b cancels where the segment passes close by (a·b < 0); there it equals
        // |a × b|² / (|a||b| − a·b).
        let sum = if ab < 0.0 { cross.norm_squared() / (la * lb - ab) } else { la * lb + ab };
        let denominator = la * lb * sum;
        if denominator <= 1e-300 {
            return Vec3::zeros();
        }
        MU0 * self.current / (4.0 * PI) * cross * (la + lb) / denominator
    }

    /// Distance from `at` to the wire (to its nearest point, an end included).
    pub fn distance(&self, at: Vec3) -> f64 {
        let along = self.to - self.from;
        let s = ((at - self.from).dot(&along) / along.norm_squared()).clamp(0.0, 1.0);
        (self.from + s * along - at).norm()
    }
}

/// One current path of a coil.
#[derive(Debug, Clone, Copy)]
pub enum Path {
    Loop(Loop),
    Segment(Segment),
}

/// A coil: current paths whose fields add.
#[derive(Debug, Clone, Default)]
pub struct Coil {
    pub paths: Vec<Path>,
}

impl Coil {
    pub fn field(&self, at: Vec3) -> Vec3 {
        self.paths
            .iter()
            .map(|p| match p {
                Path::Loop(l) => l.field(at),
                Path::Segment(s) => s.field(at),
            })
            .sum()
    }

    /// Distance from `at` to the nearest wire of the coil (infinite for a coil without paths).
    pub fn distance(&self, at: Vec3) -> f64 {
        self.paths
            .iter()
            .map(|p| match p {
                Path::Loop(l) => l.distance(at),
                Path::Segment(s) => s.distance(at),
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// G_ab = ∂B_a/∂x_b at `at` by central differences of step h = [`JACOBIAN_STEP`] × d, d the
    /// distance to the nearest wire. Error O(h²): the field of a wire varies on the scale d, so
    /// against the gradient scale |B|/d the truncation error is C (h/d)² (C ≈ 2 measured, from
    /// the error's growth with h) and the round-off ε_B d/h, ε_B ≈ 1e-15 the relative error of
    /// one field evaluation. The sum is least at h/d = (ε_B/2C)^{1/3} ≈ 6e-6; at 5e-6 they are
    /// 5e-11 and 2e-10 (measured in tests/field.rs: within 7e-11 of closed forms, 2.2e-10 of
    /// Richardson differences and of ∇·B = ∇×B = 0).
    pub fn jacobian(&self, at: Vec3) -> Matrix3<f64> {
        let d = self.distance(at);
        if !d.is_finite() {
            return Matrix3::zeros();
        }
        self.gradient(at, JACOBIAN_STEP * d)
    }

    /// Moves every path of the coil by `offset`.
    pub fn translated(mut self, offset: Vec3) -> Self {
        for p in &mut self.paths {
            match p {
                Path::Loop(l) => l.centre += offset,
                Path::Segment(s) => {
                    s.from += offset;
                    s.to += offset;
                }
            }
        }
        self
    }

    /// G_ab = ∂B_a/∂x_b by central differences of step `h` (m): error O(h²) times the field's
    /// third derivative.
    pub fn gradient(&self, at: Vec3, h: f64) -> Matrix3<f64> {
        let mut g = Matrix3::zeros();
        for b in 0..3 {
            let mut step = Vec3::zeros();
            step[b] = h;
            let column = (self.field(at + step) - self.field(at - step)) / (2.0 * h);
            g.set_column(b, &column);
        }
        g
    }

    /// Two coaxial loops of radius `radius` on `axis` through `centre`, `separation` apart, with
    /// currents `current` and `sign × current`.
    fn pair(centre: Vec3, axis: Unit<Vec3>, radius: f64, separation: f64, current: f64, sign: f64) -> Self {
        let offset = 0.5 * separation * axis.into_inner();
        let paths = vec![
            Path::Loop(Loop { centre: centre + offset, axis, radius, current }),
            Path::Loop(Loop { centre: centre - offset, axis, radius, current: sign * current }),
        ];
        Coil { paths }
    }

    /// A Helmholtz pair (separation = radius, equal currents): B = (4/5)^{3/2} μ0 I / a at its
    /// centre, uniform to fourth order.
    pub fn helmholtz(centre: Vec3, axis: Unit<Vec3>, radius: f64, current: f64) -> Self {
        Self::pair(centre, axis, radius, radius, current, 1.0)
    }

    /// A Maxwell pair (separation √3 a, opposed currents): the axial gradient
    /// ∂B_z/∂z = (48 / 7^{5/2}) √3 μ0 I / a² at its centre, linear to third order.
    pub fn maxwell(centre: Vec3, axis: Unit<Vec3>, radius: f64, current: f64) -> Self {
        Self::pair(centre, axis, radius, 3f64.sqrt() * radius, current, -1.0)
    }

    /// A Golay (saddle) pair on a cylinder of radius `radius` about z through the origin: four
    /// saddles whose 120° arcs sit at z = ±0.389 a and ±2.57 a, each arc drawn as `arc_segments`
    /// straight segments and joined to its partner by straight wires along z. It gives a
    /// transverse gradient ∂B_z/∂x at the centre (Golay's design; Turner, Prog. NMR Spectrosc.
    /// 25, 1993).
    pub fn golay(radius: f64, current: f64, arc_segments: usize) -> Self {
        let (inner, outer) = (0.389 * radius, 2.57 * radius);
        let half_arc = PI / 3.0;
        let mut paths = vec![];
        let point = |phi: f64, z: f64| Vec3::new(radius * phi.cos(), radius * phi.sin(), z);
        // Each saddle is centred on φ = 0 (x > 0) or φ = π (x < 0), and on z > 0 or z < 0. Its
        // inner arc runs along +φ on the x > 0 side and along −φ on the x < 0 side, the same at
        // ±z: B_z is then odd in x and even in z.
        for (sense, phi0) in [(1.0, 0.0), (-1.0, PI)] {
            for z_sign in [1.0, -1.0] {
                // A closed saddle: the inner arc, a wire along z, the outer arc back, a wire back.
                let mut corners = vec![];
                for k in 0..=arc_segments {
                    let phi = phi0 - half_arc + 2.0 * half_arc * k as f64 / arc_segments as f64;
                    corners.push(point(phi, z_sign * inner));
                }
                for k in 0..=arc_segments {
                    let phi = phi0 + half_arc - 2.0 * half_arc * k as f64 / arc_segments as f64;
                    corners.push(point(phi, z_sign * outer));
                }
                corners.push(corners[0]);
                for w in corners.windows(2) {
                    paths.push(Path::Segment(Segment { from: w[0], to: w[1], current: sense * current }));
                }
            }
        }
        Coil { paths }
    }
}

/// The step of [`Coil::jacobian`]'s central differences, as a fraction of the distance to the
/// nearest wire: (ε_B/2C)^{1/3} ≈ 6e-6 with ε_B = 1e-15 and C = 2, rounded down.
pub const JACOBIAN_STEP: f64 = 5e-6;

/// The gradient tensor G_ab = ∂B_a/∂x_b of an ideal MRI gradient (Gx, Gy, Gz) = ∇B_z about a
/// static field along z, with the concomitant terms Maxwell's equations impose: ∂B_x/∂z = Gx and
/// ∂B_y/∂z = Gy (∇×B = 0), and ∂B_x/∂x = ∂B_y/∂y = −Gz/2 (∇·B = 0, the symmetric choice of a
/// cylindrical coil).
pub fn mri_gradient(g: Vec3) -> Matrix3<f64> {
    Matrix3::new(-0.5 * g.z, 0.0, g.x, 0.0, -0.5 * g.z, g.y, g.x, g.y, g.z)
}

/// Rotates a gradient tensor into a frame whose z axis is `axis` (for a scanner whose B0 does not
/// lie along the scene's z): G' = R G Rᵀ.
pub fn rotate_gradient(g: &Matrix3<f64>, axis: Unit<Vec3>) -> Matrix3<f64> {
    let r = scanner_rotation(axis);
    r.matrix() * g * r.matrix().transpose()
}

/// The rotation taking z to `axis` by the smallest angle (π about x for −z).
fn scanner_rotation(axis: Unit<Vec3>) -> Rotation3<f64> {
    Rotation3::rotation_between(&Vec3::z(), &axis).unwrap_or_else(|| Rotation3::from_axis_angle(&Vec3::x_axis(), PI))
}

/// The gradient tensor of a scanner whose B0 lies along `axis`, given g = ∇B_∥ (the gradient of
/// the field's component along B0) in scene axes: [`mri_gradient`] of g in the frame whose z is
/// `axis`, rotated back, R G(Rᵀ g) Rᵀ. Its row along B0 is g: b̂ᵀ G = gᵀ.
pub fn scanner_gradient(g: Vec3, axis: Unit<Vec3>) -> Matrix3<f64> {
    let r = scanner_rotation(axis);
    rotate_gradient(&mri_gradient(r.inverse() * g), axis)
}

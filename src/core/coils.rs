//! Magnetic fields of real coils in free space: circular loops in closed form, straight segments
//! by Biot–Savart, the gradient pairs built from them (Maxwell, Golay), and the gradient tensor
//! of an ideal MRI gradient with the concomitant terms ∇·B = 0 and ∇×B = 0 impose.
//!
//! A coil here is a set of current paths; its field is their sum. Each value returns B (T) at a
//! point (m); [`Coil::gradient`] gives G_ab = ∂B_a/∂x_b by central differences.

pub use super::forces::magnetisation::MU0;
use super::vector::Vec3;
use nalgebra::{Matrix3, Rotation3, Unit};
use std::f64::consts::PI;

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
    /// α² = (a − ρ)² + z², β² = (a + ρ)² + z², m = 1 − α²/β²,
    /// B_z = μ0 I / (2π α² β) [(a² − r²) E + α² K],
    /// B_ρ = μ0 I z / (2π α² β ρ) [(a² + r²) E − α² K], r² = ρ² + z².
    pub fn field(&self, at: Vec3) -> Vec3 {
        let d = at - self.centre;
        let z = d.dot(&self.axis);
        let radial = d - z * self.axis.into_inner();
        let rho = radial.norm();
        let a = self.radius;
        let (alpha2, beta2) = ((a - rho).powi(2) + z * z, (a + rho).powi(2) + z * z);
        let (k, e) = elliptic_ke(1.0 - alpha2 / beta2);
        let r2 = rho * rho + z * z;
        let scale = MU0 * self.current / (2.0 * PI * alpha2 * beta2.sqrt());
        let bz = scale * ((a * a - r2) * e + alpha2 * k);
        // B_ρ vanishes on the axis; its formula there is 0/0.
        let b_rho = if rho > 1e-12 * a { scale * z / rho * ((a * a + r2) * e - alpha2 * k) } else { 0.0 };
        let along = if rho > 1e-12 * a { radial / rho } else { Vec3::zeros() };
        bz * self.axis.into_inner() + b_rho * along
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
    let r = Rotation3::rotation_between(&Vec3::z(), &axis)
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vec3::x_axis(), PI));
    r.matrix() * g * r.matrix().transpose()
}

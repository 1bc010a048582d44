//! Aggregates: connected components of particles in contact, and what the paper measures of them.
//!
//! Two particles belong to one aggregate when their gap is at most `gap_tolerance` times the
//! smaller radius (contacting particles overlap slightly, separated ones have a gap; the
//! tolerance only decides borderline pairs, and its effect is reported). Per aggregate:
//! - size: the number of particles;
//! - length: the extent of the centres along the aggregate's principal axis (largest eigenvector
//!   of the centres' covariance) plus one diameter — for a straight chain of n touching spheres
//!   it is n·d, the paper's "major axis length" (assumption: the paper does not define it);
//! - orientation: the angle between the principal axis and the field (0° = along it);
//! - centre-of-mass velocity;
//! - field extent: the extent of the centres along the field plus one diameter, against which a
//!   box edge caps a chain ([`Aggregate::box_limited`]);
//! - percolating: the aggregate wraps through a periodic face onto itself, so that it has no
//!   finite length (its `length` is then NaN, never one box length).
//!
//! Periodic boxes are handled by unwrapping each aggregate through its contacts (minimum-image
//! links). A cycle of links whose images add up to a non-zero lattice vector is a percolating
//! aggregate: following it returns to a member displaced by a box length.

use crate::core::domain::Domain;
use crate::core::neighbours::CellList;
use crate::core::state::Vec3;
use nalgebra::{Matrix3, SymmetricEigen};

#[derive(Debug, Clone, PartialEq)]
pub struct Aggregate {
    pub members: Vec<usize>,
    /// Length along the principal axis plus one diameter (m).
    pub length: f64,
    /// Angle between the principal axis and the field direction, 0°…90° (0 for a single particle).
    pub orientation_deg: f64,
    pub com_velocity: Vec3,
    /// Extent of the centres along the field direction plus one diameter (m).
    pub field_extent: f64,
    /// Connected to itself through a periodic face: an infinite chain in the periodic model.
    pub percolating: bool,
    /// The members' centres unwrapped through their contacts, in `members` order (m).
    pub positions: Vec<Vec3>,
}

/// An aggregate counts as held by the box when its extent along the field is at least this
/// fraction of the box's extent along the field.
pub const BOX_LIMITED_FRACTION: f64 = 0.9;

impl Aggregate {
    pub fn size(&self) -> usize {
        self.members.len()
    }

    /// Whether the box caps this aggregate: it percolates, or its field extent is at least
    /// [`BOX_LIMITED_FRACTION`] of `box_extent`, the box's extent along the field.
    pub fn box_limited(&self, box_extent: f64) -> bool {
        box_limits(self.percolating, self.field_extent, box_extent)
    }
}

/// The box caps an aggregate that percolates or whose field extent is at least
/// [`BOX_LIMITED_FRACTION`] of `box_extent`.
pub fn box_limits(percolating: bool, field_extent: f64, box_extent: f64) -> bool {
    percolating || field_extent >= BOX_LIMITED_FRACTION * box_extent
}

/// The box's extent along `direction`: Σ |dₐ| Lₐ (the edge length for a field along an axis).
pub fn box_extent_along(domain: &Domain, direction: &Vec3) -> f64 {
    let d = direction.try_normalize(0.0).unwrap_or_else(Vec3::x);
    d.abs().dot(&domain.length())
}

/// Finite lengths of `aggregates` (percolating ones have none).
pub fn finite_lengths(aggregates: &[Aggregate]) -> Vec<f64> {
    aggregates.iter().filter(|a| !a.percolating).map(|a| a.length).collect()
}

/// The particles of one frame.
pub struct Frame<'a> {
    pub position: &'a [Vec3],
    pub velocity: &'a [Vec3],
    pub radius: &'a [f64],
    pub mass: &'a [f64],
}

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

/// All aggregates of a frame (single particles included), largest first.
pub fn aggregates(frame: &Frame, domain: &Domain, field_direction: &Vec3, gap_tolerance: f64) -> Vec<Aggregate> {
    let n = frame.position.len();
    let largest = frame.radius.iter().fold(0.0_f64, |a, &r| a.max(r));
    let mut pairs = vec![];
    CellList::default().pairs_within(
        frame.position,
        domain,
        Some(2.0 * largest * (1.0 + gap_tolerance) + 1e-300),
        &mut pairs,
    );
    let mut parent: Vec<usize> = (0..n).collect();
    let mut links: Vec<Vec<(usize, Vec3)>> = vec![vec![]; n];
    for p in &pairs {
        let (i, j) = (p.i as usize, p.j as usize);
        let (ri, rj) = (frame.radius[i], frame.radius[j]);
        if p.dist - ri - rj <= gap_tolerance * ri.min(rj) {
            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
            parent[a] = b;
            // p.r = x_i − x_j (minimum image): j sits at x_i − r.
            links[i].push((j, -p.r));
            links[j].push((i, p.r));
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for i in 0..n {
        let root = find(&mut parent, i);
        groups.entry(root).or_default().push(i);
    }
    let dir = field_direction.try_normalize(0.0).unwrap_or_else(Vec3::x);
    // A cycle returning more than half the shortest periodic edge away from where it started
    // has wrapped around the box.
    let wrap = (0..3).filter(|&k| domain.periodic[k]).map(|k| 0.5 * domain.length()[k]).fold(f64::INFINITY, f64::min);
    let mut out: Vec<Aggregate> =
        groups.into_values().map(|members| describe(frame, &members, &links, &dir, wrap)).collect();
    out.sort_by(|a, b| b.size().cmp(&a.size()).then(a.members[0].cmp(&b.members[0])));
    out
}

fn describe(frame: &Frame, members: &[usize], links: &[Vec<(usize, Vec3)>], dir: &Vec3, wrap: f64) -> Aggregate {
    // Unwrap positions through the contact links (breadth first from the first member); a link
    // to a member already placed elsewhere by a box length closes a wrapping cycle.
    let mut place: std::collections::HashMap<usize, Vec3> = Default::default();
    let mut queue = std::collections::VecDeque::from([members[0]]);
    place.insert(members[0], frame.position[members[0]]);
    let mut percolating = false;
    while let Some(i) = queue.pop_front() {
        let xi = place[&i];
        for &(j, offset) in &links[i] {
            match place.entry(j) {
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(xi + offset);
                    queue.push_back(j);
                }
                std::collections::hash_map::Entry::Occupied(e) => {
                    percolating |= (e.get() - (xi + offset)).norm() > wrap
                }
            }
        }
    }
    let pts: Vec<Vec3> = members.iter().map(|i| place[i]).collect();
    let mass: f64 = members.iter().map(|&i| frame.mass[i]).sum();
    let com_velocity = members.iter().map(|&i| frame.velocity[i] * frame.mass[i]).sum::<Vec3>() / mass;
    let diameter = 2.0 * members.iter().map(|&i| frame.radius[i]).sum::<f64>() / members.len() as f64;
    if pts.len() == 1 {
        let (length, field_extent) = (diameter, diameter);
        return Aggregate {
            members: members.to_vec(),
            length,
            orientation_deg: 0.0,
            com_velocity,
            field_extent,
            percolating,
            positions: pts,
        };
    }
    let centre = pts.iter().sum::<Vec3>() / pts.len() as f64;
    let cov: Matrix3<f64> = pts.iter().map(|p| (p - centre) * (p - centre).transpose()).sum();
    let eig = SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imax();
    let axis: Vec3 = eig.eigenvectors.column(k).into();
    let proj: Vec<f64> = pts.iter().map(|p| (p - centre).dot(&axis)).collect();
    let extent =
        proj.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)) - proj.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let cos = axis.dot(dir).abs().min(1.0);
    let along: Vec<f64> = pts.iter().map(|p| p.dot(dir)).collect();
    let field_extent = along.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - along.iter().fold(f64::INFINITY, |a, &b| a.min(b))
        + diameter;
    let length = if percolating { f64::NAN } else { extent + diameter };
    let orientation_deg = cos.acos().to_degrees();
    Aggregate {
        members: members.to_vec(),
        length,
        orientation_deg,
        com_velocity,
        field_extent,
        percolating,
        positions: pts,
    }
}

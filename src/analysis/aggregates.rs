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
//! - centre-of-mass velocity.
//!
//! Periodic boxes are handled by unwrapping each aggregate through its contacts.

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
}

impl Aggregate {
    pub fn size(&self) -> usize {
        self.members.len()
    }
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
    CellList::default().pairs_within(frame.position, domain, Some(2.0 * largest * (1.0 + gap_tolerance) + 1e-300), &mut pairs);
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
    let mut out: Vec<Aggregate> = groups.into_values().map(|members| describe(frame, &members, &links, &dir)).collect();
    out.sort_by(|a, b| b.size().cmp(&a.size()).then(a.members[0].cmp(&b.members[0])));
    out
}

fn describe(frame: &Frame, members: &[usize], links: &[Vec<(usize, Vec3)>], dir: &Vec3) -> Aggregate {
    // Unwrap positions through the contact links (breadth first from the first member).
    let mut place: std::collections::HashMap<usize, Vec3> = Default::default();
    let mut queue = std::collections::VecDeque::from([members[0]]);
    place.insert(members[0], frame.position[members[0]]);
    while let Some(i) = queue.pop_front() {
        let xi = place[&i];
        for &(j, offset) in &links[i] {
            if let std::collections::hash_map::Entry::Vacant(e) = place.entry(j) {
                e.insert(xi + offset);
                queue.push_back(j);
            }
        }
    }
    let pts: Vec<Vec3> = members.iter().map(|i| place[i]).collect();
    let mass: f64 = members.iter().map(|&i| frame.mass[i]).sum();
    let com_velocity = members.iter().map(|&i| frame.velocity[i] * frame.mass[i]).sum::<Vec3>() / mass;
    let diameter = 2.0 * members.iter().map(|&i| frame.radius[i]).sum::<f64>() / members.len() as f64;
    if pts.len() == 1 {
        return Aggregate { members: members.to_vec(), length: diameter, orientation_deg: 0.0, com_velocity };
    }
    let centre = pts.iter().sum::<Vec3>() / pts.len() as f64;
    let cov: Matrix3<f64> = pts.iter().map(|p| (p - centre) * (p - centre).transpose()).sum();
    let eig = SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imax();
    let axis: Vec3 = eig.eigenvectors.column(k).into();
    let proj: Vec<f64> = pts.iter().map(|p| (p - centre).dot(&axis)).collect();
    let extent = proj.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)) - proj.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let cos = axis.dot(dir).abs().min(1.0);
    Aggregate { members: members.to_vec(), length: extent + diameter, orientation_deg: cos.acos().to_degrees(), com_velocity }
}

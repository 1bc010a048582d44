//! Particles leaving a run: through an outlet (a plane they cross), or captured by the vessel's
//! wall after touching it for a set time. They leave the state; each exit is recorded with the
//! particle's id, where and when, and the particles that stay keep their ids.

use super::forces::contact::VESSEL_FACE;
use super::renumber::Renumbering;
use super::state::{Exit, State, Touching, Vec3, Way};
use nalgebra::Unit;

/// An outlet: the particles whose centre passes the plane through `point` along `normal`,
/// (x − point)·n > 0, leave through it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outlet {
    pub point: Vec3,
    pub normal: Unit<Vec3>,
}

/// How particles leave: the outlets, in order (a particle past several leaves through the first),
/// and the capture rule.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExitRules {
    pub outlets: Vec<Outlet>,
    /// A particle in contact with the vessel's wall for at least this long (s) is captured; 0
    /// captures at the first contact.
    pub capture_after: Option<f64>,
}

impl ExitRules {
    pub fn is_empty(&self) -> bool {
        self.outlets.is_empty() && self.capture_after.is_none()
    }

    /// The particles of `state` that leave now, in slot order, with the way each leaves; updates
    /// `state.touching` from the wall contacts of the last evaluation.
    pub fn leaving(&self, state: &mut State) -> Vec<(usize, Way)> {
        let p = &state.particles;
        let mut leaving = vec![];
        if let Some(after) = self.capture_after {
            // The particles touching the wall now, by id, each with the time it first did: kept
            // from the last step's list, or now. Captured once that is `after` ago.
            let mut now: Vec<(u32, usize)> = state
                .history
                .walls
                .iter()
                .filter(|((_, face), _)| *face == VESSEL_FACE)
                .map(|((i, _), _)| (state.ids[*i as usize], *i as usize))
                .collect();
            now.sort_unstable();
            let mut touching = Touching::with_capacity(now.len());
            for (id, slot) in now {
                let since = match state.touching.binary_search_by_key(&id, |s| s.0) {
                    Ok(k) => state.touching[k].1,
                    Err(_) => state.time,
                };
                if state.time - since >= after {
                    leaving.push((slot, Way::Captured));
                }
                touching.push((id, since));
            }
            state.touching = touching;
        }
        for (i, x) in p.position.iter().enumerate() {
            if let Some(k) = self.outlets.iter().position(|o| (x - o.point).dot(&o.normal) > 0.0) {
                leaving.push((i, Way::Outlet(k as u16)));
            }
        }
        // An outlet wins over a capture in the same step.
        leaving.sort_by_key(|&(i, way)| (i, way == Way::Captured));
        leaving.dedup_by_key(|l| l.0);
        leaving
    }

    /// Records the particles of `leaving` (slots in order) as exits and returns the
    /// renumbering that removes them, for the state and everything that follows it.
    pub fn remove(state: &mut State, leaving: &[(usize, Way)]) -> Renumbering {
        let n = state.particles.len();
        let mut gone = vec![false; n];
        for &(i, way) in leaving {
            gone[i] = true;
            let (id, position) = (state.ids[i], state.particles.position[i]);
            state.exits.push(Exit { id, step: state.step, time: state.time, position, way });
        }
        let mut left: Vec<u32> = leaving.iter().map(|&(i, _)| state.ids[i]).collect();
        left.sort_unstable();
        state.touching.retain(|(id, _)| left.binary_search(id).is_err());
        Renumbering::keeping((0..n as u32).filter(|&i| !gone[i as usize]).collect(), n)
    }
}

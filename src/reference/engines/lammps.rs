//! LAMMPS (29 Sep 2021)'s dialect: `atom_style sphere` (or `hybrid sphere dipole` in the native
//! deck), `pair_style granular` with `hertz/material`, Mindlin tangential and tsuji damping
//! calibrated to LIGGGHTS' restitution damping, `wall/gran granular`, and `lj/cut/dipole/cut`
//! for the native deck's fixed dipoles.

use crate::reference::dialect::{Axis, CylinderWall, Dialect};
use crate::core::forces::contact::law::restitution_beta;
use crate::core::forces::contact::PairMaterial;
use crate::core::state::Species;
use crate::scene::{Scene, SpeciesSpec};
use std::fmt::Write as _;

/// The registered engine (`src/reference/engines/`: build.rs lists every file there).
pub const ENGINE: Lammps = Lammps;

pub struct Lammps;

impl Dialect for Lammps {
    fn name(&self) -> &'static str {
        "lammps"
    }
    fn binary(&self) -> &'static str {
        "lmp"
    }
    fn library(&self) -> &'static str {
        "liblammps.so.0"
    }
    fn refuse_species(&self, species: &[SpeciesSpec]) -> Option<(&'static str, &'static str)> {
        species
            .iter()
            .any(|s| s.restitution < 1.0 && lammps_tsuji_input(s.restitution).is_none())
            .then_some(("species.restitution below 0.11", "LAMMPS' tsuji damping cannot reach LIGGGHTS' damping there"))
    }
    fn native_dipoles(&self) -> bool {
        true
    }
    fn atom_style(&self, native: bool) -> &'static str {
        if native {
            "hybrid sphere dipole"
        } else {
            "sphere"
        }
    }
    fn communicate(&self) -> &'static str {
        "comm_modify vel yes"
    }
    fn neigh_modify(&self) -> &'static str {
        "neigh_modify delay 0\n"
    }
    fn dump_format(&self) -> &'static str {
        "format line"
    }
    fn contact_pair_style(&self) -> &'static str {
        "pair_style granular"
    }
    fn contact_pairs(&self, scene: &Scene, native: bool) -> String {
        let species = &scene.species;
        let n_types = species.len();
        let dipole = native.then(|| DipolePair::of(scene));
        let mut s = String::from(
            "# (E, nu) per pair solved so LAMMPS' effective moduli equal magdem's; tsuji input calibrated.\n",
        );
        let sub_style = match &dipole {
            Some(pair) => {
                let _ = writeln!(s, "pair_style hybrid/overlay granular {}", pair.style());
                " granular"
            }
            None => {
                s += "pair_style granular\n";
                ""
            }
        };
        for a in 0..n_types {
            for b in a..n_types {
                let _ = writeln!(
                    s,
                    "pair_coeff {} {}{sub_style} {}",
                    a + 1,
                    b + 1,
                    lammps_granular_model(&species[a], &species[b], false)
                );
            }
        }
        if let Some(pair) = &dipole {
            s += &pair.coeff(true);
        }
        s
    }
    fn without_contact(&self, scene: &Scene, native: bool) -> String {
        match native.then(|| DipolePair::of(scene)) {
            Some(pair) => {
                format!("# No contact term in the scene.\npair_style {}\n{}", pair.style(), pair.coeff(false))
            }
            None => "# No contact term in the scene.\npair_style none\n".into(),
        }
    }
    fn walls(&self, plane: &str, lo: f64, hi: f64, species: &Species) -> String {
        format!(
            "fix wall_{plane} all wall/gran granular {} {plane} {lo:.17e} {hi:.17e}\n",
            lammps_granular_model(species, species, true)
        )
    }
    /// `zcylinder R`: LAMMPS' only cylinder, along z through x = y = 0, in a box not periodic in
    /// x or y (fix_wall_gran.cpp). It takes the wall's curvature into the contact, R_eff =
    /// a r_w/(a + r_w) with r_w = −2R from inside, where magdem's wall is flat (R_eff = a): at
    /// a = R/10, R_eff is 5 % larger and the contact 2.6 % stiffer (Hertz: k ∝ √R_eff), with the
    /// same restitution (tsuji damping scales with √(m k)).
    fn cylinder_wall(&self, wall: &CylinderWall, species: &Species) -> Result<String, (&'static str, &'static str)> {
        if wall.axis != Axis::Z {
            return Err(("fluid.vessel.axis not along z", "LAMMPS' fix wall/gran has a zcylinder only"));
        }
        if wall.centre.x != 0.0 || wall.centre.y != 0.0 {
            return Err(("fluid.vessel.centre off x = y = 0", "LAMMPS' zcylinder's axis passes through x = y = 0"));
        }
        if wall.periodic[0] || wall.periodic[1] {
            return Err((
                "fluid.vessel in a box periodic in x or y",
                "LAMMPS refuses a zcylinder wall in a periodic dimension",
            ));
        }
        Ok(format!(
            "fix wall_vessel all wall/gran granular {} zcylinder {:.17e}\n",
            lammps_granular_model(species, species, true),
            wall.radius
        ))
    }
}

/// Tsuji's damping coefficient α(e) as LAMMPS evaluates it (pair_granular.cpp).
pub fn tsuji_alpha(e: f64) -> f64 {
    let c = [1.2728, -4.2783, 11.087, -22.348, 27.467, -18.022, 4.8218];
    c.iter().rev().fold(0.0, |acc, k| acc * e + k)
}

/// LAMMPS tsuji input e_in whose damping equals LIGGGHTS' damping for restitution `e`; `None`
/// below e ≈ 0.11, where LIGGGHTS damps more than tsuji's α(0) = 1.2728 can.
pub fn lammps_tsuji_input(e: f64) -> Option<f64> {
    let target = 5.0_f64.sqrt() * restitution_beta(e).abs();
    if target > tsuji_alpha(0.0) {
        return None;
    }
    // α decreases monotonically from α(0) = 1.27 to α(1) ≈ 0: bisection.
    let (mut lo, mut hi) = (1e-6, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tsuji_alpha(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// LAMMPS' Coulomb constant in SI units (its `qqr2e`, force.cpp, `units si`).
const LAMMPS_COULOMB: f64 = 8.9876e9;

/// The electric dipole p that LAMMPS' dipole styles need per unit magnetic moment m for the
/// same force: p = m √(μ0/(4π k_e)) = m √(1e-7/k_e) (REFERENCE-CODES.md).
pub fn electric_per_magnetic() -> f64 {
    (1e-7 / LAMMPS_COULOMB).sqrt()
}

/// The native deck's dipole pair style: `lj/cut/dipole/cut` with the scene's cut-off, ε = 0 (the
/// dipole terms alone) and σ the largest diameter (unused at ε = 0).
struct DipolePair {
    cutoff: f64,
    sigma: f64,
}

impl DipolePair {
    const STYLE: &'static str = "lj/cut/dipole/cut";

    fn of(scene: &Scene) -> Self {
        let sigma = crate::core::state::largest_diameter(&scene.species);
        let diameters = scene.spec.forces.dipole.as_ref().and_then(|p| p.cutoff_diameters);
        DipolePair { cutoff: diameters.expect("native_moments refuses a dipole term without a cut-off") * sigma, sigma }
    }

    fn style(&self) -> String {
        format!("{} {:.17e}", Self::STYLE, self.cutoff)
    }

    /// The coefficient line, with the sub-style's name inside `hybrid/overlay`.
    fn coeff(&self, hybrid: bool) -> String {
        let sub_style = if hybrid { format!(" {}", Self::STYLE) } else { String::new() };
        format!(
            "# Point dipoles as LAMMPS' electric dipoles (p = m sqrt(1e-7/k_e) in data.scene), fixed in the\n\
             # lab frame (nve/sphere without update dipole); LJ switched off (epsilon 0).\n\
             pair_coeff * *{sub_style} 0.0 {:.17e}\n",
            self.sigma
        )
    }
}

/// Young's modulus and Poisson ratio to give LAMMPS so that its effective moduli equal magdem's
/// E* and G* for a pair of species, or for a particle against a wall.
///
/// LAMMPS 2021 forms them as E/(2(1 − ν²)) and E/(4(2 − ν)(1 + ν)) for an explicit pair
/// coefficient, and as E/(2(1 − ν)) and E/(4(2 − ν)(1 + ν)) in `fix wall/gran` (fix_wall_gran.cpp);
/// its automatic mixing of unlike types is not used (the 2021 build's mixing is broken). Solving
/// for (E, ν) with r = E*/G*: pair ν = (r − 4)/(r − 2); wall 2ν² − (2 + r)ν + (r − 4) = 0.
pub fn lammps_equivalent_moduli(m: &PairMaterial, wall: bool) -> (f64, f64) {
    let r = m.e_star / m.g_star;
    if wall {
        let b = 2.0 + r;
        let nu = (b - (b * b - 8.0 * (r - 4.0)).sqrt()) / 4.0;
        (2.0 * (1.0 - nu) * m.e_star, nu)
    } else {
        let nu = (r - 4.0) / (r - 2.0);
        (2.0 * (1.0 - nu * nu) * m.e_star, nu)
    }
}

/// `hertz/material E η ν tangential mindlin NULL x_t μ damping …` for a pair of species (or a
/// species against a wall): tsuji damping calibrated to LIGGGHTS, or no damping when e = 1
/// (tsuji's polynomial is 3e-4, not 0, at e = 1).
fn lammps_granular_model(a: &Species, b: &Species, wall: bool) -> String {
    let m = PairMaterial::new(a, b);
    let (e_mod, nu) = lammps_equivalent_moduli(&m, wall);
    let x_t = 2.0 * (m.g_star / m.e_star).sqrt();
    let restitution = 0.5 * (a.restitution + b.restitution);
    let damping = if restitution >= 1.0 {
        "0 {nu} tangential mindlin NULL 0 {mu} damping viscoelastic".to_string()
    } else {
        let e_in = lammps_tsuji_input(restitution).expect("checked by deck::check");
        format!("{e_in:.17e} {{nu}} tangential mindlin NULL {x_t:.17e} {{mu}} damping tsuji")
    };
    format!(
        "hertz/material {e_mod:.17e} {}",
        damping.replace("{nu}", &format!("{nu:.17e}")).replace("{mu}", &m.friction.to_string())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lammps_moduli_reproduce_the_effective_ones() {
        let sp = crate::scene::Scene::parse(
            "version = 1\n[domain]\nlo = [0,0,0]\nhi = [1,1,1]\n[[species]]\nname = \"a\"\ndiameter = 0.1\ndensity = 1000.0\nyoungs_modulus = 2.0e9\npoisson_ratio = 0.3\nfriction = 0.5\nrestitution = 0.5\n\
             [[species]]\nname = \"b\"\ndiameter = 0.1\ndensity = 1000.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\n\
             [[particles]]\nspecies = \"a\"\npositions = [[0.5, 0.5, 0.5]]\n[integration]\ndt = 1e-6\nend_time = 1e-5\n",
            "t",
        )
        .unwrap()
        .species;
        for (a, b) in [(&sp[0], &sp[0]), (&sp[0], &sp[1]), (&sp[1], &sp[1])] {
            let m = PairMaterial::new(a, b);
            let (e, nu) = lammps_equivalent_moduli(&m, false);
            assert!((e / (2.0 * (1.0 - nu * nu)) / m.e_star - 1.0).abs() < 1e-12);
            assert!((e / (4.0 * (2.0 - nu) * (1.0 + nu)) / m.g_star - 1.0).abs() < 1e-12);
            let (e, nu) = lammps_equivalent_moduli(&m, true);
            assert!((e / (2.0 * (1.0 - nu)) / m.e_star - 1.0).abs() < 1e-12);
            assert!((e / (4.0 * (2.0 - nu) * (1.0 + nu)) / m.g_star - 1.0).abs() < 1e-12);
        }
        // Same material, pair: LAMMPS gets the material's own E and ν back.
        let (e, nu) = lammps_equivalent_moduli(&PairMaterial::new(&sp[1], &sp[1]), false);
        assert!((e / 1.0e9 - 1.0).abs() < 1e-12 && (nu - 0.5).abs() < 1e-12);
    }

    #[test]
    fn tsuji_calibration_matches_liggghts_damping() {
        assert_eq!(lammps_tsuji_input(0.1), None);
        for e in [0.12, 0.3, 0.5, 0.7, 0.9, 0.99] {
            let ln_e: f64 = f64::ln(e);
            let beta = ln_e / (ln_e * ln_e + std::f64::consts::PI.powi(2)).sqrt();
            let e_in = lammps_tsuji_input(e).unwrap();
            assert!((tsuji_alpha(e_in) - 5.0_f64.sqrt() * beta.abs()).abs() < 1e-12, "e = {e}");
        }
        // REFERENCE-CODES.md measured input 0.365 for e = 0.5.
        assert!((lammps_tsuji_input(0.5).unwrap() - 0.365).abs() < 0.003);
    }
}

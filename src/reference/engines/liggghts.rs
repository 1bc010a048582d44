//! LIGGGHTS-PUBLIC 3.8's dialect: `atom_style granular`, materials as `property/global` fixes,
//! `pair_style gran model hertz tangential history`, `wall/gran` primitives.

use crate::reference::dialect::{CylinderWall, Dialect};
use crate::core::state::Species;
use crate::scene::{Scene, SpeciesSpec};
use std::fmt::Write as _;

/// The registered engine (`src/reference/engines/`: build.rs lists every file there).
pub const ENGINE: Liggghts = Liggghts;

pub struct Liggghts;

impl Dialect for Liggghts {
    fn name(&self) -> &'static str {
        "liggghts"
    }
    fn binary(&self) -> &'static str {
        "liggghts"
    }
    fn library(&self) -> &'static str {
        "libliggghts.so.3"
    }
    /// `fix external` in LIGGGHTS 3.8 has no library call to set its callback: the shim does it.
    fn callback_shim(&self) -> Result<Option<&'static str>, &'static str> {
        option_env!("MAGDEM_LIGGGHTS_SHIM").map(Some).ok_or(
            "this magdem was built without the liggghts-shim feature (make build enables it when libliggghts-dev is installed)",
        )
    }
    fn open_returns_instance(&self) -> bool {
        false
    }
    fn refuse_species(&self, species: &[SpeciesSpec]) -> Option<(&'static str, &'static str)> {
        species
            .iter()
            .any(|s| s.restitution <= 0.05)
            .then_some(("species.restitution ≤ 0.05", "LIGGGHTS requires 0.05 < e ≤ 1"))
    }
    fn atom_style(&self, _native: bool) -> &'static str {
        "granular"
    }
    fn communicate(&self) -> &'static str {
        "communicate single vel yes"
    }
    fn settings(&self, species: &[Species]) -> &'static str {
        if species.iter().any(|s| s.youngs_modulus > 1e9 || s.youngs_modulus < 5e6) {
            "# LIGGGHTS checks 5e6 <= E <= 1e9 unless told otherwise\nhard_particles yes\n"
        } else {
            ""
        }
    }
    /// LIGGGHTS resets a pair's shear history only while the pair is within
    /// contact_distance_factor × (r_i + r_j) but not touching; at its default 1.0 that never
    /// happens, and a pair that separates and touches again within the neighbour list starts with
    /// the stale history. magdem (and LAMMPS) reset it at separation; 1.1 makes LIGGGHTS do so.
    fn neigh_modify(&self) -> &'static str {
        "neigh_modify delay 0 contact_distance_factor 1.1\n"
    }
    fn dump_format(&self) -> &'static str {
        "format"
    }
    fn contact_pair_style(&self) -> &'static str {
        "pair_style gran model hertz tangential history"
    }
    fn contact_pairs(&self, scene: &Scene, _native: bool) -> String {
        let species = &scene.species;
        let n_types = species.len();
        let list = |f: &dyn Fn(usize) -> f64| (0..n_types).map(|k| format!("{:e}", f(k))).collect::<Vec<_>>().join(" ");
        let matrix = |f: &dyn Fn(usize, usize) -> f64| {
            (0..n_types * n_types).map(|k| format!("{:e}", f(k / n_types, k % n_types))).collect::<Vec<_>>().join(" ")
        };
        let mut s = String::new();
        let _ = writeln!(
            s,
            "fix m1 all property/global youngsModulus peratomtype {}",
            list(&|k| species[k].youngs_modulus)
        );
        let _ =
            writeln!(s, "fix m2 all property/global poissonsRatio peratomtype {}", list(&|k| species[k].poisson_ratio));
        let _ = writeln!(
            s,
            "fix m3 all property/global coefficientRestitution peratomtypepair {n_types} {}",
            matrix(&|a, b| 0.5 * (species[a].restitution + species[b].restitution))
        );
        let _ = writeln!(
            s,
            "fix m4 all property/global coefficientFriction peratomtypepair {n_types} {}",
            matrix(&|a, b| 0.5 * (species[a].friction + species[b].friction))
        );
        s + self.contact_pair_style() + "\npair_coeff * *\n"
    }
    fn walls(&self, plane: &str, lo: f64, hi: f64, _species: &Species) -> String {
        let fix = "all wall/gran model hertz tangential history primitive type 1";
        format!("fix wall_{plane}_lo {fix} {plane} {lo:.17e}\nfix wall_{plane}_hi {fix} {plane} {hi:.17e}\n")
    }
    /// `primitive type 1 xcylinder|ycylinder|zcylinder R c1 c2`: the centre's coordinates on the
    /// two other axes in cyclic order (y z, z x, x y: `Cylinder<dim>` in LIGGGHTS'
    /// primitive_wall_definitions.h). Its contact is a flat wall's (effective radius a), touched
    /// from either side, as magdem's from inside.
    fn cylinder_wall(&self, wall: &CylinderWall, _species: &Species) -> Result<String, (&'static str, &'static str)> {
        let [c1, c2] = wall.axis.transverse().map(|a| wall.centre[a.index()]);
        Ok(format!(
            "fix wall_vessel all wall/gran model hertz tangential history primitive type 1 {}cylinder {:.17e} {c1:.17e} {c2:.17e}\n",
            wall.axis.name(),
            wall.radius
        ))
    }
}

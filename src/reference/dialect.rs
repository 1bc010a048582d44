//! What differs between the reference engines: their binaries and libraries, what their decks
//! can hold, and the lines in which a deck says the same thing. One implementation per engine
//! ([`super::liggghts`], [`super::lammps`]); everything else in a deck is common.

use crate::core::state::{Species, Vec3};
use crate::scene::{Scene, SpeciesSpec};

/// A coordinate axis, along which a deck's vessel runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// 0, 1, 2.
    pub fn index(self) -> usize {
        self as usize
    }

    /// "x", "y", "z".
    pub fn name(self) -> &'static str {
        ["x", "y", "z"][self.index()]
    }

    /// The axis a unit vector lies along (its other two components exactly zero), and its sign.
    pub fn of(direction: &Vec3) -> Option<(Axis, f64)> {
        let axes = [Axis::X, Axis::Y, Axis::Z];
        let mut along = axes.into_iter().filter(|a| direction[a.index()] != 0.0);
        match (along.next(), along.next()) {
            (Some(a), None) => Some((a, direction[a.index()].signum())),
            _ => None,
        }
    }

    /// The other two axes, in cyclic order after this one (y z, z x, x y).
    pub fn transverse(self) -> [Axis; 2] {
        let axes = [Axis::X, Axis::Y, Axis::Z];
        [axes[(self.index() + 1) % 3], axes[(self.index() + 2) % 3]]
    }
}

/// A straight vessel's wall as a deck writes it: the cylinder of `radius` about the line along
/// `axis` through `centre`.
#[derive(Debug, Clone, Copy)]
pub struct CylinderWall {
    pub axis: Axis,
    pub centre: Vec3,
    pub radius: f64,
    /// Which axes of the box are periodic.
    pub periodic: [bool; 3],
}

/// A reference engine's dialect.
pub trait Dialect: Sync {
    /// The name in messages, decks and the command line.
    fn name(&self) -> &'static str;
    /// The executable on the PATH.
    fn binary(&self) -> &'static str;
    /// The shared library of the in-process route.
    fn library(&self) -> &'static str;
    /// The in-process route's callback shim, a shared object built with magdem, if the engine
    /// needs one to set a `fix external` callback; `Err` says why this build has none.
    fn callback_shim(&self) -> Result<Option<&'static str>, &'static str> {
        Ok(None)
    }
    /// The library's `lammps_open_no_mpi` returns the instance (LAMMPS since 2020) rather than
    /// writing it through its third argument (LIGGGHTS 3.8).
    fn open_returns_instance(&self) -> bool {
        true
    }
    /// A species this engine cannot hold, beyond what no deck holds: (term, why).
    fn refuse_species(&self, _species: &[SpeciesSpec]) -> Option<(&'static str, &'static str)> {
        None
    }
    /// Whether the engine has a dipole pair style of its own (the native deck).
    fn native_dipoles(&self) -> bool {
        false
    }
    /// `atom_style`, with the dipole style of a native deck.
    fn atom_style(&self, native: bool) -> &'static str;
    /// The line that sends ghost velocities (granular pair styles need them).
    fn communicate(&self) -> &'static str;
    /// Settings the engine needs before `read_data` for these species.
    fn settings(&self, _species: &[Species]) -> &'static str {
        ""
    }
    /// The `neigh_modify` line (with its reasons as comments).
    fn neigh_modify(&self) -> &'static str;
    /// The `dump_modify` keyword that sets a format for the whole line.
    fn dump_format(&self) -> &'static str;
    /// The contact pair style's line, as the deck writes it (`pair_style …`).
    fn contact_pair_style(&self) -> &'static str;
    /// Materials, pair style and coefficients of the contact law; `native`: with the engine's
    /// dipole pair style overlaid.
    fn contact_pairs(&self, scene: &Scene, native: bool) -> String;
    /// The pair section of a scene without contact.
    fn without_contact(&self, _scene: &Scene, _native: bool) -> String {
        "# No contact term in the scene.\npair_style none\n".into()
    }
    /// The fix(es) of the plane walls normal to `plane` (`xplane` …) at `lo` and `hi`, of the
    /// material of `species`.
    fn walls(&self, plane: &str, lo: f64, hi: f64, species: &Species) -> String;
    /// The fix of a vessel's cylindrical wall, of the material of `species`, touched from inside;
    /// `Err((term, why))` for a cylinder the engine's primitive cannot hold.
    fn cylinder_wall(&self, wall: &CylinderWall, species: &Species) -> Result<String, (&'static str, &'static str)>;
}

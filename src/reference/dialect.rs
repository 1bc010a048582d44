//! What differs between the reference engines: their binaries and libraries, what their decks
//! can hold, and the lines in which a deck says the same thing. One implementation per engine
//! ([`super::liggghts`], [`super::lammps`]); everything else in a deck is common.

use crate::core::state::Species;
use crate::scene::{Scene, SpeciesSpec};

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
}

//! Numerical studies of the solver itself: accuracy against time step, stability (largest stable
//! step, stiff and extreme cases, dipole cut-off error).

pub mod accuracy;
pub mod stability;

/// The paper's 11 µm Fe3O4 species "p" (μr = 12.3) at Young's modulus `youngs_modulus` and
/// restitution `restitution`, with `extra` keys appended, as a `[[species]]` block.
pub fn fe3o4(youngs_modulus: f64, restitution: f64, extra: &str) -> String {
    format!(
        "[[species]]\nname = \"p\"\ndiameter = 11.0e-6\ndensity = 1087.0\nyoungs_modulus = {youngs_modulus:e}\npoisson_ratio = 0.5\n\
         friction = 0.5\nrestitution = {restitution:?}\nrelative_permeability = 12.3\n{extra}"
    )
}

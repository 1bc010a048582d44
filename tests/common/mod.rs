//! Scene pieces shared by the integration tests.

/// Still water, a uniform 0.4 T field along x and the paper's case-1 species "p" (Fe3O4, 11 µm,
/// restitution 0.5 — the scenes' assumption).
pub const WATER_FIELD_FE3O4: &str = r#"[fluid]
density = 1000.0
viscosity = 1.0e-3
[field]
b0 = [0.4, 0.0, 0.0]
[[species]]
name = "p"
diameter = 11.0e-6
density = 1087.0
youngs_modulus = 1.0e9
poisson_ratio = 0.5
friction = 0.5
restitution = 0.5
relative_permeability = 12.3
"#;

/// A scene: `head` (version, name, domain), the shared fluid, field and species, then `tail`.
pub fn scene(head: &str, tail: &str) -> String {
    format!("{head}{WATER_FIELD_FE3O4}{tail}")
}

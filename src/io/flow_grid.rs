//! Flow fields on a regular grid, as CFD users export them: HDF5 (any number of frames) or VTK's
//! legacy STRUCTURED_POINTS format (one frame, ASCII), read into [`GriddedFlow`].
//!
//! HDF5 layout (docs/scenes.md): `origin` (3), `spacing` (3), `velocity` (T, nx, ny, nz, 3) or
//! (nx, ny, nz, 3) for one frame, and `time` (T) when there are several frames; metres, m/s, s.

use crate::core::flow::GriddedFlow;
use crate::core::state::Vec3;
use std::path::Path;

/// Reads the grid in `path`: HDF5 unless the name ends in `.vtk`. The error names what is wrong.
pub fn read(path: &Path) -> Result<GriddedFlow, String> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("vtk") => read_vtk(path),
        _ => read_hdf5(path),
    }
}

fn read_hdf5(path: &Path) -> Result<GriddedFlow, String> {
    let file = hdf5::File::open(path).map_err(|e| format!("cannot open it as HDF5 ({e})"))?;
    let dataset = |name: &str| file.dataset(name).map_err(|_| format!("it has no `{name}` dataset"));
    let vector = |name: &str| -> Result<Vec3, String> {
        let v: Vec<f64> = dataset(name)?.read_raw().map_err(|e| format!("`{name}`: {e}"))?;
        match v[..] {
            [x, y, z] => Ok(Vec3::new(x, y, z)),
            _ => Err(format!("`{name}` has {} values, not 3", v.len())),
        }
    };
    let (origin, spacing) = (vector("origin")?, vector("spacing")?);
    let velocity = dataset("velocity")?;
    let shape = velocity.shape();
    let (frames, nodes) = match shape[..] {
        [nx, ny, nz, 3] => (1, [nx, ny, nz]),
        [t, nx, ny, nz, 3] => (t, [nx, ny, nz]),
        _ => return Err(format!("`velocity` has shape {shape:?}, not (T, nx, ny, nz, 3) or (nx, ny, nz, 3)")),
    };
    let values: Vec<f64> = velocity.read_raw().map_err(|e| format!("`velocity`: {e}"))?;
    let times: Vec<f64> = match file.dataset("time") {
        Ok(ds) => ds.read_raw().map_err(|e| format!("`time`: {e}"))?,
        Err(_) if frames == 1 => vec![0.0],
        Err(_) => return Err(format!("it has {frames} frames and no `time` dataset")),
    };
    if times.len() != frames {
        return Err(format!("`time` has {} values for {frames} frames", times.len()));
    }
    let velocity = values.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    Ok(GriddedFlow { origin, spacing, shape: nodes, times, period: None, velocity })
}

/// VTK legacy ASCII STRUCTURED_POINTS with DIMENSIONS, ORIGIN, SPACING (or ASPECT_RATIO) and
/// POINT_DATA holding one VECTORS array, x varying fastest (VTK's order).
fn read_vtk(path: &Path) -> Result<GriddedFlow, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read it ({e})"))?;
    let mut lines = text.lines();
    if !lines.next().is_some_and(|l| l.starts_with("# vtk DataFile")) {
        return Err("it is not a legacy VTK file (no `# vtk DataFile` header)".into());
    }
    lines.next(); // the title
    if lines.next().map(str::trim) != Some("ASCII") {
        return Err("only ASCII legacy VTK is read".into());
    }
    let mut words = lines.flat_map(str::split_whitespace);
    let numbers = |n: usize, what: &str, words: &mut dyn Iterator<Item = &str>| -> Result<Vec<f64>, String> {
        (0..n)
            .map(|_| words.next().and_then(|w| w.parse::<f64>().ok()).ok_or(format!("{what}: expected {n} numbers")))
            .collect()
    };
    let (mut dims, mut origin, mut spacing) = (None, None, None);
    let mut vectors = None;
    while let Some(word) = words.next() {
        match word.to_ascii_uppercase().as_str() {
            "DATASET" => {
                let kind = words.next().unwrap_or("");
                if !kind.eq_ignore_ascii_case("STRUCTURED_POINTS") {
                    return Err(format!("DATASET {kind}: only STRUCTURED_POINTS (a regular grid) is read"));
                }
            }
            "DIMENSIONS" => dims = Some(numbers(3, "DIMENSIONS", &mut words)?),
            "ORIGIN" => origin = Some(numbers(3, "ORIGIN", &mut words)?),
            "SPACING" | "ASPECT_RATIO" => spacing = Some(numbers(3, "SPACING", &mut words)?),
            "POINT_DATA" => {
                numbers(1, "POINT_DATA", &mut words)?;
            }
            "VECTORS" => {
                words.next(); // name
                words.next(); // type
                let d = dims.as_ref().ok_or("VECTORS before DIMENSIONS")?;
                let n = (d[0] * d[1] * d[2]) as usize;
                vectors = Some(numbers(3 * n, "VECTORS", &mut words)?);
                break;
            }
            _ => {}
        }
    }
    let (Some(d), Some(o), Some(s), Some(v)) = (dims, origin, spacing, vectors) else {
        return Err("it lacks DIMENSIONS, ORIGIN, SPACING or a VECTORS array".into());
    };
    let shape = [d[0] as usize, d[1] as usize, d[2] as usize];
    // VTK runs x fastest; the grid stores z fastest.
    let mut velocity = vec![Vec3::zeros(); shape.iter().product()];
    for k in 0..shape[2] {
        for j in 0..shape[1] {
            for i in 0..shape[0] {
                let at = 3 * ((k * shape[1] + j) * shape[0] + i);
                velocity[(i * shape[1] + j) * shape[2] + k] = Vec3::new(v[at], v[at + 1], v[at + 2]);
            }
        }
    }
    Ok(GriddedFlow {
        origin: Vec3::new(o[0], o[1], o[2]),
        spacing: Vec3::new(s[0], s[1], s[2]),
        shape,
        times: vec![0.0],
        period: None,
        velocity,
    })
}

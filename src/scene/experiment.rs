//! Experiment files: sweeps over scene parameters by reference to base scenes.
//!
//! ```toml
//! name = "case1-seeds"                 # runs go to runs/<name>/ unless `output` says otherwise
//! bases = ["scenes/case1-c0.563.toml"] # relative to this file
//! [sweep]                               # Cartesian product of every list (keys in
//!                                       # alphabetical order name the runs)
//! seed = [1, 2, 3]
//! "integration.dt" = [1e-8, 5e-9]       # any scene key by dotted path; array items by index,
//! "particles.0.count" = [100, 200]      # e.g. the first [[particles]] group
//! engine = ["magdem", "liggghts"]       # not a scene key: which solver runs the point
//!
//! [variants.no-induction]               # optional named override sets, one at a time: every
//! "forces.dipole.induction" = "none"    # point runs once per variant (plus the unchanged base
//!                                       # when `variants.base = {}` is listed)
//! ```
//!
//! Each point is its base scene with the overrides applied, written back as TOML: that text is
//! what the run stores and hashes, so a trajectory always says exactly what produced it.

use super::{Scene, SceneError};
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentSpec {
    pub name: String,
    pub description: Option<String>,
    /// Base scenes, relative to the experiment file.
    pub bases: Vec<PathBuf>,
    /// Output directory (default runs/<name>), relative to the current directory.
    pub output: Option<PathBuf>,
    /// Dotted scene key (or `engine`) → values.
    #[serde(default)]
    pub sweep: toml::Table,
    /// Variant name → dotted scene key → value; crossed with the sweep.
    #[serde(default)]
    pub variants: toml::Table,
}

/// One run of an experiment.
#[derive(Debug, Clone)]
pub struct Point {
    /// File-name-safe identifier: base stem plus the overrides.
    pub id: String,
    pub base: PathBuf,
    /// The variant's name, when the experiment lists variants.
    pub variant: Option<String>,
    pub overrides: Vec<(String, toml::Value)>,
    pub engine: String,
    pub scene: Scene,
}

pub struct Experiment {
    pub spec: ExperimentSpec,
    pub output: PathBuf,
    pub points: Vec<Point>,
}

fn invalid(key: &str, value: impl std::fmt::Display, reason: impl Into<String>) -> SceneError {
    SceneError::Invalid { key: key.to_string(), value: value.to_string(), reason: reason.into() }
}

/// Sets `path` (dotted; numeric parts index arrays) in `table` to `value`.
fn set_path(table: &mut toml::Table, path: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = path.split('.').collect();
    let mut node = toml::Value::Table(std::mem::take(table));
    let result = (|| {
        let mut cursor = &mut node;
        for (k, part) in parts.iter().enumerate() {
            let last = k + 1 == parts.len();
            cursor = match cursor {
                toml::Value::Table(t) => {
                    if last {
                        t.insert(part.to_string(), value.clone());
                        return Ok(());
                    }
                    t.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()))
                }
                toml::Value::Array(a) => {
                    let i: usize =
                        part.parse().map_err(|_| format!("`{part}` indexes an array: it must be a number"))?;
                    let len = a.len();
                    let slot = a.get_mut(i).ok_or_else(|| format!("index {i} beyond the {len} entries"))?;
                    if last {
                        *slot = value.clone();
                        return Ok(());
                    }
                    slot
                }
                _ => return Err(format!("`{}` is not a table or array", parts[..k].join("."))),
            };
        }
        Ok(())
    })();
    if let toml::Value::Table(t) = node {
        *table = t;
    }
    result
}

fn slug(value: &toml::Value) -> String {
    let text = match value {
        toml::Value::String(s) => s.clone(),
        toml::Value::Float(f) => format!("{f:e}"),
        other => other.to_string(),
    };
    text.chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' }).collect()
}

impl Experiment {
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| SceneError::Read { path: path.display().to_string(), source })?;
        let spec: ExperimentSpec = toml::from_str(&text).map_err(|e| SceneError::Syntax {
            origin: path.display().to_string(),
            line: e.span().map_or(0, |s| text[..s.start.min(text.len())].lines().count().max(1)),
            message: e.message().trim().replace('\n', " "),
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        if spec.bases.is_empty() {
            return Err(invalid("bases", "[]", "name at least one base scene"));
        }
        // The sweep's axes, in file order; each value list non-empty.
        let mut axes: Vec<(String, Vec<toml::Value>)> = vec![];
        for (key, values) in &spec.sweep {
            let list = match values {
                toml::Value::Array(a) if !a.is_empty() => a.clone(),
                other => return Err(invalid(&format!("sweep.{key}"), other, "must be a non-empty list of values")),
            };
            if key == "engine" {
                for v in &list {
                    if !matches!(v.as_str(), Some("magdem" | "liggghts" | "lammps")) {
                        return Err(invalid("sweep.engine", v, "one of \"magdem\", \"liggghts\", \"lammps\""));
                    }
                }
            }
            axes.push((key.clone(), list));
        }
        type Edits = Vec<(String, toml::Value)>;
        let mut variants: Vec<(Option<String>, Edits)> = vec![];
        for (name, table) in &spec.variants {
            let toml::Value::Table(table) = table else {
                return Err(invalid(&format!("variants.{name}"), table, "must be a table of dotted scene keys"));
            };
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '.') {
                return Err(invalid(&format!("variants.{name}"), name, "names use letters, digits, '-' and '.'"));
            }
            // `[variants.mu-r-12.3]` is the table `3` inside the variant `mu-r-12`: its keys are
            // dotted scene keys, which no scene section has.
            for (key, value) in table {
                if let toml::Value::Table(inner) = value {
                    if inner.keys().any(|k| k.contains('.')) || key.parse::<f64>().is_ok() {
                        return Err(invalid(
                            &format!("variants.{name}.{key}"),
                            value,
                            format!("a variant's name with a dot needs quotes: [variants.\"{name}.{key}\"]"),
                        ));
                    }
                }
            }
            variants.push((Some(name.clone()), table.iter().map(|(k, v)| (k.clone(), v.clone())).collect()));
        }
        if variants.is_empty() {
            variants.push((None, vec![]));
        }
        let mut combos: Vec<Vec<(String, toml::Value)>> = vec![vec![]];
        for (key, values) in &axes {
            combos = combos
                .into_iter()
                .flat_map(|c| values.iter().map(move |v| [c.clone(), vec![(key.clone(), v.clone())]].concat()))
                .collect();
        }
        let mut points = vec![];
        for base in &spec.bases {
            let base_path = dir.join(base);
            let base_text = std::fs::read_to_string(&base_path)
                .map_err(|source| SceneError::Read { path: base_path.display().to_string(), source })?;
            let base_table: toml::Table = toml::from_str(&base_text).map_err(|e| SceneError::Syntax {
                origin: base_path.display().to_string(),
                line: 0,
                message: e.message().trim().replace('\n', " "),
            })?;
            let stem = base_path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().to_string());
            for ((variant, fixed), combo) in variants.iter().flat_map(|v| combos.iter().map(move |c| (v, c))) {
                let mut table = base_table.clone();
                let mut engine = "magdem".to_string();
                let mut id = stem.clone();
                if let Some(name) = variant {
                    id += &format!("__{name}");
                }
                for (key, value) in fixed {
                    if key == "engine" {
                        return Err(invalid(
                            &format!("variants.{}.engine", variant.as_deref().unwrap_or("")),
                            value,
                            "sweep engines with `sweep.engine`",
                        ));
                    }
                    set_path(&mut table, key, value.clone()).map_err(|why| {
                        invalid(&format!("variants.{}.{key}", variant.as_deref().unwrap_or("")), value, why)
                    })?;
                }
                for (key, value) in combo {
                    id += &format!("__{}-{}", key.rsplit('.').next().unwrap_or(key), slug(value));
                    if key == "engine" {
                        engine = value.as_str().unwrap_or("magdem").to_string();
                        continue;
                    }
                    set_path(&mut table, key, value.clone())
                        .map_err(|why| invalid(&format!("sweep.{key}"), value, why))?;
                }
                let overrides: Vec<(String, toml::Value)> = fixed.iter().chain(combo).cloned().collect();
                let text = format!(
                    "# Experiment {} point {id}: {} with {}\n{}",
                    spec.name,
                    base.display(),
                    if overrides.is_empty() {
                        "no overrides".to_string()
                    } else {
                        overrides.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", ")
                    },
                    toml::to_string(&table).map_err(|e| invalid("sweep", "…", e.to_string()))?
                );
                let origin = format!("{} ({id})", path.display());
                let scene = Scene::parse_in(&text, &origin, base_path.parent().unwrap_or(Path::new(".")))?;
                points.push(Point { id, base: base.clone(), variant: variant.clone(), overrides, engine, scene });
            }
        }
        let output = spec.output.clone().unwrap_or_else(|| PathBuf::from("runs").join(&spec.name));
        Ok(Self { spec, output, points })
    }
}

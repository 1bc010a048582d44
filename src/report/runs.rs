//! The runs behind a report: every point of a set of experiment files, with the aggregates of
//! its last frame and the mean aggregate length at every frame.

use crate::analysis::aggregates::{box_limits, Aggregate};
use crate::analysis::image::Imaging;
use crate::analysis::stats::summary;
use crate::analysis::trajectory::FrameReader;
use crate::core::state::Vec3;
use crate::io::trajectory::{status, Trajectory};
use crate::scene::experiment::Experiment;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// How the experiment's microscope is emulated ([`Run::image`]): the imaging plane x–y (the
/// field, along x, lies in it; the view is along gravity) and pixels of 0.5 µm.
pub const IMAGING: Imaging = Imaging { axes: [0, 1], pixel: 0.5e-6 };

/// The version of [`Run::image`]'s measurement: digests made with another are not read back.
pub const IMAGE_MEASURE_VERSION: u32 = 1;

/// The Table 3 ensemble: the default experiment and its opt-in continuation to 20 seeds (the
/// runs that are imaged, [`Run::image`]).
pub const TABLE3: [&str; 2] = ["paper-table3", "paper-table3-seeds"];

/// Mean of lengths in metres as µm, NaN for none.
pub fn mean_um(lengths: &[f64]) -> f64 {
    if lengths.is_empty() {
        f64::NAN
    } else {
        1e6 * summary(lengths).mean
    }
}

/// One point of an experiment and what its trajectory holds.
#[derive(Default)]
pub struct Run {
    pub experiment: String,
    pub id: String,
    /// SHA-256 of the point's resolved scene (what its trajectory and digest are checked against).
    pub scene_hash: String,
    /// The base scene's name (e.g. `case1-c2.25`).
    pub scene: String,
    pub variant: String,
    /// The variant's own overrides (`key = value`), without the sweep's.
    pub variant_overrides: Vec<String>,
    pub seed: u64,
    pub engine: String,
    /// Mass concentration of the first particle group (mg/ml), NaN when placed otherwise.
    pub concentration: f64,
    /// Magnetisation of an isolated particle of the first species in the applied field at the
    /// box centre (A/m; saturation law applied, mutual induction not).
    pub magnetisation: f64,
    /// Fluid viscosity (Pa·s), NaN without a fluid.
    pub viscosity: f64,
    pub particles: usize,
    pub overrides: String,
    /// `completed`, `unstable`, `running`, `interrupted` or `missing`.
    pub status: String,
    pub message: String,
    pub wall_time: f64,
    /// The commit of the magdem build that ran it (empty where not recorded).
    pub build: String,
    /// Threads the run's last piece ran on (engine processes for a reference engine); NaN where
    /// the trajectory or digest predates the record.
    pub threads: f64,
    pub file: PathBuf,
    pub times: Vec<f64>,
    /// Mean aggregate length at each frame (m), over the aggregates that do not percolate.
    pub mean_length: Vec<f64>,
    /// Fraction of each frame's aggregates that the box caps ([`Aggregate::box_limited`]).
    pub box_limited: Vec<f64>,
    /// The box's extent along the field (m).
    pub box_extent: f64,
    /// Aggregates of the last frame.
    pub last: Vec<AggregateSummary>,
    /// The last frame as an image measures it (µm; [`IMAGING`]):
    /// projected and image MajorAxisLength means, each over all aggregates and over those of two
    /// or more particles. Measured on the Table 3 runs only; `None` for the others.
    pub image: Option<[f64; 4]>,
    /// The run's scene as written (TOML).
    pub scene_text: String,
    /// Where this run's numbers were read: its trajectory, or the report's digest of it.
    pub source: Source,
}

/// Where a [`Run`]'s numbers come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Source {
    /// Nothing read (missing, stale or unreadable).
    #[default]
    None,
    /// The run's trajectory file.
    Trajectory,
    /// A report's digest of a trajectory no longer on this machine ([`super::digest`]).
    Digest,
}

impl Source {
    /// How the runs table names it.
    pub fn name(self) -> &'static str {
        match self {
            Source::None => "",
            Source::Trajectory => "trajectory",
            Source::Digest => "digest",
        }
    }
}

/// What a report keeps of one of the last frame's aggregates ([`Aggregate`] without its members'
/// positions), so that a digest can hold it.
#[derive(Debug, Clone, PartialEq)]
pub struct AggregateSummary {
    pub size: usize,
    /// Length along the principal axis plus one diameter (m), NaN when percolating.
    pub length: f64,
    /// Extent of the centres along the field plus one diameter (m).
    pub field_extent: f64,
    pub orientation_deg: f64,
    /// Centre-of-mass velocity at the last frame (m/s).
    pub com_velocity: Vec3,
    pub percolating: bool,
    /// x velocity as the members' mean displacement over the last tenth of the run divided by
    /// that time (m/s): what tracking an aggregate measures, free of the instantaneous velocity
    /// of collisions.
    pub tracked_vx: f64,
    /// A member within three radii of an x wall (the gradient's direction in case 2): the wall
    /// holds the aggregate, it does not move freely.
    pub at_x_wall: bool,
}

impl AggregateSummary {
    pub fn size(&self) -> usize {
        self.size
    }

    /// As [`Aggregate::box_limited`].
    pub fn box_limited(&self, box_extent: f64) -> bool {
        box_limits(self.percolating, self.field_extent, box_extent)
    }
}

impl Run {
    pub fn completed(&self) -> bool {
        self.status == status::COMPLETED
    }

    /// Its trajectory is on this machine (not only its digest): what reads frames needs it.
    pub fn has_trajectory(&self) -> bool {
        self.source == Source::Trajectory
    }

    /// Lengths of the last frame's aggregates (µm), percolating ones (no finite length) left out.
    pub fn lengths_um(&self) -> Vec<f64> {
        self.last.iter().filter(|a| !a.percolating).map(|a| a.length * 1e6).collect()
    }

    /// Fraction of the last frame's aggregates that the box caps.
    pub fn box_limited_fraction(&self) -> f64 {
        self.box_limited.last().copied().unwrap_or(f64::NAN)
    }

    /// Aggregates of the last frame that percolate through a periodic face.
    pub fn percolating(&self) -> usize {
        self.last.iter().filter(|a| a.percolating).count()
    }

    pub fn mean_length_um(&self) -> f64 {
        summary(&self.lengths_um()).mean
    }

    /// Tracked x velocities (µm/s) of the last frame's aggregates of `min_size` or more particles
    /// that no x wall holds: the case-2 velocity of Table 2.
    pub fn free_velocities_um_per_s(&self, min_size: usize) -> Vec<f64> {
        self.last.iter().filter(|a| a.size >= min_size && !a.at_x_wall).map(|a| a.tracked_vx * 1e6).collect()
    }
}

/// Experiment files in `dir` (sorted), and in `dir/opt-in` when `opt_in`.
pub fn experiment_files(dir: &Path, opt_in: bool) -> std::io::Result<Vec<PathBuf>> {
    let mut files = vec![];
    for d in [dir.to_path_buf(), dir.join("opt-in")].iter().take(if opt_in { 2 } else { 1 }) {
        if !d.is_dir() {
            continue;
        }
        let mut here: Vec<PathBuf> = std::fs::read_dir(d)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        here.sort();
        files.extend(here);
    }
    Ok(files)
}

fn load(
    experiment: &Experiment,
    point: &crate::scene::experiment::Point,
    gap: f64,
) -> Result<Run, Box<dyn std::error::Error + Send + Sync>> {
    let spec = &point.scene.spec;
    let file = experiment.output.join(format!("{}.h5", point.id));
    let mut run = Run {
        experiment: experiment.spec.name.clone(),
        id: point.id.clone(),
        scene_hash: point.scene.hash.clone(),
        scene: point.base.file_stem().map_or(String::new(), |s| s.to_string_lossy().to_string()),
        variant: point.variant.clone().unwrap_or_default(),
        variant_overrides: point
            .overrides
            .iter()
            .take(point.overrides.len().saturating_sub(sweep_keys(experiment)))
            .map(|(k, v)| format!("{k} = {v}"))
            .collect(),
        seed: spec.seed,
        engine: point.engine.clone(),
        concentration: spec.particles.first().and_then(|g| g.concentration).unwrap_or(f64::NAN),
        magnetisation: applied_magnetisation(&point.scene),
        viscosity: spec.fluid.as_ref().map_or(f64::NAN, |f| f.viscosity),
        particles: point.scene.initial.len(),
        overrides: point.overrides.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", "),
        status: "missing".into(),
        message: String::new(),
        wall_time: f64::NAN,
        build: String::new(),
        threads: f64::NAN,
        file: file.clone(),
        times: vec![],
        mean_length: vec![],
        box_limited: vec![],
        box_extent: f64::NAN,
        last: vec![],
        image: None,
        scene_text: point.scene.text.clone(),
        source: Source::None,
    };
    if !file.exists() {
        return Ok(run);
    }
    // A file that cannot be read is marked as such; the report goes on with the others.
    if let Err(e) = read_run(&mut run, point, &file, gap) {
        run.status = status::UNREADABLE.into();
        run.message = e.to_string().split_whitespace().collect::<Vec<_>>().join(" ");
        (run.times, run.mean_length, run.box_limited, run.last) = (vec![], vec![], vec![], vec![]);
        (run.image, run.threads) = (None, f64::NAN);
    }
    Ok(run)
}

/// Fills `run` from its trajectory `file`.
fn read_run(
    run: &mut Run,
    point: &crate::scene::experiment::Point,
    file: &Path,
    gap: f64,
) -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let t = Trajectory::open(file).map_err(|e| e.to_string())?;
    if t.attr_string("scene_sha256").ok().as_deref() != Some(point.scene.hash.as_str()) {
        run.status = "stale (another scene)".into();
        return Ok(());
    }
    run.status = t.attr_string("status").map_err(|e| e.to_string())?;
    run.message = t.attr_string("status_message").unwrap_or_default();
    run.wall_time = t.attr::<f64>("wall_time_s").unwrap_or(f64::NAN);
    run.build = t.attr_string("git_commit").unwrap_or_default();
    run.threads = t.attr::<u64>("threads").map_or(f64::NAN, |n| n as f64);
    if run.completed() {
        let reader = FrameReader::new(&t).map_err(|e| e.to_string())?;
        let frames = reader.times.len();
        run.box_extent = reader.box_extent();
        let mut last = vec![];
        for k in 0..frames {
            let (time, aggs) = reader.aggregates(k as isize, gap).map_err(|e| e.to_string())?;
            let finite: Vec<f64> = aggs.iter().filter(|a| !a.percolating).map(|a| a.length).collect();
            run.times.push(time);
            run.mean_length.push(summary(&finite).mean);
            run.box_limited
                .push(aggs.iter().filter(|a| a.box_limited(run.box_extent)).count() as f64 / aggs.len() as f64);
            if k + 1 == frames {
                last = aggs;
            }
        }
        let times = &reader.times;
        let end = frames - 1;
        let start = times.iter().position(|&x| x >= 0.9 * times[end]).unwrap_or(0).min(end.saturating_sub(1));
        let (now, then) = (
            t.frame_vectors("position", end).map_err(|e| e.to_string())?,
            t.frame_vectors("position", start).map_err(|e| e.to_string())?,
        );
        let span = times[end] - times[start];
        let domain = reader.domain();
        let radius = &point.scene.initial.radius;
        let summarise = |a: &Aggregate| AggregateSummary {
            size: a.size(),
            length: a.length,
            field_extent: a.field_extent,
            orientation_deg: a.orientation_deg,
            com_velocity: a.com_velocity,
            percolating: a.percolating,
            tracked_vx: a.members.iter().map(|&i| domain.displacement(&now[i], &then[i]).x).sum::<f64>()
                / (a.members.len() as f64 * span),
            at_x_wall: !domain.periodic[0]
                && a.members
                    .iter()
                    .any(|&i| now[i].x - domain.lo.x < 3.0 * radius[i] || domain.hi.x - now[i].x < 3.0 * radius[i]),
        };
        run.last = last.iter().map(summarise).collect();
        if TABLE3.contains(&run.experiment.as_str()) {
            run.image = Some(image_measures(&last, &now, reader.radius(), domain));
        }
    }
    run.source = Source::Trajectory;
    Ok(())
}

/// [`Run::image`] of a last frame: its aggregates `last` and the particles' `position`s.
fn image_measures(
    last: &[Aggregate],
    position: &[Vec3],
    radius: &[f64],
    domain: &crate::core::domain::Domain,
) -> [f64; 4] {
    let m = |v: Vec<f64>| mean_um(&v);
    let finite = || last.iter().filter(|a| !a.percolating);
    let projected =
        |a: &Aggregate| IMAGING.major_axis(&a.positions, &a.members.iter().map(|&i| radius[i]).collect::<Vec<_>>());
    let regions = IMAGING.image(position, radius, &domain.lo, &domain.hi);
    [
        m(finite().map(projected).collect()),
        m(finite().filter(|a| a.size() > 1).map(projected).collect()),
        m(regions.iter().map(|g| g.major_axis).collect()),
        m(regions.iter().filter(|g| g.particles.len() > 1).map(|g| g.major_axis).collect()),
    ]
}

/// |M| of the first species in the applied field at the box centre (A/m).
fn applied_magnetisation(scene: &crate::scene::Scene) -> f64 {
    let (Some(field), Some(species)) = (scene.spec.field.as_ref(), scene.species.first()) else { return f64::NAN };
    let centre = 0.5 * (scene.domain.lo + scene.domain.hi);
    let h = (field.applied().on().field(&centre) / crate::core::forces::magnetisation::MU0).norm();
    let linear = species.susceptibility * h;
    species.saturation.map_or(linear, |s| s.magnetisation(linear))
}

/// Number of sweep axes (the last overrides of every point).
fn sweep_keys(experiment: &Experiment) -> usize {
    experiment.spec.sweep.len()
}

/// Every point of the experiments in `files`, analysed at aggregate gap tolerance `gap`.
pub fn load_runs(files: &[PathBuf], gap: f64) -> Result<Vec<Run>, Box<dyn std::error::Error>> {
    let mut jobs = vec![];
    let experiments: Vec<Experiment> = files
        .iter()
        .map(|f| Experiment::from_file(f).map_err(|e| format!("{}: {e}", f.display())))
        .collect::<Result<_, _>>()?;
    for e in &experiments {
        jobs.extend(e.points.iter().map(move |p| (e, p)));
    }
    let runs: Result<Vec<Run>, _> = jobs.par_iter().map(|(e, p)| load(e, p, gap)).collect();
    runs.map_err(|e| e.to_string().into())
}

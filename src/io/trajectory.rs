//! HDF5 trajectory files (schema in docs/outputs.md).
//!
//! Frames are appended one at a time into chunked datasets (deflate-compressed where a chunk is one
//! frame's row) and the file is
//! flushed after every frame, so a killed run leaves a readable file holding every frame written.
//! The `checkpoint` group holds the full state (forces and contact history included) and is
//! rewritten in place with every frame and on interruption; `--resume` continues from it.

use crate::core::state::{Exit, Way};
use crate::core::state::{PairHistory, Particles, State, Vec3};
use hdf5::types::VarLenUnicode;
use hdf5::{Dataset, Extent, File, Group, SimpleExtents};
use ndarray::{s, Array1, Array2, Array3};
use std::path::Path;

/// Format identifier and version written at the root.
pub const FORMAT: &str = "magdem-trajectory";
pub const FORMAT_VERSION: u32 = 1;

#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    #[error("HDF5 error on {path}: {}", .source.to_string().split_whitespace().collect::<Vec<_>>().join(" "))]
    Hdf5 { path: String, source: hdf5::Error },
    #[error("{path}: {message}")]
    Mismatch { path: String, message: String },
}

/// Run status stored in the `status` root attribute.
pub mod status {
    pub const RUNNING: &str = "running";
    pub const COMPLETED: &str = "completed";
    pub const INTERRUPTED: &str = "interrupted";
    pub const UNSTABLE: &str = "unstable";
    /// Not a status a file holds: what a report marks a file it cannot read as.
    pub const UNREADABLE: &str = "unreadable";
}

type H5Result<T> = hdf5::Result<T>;

/// Turns off HDF5's file locking (before the first file is opened). HDF5 takes an flock on every
/// open file through a descriptor that child processes inherit, so a LIGGGHTS/LAMMPS run started
/// while a trajectory is open would hold that lock and make a later open of the file fail.
/// magdem never opens one file from two writers, so the lock protects nothing here.
fn disable_file_locking() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if std::env::var_os("HDF5_USE_FILE_LOCKING").is_none() {
            std::env::set_var("HDF5_USE_FILE_LOCKING", "FALSE");
        }
    });
}

fn write_str_attr(loc: &hdf5::Location, name: &str, value: &str) -> H5Result<()> {
    let v: VarLenUnicode = value.parse().expect("no NUL in attribute text");
    if loc.attr_names()?.iter().any(|n| n == name) {
        loc.attr(name)?.write_scalar(&v)
    } else {
        loc.new_attr::<VarLenUnicode>().shape(()).create(name)?.write_scalar(&v)
    }
}

fn read_str_attr(loc: &hdf5::Location, name: &str) -> H5Result<String> {
    Ok(loc.attr(name)?.read_scalar::<VarLenUnicode>()?.as_str().to_string())
}

fn write_scalar_attr<T: hdf5::H5Type>(loc: &hdf5::Location, name: &str, value: T) -> H5Result<()> {
    if loc.attr_names()?.iter().any(|n| n == name) {
        loc.attr(name)?.write_scalar(&value)
    } else {
        loc.new_attr::<T>().shape(()).create(name)?.write_scalar(&value)
    }
}

/// How an extendible dataset is chunked.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Rows {
    /// One frame of per-particle rows per chunk, deflate-compressed: written whole, never again.
    Frames,
    /// 1 024 rows per chunk, uncompressed: a chunk that receives rows from several appends or
    /// rewrites (time, step, the contact list, the checkpoint's contact history) is rewritten
    /// in place; compressed, a chunk torn by a kill (-9) during a write could not be inflated
    /// when the resumed run reads or extends it.
    Appended,
}

/// Extendible dataset of shape (0.., tail...).
fn extendible<T: hdf5::H5Type>(
    group: &Group,
    name: &str,
    tail: &[usize],
    units: &str,
    rows: Rows,
) -> H5Result<Dataset> {
    let chunk = if rows == Rows::Frames { 1 } else { 1024 };
    chunked::<T>(group, name, tail, units, rows, chunk)
}

/// [`extendible`] with chunks of `chunk_rows` rows: small for datasets that stay small (the
/// exits, a small run's checkpoint), since HDF5 allocates whole chunks.
fn chunked<T: hdf5::H5Type>(
    group: &Group,
    name: &str,
    tail: &[usize],
    units: &str,
    rows: Rows,
    chunk_rows: usize,
) -> H5Result<Dataset> {
    let mut extents = vec![Extent::resizable(0)];
    extents.extend(tail.iter().map(|&n| Extent::fixed(n)));
    let mut chunk = vec![chunk_rows.max(1)];
    chunk.extend_from_slice(tail);
    let builder = group.new_dataset::<T>().shape(SimpleExtents::from_vec(extents)).chunk(chunk);
    let ds = match rows {
        Rows::Frames => builder.deflate(4).create(name)?,
        Rows::Appended => builder.create(name)?,
    };
    write_str_attr(&ds, "units", units)?;
    Ok(ds)
}

/// Writes `data` over `ds`, resizing it first if it is resizable and of another shape (the
/// checkpoint's rows follow the particles still in the run).
fn rewrite<T: hdf5::H5Type, D: ndarray::Dimension>(ds: &Dataset, data: &ndarray::Array<T, D>) -> H5Result<()> {
    if ds.shape() != data.shape() {
        ds.resize(data.shape())?;
    }
    ds.write(data)
}

/// A frame's rows: the slots' values `v` in id order over `n` ids, NaN for the particles that
/// left the run.
fn frame_rows(state: &State, v: &[Vec3], n: usize) -> Array2<f64> {
    let mut rows = Array2::from_elem((n, 3), f64::NAN);
    for (&id, x) in state.ids.iter().zip(v) {
        for k in 0..3 {
            rows[(id as usize, k)] = x[k];
        }
    }
    rows
}

fn vec3_rows(v: &[Vec3]) -> Array2<f64> {
    Array2::from_shape_fn((v.len(), 3), |(i, k)| v[i][k])
}

fn rows_vec3(a: &Array2<f64>) -> Vec<Vec3> {
    a.rows().into_iter().map(|r| Vec3::new(r[0], r[1], r[2])).collect()
}

/// Values stored by particle id (`by_id`) in the order of the slots `ids`.
fn by_slot<T: Copy>(ids: &[u32], by_id: Vec<T>) -> Vec<T> {
    ids.iter().map(|&id| by_id[id as usize]).collect()
}

/// Per-frame datasets: (name, units).
const FRAME_VECTORS: [(&str, &str); 4] =
    [("position", "m"), ("velocity", "m/s"), ("angular_velocity", "rad/s"), ("moment", "A m^2")];
const FORCE_VECTORS: [(&str, &str); 2] = [("force", "N"), ("torque", "N m")];
/// Metadata of a run, written at the root.
pub struct RunInfo<'a> {
    pub engine: &'a str,
    pub integrator: &'a str,
}

/// What a trajectory records of the scene it runs: its text, hash and name, its species' names,
/// the particles it starts from, its clock and which optional datasets it writes.
pub struct RunHeader<'a> {
    pub scene_text: &'a str,
    pub scene_hash: &'a str,
    pub scene_name: &'a str,
    pub species_names: Vec<&'a str>,
    pub initial: &'a Particles,
    pub dt: f64,
    pub total_steps: u64,
    pub steps_per_frame: u64,
    /// Write each frame's forces and torques.
    pub forces: bool,
    /// Write each frame's contacts.
    pub contacts: bool,
    /// The names of the outlets particles may leave through (`[[exits.outlets]]`), in order.
    pub outlets: Vec<&'a str>,
}

/// Appends frames to a trajectory file and keeps its checkpoint current.
pub struct TrajectoryWriter {
    path: String,
    file: File,
    n: usize,
    frames: usize,
    forces: bool,
    contacts: bool,
}

impl TrajectoryWriter {
    fn err(&self) -> impl Fn(hdf5::Error) -> TrajectoryError + '_ {
        move |source| TrajectoryError::Hdf5 { path: self.path.clone(), source }
    }

    /// Creates (overwrites) `path` for a fresh run described by `header`.
    pub fn create(path: &Path, header: &RunHeader, info: &RunInfo) -> Result<Self, TrajectoryError> {
        let p = path.display().to_string();
        let wrap = |source| TrajectoryError::Hdf5 { path: p.clone(), source };
        disable_file_locking();
        let file = File::create(path).map_err(wrap)?;
        let n = header.initial.len();
        let (forces, contacts) = (header.forces, header.contacts);
        (|| -> H5Result<()> {
            write_str_attr(&file, "format", FORMAT)?;
            write_scalar_attr(&file, "format_version", FORMAT_VERSION)?;
            write_str_attr(&file, "magdem_version", env!("CARGO_PKG_VERSION"))?;
            write_str_attr(&file, "git_commit", env!("MAGDEM_GIT_COMMIT"))?;
            write_str_attr(&file, "engine", info.engine)?;
            write_str_attr(&file, "integrator", info.integrator)?;
            write_str_attr(&file, "scene_sha256", header.scene_hash)?;
            write_str_attr(&file, "scene_name", header.scene_name)?;
            write_str_attr(&file, "units", "SI: m, s, kg, N, A m^2, T")?;
            write_scalar_attr(&file, "dt", header.dt)?;
            write_scalar_attr(&file, "total_steps", header.total_steps)?;
            write_scalar_attr(&file, "steps_per_frame", header.steps_per_frame)?;
            write_scalar_attr(&file, "n_particles", n as u64)?;
            write_str_attr(&file, "status", status::RUNNING)?;
            write_str_attr(&file, "status_message", "")?;
            let text: VarLenUnicode = header.scene_text.parse().expect("scene text has no NUL");
            file.new_dataset::<VarLenUnicode>().shape(()).create("scene")?.write_scalar(&text)?;

            let particles = file.create_group("particles")?;
            let p = header.initial;
            particles.new_dataset_builder().with_data(&Array1::from(p.radius.clone())).create("radius")?;
            particles.new_dataset_builder().with_data(&Array1::from(p.mass.clone())).create("mass")?;
            particles.new_dataset_builder().with_data(&Array1::from(p.species.clone())).create("species")?;
            let names = header.species_names.join(",");
            write_str_attr(&particles, "species_names", &names)?;

            let frames = file.create_group("frames")?;
            extendible::<f64>(&frames, "time", &[], "s", Rows::Appended)?;
            extendible::<u64>(&frames, "step", &[], "1", Rows::Appended)?;
            let vectors = FRAME_VECTORS.iter().chain(if forces { &FORCE_VECTORS[..] } else { &[] });
            for (name, units) in vectors {
                extendible::<f64>(&frames, name, &[n, 3], units, Rows::Frames)?;
            }
            if contacts {
                let c = file.create_group("contacts")?;
                extendible::<u64>(&c, "frame_start", &[], "index into pair", Rows::Appended)?;
                extendible::<u32>(&c, "pair", &[2], "particle index", Rows::Appended)?;
                extendible::<f64>(&c, "overlap", &[], "m", Rows::Appended)?;
            }
            let ck = file.create_group("checkpoint")?;
            // As many rows as particles in the run (resizable), in one chunk up to 4 096 rows.
            let rows = n.min(4096);
            for name in State::vector_names() {
                chunked::<f64>(&ck, name, &[3], "SI", Rows::Appended, rows)?.resize((n, 3))?;
            }
            chunked::<u32>(&ck, "id", &[], "particle id", Rows::Appended, rows)?.resize(n)?;
            let exits = file.create_group("exits")?;
            write_str_attr(&exits, "outlets", &header.outlets.join(","))?;
            let outlet = "index into the outlets attribute; -1 captured";
            chunked::<u32>(&exits, "id", &[], "particle id", Rows::Appended, 64)?;
            chunked::<u64>(&exits, "step", &[], "1", Rows::Appended, 64)?;
            chunked::<f64>(&exits, "time", &[], "s", Rows::Appended, 64)?;
            chunked::<f64>(&exits, "position", &[3], "m", Rows::Appended, 64)?;
            chunked::<i32>(&exits, "outlet", &[], outlet, Rows::Appended, 64)?;
            chunked::<f64>(&ck, "touching", &[2], "particle id, s since first contact", Rows::Appended, 64)?;
            extendible::<u32>(&ck, "pair_keys", &[2], "particle index", Rows::Appended)?;
            extendible::<f64>(&ck, "pair_shear", &[3], "m", Rows::Appended)?;
            extendible::<u32>(&ck, "wall_keys", &[2], "particle index, wall face", Rows::Appended)?;
            extendible::<f64>(&ck, "wall_shear", &[3], "m", Rows::Appended)?;
            file.flush()
        })()
        .map_err(wrap)?;
        Ok(Self { path: p, file, n, frames: 0, forces, contacts })
    }

    /// Opens a trajectory to continue it: checks it belongs to `scene`, drops frames written
    /// after the checkpoint, and returns the checkpointed state.
    pub fn resume(path: &Path, header: &RunHeader) -> Result<(Self, State), TrajectoryError> {
        let p = path.display().to_string();
        let wrap = |source| TrajectoryError::Hdf5 { path: p.clone(), source };
        disable_file_locking();
        let file = File::open_rw(path).map_err(wrap)?;
        let hash = read_str_attr(&file, "scene_sha256").map_err(wrap)?;
        if hash != header.scene_hash {
            return Err(TrajectoryError::Mismatch {
                path: p,
                message: format!(
                    "was written for a different scene (sha256 {hash}, this scene {}); refusing to resume into it",
                    header.scene_hash
                ),
            });
        }
        let reader = Trajectory { path: p.clone(), file };
        let (state, frames) = reader.checkpoint().map_err(wrap)?;
        let Trajectory { file, .. } = reader;
        let forces = file.link_exists("frames/force");
        let contacts = file.link_exists("contacts");
        let writer = Self { path: p, file, n: header.initial.len(), frames, forces, contacts };
        writer.truncate(frames).map_err(writer.err())?;
        write_str_attr(&writer.file, "status", status::RUNNING).map_err(writer.err())?;
        Ok((writer, state))
    }

    fn truncate(&self, frames: usize) -> H5Result<()> {
        let g = self.file.group("frames")?;
        for name in g.member_names()? {
            let ds = g.dataset(&name)?;
            let mut shape = ds.shape();
            shape[0] = frames;
            ds.resize(shape)?;
        }
        if self.contacts {
            let c = self.file.group("contacts")?;
            c.dataset("frame_start")?.resize(frames)?;
            let rows: u64 = self.file.group("checkpoint")?.attr("contact_rows")?.read_scalar()?;
            c.dataset("pair")?.resize((rows as usize, 2))?;
            c.dataset("overlap")?.resize(rows as usize)?;
        }
        self.file.flush()
    }

    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Appends one frame, rewrites the checkpoint, flushes.
    pub fn write_frame(&mut self, state: &State) -> Result<(), TrajectoryError> {
        self.append(state).map_err(self.err())?;
        self.frames += 1;
        self.write_checkpoint(state)
    }

    fn append(&self, state: &State) -> H5Result<()> {
        let f = self.frames;
        let g = self.file.group("frames")?;
        let time = g.dataset("time")?;
        time.resize(f + 1)?;
        time.write_slice(&[state.time], s![f..f + 1])?;
        let step = g.dataset("step")?;
        step.resize(f + 1)?;
        step.write_slice(&[state.step], s![f..f + 1])?;
        let vectors = FRAME_VECTORS.iter().chain(if self.forces { &FORCE_VECTORS[..] } else { &[] });
        let (vectors_now, p) = (state.vectors(), &state.fields);
        let total = |fast: &[Vec3], slow: &[Vec3]| fast.iter().zip(slow).map(|(a, b)| a + b).collect::<Vec<_>>();
        for (name, _) in vectors {
            let ds = g.dataset(name)?;
            ds.resize((f + 1, self.n, 3))?;
            // Frames hold total force and torque (fast plus slow under multiple time stepping),
            // every vector in particle id order.
            let slots = match *name {
                "force" => total(&p.force, &p.slow_force),
                "torque" => total(&p.torque, &p.slow_torque),
                _ => vectors_now.iter().find(|(n, _)| n == name).expect("a state vector").1.clone(),
            };
            ds.write_slice(&frame_rows(state, &slots, self.n), s![f, .., ..])?;
        }
        if self.contacts {
            let c = self.file.group("contacts")?;
            let pairs = c.dataset("pair")?;
            let start = pairs.shape()[0];
            let starts = c.dataset("frame_start")?;
            starts.resize(f + 1)?;
            starts.write_slice(&[start as u64], s![f..f + 1])?;
            let p = &state.particles;
            // By particle id, in id order.
            let mut active: Vec<(u32, u32, f64)> = state
                .history
                .pairs
                .iter()
                .map(|&((i, j), _)| {
                    let (a, b) = (i as usize, j as usize);
                    let (id_a, id_b) = (state.ids[a], state.ids[b]);
                    let overlap = p.radius[a] + p.radius[b] - (p.position[a] - p.position[b]).norm();
                    (id_a.min(id_b), id_a.max(id_b), overlap)
                })
                .collect();
            active.sort_unstable_by_key(|&(i, j, _)| (i, j));
            let k = active.len();
            pairs.resize((start + k, 2))?;
            c.dataset("overlap")?.resize(start + k)?;
            if k > 0 {
                let ij = Array2::from_shape_fn((k, 2), |(r, col)| if col == 0 { active[r].0 } else { active[r].1 });
                pairs.write_slice(&ij, s![start..start + k, ..])?;
                let ov = Array1::from_iter(active.iter().map(|a| a.2));
                c.dataset("overlap")?.write_slice(&ov, s![start..start + k])?;
            }
        }
        Ok(())
    }

    /// Rewrites the checkpoint group with `state` and flushes the file.
    pub fn write_checkpoint(&self, state: &State) -> Result<(), TrajectoryError> {
        (|| -> H5Result<()> {
            let ck = self.file.group("checkpoint")?;
            for (name, vector) in state.vectors() {
                rewrite(&ck.dataset(name)?, &vec3_rows(vector))?;
            }
            // The checkpoint keeps the particles' slots; `id` names the particle of each (files
            // written before renumbering existed have none: 0, 1, …).
            let ids = match ck.dataset("id") {
                Ok(ds) => ds,
                Err(_) => ck.new_dataset::<u32>().shape(self.n).create("id")?,
            };
            rewrite(&ids, &Array1::from(state.ids.clone()))?;
            // Files written before particles could leave have no exits.
            if let Ok(exits) = self.file.group("exits") {
                write_exits(&exits, &state.exits)?;
                let touching = Array2::from_shape_fn((state.touching.len(), 2), |(r, c)| match c {
                    0 => state.touching[r].0 as f64,
                    _ => state.touching[r].1,
                });
                rewrite(&ck.dataset("touching")?, &touching)?;
            }
            let (pairs, walls) = (&state.history.pairs, &state.history.walls);
            let keys =
                Array2::from_shape_vec((pairs.len(), 2), pairs.iter().flat_map(|((i, j), _)| [*i, *j]).collect())
                    .expect("two keys per spring");
            let shear = vec3_rows(&pairs.iter().map(|p| p.1).collect::<Vec<_>>());
            let wkeys =
                Array2::from_shape_fn(
                    (walls.len(), 2),
                    |(r, c)| if c == 0 { walls[r].0 .0 } else { walls[r].0 .1 as u32 },
                );
            let wshear = vec3_rows(&walls.iter().map(|p| p.1).collect::<Vec<_>>());
            for (name, data) in [("pair_keys", &keys), ("wall_keys", &wkeys)] {
                rewrite(&ck.dataset(name)?, data)?;
            }
            for (name, data) in [("pair_shear", &shear), ("wall_shear", &wshear)] {
                rewrite(&ck.dataset(name)?, data)?;
            }
            write_scalar_attr(&ck, "step", state.step)?;
            write_scalar_attr(&ck, "time", state.time)?;
            write_scalar_attr(&ck, "next_substep", state.next_substep.unwrap_or(f64::NAN))?;
            write_scalar_attr(&ck, "frames", self.frames as u64)?;
            let rows = if self.contacts { self.file.dataset("contacts/pair")?.shape()[0] } else { 0 };
            write_scalar_attr(&ck, "contact_rows", rows as u64)?;
            self.file.flush()
        })()
        .map_err(self.err())
    }

    /// Records how the run ended, adds `cost.wall_time` to the file's `wall_time_s` (summed over
    /// resumed pieces) and sets `threads` to the piece's thread count.
    pub fn finish(&self, run_status: &str, message: &str, cost: Cost) -> Result<(), TrajectoryError> {
        (|| -> H5Result<()> {
            write_str_attr(&self.file, "status", run_status)?;
            write_str_attr(&self.file, "status_message", message)?;
            let before: f64 = self.file.attr("wall_time_s").and_then(|a| a.read_scalar()).unwrap_or(0.0);
            write_scalar_attr(&self.file, "wall_time_s", before + cost.wall_time.as_secs_f64())?;
            write_scalar_attr(&self.file, "threads", cost.threads as u64)?;
            self.file.flush()
        })()
        .map_err(self.err())
    }
}

/// What a run (or a resumed piece of one) cost: its wall time and the threads it ran on (the
/// engine processes, for a reference engine).
#[derive(Debug, Clone, Copy)]
pub struct Cost {
    pub wall_time: std::time::Duration,
    pub threads: usize,
}

/// Read access to a trajectory file.
pub struct Trajectory {
    pub path: String,
    pub file: File,
}

impl Trajectory {
    pub fn open(path: &Path) -> Result<Self, TrajectoryError> {
        let p = path.display().to_string();
        disable_file_locking();
        let file = File::open(path).map_err(|source| TrajectoryError::Hdf5 { path: p.clone(), source })?;
        Ok(Self { path: p, file })
    }

    pub fn attr_string(&self, name: &str) -> H5Result<String> {
        read_str_attr(&self.file, name)
    }

    pub fn attr<T: hdf5::H5Type>(&self, name: &str) -> H5Result<T> {
        self.file.attr(name)?.read_scalar::<T>()
    }

    pub fn scene_text(&self) -> H5Result<String> {
        Ok(self.file.dataset("scene")?.read_scalar::<VarLenUnicode>()?.as_str().to_string())
    }

    pub fn frames(&self) -> H5Result<usize> {
        Ok(self.file.dataset("frames/time")?.shape()[0])
    }

    pub fn times(&self) -> H5Result<Vec<f64>> {
        self.file.dataset("frames/time")?.read_raw()
    }

    /// One per-particle vector dataset of frame `k` (e.g. "position").
    pub fn frame_vectors(&self, name: &str, k: usize) -> H5Result<Vec<Vec3>> {
        let a: Array2<f64> = self.file.dataset(&format!("frames/{name}"))?.read_slice_2d(s![k, .., ..])?;
        Ok(rows_vec3(&a))
    }

    /// All frames of one vector dataset, shape (frames, N, 3).
    pub fn all_vectors(&self, name: &str) -> H5Result<Array3<f64>> {
        self.file.dataset(&format!("frames/{name}"))?.read::<f64, ndarray::Ix3>()
    }

    /// The names of the outlets the `exits` group's `outlet` indices refer to (none in files
    /// written before particles could leave).
    pub fn outlet_names(&self) -> H5Result<Vec<String>> {
        let Ok(exits) = self.file.group("exits") else { return Ok(vec![]) };
        let names = read_str_attr(&exits, "outlets")?;
        Ok(names.split(',').filter(|n| !n.is_empty()).map(str::to_string).collect())
    }

    /// The checkpointed state and the number of frames it follows.
    pub fn checkpoint(&self) -> H5Result<(State, usize)> {
        let ck = self.file.group("checkpoint")?;
        let radius: Vec<f64> = self.file.dataset("particles/radius")?.read_raw()?;
        // The fixed properties are stored by id, the checkpoint by slot.
        let ids: Vec<u32> = match ck.dataset("id") {
            Ok(ds) => ds.read_raw()?,
            Err(_) => (0..radius.len() as u32).collect(),
        };
        let mut particles = Particles {
            radius: by_slot(&ids, radius),
            species: by_slot(&ids, self.file.dataset("particles/species")?.read_raw()?),
            ..Particles::default()
        };
        particles.set_masses(by_slot(&ids, self.file.dataset("particles/mass")?.read_raw()?));
        let mut state = State { particles, ids, ..State::default() };
        for (name, vector) in state.vectors_mut() {
            *vector = rows_vec3(&ck.dataset(name)?.read_2d()?);
        }
        let particles = &mut state.particles;
        particles.has_permanent_moments = particles.permanent_moment.iter().any(|m| *m != Vec3::zeros());
        let keys: Array2<u32> = ck.dataset("pair_keys")?.read_2d()?;
        let shear: Array2<f64> = ck.dataset("pair_shear")?.read_2d()?;
        let wkeys: Array2<u32> = ck.dataset("wall_keys")?.read_2d()?;
        let wshear: Array2<f64> = ck.dataset("wall_shear")?.read_2d()?;
        let pairs: Vec<_> = keys.rows().into_iter().zip(rows_vec3(&shear)).map(|(k, s)| ((k[0], k[1]), s)).collect();
        let mut contacts = PairHistory { pairs: pairs.into(), ..Default::default() };
        for (k, s) in wkeys.rows().into_iter().zip(rows_vec3(&wshear)) {
            contacts.walls.push(((k[0], k[1] as u8), s));
        }
        contacts.walls.sort_unstable_by_key(|(k, _)| *k);
        let step: u64 = ck.attr("step")?.read_scalar()?;
        let time: f64 = ck.attr("time")?.read_scalar()?;
        let frames: u64 = ck.attr("frames")?.read_scalar()?;
        let next_substep = ck.attr("next_substep").and_then(|a| a.read_scalar::<f64>()).ok().filter(|h| h.is_finite());
        (state.history, state.step, state.time, state.next_substep) = (contacts, step, time, next_substep);
        if let Ok(exits) = self.file.group("exits") {
            state.exits = read_exits(&exits)?;
            let touching: Array2<f64> = ck.dataset("touching")?.read_2d()?;
            state.touching = touching.rows().into_iter().map(|r| (r[0] as u32, r[1])).collect();
        }
        Ok((state, frames as usize))
    }
}

/// Rewrites the `exits` group with every exit so far.
fn write_exits(g: &Group, exits: &[Exit]) -> H5Result<()> {
    let outlet = |e: &Exit| match e.way {
        Way::Outlet(k) => k as i32,
        Way::Captured => -1,
    };
    rewrite(&g.dataset("id")?, &exits.iter().map(|e| e.id).collect::<Array1<_>>())?;
    rewrite(&g.dataset("step")?, &exits.iter().map(|e| e.step).collect::<Array1<_>>())?;
    rewrite(&g.dataset("time")?, &exits.iter().map(|e| e.time).collect::<Array1<_>>())?;
    rewrite(&g.dataset("position")?, &vec3_rows(&exits.iter().map(|e| e.position).collect::<Vec<_>>()))?;
    rewrite(&g.dataset("outlet")?, &exits.iter().map(outlet).collect::<Array1<_>>())
}

/// The exits a trajectory records.
pub fn read_exits(g: &Group) -> H5Result<Vec<Exit>> {
    let id: Vec<u32> = g.dataset("id")?.read_raw()?;
    let step: Vec<u64> = g.dataset("step")?.read_raw()?;
    let time: Vec<f64> = g.dataset("time")?.read_raw()?;
    let position = rows_vec3(&g.dataset("position")?.read_2d()?);
    let outlet: Vec<i32> = g.dataset("outlet")?.read_raw()?;
    let way = |k: i32| if k < 0 { Way::Captured } else { Way::Outlet(k as u16) };
    Ok((0..id.len())
        .map(|r| Exit { id: id[r], step: step[r], time: time[r], position: position[r], way: way(outlet[r]) })
        .collect())
}

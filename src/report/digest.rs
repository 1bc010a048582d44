//! Digests: what a report reads of each run, kept beside the report so that an ensemble can grow
//! across machines that do not keep each other's trajectories.
//!
//! A report's `digests/<experiment>/` holds three Parquet tables (h5py-free, polars/pandas read
//! them): `runs.parquet` (one row per run: id, scene hash, gap tolerance, status, message, wall
//! time, threads, box extent, and the imaging and four image measures of [`Run::image`], empty
//! and NaN for runs not imaged), `frames.parquet` (id, time, mean length, box-limited fraction per frame)
//! and `aggregates.parquet` (id and one [`AggregateSummary`] per row, the last frame's). A run
//! whose trajectory is absent is read from its digest when the digest's scene hash and gap
//! tolerance are the run's own; a run read from its trajectory replaces its digest row. The
//! members' positions are not kept: what needs them (figures, trajectory differences) reads
//! trajectories and leaves digest-only runs out, saying so.

use super::runs::{AggregateSummary, Run, Source};
use super::tables::{col, floats, scol, ucol};
use crate::core::state::Vec3;
use crate::io::trajectory::status;
use polars::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

type Error = Box<dyn std::error::Error>;

/// One run as a digest holds it.
#[derive(Debug, Clone)]
struct Entry {
    scene_hash: String,
    gap: f64,
    status: String,
    message: String,
    wall_time: f64,
    build: String,
    threads: f64,
    box_extent: f64,
    times: Vec<f64>,
    mean_length: Vec<f64>,
    box_limited: Vec<f64>,
    last: Vec<AggregateSummary>,
    image: Option<[f64; 4]>,
}

impl Entry {
    fn of(run: &Run, gap: f64) -> Self {
        Entry {
            scene_hash: run.scene_hash.clone(),
            gap,
            status: run.status.clone(),
            message: run.message.clone(),
            wall_time: run.wall_time,
            build: run.build.clone(),
            threads: run.threads,
            box_extent: run.box_extent,
            times: run.times.clone(),
            mean_length: run.mean_length.clone(),
            box_limited: run.box_limited.clone(),
            last: run.last.clone(),
            image: run.image,
        }
    }

    fn fill(&self, run: &mut Run) {
        run.status = self.status.clone();
        run.message = self.message.clone();
        run.wall_time = self.wall_time;
        run.build = self.build.clone();
        run.threads = self.threads;
        run.box_extent = self.box_extent;
        run.times = self.times.clone();
        run.mean_length = self.mean_length.clone();
        run.box_limited = self.box_limited.clone();
        run.last = self.last.clone();
        run.image = self.image;
        run.source = Source::Digest;
    }
}

/// A run worth keeping: it has finished (completed, or stopped as unstable).
fn finished(run: &Run) -> bool {
    run.source == Source::Trajectory && (run.status == status::COMPLETED || run.status == status::UNSTABLE)
}

fn read(dir: &Path) -> Result<BTreeMap<String, Entry>, Error> {
    let mut entries = BTreeMap::new();
    if !dir.join("runs.parquet").exists() {
        return Ok(entries);
    }
    let open = |name: &str| -> Result<DataFrame, Error> {
        Ok(ParquetReader::new(std::fs::File::open(dir.join(name))?).finish()?)
    };
    let strings = |df: &DataFrame, c: &str| -> Result<Vec<String>, Error> {
        Ok(df.column(c)?.str()?.into_iter().map(|s| s.unwrap_or_default().to_string()).collect())
    };
    let (runs, frames, aggs) = (open("runs.parquet")?, open("frames.parquet")?, open("aggregates.parquet")?);
    let (hash, gap, st, msg, wall, extent) = (
        strings(&runs, "scene_sha256")?,
        floats(&runs, "gap_tolerance")?,
        strings(&runs, "status")?,
        strings(&runs, "message")?,
        floats(&runs, "wall_time_s")?,
        floats(&runs, "box_extent_m")?,
    );
    // Digests written before the thread count, the build or the image measures were recorded
    // have no such columns; image measures of another imaging are not this report's.
    let threads = floats(&runs, "threads").unwrap_or_else(|_| vec![f64::NAN; runs.height()]);
    let build = strings(&runs, "build").unwrap_or_else(|_| vec![String::new(); runs.height()]);
    let imaging = strings(&runs, "imaging").unwrap_or_else(|_| vec![String::new(); runs.height()]);
    let key = imaging_key();
    let image_columns = IMAGE_COLUMNS.map(|c| floats(&runs, c).unwrap_or_else(|_| vec![f64::NAN; runs.height()]));
    for (k, id) in strings(&runs, "id")?.into_iter().enumerate() {
        let entry = Entry {
            scene_hash: hash[k].clone(),
            gap: gap[k],
            status: st[k].clone(),
            message: msg[k].clone(),
            wall_time: wall[k],
            build: build[k].clone(),
            threads: threads[k],
            box_extent: extent[k],
            times: vec![],
            mean_length: vec![],
            box_limited: vec![],
            last: vec![],
            image: (imaging[k] == key).then(|| image_columns.each_ref().map(|c| c[k])),
        };
        entries.insert(id, entry);
    }
    let (time, length, limited) =
        (floats(&frames, "time_s")?, floats(&frames, "mean_length_m")?, floats(&frames, "box_limited_fraction")?);
    for (k, id) in strings(&frames, "id")?.iter().enumerate() {
        let e = entries.get_mut(id).ok_or_else(|| format!("{}: frame of unknown run {id}", dir.display()))?;
        e.times.push(time[k]);
        e.mean_length.push(length[k]);
        e.box_limited.push(limited[k]);
    }
    let size: Vec<u64> = aggs.column("size")?.u64()?.into_iter().map(|v| v.unwrap_or(0)).collect();
    let bools = |c: &str| -> Result<Vec<bool>, Error> {
        Ok(aggs.column(c)?.bool()?.into_iter().map(|v| v.unwrap_or(false)).collect())
    };
    let (len, ext, ori, vx, vy, vz, tvx) = (
        floats(&aggs, "length_m")?,
        floats(&aggs, "field_extent_m")?,
        floats(&aggs, "orientation_deg")?,
        floats(&aggs, "vx_m_per_s")?,
        floats(&aggs, "vy_m_per_s")?,
        floats(&aggs, "vz_m_per_s")?,
        floats(&aggs, "tracked_vx_m_per_s")?,
    );
    let (perc, wall_held) = (bools("percolating")?, bools("at_x_wall")?);
    for (k, id) in strings(&aggs, "id")?.iter().enumerate() {
        let e = entries.get_mut(id).ok_or_else(|| format!("{}: aggregate of unknown run {id}", dir.display()))?;
        e.last.push(AggregateSummary {
            size: size[k] as usize,
            length: len[k],
            field_extent: ext[k],
            orientation_deg: ori[k],
            com_velocity: Vec3::new(vx[k], vy[k], vz[k]),
            percolating: perc[k],
            tracked_vx: tvx[k],
            at_x_wall: wall_held[k],
        });
    }
    Ok(entries)
}

/// The three tables of `entries`, as Parquet bytes.
fn encode(entries: &BTreeMap<String, Entry>) -> Result<[Vec<u8>; 3], Error> {
    let ids = |n: fn(&Entry) -> usize| -> Vec<String> {
        entries.iter().flat_map(|(id, e)| std::iter::repeat_n(id.clone(), n(e))).collect()
    };
    let all = |f: fn(&Entry) -> f64| entries.values().map(f).collect::<Vec<f64>>();
    let each = |f: fn(&Entry) -> &Vec<f64>| entries.values().flat_map(|e| f(e).iter().copied()).collect::<Vec<f64>>();
    let aggregates = || entries.values().flat_map(|e| e.last.iter());
    let per_aggregate = |f: fn(&AggregateSummary) -> f64| aggregates().map(f).collect::<Vec<f64>>();
    let bools = |name: &str, f: fn(&AggregateSummary) -> bool| {
        Column::new(name.into(), aggregates().map(f).collect::<Vec<bool>>())
    };
    let key = imaging_key();
    let mut runs = DataFrame::new(vec![
        scol("id", entries.keys().cloned().collect()),
        scol("scene_sha256", entries.values().map(|e| e.scene_hash.clone()).collect()),
        col("gap_tolerance", all(|e| e.gap)),
        scol("status", entries.values().map(|e| e.status.clone()).collect()),
        scol("message", entries.values().map(|e| e.message.clone()).collect()),
        col("wall_time_s", all(|e| e.wall_time)),
        scol("build", entries.values().map(|e| e.build.clone()).collect()),
        col("threads", all(|e| e.threads)),
        col("box_extent_m", all(|e| e.box_extent)),
        scol(
            "imaging",
            entries.values().map(|e| if e.image.is_some() { key.clone() } else { String::new() }).collect(),
        ),
    ])?;
    for (k, name) in IMAGE_COLUMNS.iter().enumerate() {
        runs.with_column(col(name, entries.values().map(|e| e.image.map_or(f64::NAN, |m| m[k])).collect()))?;
    }
    let mut frames = DataFrame::new(vec![
        scol("id", ids(|e| e.times.len())),
        col("time_s", each(|e| &e.times)),
        col("mean_length_m", each(|e| &e.mean_length)),
        col("box_limited_fraction", each(|e| &e.box_limited)),
    ])?;
    let mut aggs = DataFrame::new(vec![
        scol("id", ids(|e| e.last.len())),
        ucol("size", aggregates().map(|a| a.size as u64).collect()),
        col("length_m", per_aggregate(|a| a.length)),
        col("field_extent_m", per_aggregate(|a| a.field_extent)),
        col("orientation_deg", per_aggregate(|a| a.orientation_deg)),
        col("vx_m_per_s", per_aggregate(|a| a.com_velocity.x)),
        col("vy_m_per_s", per_aggregate(|a| a.com_velocity.y)),
        col("vz_m_per_s", per_aggregate(|a| a.com_velocity.z)),
        bools("percolating", |a| a.percolating),
        col("tracked_vx_m_per_s", per_aggregate(|a| a.tracked_vx)),
        bools("at_x_wall", |a| a.at_x_wall),
    ])?;
    let bytes = |df: &mut DataFrame| -> Result<Vec<u8>, Error> {
        let mut buf = vec![];
        ParquetWriter::new(&mut buf).finish(df)?;
        Ok(buf)
    };
    Ok([bytes(&mut runs)?, bytes(&mut frames)?, bytes(&mut aggs)?])
}

/// The columns of [`Run::image`], in its order.
const IMAGE_COLUMNS: [&str; 4] = ["projected_all_um", "projected_2plus_um", "image_all_um", "image_2plus_um"];

/// The imaging the image columns were measured with ("" where a run was not imaged): its
/// parameters and the version of the measurement, raised when the measurement itself changes.
fn imaging_key() -> String {
    format!("{:?} v{}", super::runs::IMAGING, super::runs::IMAGE_MEASURE_VERSION)
}

const FILES: [&str; 3] = ["runs.parquet", "frames.parquet", "aggregates.parquet"];

/// Brings `runs` and the digests in `dir` (one directory per experiment) together, reading
/// each experiment's digest once: every finished run read from its trajectory replaces its row
/// (the others are kept, and a digest is rewritten only when its content changes), and every run
/// whose trajectory is not here is filled from its row when the row was made from the same scene
/// at gap tolerance `gap`. Returns the experiments whose digest changed.
pub fn sync(runs: &mut [Run], dir: &Path, gap: f64) -> Result<Vec<String>, Error> {
    let mut experiments: Vec<String> = runs.iter().map(|r| r.experiment.clone()).collect();
    experiments.sort();
    experiments.dedup();
    let mut changed = vec![];
    for experiment in experiments {
        let here = dir.join(&experiment);
        let mut entries = read(&here).map_err(|e| format!("digest {experiment}: {e}"))?;
        let mut fresh = false;
        for r in runs.iter().filter(|r| r.experiment == experiment && finished(r)) {
            entries.insert(r.id.clone(), Entry::of(r, gap));
            fresh = true;
        }
        if fresh && write(&here, &entries)? {
            changed.push(experiment.clone());
        }
        for run in
            runs.iter_mut().filter(|r| r.experiment == experiment && r.source == Source::None && !r.file.exists())
        {
            if let Some(e) = entries.get(&run.id).filter(|e| e.scene_hash == run.scene_hash && e.gap == gap) {
                e.fill(run);
            }
        }
    }
    Ok(changed)
}

/// A finished run as a digest records it: the scene it ran and how it ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Recorded {
    pub scene_hash: String,
    /// `completed` or `unstable`.
    pub status: String,
    pub message: String,
}

/// The finished runs of experiment `experiment` that the digests under `roots` (each a report's
/// `digests/`) record, by run id. A run recorded in two roots takes the first's record.
pub fn recorded(roots: &[impl AsRef<Path>], experiment: &str) -> Result<BTreeMap<String, Recorded>, Error> {
    let mut all = BTreeMap::new();
    for root in roots.iter().rev() {
        let here = root.as_ref().join(experiment);
        let entries = read(&here).map_err(|e| format!("digest {}: {e}", here.display()))?;
        for (id, e) in entries {
            if e.status == status::COMPLETED || e.status == status::UNSTABLE {
                all.insert(id, Recorded { scene_hash: e.scene_hash, status: e.status, message: e.message });
            }
        }
    }
    Ok(all)
}

/// Brings the finished runs of the experiment files in `experiments` (and its `opt-in/`) into the
/// digests under `dir`, leaving the report itself as it is: how a machine adds its share of an
/// ensemble before the whole has been run. Returns the experiments whose digest changed.
pub fn update(experiments: &Path, dir: &Path, gap: f64) -> Result<Vec<String>, Error> {
    let files = super::runs::experiment_files(experiments, true)?;
    let mut runs = super::runs::load_runs(&files, gap)?;
    sync(&mut runs, dir, gap)
}

/// Writes `entries` as the digest in `here` unless it holds them already; whether it wrote.
fn write(here: &Path, entries: &BTreeMap<String, Entry>) -> Result<bool, Error> {
    let bytes = encode(entries)?;
    if FILES.iter().zip(&bytes).all(|(f, b)| std::fs::read(here.join(f)).is_ok_and(|old| &old == b)) {
        return Ok(false);
    }
    std::fs::create_dir_all(here)?;
    // Each table is written beside its place and renamed into it, so that an interrupted report
    // leaves the old table or the new one, never half of one.
    for (f, b) in FILES.iter().zip(&bytes) {
        let part = here.join(format!("{f}.part"));
        std::fs::write(&part, b)?;
        std::fs::rename(&part, here.join(f))?;
    }
    Ok(true)
}

/// The sentence a report gives on where its runs were read: "N from trajectories here, M from
/// the digests in `digests/`" (what needs positions uses the first only).
pub fn provenance(runs: &[Run]) -> String {
    let (here, digested) = (
        runs.iter().filter(|r| r.source == Source::Trajectory).count(),
        runs.iter().filter(|r| r.source == Source::Digest).count(),
    );
    match digested {
        0 => format!("all {here} runs read were on this machine"),
        _ => format!(
            "{here} runs read there, {digested} from the report's [`digests/`](digests/) of runs made where their \
             trajectories were kept: per-frame mean lengths, last-frame aggregates and image measures, no positions, \
             so the figures that need positions use the runs read there only"
        ),
    }
}

/// As [`super::runs::load_runs`], with the report's digests in `digests`: the finished runs read
/// from trajectories are recorded there, and the runs whose trajectories are not here are read
/// from there.
pub fn load_runs_digested(files: &[PathBuf], gap: f64, digests: &Path) -> Result<Vec<Run>, Box<dyn std::error::Error>> {
    let mut runs = super::runs::load_runs(files, gap)?;
    sync(&mut runs, digests, gap)?;
    Ok(runs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(id: &str, hash: &str) -> Run {
        Run {
            experiment: "e".into(),
            id: id.into(),
            scene_hash: hash.into(),
            file: "/nonexistent/run.h5".into(),
            status: "missing".into(),
            ..Default::default()
        }
    }

    fn finished_run(id: &str) -> Run {
        let summary = |size, length, percolating, at_x_wall| AggregateSummary {
            size,
            length,
            field_extent: 1.5e-5,
            orientation_deg: 3.25,
            com_velocity: Vec3::new(1e-6, -2e-7, 0.1 + 0.2),
            percolating,
            tracked_vx: 7.5e-6 / 3.0,
            at_x_wall,
        };
        Run {
            status: status::COMPLETED.into(),
            message: "ok".into(),
            wall_time: 12.345,
            build: "c198f6783e98".into(),
            threads: 2.0,
            box_extent: 3e-4,
            image: Some([1.25e2, f64::NAN, 3.5, 4.75]),
            times: vec![0.0, 1e-4, 2e-4],
            mean_length: vec![5.5e-6, f64::NAN, 1.1e-5],
            box_limited: vec![0.0, 0.0, 1.0 / 3.0],
            last: vec![summary(1, 5.5e-6, false, true), summary(40, f64::NAN, true, false)],
            source: Source::Trajectory,
            ..run(id, "h1")
        }
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn a_digest_gives_back_the_numbers_it_was_made_from() {
        let dir = tempfile::tempdir().unwrap();
        let mut made = vec![finished_run("a"), finished_run("b"), run("c", "h1")];
        assert_eq!(sync(&mut made, dir.path(), 1e-3).unwrap(), vec!["e".to_string()]);
        // Unchanged content is not rewritten.
        assert!(sync(&mut made, dir.path(), 1e-3).unwrap().is_empty());

        let mut read_back = vec![run("a", "h1"), run("b", "other scene"), run("c", "h1")];
        assert!(sync(&mut read_back, dir.path(), 1e-3).unwrap().is_empty());
        assert_eq!(read_back.iter().filter(|r| r.source == Source::Digest).count(), 1);
        let (a, b, c) = (&read_back[0], &read_back[1], &read_back[2]);
        assert_eq!(a.source, Source::Digest);
        assert_eq!((a.status.as_str(), a.message.as_str()), ("completed", "ok"));
        assert_eq!(bits(&[a.wall_time, a.threads, a.box_extent]), bits(&[12.345, 2.0, 3e-4]));
        assert_eq!(a.build, "c198f6783e98");
        assert_eq!(bits(&a.times), bits(&made[0].times));
        assert_eq!(a.image.map(|m| bits(&m)), made[0].image.map(|m| bits(&m)));
        assert_eq!(bits(&a.mean_length), bits(&made[0].mean_length));
        assert_eq!(bits(&a.box_limited), bits(&made[0].box_limited));
        assert_eq!(a.last.len(), 2);
        for (x, y) in a.last.iter().zip(&made[0].last) {
            assert_eq!((x.size, x.percolating, x.at_x_wall), (y.size, y.percolating, y.at_x_wall));
            let v = |s: &AggregateSummary| {
                bits(&[s.length, s.field_extent, s.orientation_deg, s.tracked_vx, s.com_velocity.x, s.com_velocity.z])
            };
            assert_eq!(v(x), v(y));
        }
        // Another scene under the same id, and a run never finished, are not filled.
        assert_eq!((b.source, b.status.as_str()), (Source::None, "missing"));
        assert_eq!(c.source, Source::None);
        // Another gap tolerance is another analysis.
        let mut other_gap = vec![run("a", "h1")];
        sync(&mut other_gap, dir.path(), 2e-3).unwrap();
        assert_eq!(other_gap[0].source, Source::None);

        // A later report keeps the rows it did not read and replaces those it did.
        let mut again = finished_run("a");
        again.wall_time = 1.0;
        sync(&mut [again], dir.path(), 1e-3).unwrap();
        let mut both = vec![run("a", "h1"), run("b", "h1")];
        sync(&mut both, dir.path(), 1e-3).unwrap();
        assert!(both.iter().all(|r| r.source == Source::Digest));
        assert_eq!((both[0].wall_time, both[1].wall_time), (1.0, 12.345));
    }

    /// A digest written before threads or image measures were recorded (no such columns) still
    /// reads, with them unknown.
    #[test]
    fn a_digest_without_thread_counts_reads_them_as_unknown() {
        let dir = tempfile::tempdir().unwrap();
        sync(&mut [finished_run("a")], dir.path(), 1e-3).unwrap();
        let path = dir.path().join("e").join("runs.parquet");
        let mut old =
            ParquetReader::new(std::fs::File::open(&path).unwrap()).finish().unwrap().drop("threads").unwrap();
        ParquetWriter::new(std::fs::File::create(&path).unwrap()).finish(&mut old).unwrap();
        let mut read_back = vec![run("a", "h1")];
        sync(&mut read_back, dir.path(), 1e-3).unwrap();
        assert_eq!(read_back[0].source, Source::Digest);
        assert!(read_back[0].threads.is_nan());
        assert!(read_back[0].image.is_some(), "the image columns were kept");
        assert_eq!(read_back[0].wall_time, 12.345);

        // Nor an imaging: the run's image measures are unknown.
        let mut older =
            ParquetReader::new(std::fs::File::open(&path).unwrap()).finish().unwrap().drop("imaging").unwrap();
        ParquetWriter::new(std::fs::File::create(&path).unwrap()).finish(&mut older).unwrap();
        let mut read_back = vec![run("a", "h1")];
        sync(&mut read_back, dir.path(), 1e-3).unwrap();
        assert_eq!((read_back[0].source, read_back[0].image), (Source::Digest, None));
    }
}

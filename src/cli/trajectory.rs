//! Commands that read trajectories: `magdem analyse`, `magdem info` and `magdem export`.

use magdem::analysis::aggregates::{finite_lengths, Aggregate, BOX_LIMITED_FRACTION};
use magdem::analysis::stats::summary;
use magdem::analysis::trajectory::FrameReader;
use magdem::core::state::Way;
use magdem::io::export;
use magdem::io::trajectory::Trajectory;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

type Error = Box<dyn std::error::Error>;

/// `magdem export --format`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum ExportFormat {
    /// An XDMF sidecar (FILE.xdmf) for ParaView.
    Xdmf,
    /// A LAMMPS text dump for OVITO: id type x y z vx vy vz radius mux muy muz.
    LammpsDump,
    /// A picture of the last frame (FILE.png): ParaView's pvbatch on a virtual X server, spheres
    /// of their radius coloured by the moment along x, seen along −z.
    Png,
}

/// Exit code 0, or 2 after `error: FILE: why` (an unreadable or foreign file is invalid input).
fn file_result(file: &Path, result: Result<(), Error>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}: {e}", file.display());
            ExitCode::from(2)
        }
    }
}

/// `magdem analyse FILE`: the aggregates of one frame, as a report or (`csv`) one CSV line.
pub fn analyse(file: &Path, frame: isize, gap: f64, csv: bool, header: bool) -> ExitCode {
    file_result(file, analyse_frame(file, frame, gap, csv, header))
}

fn analyse_frame(path: &Path, frame: isize, gap: f64, csv: bool, header: bool) -> Result<(), Error> {
    let t = Trajectory::open(path)?;
    let reader = FrameReader::new(&t)?;
    let (time, aggs) = reader.aggregates(frame, gap)?;
    if csv {
        print_csv(path, time, &aggs, reader.box_extent(), header);
        return Ok(());
    }
    print_report(time, &aggs, reader.box_extent(), gap);
    print!("gap tolerance sensitivity (mean length µm):");
    for g in [1e-4, 1e-3, 1e-2, 5e-2] {
        let (_, a) = reader.aggregates(frame, g)?;
        print!("  {g:e}: {:.2}", summary(&finite_lengths(&a)).mean * 1e6);
    }
    println!();
    Ok(())
}

/// Aggregates that reach the box-limited fraction of the box along the field (or percolate),
/// and those that percolate.
fn limited(aggs: &[Aggregate], box_extent: f64) -> (usize, usize) {
    (aggs.iter().filter(|a| a.box_limited(box_extent)).count(), aggs.iter().filter(|a| a.percolating).count())
}

fn print_csv(path: &Path, time: f64, aggs: &[Aggregate], box_extent: f64, header: bool) {
    let lengths: Vec<f64> = finite_lengths(aggs).iter().map(|l| l * 1e6).collect();
    let s = summary(&lengths);
    let (capped, percolating) = limited(aggs, box_extent);
    let sizes = summary(&aggs.iter().map(|a| a.size() as f64).collect::<Vec<_>>());
    let vx = summary(&aggs.iter().map(|a| a.com_velocity.x * 1e6).collect::<Vec<_>>());
    if header {
        println!(
            "file,time_s,aggregates,particles,mean_length_um,pop_std_length_um,sample_std_length_um,mean_size,pop_std_size,\
             mean_vx_um_s,pop_std_vx_um_s,box_limited_fraction,percolating"
        );
    }
    println!(
        "{},{time:e},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.4},{percolating}",
        path.display(),
        aggs.len(),
        aggs.iter().map(|a| a.size()).sum::<usize>(),
        s.mean,
        s.population_std,
        s.sample_std,
        sizes.mean,
        sizes.population_std,
        vx.mean,
        vx.population_std,
        capped as f64 / aggs.len() as f64
    );
}

/// The report's lines up to the gap-tolerance sensitivity: counts, lengths, box limits,
/// orientation and the size histogram.
fn print_report(time: f64, aggs: &[Aggregate], box_extent: f64, gap: f64) {
    let lengths: Vec<f64> = finite_lengths(aggs).iter().map(|l| l * 1e6).collect();
    let s = summary(&lengths);
    let (capped, percolating) = limited(aggs, box_extent);
    println!(
        "t = {time:e} s: {} aggregates of {} particles (gap tolerance {gap:e} of the smaller radius)",
        aggs.len(),
        aggs.iter().map(|a| a.size()).sum::<usize>()
    );
    println!("length (µm): mean {:.2}, population std {:.2}, sample std {:.2}", s.mean, s.population_std, s.sample_std);
    println!(
        "box-limited: {capped} of {} aggregates ({:.1} %) reach {:.0} % of the box's {:.1} µm along the field or percolate; \
         {percolating} percolate through a periodic face (no finite length, left out of the mean)",
        aggs.len(),
        100.0 * capped as f64 / aggs.len() as f64,
        100.0 * BOX_LIMITED_FRACTION,
        box_extent * 1e6
    );
    let chains: Vec<f64> = aggs.iter().filter(|a| a.size() > 1).map(|a| a.orientation_deg).collect();
    if !chains.is_empty() {
        println!("orientation to the field (aggregates of 2+): mean {:.1}°", summary(&chains).mean);
    }
    let mut histogram = std::collections::BTreeMap::new();
    for a in aggs {
        *histogram.entry(a.size()).or_insert(0) += 1;
    }
    println!("size: count  {}", histogram.iter().map(|(k, v)| format!("{k}:{v}")).collect::<Vec<_>>().join("  "));
}

/// `magdem info FILE`: the trajectory's attributes, frames and checkpoint.
pub fn info(file: &Path) -> ExitCode {
    file_result(file, describe(file))
}

fn describe(path: &Path) -> Result<(), Error> {
    let t = Trajectory::open(path)?;
    for key in [
        "format",
        "magdem_version",
        "git_commit",
        "engine",
        "integrator",
        "scene_name",
        "scene_sha256",
        "status",
        "status_message",
        "units",
    ] {
        println!("{key:<16} {}", t.attr_string(key)?);
    }
    println!("{:<16} {}", "particles", t.attr::<u64>("n_particles")?);
    println!("{:<16} {:e} s", "dt", t.attr::<f64>("dt")?);
    let times = t.times()?;
    println!(
        "{:<16} {} ({} to {} s)",
        "frames",
        times.len(),
        times.first().map_or("-".into(), |v| format!("{v:e}")),
        times.last().map_or("-".into(), |v| format!("{v:e}"))
    );
    let (state, frames) = t.checkpoint()?;
    println!(
        "{:<16} step {} (t = {:e} s) after frame {}, {} contacts",
        "checkpoint",
        state.step,
        state.time,
        frames,
        state.history.pairs.len()
    );
    if !state.exits.is_empty() {
        let names = t.outlet_names()?;
        let captured = state.exits.iter().filter(|e| e.way == Way::Captured).count();
        let mut ways = vec![format!("{captured} captured")];
        for (k, name) in names.iter().enumerate() {
            let through = state.exits.iter().filter(|e| e.way == Way::Outlet(k as u16)).count();
            ways.push(format!("{through} through {name}"));
        }
        println!("{:<16} {} left the run: {}", "exits", state.exits.len(), ways.join(", "));
    }
    Ok(())
}

/// `magdem export FILE… --format F [-o OUT]`: an XDMF sidecar, a LAMMPS dump or a picture of the
/// last frame per trajectory.
pub fn export(files: &[PathBuf], format: ExportFormat, output: Option<&Path>) -> ExitCode {
    if output.is_some() && files.len() > 1 {
        eprintln!("error: --output names one file; {} trajectories given", files.len());
        return ExitCode::from(2);
    }
    for file in files {
        let written = match format {
            ExportFormat::Xdmf => export::write_xdmf(file),
            ExportFormat::LammpsDump => {
                let out = output.map_or_else(|| export::beside(file, "dump"), Path::to_path_buf);
                export::write_lammps_dump(file, &out).map(|_| out)
            }
            ExportFormat::Png => {
                let out = output.map_or_else(|| export::beside(file, "png"), Path::to_path_buf);
                let xdmf = export::write_xdmf(file);
                xdmf.and_then(|xdmf| export::render_last_frame(&xdmf, &out).map(|()| out).map_err(Error::from))
            }
        };
        match written {
            Ok(out) => println!("{}: wrote {}", file.display(), out.display()),
            // A render that fails is the machine's, not the file's: exit 1, not 2.
            Err(e) => {
                eprintln!(
                    "error: {}: {}",
                    file.display(),
                    e.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
                );
                return ExitCode::from(if e.is::<export::RenderError>() { 1 } else { 2 });
            }
        }
    }
    ExitCode::SUCCESS
}

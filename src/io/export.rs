//! Trajectories for the tools of the field: an XDMF sidecar (`OUT.xdmf` beside `OUT.h5`) that
//! ParaView reads, describing each frame as points with radius, species, velocity, angular
//! velocity and moment, and a LAMMPS text dump (`id type x y z vx vy vz radius mux muy muz`) that
//! OVITO and LAMMPS' own tools read.
//!
//! ParaView's two XDMF readers name a frame of `/frames/<name>` differently (the legacy reader a
//! `HyperSlab` item, the default `Xdmf3ReaderS` a `path|start:stride:count:dims` suffix), and
//! neither reads the other's form. So the sidecar names plain datasets `/xdmf/<name>/<frame>`:
//! HDF5 virtual datasets, each mapping one frame of `/frames/<name>` (no copy of the data).

use super::trajectory::Trajectory;
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

type Error = Box<dyn std::error::Error>;

/// Per-frame vector datasets described in the sidecar, with their XDMF attribute names.
const VECTORS: [(&str, &str); 3] =
    [("velocity", "velocity"), ("angular_velocity", "angular_velocity"), ("moment", "moment")];

/// `path` with its extension replaced by `ext`.
pub fn beside(path: &Path, ext: &str) -> PathBuf {
    path.with_extension(ext)
}

/// A hyperslab of frame `k` of the (F, N, 3) dataset `name` of `file`.
/// The sidecar's item for frame `k` of `/frames/<name>`: its virtual dataset.
fn slab(file: &str, name: &str, k: usize, n: usize) -> String {
    format!(
        "<DataItem Dimensions=\"{n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{file}:/{VIEWS}/{name}/{k}</DataItem>"
    )
}

/// The group of the per-frame virtual datasets the sidecar names.
pub const VIEWS: &str = "xdmf";

/// Frame `k` of a `frames × n × 3` dataset.
fn frame_of(k: usize, n: usize) -> hdf5::Hyperslab {
    vec![(k..k + 1).into(), (0..n).into(), (0..3).into()].into()
}

/// Adds to `h5` the virtual dataset `/xdmf/<name>/<k>` of every frame `k` and per-frame vector
/// `name` that it lacks: an `n × 3` view of `/frames/<name>[k]` in the same file.
fn write_frame_views(h5: &Path, frames: usize, n: usize) -> Result<(), Error> {
    let file = hdf5::File::open_rw(h5)?;
    let views = file.group(VIEWS).or_else(|_| file.create_group(VIEWS))?;
    for name in std::iter::once("position").chain(VECTORS.iter().map(|(name, _)| *name)) {
        let group = views.group(name).or_else(|_| views.create_group(name))?;
        let source = format!("frames/{name}");
        let extents = file.dataset(&source)?.shape();
        for k in 0..frames {
            if group.link_exists(&k.to_string()) {
                continue;
            }
            group
                .new_dataset::<f64>()
                .shape((n, 3))
                .virtual_map(".", &source, extents.clone(), frame_of(k, n), (n, 3), ..)
                .create(k.to_string().as_str())?;
        }
    }
    Ok(())
}

/// Writes the XDMF sidecar of trajectory `h5` (every frame it holds); returns its path.
pub fn write_xdmf(h5: &Path) -> Result<PathBuf, Error> {
    let t = Trajectory::open(h5)?;
    let (frames, n) = (t.frames()?, t.attr::<u64>("n_particles")? as usize);
    let times = t.times()?;
    drop(t);
    write_frame_views(h5, frames, n)?;
    // The sidecar sits beside the file and names it relatively, so the pair can move together.
    let file = h5.file_name().and_then(|f| f.to_str()).ok_or("trajectory path has no file name")?;
    let mut x = String::from(
        "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n<Domain>\n\
         <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
    );
    for (k, time) in times.iter().enumerate().take(frames) {
        let _ = write!(
            x,
            "<Grid Name=\"frame {k}\" GridType=\"Uniform\">\n<Time Value=\"{time:e}\"/>\n\
             <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{n}\" NodesPerElement=\"1\"/>\n\
             <Geometry GeometryType=\"XYZ\">{}</Geometry>\n\
             <Attribute Name=\"radius\" AttributeType=\"Scalar\" Center=\"Node\">\
             <DataItem Dimensions=\"{n}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{file}:/particles/radius</DataItem></Attribute>\n\
             <Attribute Name=\"species\" AttributeType=\"Scalar\" Center=\"Node\">\
             <DataItem Dimensions=\"{n}\" NumberType=\"UInt\" Precision=\"2\" Format=\"HDF\">{file}:/particles/species</DataItem></Attribute>\n",
            slab(file, "position", k, n)
        );
        for (name, label) in VECTORS {
            let _ = writeln!(
                x,
                "<Attribute Name=\"{label}\" AttributeType=\"Vector\" Center=\"Node\">{}</Attribute>",
                slab(file, name, k, n)
            );
        }
        x += "</Grid>\n";
    }
    x += "</Grid>\n</Domain>\n</Xdmf>\n";
    let out = beside(h5, "xdmf");
    std::fs::write(&out, x)?;
    Ok(out)
}

/// Writes every frame of trajectory `h5` as a LAMMPS text dump to `out`.
pub fn write_lammps_dump(h5: &Path, out: &Path) -> Result<(), Error> {
    let t = Trajectory::open(h5)?;
    let (_, domain) = Scene::layout(&t.scene_text()?, &h5.display().to_string())?;
    let (d, frames) = (&domain, t.frames()?);
    let steps: Vec<u64> = t.file.dataset("frames/step")?.read_raw()?;
    let radius: Vec<f64> = t.file.dataset("particles/radius")?.read_raw()?;
    let species: Vec<u16> = t.file.dataset("particles/species")?.read_raw()?;
    let bounds: Vec<&str> = d.periodic.iter().map(|&p| if p { "pp" } else { "ff" }).collect();
    let mut text = String::new();
    for (k, step) in steps.iter().enumerate().take(frames) {
        let (x, v, m) =
            (t.frame_vectors("position", k)?, t.frame_vectors("velocity", k)?, t.frame_vectors("moment", k)?);
        // The particles in the run: those that left it (NaN rows) are not written, as a LAMMPS
        // dump lists the atoms present in each snapshot.
        let present: Vec<usize> = (0..x.len()).filter(|&i| !x[i].x.is_nan()).collect();
        let _ = writeln!(
            text,
            "ITEM: TIMESTEP\n{}\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS {}",
            step,
            present.len(),
            bounds.join(" ")
        );
        for a in 0..3 {
            let _ = writeln!(text, "{:e} {:e}", d.lo[a], d.hi[a]);
        }
        text += "ITEM: ATOMS id type x y z vx vy vz radius mux muy muz\n";
        for i in present {
            let _ = writeln!(
                text,
                "{} {} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e}",
                i + 1,
                species[i] + 1,
                x[i].x,
                x[i].y,
                x[i].z,
                v[i].x,
                v[i].y,
                v[i].z,
                radius[i],
                m[i].x,
                m[i].y,
                m[i].z
            );
        }
    }
    std::fs::write(out, text)?;
    Ok(())
}

/// A pvbatch script (arguments: XDMF file, PNG file) that renders a trajectory's last frame:
/// the particles as spheres of their radius, coloured by the moment along x (one colour where all
/// moments are equal), seen along −z (the field along x lies in the picture), the view fitted to
/// the particles with the colour bar on its right.
/// [`render_last_frame`] runs it.
pub const PARAVIEW_RENDER: &str = r#"
import sys
from paraview.simple import *
reader = XDMFReader(FileNames=[sys.argv[1]])
reader.UpdatePipelineInformation()
view = CreateRenderView()
view.ViewSize = [1400, 1000]
view.Background = [1, 1, 1]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
view.ViewTime = reader.TimestepValues[-1]
shown = Show(reader, view)
shown.SetRepresentationType("Point Gaussian")
shown.ShaderPreset = "Sphere"
shown.ScaleByArray = 1
shown.SetScaleArray = ["POINTS", "radius"]
shown.ScaleTransferFunction.Points = [0.0, 0.0, 0.5, 0.0, 1.0, 1.0, 0.5, 0.0]
shown.GaussianRadius = 1.0
reader.UpdatePipeline(reader.TimestepValues[-1])
low, high = reader.PointData["moment"].GetRange(0)
if high > low:
    ColorBy(shown, ("POINTS", "moment", "X"))
    shown.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(GetColorTransferFunction("moment"), view)
    bar.Title = "moment along x (A m^2)"
    bar.ComponentTitle = ""
    bar.TitleColor = [0, 0, 0]
    bar.LabelColor = [0, 0, 0]
else:
    ColorBy(shown, None)
    shown.AmbientColor = shown.DiffuseColor = [0.35, 0.45, 0.75]
outline = Show(Outline(Input=reader), view)
outline.DiffuseColor = [0, 0, 0]
outline.AmbientColor = [0, 0, 0]
# A view fitted to the particles (centres plus the largest radius and a small margin), seen along
# -z, with room on the right for the colour bar: no empty border around the picture.
x0, x1, y0, y1, z0, z1 = reader.GetDataInformation().GetBounds()
pad = reader.PointData["radius"].GetRange()[1] + 0.02 * max(x1 - x0, y1 - y0)
width, height = x1 - x0 + 2 * pad, y1 - y0 + 2 * pad
pixels = 1000
bar_pixels = 220 if high > low else 0
picture = [int(pixels * width / height) + bar_pixels, pixels]
per_pixel = height / pixels
view.ViewSize = picture
# The first render resets the camera to the scene's bounding sphere; the fitted view comes after.
Render(view)
cx, cy, cz = 0.5 * (x0 + x1) + 0.5 * bar_pixels * per_pixel, 0.5 * (y0 + y1), 0.5 * (z0 + z1)
view.CameraPosition = [cx, cy, cz + 10 * max(width, height, z1 - z0)]
view.CameraFocalPoint = [cx, cy, cz]
view.CameraViewUp = [0, 1, 0]
view.CameraParallelProjection = 1
view.CameraParallelScale = 0.5 * height
view.OrientationAxesVisibility = 0
if high > low:
    bar.WindowLocation = "Any Location"
    bar.Orientation = "Vertical"
    bar.Position = [1.0 - 0.9 * bar_pixels / picture[0], 0.1]
    bar.ScalarBarLength = 0.8
Render(view)
SaveScreenshot(sys.argv[2], view, ImageResolution=picture)
"#;

/// Why [`render_last_frame`] made no picture.
#[derive(Debug)]
pub enum RenderError {
    /// The program (`Xvfb` or `pvbatch`) is not installed.
    Missing(&'static str),
    /// It ran and failed, timed out, or wrote no picture: what happened.
    Failed(String),
}

impl std::fmt::Display for RenderError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            RenderError::Missing(program) => write!(f, "{program} is not installed"),
            RenderError::Failed(why) => write!(f, "the render failed: {why}"),
        }
    }
}

impl std::error::Error for RenderError {}

/// Seconds Xvfb may take to name its display.
const XVFB_START_S: u64 = 20;
/// Seconds pvbatch may take to render one frame.
const PVBATCH_S: u64 = 300;

/// `Missing(program)` where it is not installed, else `Failed` with the reason.
fn spawn_error(program: &'static str, e: std::io::Error) -> RenderError {
    if e.kind() == std::io::ErrorKind::NotFound {
        RenderError::Missing(program)
    } else {
        RenderError::Failed(format!("{program}: {e}"))
    }
}

/// The last line of `text` that is not blank.
fn last_line(text: &[u8]) -> String {
    let text = String::from_utf8_lossy(text);
    text.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no message").trim().to_string()
}

/// A child process, stopped with SIGTERM (so that Xvfb removes its lock and socket) and reaped
/// when dropped.
struct Stopped(std::process::Child);

impl Drop for Stopped {
    fn drop(&mut self) {
        if let Ok(None) = self.0.try_wait() {
            // SAFETY: kill(2) on the pid of our own child, which has not been reaped yet.
            unsafe { libc::kill(self.0.id() as libc::pid_t, libc::SIGTERM) };
        }
        let _ = self.0.wait();
    }
}

/// A virtual X server and its display (`:N`). `-displayfd` makes Xvfb name its display only once
/// it accepts clients; `xvfb-run` waits for SIGUSR1 instead, and on a loaded machine its pvbatch
/// met no server ("bad X server connection") three times running.
fn virtual_display() -> Result<(Stopped, String), RenderError> {
    use std::io::BufRead;
    use std::process::{Command, Stdio};
    let mut server = Command::new("Xvfb")
        .args(["-displayfd", "1", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| spawn_error("Xvfb", e))?;
    let stdout = server.stdout.take();
    let server = Stopped(server);
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        if let Some(out) = stdout {
            let _ = std::io::BufReader::new(out).read_line(&mut line);
        }
        let _ = send.send(line);
    });
    let line = receive.recv_timeout(std::time::Duration::from_secs(XVFB_START_S)).unwrap_or_default();
    match line.trim().parse::<u32>() {
        Ok(number) => Ok((server, format!(":{number}"))),
        Err(_) => Err(RenderError::Failed(format!("Xvfb named no display within {XVFB_START_S} s"))),
    }
}

/// One pvbatch run of `script` on `display`, stopped after [`PVBATCH_S`] seconds.
fn pvbatch(script: &Path, xdmf: &Path, png: &Path, display: &str) -> Result<(), RenderError> {
    use std::process::{Command, Stdio};
    let stderr = tempfile_beside(png, "pvbatch-log");
    let log = std::fs::File::create(&stderr).map_err(|e| RenderError::Failed(e.to_string()))?;
    let child = Command::new("pvbatch")
        .arg(script)
        .arg(xdmf)
        .arg(png)
        .env("DISPLAY", display)
        .stdout(Stdio::null())
        .stderr(log)
        .spawn()
        .map_err(|e| spawn_error("pvbatch", e))?;
    let mut child = Stopped(child);
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(PVBATCH_S);
    let status = loop {
        match child.0.try_wait() {
            Ok(Some(status)) => break Some(status),
            Ok(None) if std::time::Instant::now() < deadline => {
                std::thread::sleep(std::time::Duration::from_millis(50))
            }
            _ => break None,
        }
    };
    let why = last_line(&std::fs::read(&stderr).unwrap_or_default());
    let _ = std::fs::remove_file(&stderr);
    match status {
        Some(s) if s.success() => Ok(()),
        Some(_) => Err(RenderError::Failed(why)),
        None => Err(RenderError::Failed(format!("pvbatch did not finish within {PVBATCH_S} s"))),
    }
}

/// A path beside `path` for a scratch file of this process (`.FILE.PID.K.NAME`, `NAME` last so
/// that its extension is NAME's).
fn tempfile_beside(path: &Path, name: &str) -> PathBuf {
    static FILES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = FILES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let file = path.file_name().and_then(|f| f.to_str()).unwrap_or("render");
    path.with_file_name(format!(".{file}.{}.{k}.{name}", std::process::id()))
}

/// Renders the last frame of the trajectory that `xdmf` describes into `png` with
/// [`PARAVIEW_RENDER`], under pvbatch on a virtual X server of its own. Up to three attempts,
/// a second apart (pvbatch can fail to start on a loaded machine); the picture is written under
/// a scratch name and moved into place only when it is there, so a failed render leaves an
/// earlier `png` as it was.
pub fn render_last_frame(xdmf: &Path, png: &Path) -> Result<(), RenderError> {
    let failed = |e: std::io::Error| RenderError::Failed(e.to_string());
    let script = tempfile_beside(png, "render.py");
    let scratch = tempfile_beside(png, "png");
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&script)
        .and_then(|mut f| std::io::Write::write_all(&mut f, PARAVIEW_RENDER.as_bytes()))
        .map_err(failed)?;
    let outcome = virtual_display().and_then(|(_server, display)| {
        let mut why = RenderError::Failed("no attempt".into());
        for attempt in 1..=3 {
            if attempt > 1 {
                std::thread::sleep(std::time::Duration::from_secs(1));
            }
            why = match pvbatch(&script, xdmf, &scratch, &display) {
                Ok(()) if std::fs::metadata(&scratch).is_ok_and(|m| m.len() > 0) => {
                    return std::fs::rename(&scratch, png).map_err(failed)
                }
                Ok(()) => RenderError::Failed("pvbatch wrote no picture".into()),
                Err(missing @ RenderError::Missing(_)) => return Err(missing),
                Err(e) => e,
            };
            eprintln!("pvbatch, attempt {attempt} of 3: {why}");
        }
        Err(why)
    });
    let _ = std::fs::remove_file(&script);
    let _ = std::fs::remove_file(&scratch);
    outcome
}

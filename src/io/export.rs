//! Trajectories for the tools of the field: an XDMF sidecar (`OUT.xdmf` beside `OUT.h5`) that
//! ParaView reads, describing each frame as points with radius, species, velocity, angular
//! velocity and moment by reference to the HDF5 datasets in place (hyperslabs, no copy), and a
//! LAMMPS text dump (`id type x y z vx vy vz radius mux muy muz`) that OVITO and LAMMPS' own
//! tools read.

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
fn slab(file: &str, name: &str, k: usize, frames: usize, n: usize) -> String {
    format!(
        "<DataItem ItemType=\"HyperSlab\" Dimensions=\"{n} 3\" Type=\"HyperSlab\">\
         <DataItem Dimensions=\"3 3\" Format=\"XML\">{k} 0 0 1 1 1 1 {n} 3</DataItem>\
         <DataItem Dimensions=\"{frames} {n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{file}:/frames/{name}</DataItem>\
         </DataItem>"
    )
}

/// Writes the XDMF sidecar of trajectory `h5` (every frame it holds); returns its path.
pub fn write_xdmf(h5: &Path) -> Result<PathBuf, Error> {
    let t = Trajectory::open(h5)?;
    let (frames, n) = (t.frames()?, t.attr::<u64>("n_particles")? as usize);
    let times = t.times()?;
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
            slab(file, "position", k, frames, n)
        );
        for (name, label) in VECTORS {
            let _ = writeln!(
                x,
                "<Attribute Name=\"{label}\" AttributeType=\"Vector\" Center=\"Node\">{}</Attribute>",
                slab(file, name, k, frames, n)
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
        let _ = writeln!(
            text,
            "ITEM: TIMESTEP\n{}\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS {}",
            step,
            x.len(),
            bounds.join(" ")
        );
        for a in 0..3 {
            let _ = writeln!(text, "{:e} {:e}", d.lo[a], d.hi[a]);
        }
        text += "ITEM: ATOMS id type x y z vx vy vz radius mux muy muz\n";
        for i in 0..x.len() {
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
/// the particles as spheres of their radius, coloured by the moment along x, seen along −z (the
/// field along x lies in the picture). Run it as `xvfb-run -a pvbatch SCRIPT FILE.xdmf OUT.png`.
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
ColorBy(shown, ("POINTS", "moment", "X"))
shown.SetScalarBarVisibility(view, True)
bar = GetScalarBar(GetColorTransferFunction("moment"), view)
bar.Title = "moment along x (A m^2)"
bar.ComponentTitle = ""
bar.TitleColor = [0, 0, 0]
bar.LabelColor = [0, 0, 0]
outline = Show(Outline(Input=reader), view)
outline.DiffuseColor = [0, 0, 0]
outline.AmbientColor = [0, 0, 0]
view.CameraPosition = [0, 0, 1]
view.CameraFocalPoint = [0, 0, 0]
view.CameraViewUp = [0, 1, 0]
view.CameraParallelProjection = 1
view.ResetCamera()
view.OrientationAxesVisibility = 1
Render(view)
SaveScreenshot(sys.argv[2], view, ImageResolution=[1400, 1000])
"#;

//! The experiment's length measurement emulated: particles projected onto an imaging plane as
//! discs, rasterised, labelled into 8-connected regions (the default of MATLAB's `bwlabel` and
//! `regionprops`), and each region's `MajorAxisLength` as `regionprops` defines it: the major
//! axis of the ellipse with the region's normalised second central moments,
//!
//!   u_xx = Σ(x − x̄)²/N + 1/12,  u_yy = Σ(y − ȳ)²/N + 1/12,  u_xy = Σ(x − x̄)(y − ȳ)/N,
//!   MajorAxisLength = 2√2 √(u_xx + u_yy + √((u_xx − u_yy)² + 4 u_xy²))
//!
//! over the N pixel centres (1/12 is a unit pixel's own second moment). For a disc it is the
//! diameter; for a straight chain of n touching discs 4√(d²(n² − 1)/12 + d²/16), which tends to
//! 1.155 n d: the ellipse of a rod is longer than the rod.
//!
//! A pixel belongs to a disc when its centre lies within the disc's radius.

use crate::core::state::Vec3;

/// One labelled region of an image.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Particles whose discs make up the region.
    pub particles: Vec<usize>,
    pub pixels: usize,
    /// MajorAxisLength (m).
    pub major_axis: f64,
}

/// Running second moments of a set of pixel centres (pixel units).
#[derive(Debug, Clone, Copy, Default)]
struct Moments {
    n: f64,
    x: f64,
    y: f64,
    xx: f64,
    yy: f64,
    xy: f64,
}

impl Moments {
    fn add(&mut self, i: usize, j: usize) {
        let (x, y) = (i as f64, j as f64);
        self.n += 1.0;
        self.x += x;
        self.y += y;
        self.xx += x * x;
        self.yy += y * y;
        self.xy += x * y;
    }

    /// MajorAxisLength in pixels.
    fn major_axis(&self) -> f64 {
        let (mx, my) = (self.x / self.n, self.y / self.n);
        let uxx = self.xx / self.n - mx * mx + 1.0 / 12.0;
        let uyy = self.yy / self.n - my * my + 1.0 / 12.0;
        let uxy = self.xy / self.n - mx * my;
        let common = ((uxx - uyy).powi(2) + 4.0 * uxy * uxy).sqrt();
        2.0 * std::f64::consts::SQRT_2 * (uxx + uyy + common).sqrt()
    }
}

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

/// A raster of discs on the rectangle `lo`–`hi` of the imaging plane.
struct Raster {
    nx: usize,
    ny: usize,
    /// Disc that first covered each pixel (`u32::MAX`: background).
    owner: Vec<u32>,
    parent: Vec<usize>,
}

impl Raster {
    fn new(centres: &[[f64; 2]], radii: &[f64], lo: [f64; 2], hi: [f64; 2], pixel: f64) -> Self {
        let nx = ((hi[0] - lo[0]) / pixel).ceil().max(1.0) as usize;
        let ny = ((hi[1] - lo[1]) / pixel).ceil().max(1.0) as usize;
        let mut raster = Self { nx, ny, owner: vec![u32::MAX; nx * ny], parent: (0..centres.len()).collect() };
        for (k, (c, &r)) in centres.iter().zip(radii).enumerate() {
            // Pixel (i, j) has its centre at lo + (i + ½, j + ½)·pixel.
            let (u, v) = ((c[0] - lo[0]) / pixel - 0.5, (c[1] - lo[1]) / pixel - 0.5);
            let rp = r / pixel;
            let span = |centre: f64, n: usize| {
                ((centre - rp).ceil().max(0.0) as usize, ((centre + rp).floor().max(-1.0) + 1.0).min(n as f64) as usize)
            };
            let ((i0, i1), (j0, j1)) = (span(u, nx), span(v, ny));
            for j in j0..j1 {
                for i in i0..i1 {
                    if (i as f64 - u).powi(2) + (j as f64 - v).powi(2) <= rp * rp {
                        let cell = &mut raster.owner[j * nx + i];
                        if *cell == u32::MAX {
                            *cell = k as u32;
                        } else {
                            let (a, b) = (find(&mut raster.parent, k), find(&mut raster.parent, *cell as usize));
                            raster.parent[a] = b;
                        }
                    }
                }
            }
        }
        raster.join_neighbours();
        raster
    }

    /// Joins the discs of 8-connected covered pixels.
    fn join_neighbours(&mut self) {
        let (nx, ny) = (self.nx, self.ny);
        for j in 0..ny {
            for i in 0..nx {
                let a = self.owner[j * nx + i];
                if a == u32::MAX {
                    continue;
                }
                // Right, and the three neighbours of the row above: every 8-neighbour pair once.
                let right = (i + 1 < nx).then(|| (i + 1, j));
                let above = (j + 1 < ny)
                    .then_some(j + 1)
                    .into_iter()
                    .flat_map(|jj| [i.wrapping_sub(1), i, i + 1].map(|ii| (ii, jj)));
                for (ii, jj) in right.into_iter().chain(above) {
                    if ii >= nx {
                        continue;
                    }
                    let b = self.owner[jj * nx + ii];
                    if b != u32::MAX && b != a {
                        let (ra, rb) = (find(&mut self.parent, a as usize), find(&mut self.parent, b as usize));
                        self.parent[ra] = rb;
                    }
                }
            }
        }
    }

    /// The regions, largest first, with lengths in metres.
    fn regions(mut self, pixel: f64) -> Vec<Region> {
        let n = self.parent.len();
        let mut moments = vec![Moments::default(); n];
        for j in 0..self.ny {
            for i in 0..self.nx {
                let a = self.owner[j * self.nx + i];
                if a != u32::MAX {
                    let root = find(&mut self.parent, a as usize);
                    moments[root].add(i, j);
                }
            }
        }
        let mut members: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for k in 0..n {
            let root = find(&mut self.parent, k);
            members.entry(root).or_default().push(k);
        }
        let mut out: Vec<Region> = members
            .into_iter()
            .filter(|(root, _)| moments[*root].n > 0.0)
            .map(|(root, particles)| Region {
                particles,
                pixels: moments[root].n as usize,
                major_axis: moments[root].major_axis() * pixel,
            })
            .collect();
        out.sort_by(|a, b| b.pixels.cmp(&a.pixels).then(a.particles[0].cmp(&b.particles[0])));
        out
    }
}

/// How the particles are imaged: the two in-plane axes (the viewing direction is the third)
/// and the pixel size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Imaging {
    pub axes: [usize; 2],
    /// m
    pub pixel: f64,
}

impl Imaging {
    fn project(&self, x: &Vec3) -> [f64; 2] {
        [x[self.axes[0]], x[self.axes[1]]]
    }

    /// Every particle projected through the whole depth onto the rectangle `lo`–`hi` (in 3-D;
    /// the in-plane components are used) and labelled: what an image in which every depth is in
    /// focus shows. Discs that overlap in projection merge although the particles may not touch.
    pub fn image(&self, positions: &[Vec3], radii: &[f64], lo: &Vec3, hi: &Vec3) -> Vec<Region> {
        let centres: Vec<[f64; 2]> = positions.iter().map(|x| self.project(x)).collect();
        Raster::new(&centres, radii, self.project(lo), self.project(hi), self.pixel).regions(self.pixel)
    }

    /// MajorAxisLength (m) of one group of particles imaged alone (unwrapped positions): the
    /// experiment's measure of one aggregate under perfect segmentation.
    pub fn major_axis(&self, positions: &[Vec3], radii: &[f64]) -> f64 {
        let centres: Vec<[f64; 2]> = positions.iter().map(|x| self.project(x)).collect();
        let margin = 2.0 * self.pixel + radii.iter().fold(0.0_f64, |a, &r| a.max(r));
        let lo = [0, 1].map(|k| centres.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min) - margin);
        let hi = [0, 1].map(|k| centres.iter().map(|c| c[k]).fold(f64::NEG_INFINITY, f64::max) + margin);
        let mut raster = Raster::new(&centres, radii, lo, hi, self.pixel);
        // One region whatever the pixels' connectivity: join every disc.
        raster.parent.iter_mut().for_each(|p| *p = 0);
        raster.regions(self.pixel).first().map_or(f64::NAN, |r| r.major_axis)
    }
}

/// MajorAxisLength of a straight chain of `n` touching discs of diameter `d` in the limit of
/// small pixels: 4√(d²(n² − 1)/12 + d²/16).
pub fn chain_major_axis(n: usize, d: f64) -> f64 {
    let n = n as f64;
    4.0 * (d * d * (n * n - 1.0) / 12.0 + d * d / 16.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    const D: f64 = 11e-6;
    const XY: Imaging = Imaging { axes: [0, 1], pixel: 0.25e-6 };

    #[test]
    fn a_disc_measures_its_diameter() {
        let l = XY.major_axis(&[Vec3::new(1e-5, 2e-5, 3e-5)], &[0.5 * D]);
        assert!((l / D - 1.0).abs() < 0.01, "{l}");
    }

    #[test]
    fn a_straight_chain_measures_its_ellipse_not_its_length() {
        for n in [2, 5, 20] {
            let pos: Vec<Vec3> = (0..n).map(|k| Vec3::new(k as f64 * D, 0.0, 0.0)).collect();
            let l = XY.major_axis(&pos, &vec![0.5 * D; n]);
            let exact = chain_major_axis(n, D);
            assert!((l / exact - 1.0).abs() < 0.01, "n = {n}: {l} against {exact}");
            // Along the viewing axis the chain is one disc.
            let end_on: Vec<Vec3> = pos.iter().map(|p| Vec3::new(0.0, 0.0, p.x)).collect();
            assert!((XY.major_axis(&end_on, &vec![0.5 * D; n]) / D - 1.0).abs() < 0.01);
        }
        assert!((chain_major_axis(1000, D) / (1000.0 * D) - 4.0 / 12f64.sqrt()).abs() < 1e-3);
    }

    #[test]
    fn discs_that_overlap_in_projection_merge_and_separate_ones_do_not() {
        let lo = Vec3::zeros();
        let hi = Vec3::new(2e-4, 2e-4, 2e-4);
        // Two particles far apart in depth but overlapping in projection, and one alone.
        let pos =
            [Vec3::new(5e-5, 5e-5, 1e-5), Vec3::new(5e-5 + 0.5 * D, 5e-5, 1.5e-4), Vec3::new(1.5e-4, 1.5e-4, 1e-4)];
        let regions = XY.image(&pos, &[0.5 * D; 3], &lo, &hi);
        assert_eq!(regions.len(), 2);
        assert_eq!(regions[0].particles, vec![0, 1]);
        assert_eq!(regions[1].particles, vec![2]);
        assert!((regions[1].major_axis / D - 1.0).abs() < 0.01);
        // Gap of two pixels: apart.
        let pos = [Vec3::new(5e-5, 5e-5, 0.0), Vec3::new(5e-5 + D + 2.0 * XY.pixel, 5e-5, 0.0)];
        assert_eq!(XY.image(&pos, &[0.5 * D; 2], &lo, &hi).len(), 2);
    }
}

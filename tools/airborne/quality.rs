//! A scan's splats against the scene's true surfaces (`gen_airborne`'s `truth.ply`),
//! view by view: the scan leaves only, the truth mesh rendered at 4×4 the size and
//! averaged in linear light, both from the same orbit cameras about the truth's centre.
//! Prints FLIP and SSIM, and the *invented surface*: among the open-space pixels (the
//! truth shows the ground there, through the space under a crown, the bridge's deck or
//! the carport's roof, which `truth_regions.ply` fills from the same camera), those
//! where the splats stand more than half a metre above what the truth shows there (a
//! crown's curtain, a sheet under the deck, a block under the roof), by open space,
//! and those of them beyond the rim of the truth's objects.
//! Heights come from both drawn in `--mode elevation`, decoded from the ramp's colour
//! by chromaticity, which shading does not change ([`heights_of`]).
//!
//! ```text
//! cargo run --release --example airborne_quality -- data/airborne/scan.las \
//!     data/airborne/truth.ply [--views 4] [--images DIR]
//! ```

mod classes;

use std::path::{Path, PathBuf};

use clap::Parser;
use glam::DVec3;
use spt::apps::stats::quantile;
use spt::eval::perceptual::{downsample, flip_mean, ssim_mean};
use spt::io::png::write_png;
use spt::render::camera::heights;
use spt::render::{Camera, Gpu, GpuScene, Image, Mode, Renderer, Settings};
use spt::tree::scene::Scene;

use classes::{Kind, UNDER};

#[derive(Parser)]
struct Args {
    /// The scan (LAS, LAZ, PLY or .spt).
    scan: PathBuf,
    /// The truth mesh (`truth_regions.ply` beside it marks the overhung ground).
    truth: PathBuf,
    /// Orbit views, azimuth every 360°/views.
    #[arg(long, default_value_t = 4)]
    views: u32,
    /// Elevation of the views, degrees.
    #[arg(long, default_value_t = 35.0)]
    elevation: f64,
    /// Distance in the truth's bounding-sphere radii.
    #[arg(long, default_value_t = 1.2)]
    distance: f64,
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// The splats' display mode (the truth is drawn shaded).
    #[arg(long, value_enum, default_value = "shaded")]
    mode: Mode,
    /// Write each view's splats and truth into DIR.
    #[arg(long)]
    images: Option<PathBuf>,
}

const SUPERSAMPLE: u32 = 4;

/// The colour of `rgba` nearest by hue in linear light among `colors` (its index);
/// `None` for the white background or a grey. Shading scales a colour and light adds
/// white to it: neither turns its hue.
fn nearest(rgba: &[u8], colors: &[[u8; 3]]) -> Option<usize> {
    let h = hue(rgba)?;
    let apart =
        |c: &[u8; 3]| hue(c).map_or(f64::INFINITY, |k| (h - k).abs().min(360.0 - (h - k).abs()));
    (0..colors.len()).min_by(|&a, &b| apart(&colors[a]).total_cmp(&apart(&colors[b])))
}

/// The hue (degrees) of the sRGB colour `c` in linear light; `None` when it is nearly
/// grey (its channels within 5 % of its largest).
fn hue(c: &[u8]) -> Option<f64> {
    let [r, g, b] = [0, 1, 2].map(|i| linear(c[i]));
    let (max, min) = (r.max(g).max(b), r.min(g).min(b));
    if max <= 0.0 || (max - min) / max < 0.05 {
        return None;
    }
    let d = max - min;
    let h = if max == r {
        60.0 * ((g - b) / d)
    } else if max == g {
        60.0 * ((b - r) / d) + 120.0
    } else {
        60.0 * ((r - g) / d) + 240.0
    };
    Some(h.rem_euclid(360.0))
}

/// An sRGB channel in linear light.
fn linear(c: u8) -> f64 {
    let v = f64::from(c) / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// A colour's chromaticity: its channels over their sum, which a diffuse shade does not
/// change (in linear light).
fn chroma(c: impl Iterator<Item = f64>) -> [f64; 3] {
    let c: Vec<f64> = c.collect();
    let sum = (c[0] + c[1] + c[2]).max(1e-9);
    [c[0] / sum, c[1] / sum, c[2] / sum]
}

/// The chromaticity of the sRGB colour `c` in linear light.
fn linear_chroma(c: &[u8]) -> [f64; 3] {
    chroma(c[..3].iter().map(|&v| linear(v)))
}

fn chroma_distance(p: [f64; 3], q: [f64; 3]) -> f64 {
    (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt()
}

/// The elevation ramp of `shaders/common.wgsl` (linear RGB stops), at 400 steps, as
/// chromaticities: a pixel of `--mode elevation` is the step whose chromaticity is
/// nearest its own (in linear light), whatever its shade.
fn ramp() -> Vec<[f64; 3]> {
    const STOPS: [[f64; 3]; 5] = [
        [0.02, 0.08, 0.6],
        [0.0, 0.55, 0.65],
        [0.1, 0.55, 0.05],
        [0.9, 0.75, 0.02],
        [0.7, 0.02, 0.01],
    ];
    (0..=RAMP_STEPS)
        .map(|i| {
            let t = 4.0 * i as f64 / RAMP_STEPS as f64;
            let k = (t as usize).min(3);
            let f = t - k as f64;
            chroma((0..3).map(|c| STOPS[k][c] + (STOPS[k + 1][c] - STOPS[k][c]) * f))
        })
        .collect()
}

const RAMP_STEPS: usize = 400;

/// The height (the file's z) each pixel of an elevation image of the tree `meta` shows;
/// NaN on the background.
fn heights_of(image: &Image, meta: &spt::tree::TreeMeta, ramp: &[[f64; 3]]) -> Vec<f64> {
    let [lo, hi] = heights(meta, DVec3::Z).map(f64::from);
    image
        .rgba
        .chunks_exact(4)
        .map(|p| {
            if p[..3].iter().all(|&c| c >= 245) {
                return f64::NAN;
            }
            let c = linear_chroma(p);
            let step = (0..ramp.len())
                .min_by(|&a, &b| {
                    chroma_distance(c, ramp[a]).total_cmp(&chroma_distance(c, ramp[b]))
                })
                .unwrap_or(0);
            meta.origin[2] + lo + (hi - lo) * step as f64 / RAMP_STEPS as f64
        })
        .collect()
}

/// How far above what the truth shows a splat may stand before it counts as invented
/// surface, metres.
const ABOVE: f64 = 0.5;

/// Per open space of [`UNDER`]: its pixels where the truth shows the ground through it
/// (`regions` fills it; `truth` shows ground there), how many of those the splats
/// cover with something standing more than [`ABOVE`] over the truth's height there,
/// and how many of these lie beyond [`RIM`] pixels of the truth's objects (a crown, a
/// deck: a splat of a sample on an object's outline reaches about a spacing beyond
/// it); last, the same of the ground elsewhere (a check of the measure: near 0).
fn invented(
    (scan_heights, truth_heights): (&[f64], &[f64]),
    truth: &Image,
    regions: &Image,
) -> ([Count; 4], Vec<Invented>) {
    let classes = Kind::ALL.map(Kind::color);
    // The classes first, then the open spaces.
    let mut marks: Vec<[u8; 3]> = classes.to_vec();
    marks.extend(UNDER.iter().map(|(_, c)| *c));
    let object: Vec<bool> = (truth.rgba.chunks_exact(4))
        .map(|t| nearest(t, &classes).is_some_and(|k| k != 0))
        .collect();
    let (w, h) = (truth.width as i64, truth.height as i64);
    let near_object = |i: usize| {
        let (x, y) = ((i as i64) % w, (i as i64) / w);
        (-RIM..=RIM).any(|dy| {
            (-RIM..=RIM).any(|dx| {
                let (u, v) = (x + dx, y + dy);
                (0..w).contains(&u) && (0..h).contains(&v) && object[(v * w + u) as usize]
            })
        })
    };
    let mut counts = [Count::default(); 4];
    let mut shown = vec![Invented::No; object.len()];
    let pixels = truth.rgba.chunks_exact(4).zip(regions.rgba.chunks_exact(4));
    for (i, (t, r)) in pixels.enumerate() {
        let Some(mark) = nearest(r, &marks).filter(|&m| m == 0 || m >= classes.len()) else {
            continue;
        };
        if nearest(t, &classes) != Some(0) {
            continue;
        }
        // Ground elsewhere last.
        let count = &mut counts[if mark == 0 { 3 } else { mark - classes.len() }];
        count.pixels += 1;
        if scan_heights[i] > truth_heights[i] + ABOVE {
            let beyond = !near_object(i);
            count.invented += 1;
            count.beyond_rim += u64::from(beyond);
            shown[i] = if beyond {
                Invented::BeyondTheRim
            } else {
                Invented::OnTheRim
            };
        }
    }
    (counts, shown)
}

/// Whether an open-space pixel is invented surface, and where.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Invented {
    No,
    OnTheRim,
    BeyondTheRim,
}

/// Pixels around the truth's objects that [`invented`] also counts apart (one pixel
/// is 0.28 m at the scene's centre from the default views, about half a pulse
/// spacing).
const RIM: i64 = 1;

/// An open space's pixels, those invented among them, and those invented beyond the
/// [`RIM`] of the truth's objects.
#[derive(Debug, Clone, Copy, Default)]
struct Count {
    pixels: u64,
    invented: u64,
    beyond_rim: u64,
}

impl std::ops::Add for Count {
    type Output = Count;
    fn add(self, o: Count) -> Count {
        Count {
            pixels: self.pixels + o.pixels,
            invented: self.invented + o.invented,
            beyond_rim: self.beyond_rim + o.beyond_rim,
        }
    }
}

fn save(image: &Image, path: &Path) -> anyhow::Result<()> {
    write_png(path, image.width, image.height, &image.rgba)
}

/// One view's figures: FLIP, SSIM, and per open space (and the ground elsewhere) its
/// pixels and the invented ones among them.
struct View {
    flip: f64,
    ssim: f64,
    counts: [Count; 4],
}

/// The models of a measurement, on the GPU: the scan, the truth, the truth's regions.
struct Models<'a> {
    renderer: &'a Renderer,
    scan: (Scene, GpuScene),
    truth: (Scene, GpuScene),
    regions: (Scene, GpuScene),
    ramp: Vec<[f64; 3]>,
    mode: Mode,
}

impl Models<'_> {
    fn draw(
        &self,
        model: &(Scene, GpuScene),
        camera: &Camera,
        settings: &Settings,
        size: u32,
    ) -> anyhow::Result<Image> {
        Ok(self
            .renderer
            .render(&model.0, &model.1, camera, settings, size, size)?
            .0)
    }

    /// The figures of the view from `camera` at `size`; its images into `images`
    /// (file names prefixed `prefix`) when given.
    fn view(
        &self,
        camera: &Camera,
        size: u32,
        images: Option<(&Path, String)>,
    ) -> anyhow::Result<View> {
        let big = self.draw(&self.truth, camera, &Settings::mesh(), size * SUPERSAMPLE)?;
        let reference = downsample(&big, SUPERSAMPLE);
        let shown = Settings {
            mode: self.mode,
            ..Settings::leaves()
        };
        let splats = self.draw(&self.scan, camera, &shown, size)?;
        let marked = self.draw(&self.regions, camera, &Settings::mesh(), size)?;
        let elevation = Settings {
            mode: Mode::Elevation,
            ..Settings::leaves()
        };
        let scan_heights = heights_of(
            &self.draw(&self.scan, camera, &elevation, size)?,
            self.scan.0.meta(),
            &self.ramp,
        );
        let truth_heights = heights_of(
            &self.draw(&self.truth, camera, &elevation, size)?,
            self.truth.0.meta(),
            &self.ramp,
        );
        let (counts, pixels) = invented((&scan_heights, &truth_heights), &reference, &marked);
        if let Some((dir, prefix)) = images {
            std::fs::create_dir_all(dir)?;
            save(&splats, &dir.join(format!("{prefix}_splats.png")))?;
            save(&reference, &dir.join(format!("{prefix}_truth.png")))?;
            save(&marked, &dir.join(format!("{prefix}_regions.png")))?;
            let mut shown = reference.clone();
            for (px, p) in shown.rgba.chunks_exact_mut(4).zip(&pixels) {
                match p {
                    Invented::OnTheRim => px[..3].copy_from_slice(&[255, 160, 0]),
                    Invented::BeyondTheRim => px[..3].copy_from_slice(&[255, 0, 255]),
                    Invented::No => {}
                }
            }
            save(&shown, &dir.join(format!("{prefix}_invented.png")))?;
        }
        Ok(View {
            flip: flip_mean(&splats, &reference),
            ssim: ssim_mean(&splats, &reference),
            counts,
        })
    }
}

/// The share of invented pixels among `c`'s, and of those beyond the rim, percent.
fn share(c: Count) -> (f64, f64) {
    let of = |n: u64| 100.0 * n as f64 / c.pixels.max(1) as f64;
    (of(c.invented), of(c.beyond_rim))
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let renderer = Renderer::new(Gpu::new(None)?);
    eprintln!("adapter: {}", renderer.gpu.describe());
    let open = |path: &Path| -> anyhow::Result<(Scene, GpuScene)> {
        let scene = Scene::open(path)?;
        let gpu = renderer.upload(&scene);
        Ok((scene, gpu))
    };
    let models = Models {
        renderer: &renderer,
        scan: open(&args.scan)?,
        truth: open(&args.truth)?,
        regions: open(&args.truth.with_file_name("truth_regions.ply"))?,
        ramp: ramp(),
        mode: args.mode,
    };
    let (mut flips, mut ssims) = (Vec::new(), Vec::new());
    let (mut shares, mut beyond_rims) = (Vec::new(), Vec::new());
    for k in 0..args.views {
        let azimuth = 30.0 + 360.0 * k as f64 / args.views as f64;
        let meta = models.truth.0.meta();
        let camera = Camera::orbit(
            meta,
            azimuth,
            args.elevation,
            args.distance,
            45f64.to_radians(),
        );
        let images = args.images.as_deref().map(|d| (d, format!("view{k}")));
        let v = models.view(&camera, args.size, images)?;
        let open = v.counts[..3].iter().fold(Count::default(), |a, &c| a + c);
        let mut parts: Vec<String> = UNDER
            .iter()
            .zip(v.counts)
            .map(|((name, _), c)| {
                let (all, beyond) = share(c);
                format!("under {name} {all:.1} % ({beyond:.1} %) of {}", c.pixels)
            })
            .collect();
        parts.push(format!(
            "the ground elsewhere {:.1} %",
            share(v.counts[3]).0
        ));
        let (all, beyond) = share(open);
        println!(
            "view {azimuth:5.1}°: FLIP {:.4}  SSIM {:.3}  invented {all:.1} % ({beyond:.1} % beyond the rim) of {} open-space pixels ({})",
            v.flip,
            v.ssim,
            open.pixels,
            parts.join(", ")
        );
        flips.push(v.flip);
        ssims.push(v.ssim);
        shares.push(all);
        beyond_rims.push(beyond);
    }
    let median = |v: &mut Vec<f64>| quantile(v, 0.5).unwrap_or(f64::NAN);
    println!(
        "median over {} views: FLIP {:.4}, SSIM {:.3}, invented surface {:.1} % of the open space's pixels ({:.1} % beyond the rim of the truth's objects)",
        args.views,
        median(&mut flips),
        median(&mut ssims),
        median(&mut shares),
        median(&mut beyond_rims)
    );
    Ok(())
}

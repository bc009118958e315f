//! `spt info FILE [--json]`: what a model file (PLY, LAS, LAZ) holds, how it loads and
//! the leaf surfels it gives; or what an `.spt` file holds and whether its checksum holds.

use crate::io::up::UpAxis;
use crate::tree::up::up_of_shape;
use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::apps::progress::{BYTES, Stage};
use crate::apps::stats::peak_memory_bytes;
use crate::apps::text::{bytes, count, readable};
use crate::io::formats::read_model_telling;
use crate::io::las::LasSummary;
use crate::io::model::{ElementSummary, Model, Summary};
use crate::io::rebase::MAX_OFFSET;
use crate::io::{Bounds, GeometryStats};
use crate::surfel::outward::{OPEN_AREA, Sides};
use crate::surfel::progress::Progress;
use crate::surfel::{LeafSurfels, NormalsTurned, SurfelStats, leaf_surfels_with_progress};
use crate::tree::spt_file::{SptFile, is_spt};
use crate::tree::{NodeRecord, TreeMeta};

/// How `spt info` names estimated normals turned `turned`, and what the renderer does
/// with them.
fn estimated_normals(turned: NormalsTurned) -> &'static str {
    match turned {
        NormalsTurned::No => "unoriented (two-sided)",
        NormalsTurned::Up => "up (a terrain's: a splat's underside weighs 1/64, as a mesh's back)",
        NormalsTurned::TowardOrigin => {
            "toward the sensor at the file's origin (a frame's: drawn two-sided)"
        }
    }
}

/// What the orientation vote did to a mesh's pieces ([`crate::surfel::outward`]).
fn mesh_sides(sides: Sides) -> String {
    let mut kinds = Vec::new();
    let pieces = |n: u64| if n == 1 { "piece" } else { "pieces" };
    if sides.turned > 0 {
        let n = sides.turned;
        kinds.push(format!(
            "{n} closed {} turned outward (wound inward)",
            pieces(n)
        ));
    }
    if sides.kept > 0 {
        let n = sides.kept;
        kinds.push(format!("{n} closed {} facing outward as wound", pieces(n)));
    }
    if sides.open > 0 {
        let n = sides.open;
        let drawn = if sides.two_sided {
            "drawn two-sided: their front is not known".to_owned()
        } else {
            format!("under {} % of the area", 100.0 * OPEN_AREA)
        };
        kinds.push(format!(
            "{n} open {} keeping the file's winding ({drawn})",
            pieces(n)
        ));
    }
    format!("by piece: {}", kinds.join(", "))
}

#[derive(Debug, Serialize)]
pub struct Present {
    pub faces: bool,
    pub normals: bool,
    pub colors: bool,
}

#[derive(Debug, Serialize)]
pub struct SurfelInfo {
    pub count: usize,
    pub radius_min: f32,
    pub radius_median: f32,
    pub radius_max: f32,
    pub oriented_normals: bool,
    /// Which way estimated normals were turned (up on a terrain, toward the sensor on a
    /// frame): see [`estimated_normals`].
    pub normals_turned: NormalsTurned,
    #[serde(flatten)]
    pub stats: SurfelStats,
}

#[derive(Debug, Serialize)]
pub struct Timing {
    pub load_seconds: f64,
    pub load_mb_per_s: f64,
    pub surfels_seconds: f64,
    pub surfels_per_second: f64,
}

/// Everything `spt info` reports on a model file.
#[derive(Debug, Serialize)]
pub struct ModelInfo {
    pub file: String,
    pub bytes: u64,
    pub format: String,
    pub comments: Vec<String>,
    pub obj_info: Vec<String>,
    /// What a LAS or LAZ file says of itself.
    pub las: Option<LasSummary>,
    /// Elements of a PLY file that the reader skips (neither the vertices nor the faces
    /// or triangle strips it reads).
    pub skipped_elements: Vec<String>,
    pub elements: Vec<ElementSummary>,
    /// Bounding box of the finite vertices, in the file's coordinates (exact f64).
    pub bounds: Bounds,
    /// Bounding box of the vertices that are not outliers (`bounds` when none is).
    pub core: Bounds,
    /// Centre of `core`: every position is stored relative to it.
    pub origin: [f64; 3],
    pub present: Present,
    /// The axis the model is shown standing on (`None`: a sensor frame, seen as its
    /// sensor saw it), and why.
    pub up: Option<UpAxis>,
    pub up_because: &'static str,
    pub geometry: GeometryStats,
    pub surfels: SurfelInfo,
    pub timing: Timing,
    /// Peak resident memory of the process (Linux), bytes.
    pub peak_memory_bytes: Option<u64>,
}

impl ModelInfo {
    /// Reads `path` and makes its leaf surfels, with a bar for each on a terminal
    /// (stderr; the report is printed on stdout).
    pub fn gather(path: &Path) -> anyhow::Result<ModelInfo> {
        let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
        let read = Stage::start("read", bytes, BYTES);
        let model: Model = read_model_telling(path, &|n| read.advance(n))?;
        read.clear();
        let start = Instant::now();
        let made = Stage::start("surfels", model.geometry.positions.len() as u64, "samples");
        let done = |n: u64| made.advance(n);
        let leaves: LeafSurfels = leaf_surfels_with_progress(&model.geometry, Progress::to(&done));
        made.clear();
        let surfels_seconds = start.elapsed().as_secs_f64();
        let (radius_min, radius_median, radius_max) = leaves.radius_range().unwrap_or_default();
        let load_seconds = model.load_time.as_secs_f64();
        let g = &model.geometry;
        let Summary {
            format,
            comments,
            obj_info,
            elements,
            skipped_elements,
            las,
            up: file_up,
        } = model.summary;
        let shape_up = up_of_shape(leaves.normals_turned, &g.bounds, g.origin);
        let up_because = match (file_up, shape_up) {
            (Some(_), _) if las.is_some() => "LAS and LAZ are z-up",
            (Some(_), _) => "a comment of the header says so",
            (None, None) => "a sensor frame: seen as its sensor saw it",
            (None, Some(UpAxis::Z)) => "a terrain: flat in z",
            (None, _) => "the default of models whose file does not say",
        };
        Ok(ModelInfo {
            file: path.display().to_string(),
            bytes: model.file_bytes,
            format,
            comments,
            obj_info,
            elements,
            las,
            skipped_elements,
            bounds: g.bounds,
            core: g.core,
            origin: g.origin.to_array(),
            up: file_up.or(shape_up),
            up_because,
            present: Present {
                faces: !g.triangles.is_empty(),
                normals: g.normals.is_some(),
                colors: g.colors.is_some(),
            },
            geometry: model.stats.clone(),
            surfels: SurfelInfo {
                count: leaves.surfels.len(),
                radius_min,
                radius_median,
                radius_max,
                oriented_normals: leaves.oriented_normals,
                normals_turned: leaves.normals_turned,
                stats: leaves.stats,
            },
            timing: Timing {
                load_seconds,
                load_mb_per_s: model.file_bytes as f64 / 1e6 / load_seconds.max(1e-9),
                surfels_seconds,
                surfels_per_second: leaves.surfels.len() as f64 / surfels_seconds.max(1e-9),
            },
            peak_memory_bytes: peak_memory_bytes(),
        })
    }

    /// File, format, comments, elements and properties.
    fn header_lines(&self, out: &mut String) {
        let mut line = |k: &str, v: String| field(out, k, v);
        line("file", format!("{} ({})", self.file, bytes(self.bytes)));
        line("format", self.format.clone());
        for c in &self.comments {
            line("comment", c.clone());
        }
        for c in &self.obj_info {
            line("obj_info", c.clone());
        }
        for e in &self.elements {
            line("element", format!("{} {}", e.name, count(e.count)));
            for p in &e.properties {
                line("", format!("property {p}"));
            }
        }
        if !self.skipped_elements.is_empty() {
            line(
                "skipped",
                format!("elements {}", self.skipped_elements.join(", ")),
            );
        }
        if let Some(las) = &self.las {
            las_lines(las, out);
        }
    }

    /// What was read and dropped, the boxes and the origin.
    fn geometry_lines(&self, out: &mut String) {
        let g = &self.geometry;
        let mut vertices = format!(
            "{} read, {} dropped (NaN or infinite coordinates)",
            count(g.vertices_in_file),
            count(g.vertices_dropped_nonfinite)
        );
        if g.vertices_dropped_out_of_range > 0 {
            vertices += &format!(
                ", {} dropped (beyond ±{MAX_OFFSET:.3e} of the origin)",
                count(g.vertices_dropped_out_of_range)
            );
        }
        if g.outliers > 0 {
            vertices += &format!(
                ", {} outliers (far outside the core box)",
                count(g.outliers)
            );
        }
        if g.z_absent {
            vertices += ", no z in the file: read as z = 0";
        }
        field(out, "vertices", vertices);
        if g.triangle_strips > 0 {
            field(
                out,
                "strips",
                format!(
                    "{} rows of triangle strips (tristrips) read → {} triangles, {} on dropped vertices",
                    count(g.triangle_strips),
                    count(g.triangles),
                    count(g.triangles_dropped_nonfinite)
                ),
            );
        } else if self.present.faces || g.faces_in_file > 0 {
            field(
                out,
                "faces",
                format!(
                    "{} read → {} triangles; skipped: {} with < 3 vertices, {} triangles on dropped vertices",
                    count(g.faces_in_file),
                    count(g.triangles),
                    count(g.faces_with_fewer_than_3_vertices),
                    count(g.triangles_dropped_nonfinite)
                ),
            );
        }
        place_fields(out, &self.bounds, self.origin);
        if self.core != self.bounds {
            field(out, "core min", xyz(self.core.min));
            field(out, "core max", xyz(self.core.max));
        }
    }

    /// What the file gives (faces, normals, colours) and the up axis chosen.
    fn present_lines(&self, out: &mut String) {
        let yes = |b: bool| if b { "yes" } else { "no" };
        let colours = if self.geometry.colors_all_zero {
            "no (the file's are zero everywhere: shaded grey)"
        } else {
            yes(self.present.colors)
        };
        let (faces, normals) = (yes(self.present.faces), yes(self.present.normals));
        field(
            out,
            "present",
            format!("faces {faces}, normals {normals}, colours {colours}"),
        );
        let up = self.up.map_or("none", UpAxis::name);
        field(
            out,
            "up",
            format!("{up} ({}; --up overrides)", self.up_because),
        );
    }

    /// The report as a person reads it.
    pub fn to_text(&self) -> String {
        let s = &self.surfels;
        let mut out = String::new();
        self.header_lines(&mut out);
        if self.geometry.vertices_in_file == 0 {
            field(
                &mut out,
                "vertices",
                "none: the file holds no points, nothing to draw".to_owned(),
            );
            return out;
        }
        self.geometry_lines(&mut out);
        self.present_lines(&mut out);
        let mut line = |k: &str, v: String| field(&mut out, k, v);
        line(
            "surfels",
            format!(
                "{}, radius min {:.6e} / median {:.6e} / max {:.6e}, normals {}",
                count(s.count as u64),
                s.radius_min,
                s.radius_median,
                s.radius_max,
                match (s.oriented_normals, s.stats.sides) {
                    (_, sides) if sides != Sides::default() => mesh_sides(sides),
                    (true, _) => "oriented".to_owned(),
                    _ => estimated_normals(s.normals_turned).to_owned(),
                }
            ),
        );
        let st = &s.stats;
        if let Some(grid) = st.pixel_grid {
            // The grid's last rows may have no sample (the reader dropped them); the
            // file's row count tells its height when it is whole rows.
            let rows = self.geometry.vertices_in_file;
            let height = match rows % grid.width as u64 {
                0 => rows / grid.width as u64,
                _ => grid.height as u64,
            };
            let triangles = if self.present.faces {
                "the file's triangles, wound to face the sensor"
            } else {
                "neighbouring pixels joined, not across a depth edge"
            };
            line(
                "pixel grid",
                format!(
                    "{} × {height} in the file's row order: splats of the grid's triangles \
                     ({triangles}; a long one drawn by a splat of its own)",
                    grid.width
                ),
            );
        }
        line(
            "",
            format!(
                "degenerate triangles {}, isolated vertices {} ({} within the triangles' splats: not drawn), cancelled normals {}, given normals {}, fallback radii {}, capped radii {}, clipped boundaries {}, wall splats under a terrain's edges {}, splats of long triangles (a frame's grid, a terrain's TIN) {}, normals on a depth step from the steps around {}, splats shrunk to the sensor's pixels {}, a terrain's splats held to its tile's spacing {}, a terrain's vegetation and lone returns drawn apart from its TIN {}, samples of bridge decks and free-standing roofs in a TIN of their own {}",
                count(st.degenerate_triangles),
                count(st.isolated_vertices),
                count(st.redundant_vertices),
                count(st.cancelled_normals),
                count(st.given_normals),
                count(st.fallback_radii),
                count(st.capped_radii),
                count(st.clipped_boundaries),
                count(st.wall_splats),
                count(st.triangle_splats),
                count(st.step_treads),
                count(st.footprint_capped),
                count(st.tile_capped),
                count(st.vegetation),
                count(st.decks)
            ),
        );
        let t = &self.timing;
        line(
            "load",
            format!(
                "{:.1} ms, {:.0} MB/s, {:.2} M points/s",
                t.load_seconds * 1e3,
                t.load_mb_per_s,
                self.geometry.vertices_in_file as f64 / 1e6 / t.load_seconds.max(1e-9)
            ),
        );
        line(
            "surfels time",
            format!(
                "{:.1} ms, {:.2} M surfels/s",
                t.surfels_seconds * 1e3,
                t.surfels_per_second / 1e6
            ),
        );
        if let Some(m) = self.peak_memory_bytes {
            line("peak memory", bytes(m));
        }
        out
    }
}

/// The names of the elements of `h` that the PLY reader does not use.
/// What a LAS file says of itself: software, points by return and class, intensity,
/// scale and offset, CRS, colours.
fn las_lines(s: &LasSummary, out: &mut String) {
    let mut line = |k: &str, v: String| field(out, k, v);
    line(
        "software",
        format!("{} / {}", s.generating_software, s.system_identifier),
    );
    line("points", count(s.points));
    let counts = |pairs: &[(u8, u64)], name: &dyn Fn(u8) -> String| {
        pairs
            .iter()
            .map(|(k, n)| format!("{} {}", name(*k), count(*n)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if s.points > 0 {
        line("by return", counts(&s.by_return, &|r| format!("#{r}")));
        line(
            "by class",
            counts(&s.by_class, &|c| format!("{c} ({})", asprs_class(c))),
        );
    }
    if let Some((lo, hi)) = s.intensity {
        line("intensity", format!("{lo} – {hi}"));
    }
    line("scale", xyz(s.scale));
    line("offset", xyz(s.offset));
    line(
        "CRS",
        s.crs
            .clone()
            .unwrap_or_else(|| "none in the file".to_owned()),
    );
    if let Some(c) = &s.colors {
        line("colours", c.clone());
    }
}

/// The ASPRS name of standard point class `c` (LAS 1.4, table 17).
pub fn asprs_class(c: u8) -> &'static str {
    match c {
        0 => "never classified",
        1 => "unclassified",
        2 => "ground",
        3 => "low vegetation",
        4 => "medium vegetation",
        5 => "high vegetation",
        6 => "building",
        7 => "low point (noise)",
        8 => "model key point",
        9 => "water",
        10 => "rail",
        11 => "road surface",
        12 => "overlap",
        13 => "wire guard",
        14 => "wire conductor",
        15 => "transmission tower",
        16 => "wire connector",
        17 => "bridge deck",
        18 => "high noise",
        19..=63 => "reserved",
        _ => "user defined",
    }
}

/// Appends one `key  value` line of a report.
fn field(out: &mut String, key: &str, value: String) {
    out.push_str(&format!("{key:<14}{value}\n"));
}

/// The bounding box and origin lines, shared by both reports.
fn place_fields(out: &mut String, bounds: &Bounds, origin: [f64; 3]) {
    field(out, "bbox min", xyz(bounds.min));
    field(out, "bbox max", xyz(bounds.max));
    field(out, "origin", xyz(origin));
}

fn xyz(p: [f64; 3]) -> String {
    format!("{} {} {}", readable(p[0]), readable(p[1]), readable(p[2]))
}

/// What `spt info` reports on an `.spt` file.
#[derive(Debug, Serialize)]
pub struct SptInfo {
    pub file: String,
    pub bytes: u64,
    pub format_version: u32,
    /// Whether the stored checksum matches the header and sections.
    pub checksum_ok: bool,
    pub checksum: String,
    /// What makes the tree invalid (a value no reader can use), when the checksum holds.
    pub invalid: Option<String>,
    #[serde(flatten)]
    pub meta: TreeMeta,
    pub record_bytes: usize,
    /// Chunks of the list (each sorted on its own, with its box), and the most nodes in one.
    pub chunks: usize,
    pub largest_chunk: u32,
    /// The root's error, model units.
    pub root_error: f64,
    pub open_seconds: f64,
    pub verify_seconds: f64,
}

impl SptInfo {
    pub fn gather(path: &Path) -> anyhow::Result<SptInfo> {
        let start = Instant::now();
        let file = SptFile::open_unverified(path)?;
        let open_seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let checksum_ok = file.verify().is_ok();
        let verify_seconds = start.elapsed().as_secs_f64();
        let invalid = if checksum_ok {
            file.validate().err().map(|e| e.to_string())
        } else {
            None
        };
        let chunks = file.chunks().len();
        let largest_chunk = file.chunks().iter().map(|c| c.count).max().unwrap_or(0);
        let scale = file.meta.error_scale;
        let root_error = file
            .nodes()
            .iter()
            .map(|r| r.error(scale))
            .fold(0.0, f64::max);
        Ok(SptInfo {
            file: path.display().to_string(),
            bytes: file.file_bytes(),
            format_version: file.version,
            checksum_ok,
            checksum: format!("{:016x}", file.checksum),
            invalid,
            meta: file.meta.clone(),
            record_bytes: std::mem::size_of::<NodeRecord>(),
            chunks,
            largest_chunk,
            root_error,
            open_seconds,
            verify_seconds,
        })
    }

    pub fn to_text(&self) -> String {
        let m = &self.meta;
        let mut out = String::new();
        let mut line = |k: &str, v: String| field(&mut out, k, v);
        line("file", format!("{} ({})", self.file, bytes(self.bytes)));
        line("format", format!("spt version {}", self.format_version));
        line(
            "checksum",
            format!(
                "{} ({})",
                self.checksum,
                if self.checksum_ok {
                    "holds"
                } else {
                    "MISMATCH: the file is corrupt"
                }
            ),
        );
        if let Some(why) = &self.invalid {
            line("tree", format!("INVALID: {why}"));
        }
        line(
            "nodes",
            format!(
                "{} ({} leaves, {} internal), depth {}, {} bytes per record",
                count(m.node_count),
                count(m.leaf_count),
                count(m.node_count - m.leaf_count),
                m.depth,
                self.record_bytes
            ),
        );
        line(
            "chunks",
            format!(
                "{} (at most {} nodes each)",
                count(self.chunks as u64),
                count(self.largest_chunk as u64)
            ),
        );
        place_fields(&mut out, &m.bounds, m.origin);
        let mut line = |k: &str, v: String| field(&mut out, k, v);
        line(
            "errors",
            format!(
                "root {:.6e}, stored relative to {:.6e} (model units)",
                self.root_error, m.error_scale
            ),
        );
        line(
            "present",
            format!(
                "colours {}, normals {}, LiDAR attributes {}",
                if m.has_colors { "yes" } else { "no" },
                if m.oriented_normals && m.two_sided {
                    "oriented, their front not known (an open mesh's: drawn two-sided)"
                } else if m.oriented_normals {
                    "oriented"
                } else {
                    estimated_normals(m.normals_turned)
                },
                if m.has_attributes {
                    format!(
                        "yes (intensity 1st–99th percentile {}–{})",
                        m.intensity_range[0], m.intensity_range[1]
                    )
                } else {
                    "no".to_owned()
                }
            ),
        );
        line(
            "open",
            format!(
                "{:.1} ms (memory map), checksum {:.1} ms",
                self.open_seconds * 1e3,
                self.verify_seconds * 1e3
            ),
        );
        out
    }
}

/// Runs `spt info` on a model file (PLY, LAS, LAZ) or an `.spt` file: prints the report as text or JSON. A
/// corrupt `.spt` is reported, then the command fails.
pub fn run(path: &Path, json: bool) -> anyhow::Result<()> {
    if crate::tree::instances::is_scene(path) {
        return crate::apps::info_scene::run(path, json);
    }
    if is_spt(path) {
        let info = SptInfo::gather(path)?;
        if json {
            say!("{}", serde_json::to_string_pretty(&info)?);
        } else {
            crate::apps::say_text(&info.to_text());
        }
        if !info.checksum_ok {
            anyhow::bail!("{}: checksum mismatch: the file is corrupt", path.display());
        }
        if let Some(why) = info.invalid {
            anyhow::bail!("{why}");
        }
        return Ok(());
    }
    let info = ModelInfo::gather(path)?;
    if json {
        say!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        crate::apps::say_text(&info.to_text());
    }
    Ok(())
}

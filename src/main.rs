//! The `spt` command line.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Parses `spt view`'s options on their own (for the default command).
#[derive(Parser)]
struct ViewOnly {
    #[command(flatten)]
    args: spt::apps::view::ViewArgs,
}

#[derive(Parser)]
#[command(
    name = "spt",
    version,
    about = "Point-based rendering engine: sequential point trees and EWA splatting",
    long_about = "spt turns scanned meshes and point clouds (PLY, LAS, LAZ) into disks (surfels) for \
                  point-based rendering, and builds their sequential point trees.\n\nStart with \
                  `spt info MODEL.ply` to see what a file holds and how it loads, then \
                  `spt convert MODEL.ply MODEL.spt`."
)]
struct Cli {
    /// Without a command: the viewer on the default model (`spt view`).
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// What a model file holds. PLY: format, elements, counts, bounding box (exact f64),
    /// what was dropped and why, leaf surfels (count, radii), load time and throughput.
    /// LAS/LAZ: version, point format, counts by return and by class, intensity range,
    /// scale, offset, CRS, and the same bounds, surfels and timing.
    /// .spt: nodes, depth, bounds, errors, and whether its checksum holds. A scene
    /// (.json): its models, instances, box and memory per instance.
    Info {
        /// A PLY file (ASCII or binary, mesh or point cloud), a LAS or LAZ file, or an
        /// .spt file.
        file: PathBuf,
        /// Print the report as JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Places instances of models over a base surface (a mesh, or a terrain cloud's
    /// triangulation) at a density per unit area, with random yaw and scale, and writes
    /// a scene file (the base drawn once, the instances over it) and its instance file
    /// (docs/scenes.md). `spt render`, `view`, `info` and `bench` take the scene.
    Scatter(Box<spt::apps::scatter::ScatterArgs>),
    /// Renders one frame of a model (PLY, LAS, LAZ or .spt) to PNG, headless, by three-pass EWA
    /// splatting of its sequential point tree; prints splats drawn, prefix length and GPU
    /// time. `--mode mesh` draws the mesh itself as the reference.
    Render {
        /// The model: a PLY, LAS or LAZ file, or an .spt file; or a scene of instances
        /// (a .json file, docs/scenes.md).
        model: PathBuf,
        /// The PNG to write.
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        args: Box<spt::apps::render::RenderArgs>,
    },
    /// Opens the viewer: a window that draws the model (PLY, LAS, LAZ or .spt; default
    /// data/torus_knot.ply) and turns under the mouse, with a panel for the level of detail,
    /// display modes and statistics. PLY, LAS and LAZ files are converted in the background with a
    /// progress bar; .spt files open by memory map. Drop a file on the window or press
    /// Ctrl+O to open another. `--screenshot out.png` draws --frames frames, saves the
    /// picture and exits.
    View(Box<spt::apps::view::ViewArgs>),
    /// Measures speed against error: orbits near, mid and far and a fly-through, a sweep
    /// of ε, SPT with both culling strategies, a random subset of leaves at equal splat
    /// counts, and leaves only; GPU and wall ms, splats, prefix, PSNR, holes and spill
    /// against the mesh (or the leaves-only image for point clouds). Writes results.csv,
    /// summary.md and speed_vs_error.png to --out, and checks that a repeated
    /// configuration gives the same numbers.
    Bench(Box<spt::apps::bench::BenchArgs>),
    /// Builds the sequential point tree of a PLY, LAS or LAZ model and writes it as an .spt file,
    /// which opens instantly (memory-mapped). Shows each stage (load, surfels, tree,
    /// errors, sort, write) with its time, then a summary. The output is written to a
    /// temporary file and renamed: a failed convert never leaves a partial file. A model
    /// too large for the memory budget (a LAS, LAZ or PLY cloud, or a PLY mesh) is
    /// built out of core: read in passes, split into jobs spilled to disk beside the
    /// output (each with the points or triangles around its border), each job built
    /// alone, then joined and streamed into the file.
    Convert {
        /// The model: a PLY, LAS or LAZ file.
        input: PathBuf,
        /// The .spt file to write (replaced if it exists).
        output: PathBuf,
        /// Memory budget in MiB (default: half of the machine's memory).
        #[arg(long, value_name = "MIB")]
        memory: Option<u64>,
        /// Build out of core even when the model would fit in memory.
        #[arg(long)]
        out_of_core: bool,
    },
    /// The out-of-core build's three steps as separate commands over a shared job
    /// directory, for a cluster to run the jobs (docs/cluster.md): `plan` splits and
    /// spills the model, `build` builds jobs into parts, `join` writes the .spt file.
    /// The same budget gives the same file as `spt convert --out-of-core`.
    Jobs {
        #[command(subcommand)]
        command: spt::apps::jobs::JobsCommand,
    },
}

fn main() -> ExitCode {
    // Before any thread starts: an out-of-core build's jobs reuse what each other frees.
    spt::io::heap::share_one_heap();
    // The LAZ decoder's threads get deep stacks (spt::io::las::DECODER_STACK); the
    // pool is not made yet, so this cannot fail.
    let _ = spt::io::las::use_decoder_stacks();
    // The LAZ decoder's panics on damaged files become errors that name the file
    // (spt::io::las); only other panics are reported as panics.
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !info
            .location()
            .is_some_and(|l| spt::io::las::is_decoder_panic(l.file()))
        {
            report(info);
        }
    }));
    let cli = Cli::parse();
    let command = cli
        .command
        .unwrap_or_else(|| Command::View(Box::new(ViewOnly::parse_from(["spt"]).args)));
    let result = match command {
        Command::View(args) => spt::apps::view::run(*args),
        Command::Bench(args) => spt::apps::bench::run(&args),
        Command::Info { file, json } => spt::apps::info::run(&file, json),
        Command::Scatter(args) => spt::apps::scatter::run(&args),
        Command::Jobs { command } => spt::apps::jobs::run(&command),
        Command::Convert {
            input,
            output,
            memory,
            out_of_core,
        } => spt::apps::convert::run_either(&input, &output, memory, out_of_core),
        Command::Render {
            model,
            output,
            args,
        } if spt::tree::instances::is_scene(&model) => {
            spt::apps::render_scene::run(&model, &output, &args)
        }
        Command::Render {
            model,
            output,
            args,
        } => spt::apps::render::run(&model, &output, &args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<spt::apps::jobs::RebuildNeeded>() => {
            eprintln!("{e:#}");
            ExitCode::from(spt::apps::jobs::REBUILD_STATUS)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

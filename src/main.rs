//! The `spt` command line.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "spt",
    version,
    about = "Point-based rendering engine: sequential point trees and EWA splatting",
    long_about = "spt turns scanned meshes and point clouds (PLY) into disks (surfels) for \
                  point-based rendering.\n\nStart with `spt info MODEL.ply` to see what a file \
                  holds and how it loads."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// What a PLY file holds: format, elements, counts, bounding box (exact f64), what was
    /// dropped and why, leaf surfels (count, radii), load time and throughput.
    Info {
        /// The model: a PLY file (ASCII or binary, mesh or point cloud).
        file: PathBuf,
        /// Print the report as JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info { file, json } => spt::apps::info::run(&file, json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

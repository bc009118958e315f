//! A mutation fuzzer for spt's readers (PLY, LAS, LAZ, `.spt`, scene files and instance
//! files), on the stable toolchain.
//!
//! ```text
//! cargo run --release --example fuzz -- --seconds 60
//! ```
//!
//! Seeds are made by the project's own writers ([`seeds`]); each input is a seed with
//! one to four stacked mutations ([`mutate`]) and runs through load, surfels, tree,
//! `.spt` write and reopen with every invariant checked ([`target`]). Counted as
//! failures, and saved under `--out` with a note: panics, violated invariants, inputs
//! that take longer than `--slow` seconds, and single allocations larger than
//! [`justified`] bytes for the input's size. A watchdog ends the run when one input
//! hangs (the input is left in `--out/current.*`). Exit code 0 when nothing failed.

mod mutate;
mod seeds;
mod target;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use clap::Parser;

use mutate::{Rng, mutate};
use seeds::{Kind, Seed};
use target::Outcome;

#[path = "../largest_allocation.rs"]
mod largest_allocation;

#[global_allocator]
static ALLOC: largest_allocation::Largest = largest_allocation::Largest;

/// The largest single allocation an input of `len` bytes justifies: 64 bytes per input
/// byte (a vertex of three `char`s becomes a 32-byte surfel and about 1.3 node records;
/// a face of `char` indices, 12 bytes per triangle; vectors grow by doubling) and 1 MiB
/// of fixed buffers.
/// An input of the LAS reader (which reads LAZ whatever the extension) also justifies
/// one decompressed chunk, which the decoder allocates whole
/// ([`spt::io::las::MAX_CHUNK_BYTES`]).
pub fn justified(kind: Kind, len: usize) -> usize {
    let chunk = if matches!(kind, Kind::Las | Kind::Laz) {
        spt::io::las::MAX_CHUNK_BYTES as usize
    } else {
        0
    };
    64 * len + (1 << 20) + chunk
}

/// Every this many accepted PLY, LAS or LAZ inputs, one is also built out of core.
const OUT_OF_CORE_EVERY: u64 = 16;
/// An out-of-core build's fixed tables, whatever its input: the 64³ counting grid's
/// counts (u64) and cells' jobs (u32).
const OUT_OF_CORE_TABLES: usize = 64 * 64 * 64 * 12;

#[derive(Parser)]
#[command(
    about = "Mutation fuzzer for spt's readers: PLY, LAS, LAZ, .spt, scene and instance files"
)]
struct Args {
    /// How long to run, in seconds.
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Seed of the random mutations (runs with the same seed make the same inputs).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Folder for failing inputs and the input in progress.
    #[arg(long, default_value = "target/fuzz")]
    out: PathBuf,
    /// An input that takes longer than this (seconds) counts as a failure.
    #[arg(long, default_value_t = 2.0)]
    slow: f64,
    /// Run one saved input (any file the fuzzer saved under --out) instead, and print
    /// what happens.
    #[arg(long)]
    replay: Option<PathBuf>,
}

#[derive(Default)]
struct Tally {
    executions: u64,
    /// Per reader (PLY, .spt): inputs accepted and refused.
    accepted: [u64; 6],
    refused: [u64; 6],
    panics: u64,
    violations: u64,
    slow: u64,
    oversized: u64,
    /// Inputs also built out of core.
    out_of_core: u64,
    slowest: Duration,
    /// The largest allocation as a fraction of what its input justified, the
    /// allocation and the input's size.
    worst: (f64, usize, usize),
}

impl Tally {
    fn failures(&self) -> u64 {
        self.panics + self.violations + self.slow + self.oversized
    }
}

/// Panics of the LAZ decoder that `spt::io::las` turned into errors (the input counts as
/// refused): reported, as a property of the `laz` crate, not as failures of spt.
static CONTAINED: AtomicU64 = AtomicU64::new(0);

/// Whether an input is running (its panics are caught and need no message).
static IN_INPUT: AtomicBool = AtomicBool::new(false);

/// Runs one input; panics are caught and returned as text.
fn execute(kind: Kind, path: &Path) -> Result<Outcome, String> {
    caught(|| target::run(kind, path))
}

/// Runs `f`; a panic is caught and returned as text.
fn caught(f: impl FnOnce() -> Outcome) -> Result<Outcome, String> {
    IN_INPUT.store(true, Ordering::Relaxed);
    let result = catch_unwind(AssertUnwindSafe(f));
    IN_INPUT.store(false, Ordering::Relaxed);
    result.map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "a panic".into())
    })
}

fn save(out: &Path, n: u64, what: &str, kind: Kind, bytes: &[u8], note: &str) {
    let stem = out.join(format!("{what}-{n}"));
    let _ = std::fs::write(stem.with_extension(kind.extension()), bytes);
    let _ = std::fs::write(stem.with_extension("txt"), note);
    eprintln!(
        "{what}: {note} (saved as {}.{})",
        stem.display(),
        kind.extension()
    );
}

/// Ends the process when one input runs for over 60 s: a hang cannot be caught.
fn watchdog(started_ms: &'static AtomicU64, origin: Instant, out: PathBuf) {
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_secs(1));
            let since = started_ms.load(Ordering::Relaxed);
            let now = origin.elapsed().as_millis() as u64;
            if since != u64::MAX && now.saturating_sub(since) > 60_000 {
                eprintln!(
                    "hang: an input runs for over 60 s; it is {}/current.*",
                    out.display()
                );
                std::process::exit(3);
            }
        }
    });
}

fn replay(path: &Path) -> i32 {
    let kind = Kind::of(path);
    let start = Instant::now();
    let result = execute(kind, path);
    let took = start.elapsed();
    match result {
        Ok(Outcome::Accepted { samples }) => {
            println!("accepted in {took:?}");
            // As the run does with every 16th accepted input.
            if let Some(samples) = samples {
                if let Outcome::Violation(why) = target::out_of_core(path, samples) {
                    println!("invariant violated: {why}");
                    return 1;
                }
                println!("built out of core alike");
            }
        }
        Ok(Outcome::Refused) => println!("refused in {took:?}"),
        Ok(Outcome::Violation(why)) => {
            println!("invariant violated: {why}");
            return 1;
        }
        Err(panic) => {
            println!("panic: {panic}");
            return 1;
        }
    }
    0
}

fn main() {
    let args = Args::parse();
    // As the spt binary does: the LAZ decoder's threads get deep stacks.
    let _ = spt::io::las::use_decoder_stacks();
    // Panics of the inputs are expected and reported; any other is printed as usual.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if info
            .location()
            .is_some_and(|l| spt::io::las::is_decoder_panic(l.file()))
        {
            CONTAINED.fetch_add(1, Ordering::Relaxed);
        }
        if !IN_INPUT.load(Ordering::Relaxed) {
            default_hook(info)
        }
    }));
    if let Some(path) = &args.replay {
        std::process::exit(replay(path));
    }
    std::fs::create_dir_all(&args.out).expect("create the output folder");
    seeds::write_scene_files(&args.out);
    let work = tempfile::tempdir_in(std::env::temp_dir()).expect("a temporary folder");
    let seeds: Vec<Seed> = seeds::all(work.path());
    static STARTED: AtomicU64 = AtomicU64::new(u64::MAX);
    let origin = Instant::now();
    watchdog(&STARTED, origin, args.out.clone());

    let mut rng = Rng::new(args.seed);
    let mut tally = Tally::default();
    let deadline = Duration::from_secs_f64(args.seconds);
    let slow = Duration::from_secs_f64(args.slow);
    let mut last_report = Instant::now();
    while origin.elapsed() < deadline {
        // Every seed once as it is, then mutants.
        let (seed, bytes) = match seeds.get(tally.executions as usize) {
            Some(s) => (s, s.bytes.clone()),
            None => {
                let s = rng.pick(&seeds);
                (s, mutate(&mut rng, s, &seeds))
            }
        };
        let path = args.out.join(format!("current.{}", seed.kind.extension()));
        std::fs::write(&path, &bytes).expect("write the input");
        largest_allocation::reset();
        STARTED.store(origin.elapsed().as_millis() as u64, Ordering::Relaxed);
        let start = Instant::now();
        let result = execute(seed.kind, &path);
        let took = start.elapsed();
        STARTED.store(u64::MAX, Ordering::Relaxed);
        let largest = largest_allocation::largest();
        tally.executions += 1;
        let n = tally.executions;
        let note = |what: &str| format!("{what} (mutant of {}, {} bytes)", seed.name, bytes.len());
        let samples = match result {
            Ok(Outcome::Accepted { samples }) => samples,
            _ => None,
        };
        match result {
            Ok(Outcome::Accepted { .. }) => tally.accepted[seed.kind as usize] += 1,
            Ok(Outcome::Refused) => tally.refused[seed.kind as usize] += 1,
            Ok(Outcome::Violation(why)) => {
                tally.violations += 1;
                save(&args.out, n, "violation", seed.kind, &bytes, &note(&why));
            }
            Err(panic) => {
                tally.panics += 1;
                save(&args.out, n, "panic", seed.kind, &bytes, &note(&panic));
            }
        }
        if let Some(samples) =
            samples.filter(|_| tally.accepted[seed.kind as usize].is_multiple_of(OUT_OF_CORE_EVERY))
        {
            largest_allocation::reset();
            let built = caught(|| target::out_of_core(&path, samples));
            let largest = largest_allocation::largest();
            tally.out_of_core += 1;
            let failure = match built {
                Ok(Outcome::Violation(why)) => Some(("violation", why)),
                Err(panic) => Some(("panic", panic)),
                _ if largest > justified(seed.kind, bytes.len()) + OUT_OF_CORE_TABLES => {
                    Some(("allocation", format!("one allocation of {largest} bytes")))
                }
                _ => None,
            };
            if let Some((what, why)) = failure {
                tally.violations += 1;
                let why = format!("out of core: {why}");
                save(&args.out, n, what, seed.kind, &bytes, &note(&why));
            }
        }
        tally.slowest = tally.slowest.max(took);
        if took > slow {
            tally.slow += 1;
            save(
                &args.out,
                n,
                "slow",
                seed.kind,
                &bytes,
                &note(&format!("{took:?}")),
            );
        }
        let fraction = largest as f64 / justified(seed.kind, bytes.len()) as f64;
        if fraction > tally.worst.0 {
            tally.worst = (fraction, largest, bytes.len());
        }
        if largest > justified(seed.kind, bytes.len()) {
            tally.oversized += 1;
            let what = format!("one allocation of {largest} bytes");
            save(&args.out, n, "allocation", seed.kind, &bytes, &note(&what));
        }
        if last_report.elapsed() > Duration::from_secs(30) {
            last_report = Instant::now();
            report(&tally, origin.elapsed(), false);
        }
    }
    for kind in Kind::ALL {
        let _ = std::fs::remove_file(args.out.join(format!("current.{}", kind.extension())));
    }
    report(&tally, origin.elapsed(), true);
    std::process::exit(if tally.failures() == 0 { 0 } else { 1 });
}

fn report(t: &Tally, elapsed: Duration, last: bool) {
    let s = elapsed.as_secs_f64();
    let readers: Vec<String> = Kind::NAMES
        .iter()
        .enumerate()
        .map(|(k, name)| format!("{name} accepted {} refused {}", t.accepted[k], t.refused[k]))
        .collect();
    println!(
        "{}executions {} in {s:.0} s ({:.0}/s): {}; panics {}, invariant violations {}, slower \
         than the limit {}, oversized allocations {}; slowest input {:.1} ms; largest \
         allocation {:.0} % of what its input justified ({} bytes for {} input bytes); LAZ \
         decoder panics contained as errors {}; also built out of core {}",
        if last { "fuzz: " } else { "      " },
        t.executions,
        t.executions as f64 / s.max(1e-9),
        readers.join(", "),
        t.panics,
        t.violations,
        t.slow,
        t.oversized,
        t.slowest.as_secs_f64() * 1e3,
        t.worst.0 * 100.0,
        t.worst.1,
        t.worst.2,
        CONTAINED.load(Ordering::Relaxed),
        t.out_of_core,
    );
}

//! Opening a model off the window's thread: a PLY is built into a tree, an `.spt` is
//! memory-mapped and checked, then either is uploaded, while the window goes on drawing
//! the progress. A failure (or a panic) comes back as an error for the window to show.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::Instant;

use crate::render::{GpuScene, LoadReport, Renderer, Scene};

/// The stage a load is in and how far along it is.
#[derive(Default)]
pub struct Progress {
    stage: Mutex<&'static str>,
    total: AtomicU64,
    done: AtomicU64,
}

impl LoadReport for Progress {
    fn stage(&self, name: &'static str, total: u64) {
        *self.stage.lock().unwrap_or_else(|e| e.into_inner()) = name;
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    fn advance(&self, done: u64) {
        self.done.fetch_add(done, Ordering::Relaxed);
    }
}

impl Progress {
    /// The current stage and its fraction done (None when its size is unknown).
    pub fn snapshot(&self) -> (&'static str, Option<f32>) {
        let stage = *self.stage.lock().unwrap_or_else(|e| e.into_inner());
        let total = self.total.load(Ordering::Relaxed);
        let done = self.done.load(Ordering::Relaxed);
        (
            stage,
            (total > 0).then(|| (done as f64 / total as f64).min(1.0) as f32),
        )
    }
}

/// A model being opened.
pub struct Loading {
    pub path: PathBuf,
    pub progress: Arc<Progress>,
    pub started: Instant,
    result: mpsc::Receiver<anyhow::Result<(Scene, GpuScene)>>,
}

impl Loading {
    /// Starts opening `path` on its own thread; `wake` is called once it is done.
    pub fn start(
        path: &Path,
        renderer: Arc<Renderer>,
        wake: impl FnOnce() + Send + 'static,
    ) -> Loading {
        let progress = Arc::new(Progress::default());
        let (send, result) = mpsc::channel();
        let (report, owned_path) = (progress.clone(), path.to_path_buf());
        let spawned = std::thread::Builder::new()
            .name("loader".into())
            .spawn(move || {
                let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let scene = Scene::open_reporting(&owned_path, &*report)?;
                    let gpu_scene = renderer.upload_reporting(&scene, &*report);
                    Ok((scene, gpu_scene))
                }))
                .unwrap_or_else(|panic| {
                    let what = panic
                        .downcast_ref::<String>()
                        .map(String::as_str)
                        .or_else(|| panic.downcast_ref::<&str>().copied())
                        .unwrap_or("unknown cause");
                    Err(anyhow::anyhow!(
                        "{}: loading failed unexpectedly ({what})",
                        owned_path.display()
                    ))
                });
                let _ = send.send(outcome);
                wake();
            });
        let result = match spawned {
            Ok(_) => result,
            Err(e) => {
                let (send, receiver) = mpsc::channel();
                let _ = send.send(Err(anyhow::anyhow!("cannot start loading: {e}")));
                receiver
            }
        };
        Loading {
            path: path.to_path_buf(),
            progress,
            started: Instant::now(),
            result,
        }
    }

    /// The outcome, once the loader is done.
    pub fn try_finish(&self) -> Option<anyhow::Result<(Scene, GpuScene)>> {
        match self.result.try_recv() {
            Ok(outcome) => Some(outcome),
            Err(mpsc::TryRecvError::Empty) => None,
            Err(mpsc::TryRecvError::Disconnected) => Some(Err(anyhow::anyhow!(
                "{}: the loader stopped without an answer",
                self.path.display()
            ))),
        }
    }

    /// Blocks until the load ends (for scripts and tests).
    pub fn wait(self) -> anyhow::Result<(Scene, GpuScene)> {
        self.result
            .recv()
            .map_err(|_| anyhow::anyhow!("{}: the loader stopped", self.path.display()))?
    }
}

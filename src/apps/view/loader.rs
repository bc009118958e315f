//! Opening a model off the window's thread: a PLY is built into a tree, an `.spt` is
//! memory-mapped and checked, then either is uploaded, while the window goes on drawing
//! the progress. A failure (or a panic) comes back as an error for the window to show.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::thread::JoinHandle;
use std::time::Instant;

use crate::render::residency::Residency;
use crate::render::{GpuInstances, GpuScene, MeshUpload, Renderer, SliceUpload};
use crate::tree::instances::{InstancedScene, is_scene};
use crate::tree::report::{Report, Step};
use crate::tree::scene::Scene;

/// The stage a load is in, how far along it is, and when each stage started.
#[derive(Default)]
pub struct Progress {
    stage: Mutex<&'static str>,
    total: AtomicU64,
    done: AtomicU64,
    started: Mutex<Vec<(&'static str, Instant)>>,
}

impl Report for Progress {
    fn step(&self, step: Step, total: u64) {
        let name = step.name();
        *self.stage.lock().unwrap_or_else(|e| e.into_inner()) = name;
        self.started
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((name, Instant::now()));
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    fn advance(&self, done: u64) {
        self.done.fetch_add(done, Ordering::Relaxed);
    }
}

impl Progress {
    /// Each stage so far and its seconds (the last one until `end`), e.g.
    /// "checking 0.08 s, indexing 0.31 s, uploading 0.92 s".
    pub fn timeline(&self, end: Instant) -> String {
        let started = self.started.lock().unwrap_or_else(|e| e.into_inner());
        let ends = started.iter().skip(1).map(|s| s.1).chain([end]);
        started
            .iter()
            .zip(ends)
            .map(|((name, t0), t1)| format!("{name} {:.2} s", t1.duration_since(*t0).as_secs_f64()))
            .collect::<Vec<_>>()
            .join(", ")
    }

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

/// What the loader hands over, in order: the scene with the first slice of its list on
/// the GPU, then either the list's other slices front (coarse) first, or under a GPU
/// memory budget the residency to stream the list with (and, for an `.spt` file, its
/// checks run meanwhile); the mesh if any, then `Done`. The viewer draws from the first
/// message on.
pub enum Loaded {
    Scene(Arc<Scene>, GpuScene),
    /// A scene of instances, its models on the GPU.
    Instances(Arc<InstancedScene>, GpuInstances),
    Streamed(Residency),
    Slice(SliceUpload),
    Mesh(MeshUpload),
    Done,
}

/// A model being opened.
pub struct Loading {
    pub path: PathBuf,
    pub progress: Arc<Progress>,
    pub started: Instant,
    result: mpsc::Receiver<anyhow::Result<Loaded>>,
    finished: bool,
    /// The loading thread, joined on drop once finished (see [`Loading::drop`]).
    loader: Option<JoinHandle<()>>,
}

/// Opens the scene and uploads it (all of it, or under `budget` bytes its first slice),
/// message by message; `wake` after each.
fn load(
    path: &Path,
    (renderer, budget): (&Renderer, Option<u64>),
    report: &Progress,
    send: &dyn Fn(Loaded) -> bool,
) -> anyhow::Result<()> {
    if is_scene(path) {
        if budget.is_some() {
            anyhow::bail!("--gpu-memory streams one model; a scene's models are uploaded whole");
        }
        let scene = InstancedScene::open(path, report)?;
        let total = scene.models.iter().map(|m| m.nodes().len() as u64).sum();
        report.step(Step::Upload, total);
        let gpu = renderer.upload_instanced(&scene);
        report.advance(total);
        send(Loaded::Instances(Arc::new(scene), gpu));
        send(Loaded::Done);
        return Ok(());
    }
    if let Some(budget) = budget {
        return load_streamed(path, (renderer, budget), report, send);
    }
    let scene = Arc::new(Scene::open_reporting(path, report)?);
    let total = scene.nodes().len();
    let planned = renderer.empty_gpu_scene(&scene, None);
    let home = planned.home();
    let ranges: Vec<_> = (0..planned.planned_slices())
        .map(|k| planned.slice_range(k))
        .collect();
    let mut gpu_scene = Some(planned);
    report.step(Step::Upload, total as u64);
    for (k, range) in ranges.into_iter().enumerate() {
        report.advance(range.len() as u64);
        let slice = renderer.upload_slice(&scene, &home, k, range);
        // The first slice goes with the scene, so that the first frame has something.
        let message = match gpu_scene.take() {
            Some(mut g) => {
                g.insert(slice);
                Loaded::Scene(scene.clone(), g)
            }
            None => Loaded::Slice(slice),
        };
        if !send(message) {
            return Ok(()); // nobody waits any more
        }
    }
    if let Some(g) = gpu_scene {
        send(Loaded::Scene(scene.clone(), g)); // an empty list
    }
    if scene.mesh.is_some() {
        report.step(Step::Mesh, 0);
    }
    if let Some(mesh) = renderer.upload_mesh(&scene) {
        send(Loaded::Mesh(mesh));
    }
    send(Loaded::Done);
    Ok(())
}

/// [`load`] under a GPU memory budget: the scene with its first slice, the residency,
/// the mesh, then the checks of an `.spt` file that its opening left out.
fn load_streamed(
    path: &Path,
    (renderer, budget): (&Renderer, u64),
    report: &Progress,
    send: &dyn Fn(Loaded) -> bool,
) -> anyhow::Result<()> {
    let scene = Arc::new(Scene::open_for_streaming(path, report)?);
    let (gpu_scene, residency) = renderer.begin_streaming(&scene, budget)?;
    if !send(Loaded::Scene(scene.clone(), gpu_scene)) || !send(Loaded::Streamed(residency)) {
        return Ok(());
    }
    if let Some(mesh) = renderer.upload_mesh(&scene) {
        send(Loaded::Mesh(mesh));
    }
    report.step(Step::Check, 0);
    scene.check_file()?;
    send(Loaded::Done);
    Ok(())
}

impl Loading {
    /// Starts opening `path` on its own thread; `wake` is called after each message.
    pub fn start(
        path: &Path,
        renderer: Arc<Renderer>,
        wake: impl Fn() + Send + 'static,
    ) -> Loading {
        Loading::start_within(path, (renderer, None), wake)
    }

    /// [`Loading::start`] under a GPU memory budget of `budget` bytes, when given.
    pub fn start_within(
        path: &Path,
        (renderer, budget): (Arc<Renderer>, Option<u64>),
        wake: impl Fn() + Send + 'static,
    ) -> Loading {
        let progress = Arc::new(Progress::default());
        let (send, result) = mpsc::channel();
        let (report, owned_path) = (progress.clone(), path.to_path_buf());
        let spawned = std::thread::Builder::new()
            .name("loader".into())
            // A point-wise LAZ file is decoded on this thread (las::DECODER_STACK).
            .stack_size(crate::io::las::DECODER_STACK)
            .spawn(move || {
                let deliver = |message: anyhow::Result<Loaded>| {
                    let delivered = send.send(message).is_ok();
                    wake();
                    delivered
                };
                let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    load(&owned_path, (&renderer, budget), &report, &|m| {
                        deliver(Ok(m))
                    })
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
                if let Err(e) = outcome {
                    deliver(Err(e));
                }
            });
        let (result, loader) = match spawned {
            Ok(loader) => (result, Some(loader)),
            Err(e) => {
                let (send, receiver) = mpsc::channel();
                let _ = send.send(Err(anyhow::anyhow!("cannot start loading: {e}")));
                (receiver, None)
            }
        };
        Loading {
            path: path.to_path_buf(),
            progress,
            started: Instant::now(),
            result,
            finished: false,
            loader,
        }
    }

    /// The messages that arrived since the last call. After `Done` or an error, the
    /// load is finished.
    pub fn poll(&mut self) -> Vec<anyhow::Result<Loaded>> {
        let mut messages = Vec::new();
        loop {
            match self.result.try_recv() {
                Ok(m) => {
                    self.finished |= matches!(m, Ok(Loaded::Done) | Err(_));
                    messages.push(m);
                }
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => {
                    if !self.finished {
                        self.finished = true;
                        messages.push(Err(anyhow::anyhow!(
                            "{}: the loader stopped without an answer",
                            self.path.display()
                        )));
                    }
                    break;
                }
            }
        }
        messages
    }

    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Blocks until the load ends and returns the whole scene (for scripts and tests).
    pub fn wait(mut self) -> anyhow::Result<(Arc<Scene>, GpuScene)> {
        // It returns after the last message: the thread is ending, and drop joins it.
        self.finished = true;
        let mut scene = None;
        for message in self.result.iter() {
            match message? {
                Loaded::Scene(s, g) => scene = Some((s, g)),
                Loaded::Slice(slice) => scene.as_mut().expect("scene first").1.insert(slice),
                Loaded::Streamed(_) => {}
                Loaded::Instances(..) => {
                    anyhow::bail!(
                        "{}: a scene of instances, not one model",
                        self.path.display()
                    )
                }
                Loaded::Mesh(mesh) => scene.as_mut().expect("scene first").1.set_mesh(mesh),
                Loaded::Done => break,
            }
        }
        scene.ok_or_else(|| anyhow::anyhow!("{}: the loader stopped", self.path.display()))
    }
}

impl Drop for Loading {
    /// Joins a finished load's thread, whose handle on the renderer must be gone before
    /// the window's (see `Streamer::drop`). An unfinished load is left to run: its end is
    /// far off, and nobody reads its messages any more.
    fn drop(&mut self) {
        if self.finished
            && let Some(loader) = self.loader.take()
        {
            let _ = loader.join();
        }
    }
}

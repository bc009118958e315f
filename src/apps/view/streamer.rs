//! Streaming a model's list under a GPU memory budget (`--gpu-memory`): after each
//! frame the [`Residency`] policy says which slices to evict and which to fetch (those
//! the frame's asked ε wanted, coarse first); a background thread uploads the fetched
//! ones, and the frames after their arrival use them. Frames meanwhile are drawn at the
//! least ε whose ranges are resident (`render/plan.rs`): coarser, never holed.

use std::ops::Range;
use std::sync::{Arc, mpsc};
use std::thread::JoinHandle;

use crate::render::residency::Residency;
use crate::render::{GpuScene, Renderer, SliceHome, SliceUpload};
use crate::tree::scene::Scene;

/// Uploads asked and not arrived at most: enough to keep the uploading thread busy,
/// few enough that a camera that moves on redirects the stream quickly.
const MAX_IN_FLIGHT: usize = 4;

pub struct Streamer {
    requests: mpsc::Sender<(usize, Range<usize>)>,
    /// The uploading thread, joined on drop (see [`Streamer::drop`]).
    uploader: Option<JoinHandle<()>>,
    arrivals: mpsc::Receiver<SliceUpload>,
    pub residency: Residency,
    /// The last frame asked for nothing new: what the view wants is resident, or as much
    /// of it as the budget holds.
    settled: bool,
}

impl Streamer {
    /// Starts the uploading thread for `scene`, whose list `residency` mirrors, its
    /// slices made for `home` ([`crate::render::GpuScene::home`]); `wake` after each
    /// upload (the window redraws).
    pub fn start(
        (scene, home): (Arc<Scene>, SliceHome),
        renderer: Arc<Renderer>,
        residency: Residency,
        wake: impl Fn() + Send + 'static,
    ) -> anyhow::Result<Streamer> {
        let (requests, asked) = mpsc::channel::<(usize, Range<usize>)>();
        let (deliver, arrivals) = mpsc::channel();
        let uploader = std::thread::Builder::new()
            .name("streamer".into())
            .spawn(move || {
                for (k, range) in asked {
                    if deliver
                        .send(renderer.upload_slice(&scene, &home, k, range))
                        .is_err()
                    {
                        return;
                    }
                    wake();
                }
            })?;
        Ok(Streamer {
            requests,
            uploader: Some(uploader),
            arrivals,
            residency,
            settled: false,
        })
    }

    /// Puts the slices that arrived into `gpu`; returns how many.
    pub fn receive(&mut self, gpu: &mut GpuScene) -> usize {
        let mut n = 0;
        while let Ok(slice) = self.arrivals.try_recv() {
            self.residency.arrived(slice.index(), slice.bytes());
            gpu.insert(slice);
            n += 1;
        }
        n
    }

    /// After a frame that wanted `wanted` slices: evicts from `gpu` and asks for uploads
    /// as [`Residency::after_frame`] decides.
    pub fn after_frame(
        &mut self,
        (renderer, scene): (&Renderer, &Scene),
        gpu: &mut GpuScene,
        wanted: &[usize],
    ) {
        let bytes_of = |k| renderer.slice_bytes(scene, gpu, k);
        let decision = self.residency.after_frame(wanted, bytes_of, MAX_IN_FLIGHT);
        for &k in &decision.evict {
            gpu.evict(k);
        }
        for &k in &decision.fetch {
            // A closed channel means the thread is gone: the frames stay coarser.
            let _ = self.requests.send((k, gpu.slice_range(k)));
        }
        self.settled = decision.fetch.is_empty() && self.residency.in_flight() == 0;
    }

    /// Nothing in flight and nothing more to fetch for the last frame's view.
    pub fn is_settled(&self) -> bool {
        self.settled
    }
}

impl Drop for Streamer {
    /// Closes the requests and waits for the upload under way, so that the thread's
    /// handle on the renderer is gone before the window's: a device destroyed on another
    /// thread while the process exits crashed in the Vulkan driver's exit handlers
    /// (lavapipe, 1 exit in 10 to 40 under load).
    fn drop(&mut self) {
        drop(std::mem::replace(&mut self.requests, mpsc::channel().0));
        if let Some(uploader) = self.uploader.take() {
            let _ = uploader.join();
        }
    }
}

//! The GPU's time on each frame, measured without holding the frame loop back.

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::mpsc::{Sender, channel};
use std::thread::JoinHandle;
use std::time::Instant;

/// Times submitted frames on a thread of its own, so the loop that submits them need not
/// wait for the GPU: the CPU builds the next frame while the GPU draws this one. The thread
/// waits for each submission in turn; a frame's time runs from when its uploads and
/// commands began (a software rasteriser such as lavapipe may draw inside the submit
/// itself), or when the frame before it finished if that was later (the GPU was still
/// busy), to when it finished. Its finish is seen when the wait returns, so a figure is
/// late by the thread's wake-up, microseconds.
#[derive(Debug)]
pub struct GpuTimer {
    tx: Option<Sender<(wgpu::SubmissionIndex, Instant)>>,
    last_ms: Arc<AtomicU32>,
    frames: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

impl GpuTimer {
    /// A timer of the submissions to `device`'s queue.
    pub fn new(device: wgpu::Device) -> GpuTimer {
        let (tx, rx) = channel::<(wgpu::SubmissionIndex, Instant)>();
        let last_ms = Arc::new(AtomicU32::new(0.0f32.to_bits()));
        let frames = Arc::new(AtomicU64::new(0));
        let (ms, count) = (last_ms.clone(), frames.clone());
        let thread = std::thread::Builder::new()
            .name("gpu timer".into())
            .spawn(move || {
                let mut previous: Option<Instant> = None;
                for (index, submitted) in rx {
                    let wait =
                        wgpu::PollType::Wait { submission_index: Some(index), timeout: None };
                    if device.poll(wait).is_err() {
                        break; // the device is lost: nothing more will finish
                    }
                    let done = Instant::now();
                    let from = previous.map_or(submitted, |p| p.max(submitted));
                    ms.store((1e3 * (done - from).as_secs_f32()).to_bits(), Ordering::Relaxed);
                    count.fetch_add(1, Ordering::Release);
                    previous = Some(done);
                }
            })
            .ok();
        GpuTimer { tx: Some(tx), last_ms, frames, thread }
    }

    /// Time the frame whose work began at `began` (before its uploads and encoding) and
    /// ends with the submission `index` (the frame's last `queue.submit`; `queue.submit([])`
    /// gives an index after everything submitted so far).
    pub fn submitted(&self, index: wgpu::SubmissionIndex, began: Instant) {
        if let Some(tx) = &self.tx {
            let _ = tx.send((index, began));
        }
    }

    /// The GPU time of the latest frame finished, ms (0 before the first).
    pub fn last_ms(&self) -> f32 {
        f32::from_bits(self.last_ms.load(Ordering::Relaxed))
    }

    /// How many submitted frames have finished.
    pub fn frames(&self) -> u64 {
        self.frames.load(Ordering::Acquire)
    }

    /// Wait until every frame submitted so far has finished and been timed, and stop
    /// timing (frames submitted later are not); returns how many were timed.
    pub fn finish(&mut self) -> u64 {
        self.stop();
        self.frames()
    }

    fn stop(&mut self) {
        self.tx = None; // the thread's loop ends after the frames already sent
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        self.stop();
    }
}

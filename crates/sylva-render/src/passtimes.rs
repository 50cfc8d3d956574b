//! The GPU's time in each part of a frame, from timestamp queries written between the
//! renderer's passes and draw groups.
//!
//! Seven timestamps a frame: the shadow pass's start (before it clears the map) and end,
//! then inside the image pass its start (after it cleared its targets) and the points
//! after the trees, after the impostors and after the ground, and the pass's end (after
//! the sky and the MSAA resolve). The five differences are the parts; the image pass's
//! clear falls in none of them.
//!
//! On a GPU that draws commands in order (every desktop GPU), a timestamp inside a pass is
//! written when the work recorded before it has left the pipeline, so draws that overlap
//! across a boundary share their time between its two sides: the parts are a breakdown,
//! good to a fraction of a millisecond, not separate runs. Lavapipe draws what it has
//! binned before it writes a timestamp inside a pass, so its split is real too. Timing is
//! off unless asked for: it adds work no frame needs (within the run-to-run spread where
//! measured: about 1 % on an H200, inside lavapipe's ±15 % noise in scene D), and a GPU
//! that bins a whole pass before drawing it (a tiler) gives the split inside it no
//! meaning.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crate::gpu::{Gpu, RenderError};

/// The parts of a frame, in order: [`crate::Renderer::pass_times`] gives one time for each.
pub const PARTS: [&str; 5] = ["shadows", "trees", "impostors", "ground", "sky + resolve"];

/// Timestamps written each frame.
pub(crate) const STAMPS: u32 = PARTS.len() as u32 + 2;

/// Index of each timestamp in the query set.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Stamp {
    ShadowStart = 0,
    ShadowEnd = 1,
    ImageStart = 2,
    Trees = 3,
    Impostors = 4,
    Ground = 5,
    ImageEnd = 6,
}

/// A query set of [`STAMPS`] timestamps, and the buffers its values are read back through:
/// a few, each mapped once its frame is done, so frames in flight need not wait for one
/// another's read-back.
#[derive(Debug)]
pub(crate) struct PassTimes {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    slots: Vec<Slot>,
    /// The slot to try first for the next frame.
    next: usize,
    /// The slot the frame being recorded copies its timestamps into, if one was free.
    pending: Option<usize>,
    /// The parts of the latest frame read back.
    latest: Arc<Mutex<Option<[f64; PARTS.len()]>>>,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

/// A read-back buffer, busy from the copy into it until its mapping has been read.
#[derive(Debug)]
struct Slot {
    buffer: wgpu::Buffer,
    busy: Arc<AtomicBool>,
}

/// Read-back buffers: one more than the frames a surface holds in flight.
const SLOTS: usize = 3;

/// Bytes of one frame's timestamps.
const BYTES: u64 = STAMPS as u64 * 8;

impl PassTimes {
    /// The features pass timing needs: timestamps, also inside passes.
    pub(crate) const FEATURES: wgpu::Features =
        wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);

    /// A query set and its buffers on `gpu`; `None` where its device lacks the features.
    pub(crate) fn new(gpu: &Gpu) -> Option<PassTimes> {
        if !gpu.device.features().contains(Self::FEATURES) {
            return None;
        }
        let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass times"),
            ty: wgpu::QueryType::Timestamp,
            count: STAMPS,
        });
        let buffer = |label, usage| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: BYTES,
                usage,
                mapped_at_creation: false,
            })
        };
        let resolved = buffer(
            "pass times resolved",
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        );
        let slots = (0..SLOTS)
            .map(|_| Slot {
                buffer: buffer(
                    "pass times read",
                    wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                ),
                busy: Arc::new(AtomicBool::new(false)),
            })
            .collect();
        let period_ns = gpu.queue.get_timestamp_period() as f64;
        let latest = Arc::new(Mutex::new(None));
        Some(PassTimes { set, resolved, slots, next: 0, pending: None, latest, period_ns })
    }

    /// After the frame's passes: copy its timestamps into a free read-back buffer (none
    /// free: this frame is not read back).
    pub(crate) fn resolve(&mut self, enc: &mut wgpu::CommandEncoder) {
        self.pending = (0..SLOTS)
            .map(|k| (self.next + k) % SLOTS)
            .find(|&k| !self.slots[k].busy.load(Ordering::Acquire));
        if let Some(k) = self.pending {
            self.slots[k].busy.store(true, Ordering::Release);
            self.next = (k + 1) % SLOTS;
            enc.resolve_query_set(&self.set, 0..STAMPS, &self.resolved, 0);
            enc.copy_buffer_to_buffer(&self.resolved, 0, &self.slots[k].buffer, 0, BYTES);
        }
    }

    /// After the frame's submission: read its timestamps back once the GPU has drawn it
    /// (when the device is next polled), into [`latest`](Self::latest).
    pub(crate) fn submitted(&mut self) {
        let Some(k) = self.pending.take() else { return };
        let Slot { buffer, busy } = &self.slots[k];
        let (buffer, busy, latest) = (buffer.clone(), busy.clone(), self.latest.clone());
        let period_ns = self.period_ns;
        self.slots[k].buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            if r.is_ok() {
                let ticks: Option<Vec<u64>> = buffer.slice(..).get_mapped_range().ok().map(|d| {
                    d.chunks_exact(8)
                        .map(|b| u64::from_le_bytes(b.try_into().expect("chunks of 8 bytes")))
                        .collect()
                });
                buffer.unmap();
                if let (Some(t), Ok(mut l)) = (ticks, latest.lock()) {
                    *l = Some(parts(&t, period_ns));
                }
            }
            busy.store(false, Ordering::Release);
        });
    }

    /// The parts' times (ms, in the order of [`PARTS`]) of the latest frame read back,
    /// without waiting.
    pub(crate) fn latest(&self) -> Option<[f64; PARTS.len()]> {
        self.latest.lock().ok().and_then(|l| *l)
    }

    /// The parts' times of the last frame submitted; waits for the GPU to finish it.
    pub(crate) fn read(&self, gpu: &Gpu) -> Result<Option<[f64; PARTS.len()]>, RenderError> {
        gpu.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| RenderError::Readback(format!("pass times: {e}")))?;
        Ok(self.latest())
    }
}

/// Timestamps `begin` and `end` written at a pass's start (before its clears) and end
/// (after its resolve), where timing is on.
pub(crate) fn pass_writes(
    timing: Option<&PassTimes>,
    begin: Stamp,
    end: Stamp,
) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
    timing.map(|t| wgpu::RenderPassTimestampWrites {
        query_set: &t.set,
        beginning_of_pass_write_index: Some(begin as u32),
        end_of_pass_write_index: Some(end as u32),
    })
}

impl PassTimes {
    /// Timestamp `end` written at a pass's end, after its resolve.
    pub(crate) fn end_of_pass(&self, end: Stamp) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: None,
            end_of_pass_write_index: Some(end as u32),
        }
    }
}

/// Write timestamp `at` at this point of `pass`, where timing is on.
pub(crate) fn stamp(timing: Option<&PassTimes>, pass: &mut wgpu::RenderPass<'_>, at: Stamp) {
    if let Some(t) = timing {
        pass.write_timestamp(&t.set, at as u32);
    }
}

/// The parts' times (ms) from one frame's timestamps (`ticks`, [`STAMPS`] of them) at
/// `period_ns` a tick; a part whose end reads before its start (a counter that wrapped, or
/// a GPU that reorders) is 0.
fn parts(ticks: &[u64], period_ns: f64) -> [f64; PARTS.len()] {
    let span = |a: Stamp, b: Stamp| {
        ticks[b as usize].saturating_sub(ticks[a as usize]) as f64 * period_ns / 1e6
    };
    [
        span(Stamp::ShadowStart, Stamp::ShadowEnd),
        span(Stamp::ImageStart, Stamp::Trees),
        span(Stamp::Trees, Stamp::Impostors),
        span(Stamp::Impostors, Stamp::Ground),
        span(Stamp::Ground, Stamp::ImageEnd),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_part_runs_from_its_own_start_to_its_end_in_milliseconds() {
        // Shadow pass 0 → 2 000 ticks; the image pass starts later (the gap between the
        // passes belongs to no part), then 1 000, 3 000, 500 and 250 ticks; 2 ns a tick.
        let ticks = [100, 2_100, 2_600, 3_600, 6_600, 7_100, 7_350];
        let p = parts(&ticks, 2.0);
        assert_eq!(p, [0.004, 0.002, 0.006, 0.001, 0.0005]);
        // A stamp that reads before the one it follows gives 0, not a wrapped huge time.
        let p = parts(&[0, 10, 20, 15, 30, 40, 50], 1.0);
        assert_eq!(p[1], 0.0);
        assert!(p.iter().all(|&t| t < 1e-3));
    }
}

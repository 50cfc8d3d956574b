//! The GPU's time in each part of a frame, from timestamp queries written between the
//! renderer's passes and draw groups.
//!
//! Seven timestamps a frame: the shadow pass's start (before it clears the map) and end,
//! then inside the image pass its start (after it cleared its targets) and the points
//! after the trees, after the impostors and after the ground, and the pass's end (after
//! the sky and the MSAA resolve). The five differences are the parts; the image pass's
//! clear falls in none of them. On a GPU that draws commands in order (every desktop GPU), a timestamp
//! inside a pass is written when the work recorded before it has left the pipeline, so
//! draws that overlap across a boundary share their time between its two sides: the parts
//! are a breakdown, good to a fraction of a millisecond, not separate runs. Lavapipe
//! draws what it has binned before it writes a timestamp inside a pass, so its split is
//! real too, but the extra flushes cost: scene D at 640×360 rendered in 1 038 ms a frame
//! timed against 807 ms untimed. Timing is therefore off unless asked for.

use crate::gpu::{Gpu, RenderError};

/// The parts of a frame, in order: [`PassTimes::read`] returns one time for each.
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

/// A query set of [`STAMPS`] timestamps, and the buffers its values are read back through.
#[derive(Debug)]
pub(crate) struct PassTimes {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    read: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

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
        let read =
            buffer("pass times read", wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
        let period_ns = gpu.queue.get_timestamp_period() as f64;
        Some(PassTimes { set, resolved, read, period_ns })
    }

    /// After the frame's passes: copy its timestamps where [`read`](Self::read) finds them.
    pub(crate) fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        enc.resolve_query_set(&self.set, 0..STAMPS, &self.resolved, 0);
        enc.copy_buffer_to_buffer(&self.resolved, 0, &self.read, 0, BYTES);
    }

    /// The parts' times (ms, in the order of [`PARTS`]) of the last frame submitted; waits
    /// for the GPU to finish it.
    pub(crate) fn read(&self, gpu: &Gpu) -> Result<[f64; PARTS.len()], RenderError> {
        let slice = self.read.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        let fail = |e: String| RenderError::Readback(format!("pass times: {e}"));
        gpu.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| fail(e.to_string()))?;
        rx.recv().map_err(|e| fail(e.to_string()))?.map_err(|e| fail(e.to_string()))?;
        let ticks: Vec<u64> = {
            let data = slice.get_mapped_range().map_err(|e| fail(e.to_string()))?;
            data.chunks_exact(8)
                .map(|b| u64::from_le_bytes(b.try_into().expect("chunks of 8 bytes")))
                .collect()
        };
        self.read.unmap();
        Ok(parts(&ticks, self.period_ns))
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

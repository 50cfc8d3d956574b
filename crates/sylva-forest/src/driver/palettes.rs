//! A frame's palettes: where each lane group's go in the frame's buffer
//! ([`lay_out`]) and the copy out of the batches into it ([`copy_palettes`]), in parallel
//! (see [`FrameData::palettes`](super::FrameData::palettes) for the layout).

use sylva_sway::{IDENTITY, LANES, PaletteSlot};

use super::SpeciesRuntime;

/// How a lane group's palettes are laid out in a frame's buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Layout {
    /// Before the first step: every joint at rest, lanes side by side.
    Rest,
    /// As the batch holds them, lanes side by side (each joint's `used` lanes in a row).
    Lanes,
    /// Each simulation's own prefix in a row: where the lanes' prefixes differ or a lane
    /// was stepped alone.
    Rows,
}

/// One lane group's palettes in a frame: where they go and how.
#[derive(Debug, Clone, Copy)]
pub(super) struct PaletteCopy {
    pub(super) species: u32,
    pub(super) group: u32,
    /// First value in the frame's buffer, and values.
    pub(super) start: usize,
    pub(super) len: usize,
    /// Joints of the group's finest prefix, and simulations copied (its used lanes).
    pub(super) joints: u32,
    pub(super) used: u32,
    pub(super) kind: Layout,
}

/// Where lane group `k` of species `s` (index `si`) puts its palettes, from `start` in the
/// frame's buffer, given what each simulation's drawn trees read (`need`); `None` where
/// none is drawn.
pub(super) fn lay_out(
    s: &SpeciesRuntime,
    si: usize,
    k: usize,
    need: &[u32],
    start: usize,
) -> Option<PaletteCopy> {
    let n = s.batch.species().len();
    // The batch pads its last lane group (to 16, or a narrow batch to its 4 or 8 lanes):
    // only the simulated lanes are copied.
    let used = (s.groups.len() - k * LANES).min(s.batch.width());
    let need = &need[(s.lane_base + k) * LANES..][..used];
    // The group's finest prefix: what the lane layout would send for each lane.
    let joints = (need.iter().copied().max().unwrap_or(0) as usize).min(n);
    if joints == 0 {
        return None;
    }
    let first = k * LANES;
    let simulated_in = |l: usize| s.batch.simulated(first + l);
    let simulated = (0..used).map(simulated_in).min().unwrap_or(0);
    let uniform = (0..used)
        .all(|l| simulated_in(l) == simulated && s.batch.lane_palettes(first + l).is_none());
    let own: usize = need.iter().map(|&m| (m as usize).min(n)).sum();
    let (kind, len) = if !s.batch.has_stepped() {
        (Layout::Rest, joints * 12 * used)
    } else if own < joints * used || !uniform {
        (Layout::Rows, 12 * own)
    } else {
        (Layout::Lanes, joints * 12 * used)
    };
    Some(PaletteCopy {
        species: si as u32,
        group: k as u32,
        start,
        len,
        joints: joints as u32,
        used: used as u32,
        kind,
    })
}

/// Values a thread copies at least, rather than split the copies further.
const COPY_GRAIN: usize = 1 << 16;

/// Write the palettes of `copies` (in buffer order, from `copies[0].start`) into `buf`:
/// split near the middle value, the halves in parallel, down to [`COPY_GRAIN`] values; each
/// lane group by one thread.
pub(super) fn copy_palettes(
    species: &[SpeciesRuntime],
    need: &[u32],
    slots: &[PaletteSlot],
    copies: &[PaletteCopy],
    buf: &mut [f32],
) {
    if copies.len() > 1 && buf.len() > COPY_GRAIN {
        let half = copies[0].start + buf.len() / 2;
        let mid = copies.partition_point(|c| c.start < half).clamp(1, copies.len() - 1);
        let (a, b) = buf.split_at_mut(copies[mid].start - copies[0].start);
        rayon::join(
            || copy_palettes(species, need, slots, &copies[..mid], a),
            || copy_palettes(species, need, slots, &copies[mid..], b),
        );
        return;
    }
    let mut rest = buf;
    for c in copies {
        let (dst, after) = rest.split_at_mut(c.len);
        rest = after;
        copy_group(&species[c.species as usize], need, slots, c, dst);
    }
}

/// Write one lane group's palettes (`c`) into `dst`, all `c.len` values of it, where the
/// simulations' `slots` (set when it was laid out) say.
fn copy_group(
    s: &SpeciesRuntime,
    need: &[u32],
    slots: &[PaletteSlot],
    c: &PaletteCopy,
    dst: &mut [f32],
) {
    let (k, joints, used) = (c.group as usize, c.joints as usize, c.used as usize);
    let n = s.batch.species().len();
    // Per joint, its 12 elements × `width` lanes.
    let width = s.batch.width();
    let joint = 12 * width;
    // The group stores (at least) the joints it simulates; those it does not are read at
    // their anchors below.
    let block = s.batch.group_palettes(k);
    let need = &need[(s.lane_base + k) * LANES..][..used];
    if c.kind == Layout::Rest {
        // Before the first step the batch stores nothing: every joint at rest.
        for joint in dst.chunks_exact_mut(12 * used) {
            for (lanes, x) in joint.chunks_exact_mut(used).zip(IDENTITY) {
                lanes.fill(x);
            }
        }
        return;
    }
    // Joints drawn beyond what a lane simulates (the animation LOD by size) rest on their
    // parents: each shows its nearest simulated ancestor's palette.
    let first = k * LANES;
    let simulated_in = |l: usize| s.batch.simulated(first + l);
    if c.kind == Layout::Rows {
        // A transpose of lanes and elements (`sylva_core::lanes`: eight lanes at a time in
        // registers where the CPU has AVX), each joint's block read from memory once.
        // Each simulation's run, from its slot.
        let slots = &slots[(s.lane_base + k) * LANES..][..used];
        let start = |l: usize| slots[l].base as usize - c.start;
        // Each lane's own anchors where its simulated prefix is its own; lanes stepped
        // alone keep their palettes in a row of their own.
        let mut lane_src = [None; LANES];
        for (l, a) in lane_src.iter_mut().enumerate().take(used) {
            let sim = simulated_in(l);
            *a = if joints > sim { s.batch.anchors(sim) } else { None };
        }
        // Each lane's run: the joints it shows as its own (within its simulated prefix)
        // transposed out of the group's lanes in one pass; then the joints resting on an
        // anchor, and the runs of lanes stepped alone, joint by joint.
        let mut runs: [&mut [f32]; LANES] = Default::default();
        let mut own = [0; LANES];
        let dst_len = dst.len();
        let mut rest = &mut *dst;
        for (l, &m) in need.iter().enumerate() {
            let m = (m as usize).min(n);
            debug_assert_eq!(dst_len - rest.len(), start(l), "lane runs lie in lane order");
            let (run, after) = std::mem::take(&mut rest).split_at_mut(12 * m);
            rest = after;
            own[l] = match (s.batch.lane_palettes(first + l), lane_src[l]) {
                (Some(_), _) => 0,
                (None, Some(_)) => m.min(simulated_in(l)),
                (None, None) => m,
            };
            runs[l] = run;
        }
        {
            let mut heads: [&mut [f32]; LANES] = Default::default();
            for ((head, run), &o) in heads.iter_mut().zip(runs.iter_mut()).zip(&own) {
                *head = &mut run[..12 * o];
            }
            sylva_core::lanes::lanes_to_rows(block, width, &mut heads[..used]);
        }
        for (l, run) in runs.iter_mut().enumerate().take(used) {
            let src = |j: usize| lane_src[l].map_or(j, |a| a[j] as usize);
            let tail = run.chunks_exact_mut(12).enumerate().skip(own[l]);
            if let Some(row) = s.batch.lane_palettes(first + l) {
                for (j, v) in tail {
                    v.copy_from_slice(&row[12 * src(j)..][..12]);
                }
                continue;
            }
            for (j, v) in tail {
                let lanes = &block[src(j) * joint..][..joint];
                for (e, x) in v.iter_mut().enumerate() {
                    *x = lanes[e * width + l];
                }
            }
        }
        return;
    }
    let simulated = (0..used).map(simulated_in).min().unwrap_or(0);
    let anchors = if joints > simulated { s.batch.anchors(simulated) } else { None };
    let src = |j: usize| anchors.map_or(j, |a| a[j] as usize);
    let copied = joints.min(simulated);
    let (head, tail) = dst.split_at_mut(copied * 12 * used);
    if used == width {
        head.copy_from_slice(&block[..copied * joint]);
    } else {
        for (to, lanes) in head.chunks_exact_mut(used).zip(block[..copied * joint].chunks(width)) {
            to.copy_from_slice(&lanes[..used]);
        }
    }
    let mut to = tail.chunks_exact_mut(used);
    for j in copied..joints {
        for lanes in block[src(j) * joint..][..joint].chunks(width) {
            if let Some(v) = to.next() {
                v.copy_from_slice(&lanes[..used]);
            }
        }
    }
}

//! Where a batch keeps its state: per lane group a [`Block`] of the joints it steps its
//! lanes together to, and per lane stepped alone a [`Row`] of its own (see the module
//! documentation of `batch`).

/// One group's stored state: its first `joints` joints for every lane (a prefix: those it
/// steps its lanes together to, and none beyond), `width` lanes inner. A lane's joints are
/// in its row where the row holds them, else here where stored, else at rest.
///
/// The memory behind it may hold more joints than are stored: a group whose prefix shrinks
/// keeps its memory for [`TRIM_STEPS`] steps before giving it back, so a prefix that comes
/// and goes (a tree at the edge of a level, lanes repacked) costs no allocation and no
/// page faults each time.
#[derive(Debug, Clone, Default)]
pub(super) struct Block {
    /// Per joint, per axis: bending angle (rad) and rate (rad/s).
    pub(super) theta: Vec<f32>,
    pub(super) rate: Vec<f32>,
    /// Displayed fraction of each joint's rotation (animation-LOD blend), 0 … 1.
    pub(super) weight: Vec<f32>,
    /// Palettes per (joint, element) (parents are read from here).
    pub(super) pal: Vec<f32>,
    /// Joints stored (the vectors hold at least these).
    pub(super) joints: usize,
    /// Steps in a row this block has held memory for more joints than it stores.
    pub(super) idle: u32,
    /// Lanes the last step stepped alone (a bit each): their palettes are in `rows`, not
    /// in `pal`.
    pub(super) alone: u32,
    /// Per lane stepped alone: its row (empty for the others).
    pub(super) rows: Vec<Row>,
}

/// The state of a lane stepped alone, one value per joint in a row rather than strided
/// across its group's lanes: its palettes (12 per joint) for the joints it simulates, and
/// its angles, rates and blend weights for the first `joints` joints, which stand for the
/// group's values of that lane (the group need not store them: it stores what it steps all
/// its lanes to). The state stays in the row while the lane goes alone from step to step
/// (copying it in and out of the group each step, through memory strided by the group's
/// width, cost a third of a near tree's step), moves with the lane when lanes are
/// exchanged, and goes back to the group when the lane rejoins it.
#[derive(Debug, Clone, Default)]
pub(super) struct Row {
    pub(super) pal: Vec<f32>,
    pub(super) theta: Vec<f32>,
    pub(super) rate: Vec<f32>,
    pub(super) weight: Vec<f32>,
    /// Joints whose state the row holds (the group's values of the lane for them are not
    /// current).
    pub(super) joints: usize,
}

impl Row {
    /// Values held (capacity), all four vectors.
    pub(super) fn capacity(&self) -> usize {
        self.pal.capacity() + self.theta.capacity() + self.rate.capacity() + self.weight.capacity()
    }

    /// Hold the state of joints `..joints` of lane `l` of a group of `width` lanes (angles
    /// `theta`, rates `rate`, weights `weight`) that stores its first `stored` joints for
    /// every lane: joints the row held beyond go back to the group (those it stores; the
    /// others are at rest, as the lane shows them there), joints it lacks come from it (at
    /// rest, with blend weight `rest`, where it does not store them). Grown exactly, so
    /// that the bytes held are the bytes counted.
    pub(super) fn hold(
        &mut self,
        joints: usize,
        group: [&mut Vec<f32>; 3],
        width: usize,
        l: usize,
        (stored, rest): (usize, f32),
    ) {
        let [theta, rate, weight] = group;
        let had = self.joints;
        for j in joints..stored.min(had) {
            for k in 0..2 {
                theta[(2 * j + k) * width + l] = self.theta[2 * j + k];
                rate[(2 * j + k) * width + l] = self.rate[2 * j + k];
            }
            weight[j * width + l] = self.weight[j];
        }
        self.theta.truncate(2 * joints.min(had));
        self.rate.truncate(2 * joints.min(had));
        self.weight.truncate(joints.min(had));
        if joints > had {
            for v in [&mut self.theta, &mut self.rate] {
                v.reserve_exact(2 * (joints - had));
            }
            self.weight.reserve_exact(joints - had);
            for j in had..joints.min(stored) {
                for k in 0..2 {
                    self.theta.push(theta[(2 * j + k) * width + l]);
                    self.rate.push(rate[(2 * j + k) * width + l]);
                }
                self.weight.push(weight[j * width + l]);
            }
            self.theta.resize(2 * joints, 0.0);
            self.rate.resize(2 * joints, 0.0);
            self.weight.resize(joints, rest);
        }
        self.joints = joints;
    }
}

impl Block {
    /// Lane `l`'s row, if it holds the state of joint `j`.
    pub(super) fn row_holding(&self, l: usize, j: usize) -> Option<&Row> {
        self.rows.get(l).filter(|r| j < r.joints)
    }

    /// Take lane `l`'s state (of a group of `width` lanes) for its first `m` joints at
    /// least, as a row: its row, extended with what the group stores for it beyond, and
    /// whether the row's palettes are current (the lane was stepped alone). The lane's
    /// values in the group are left for [`Block::put_lane`] to overwrite.
    pub(super) fn take_lane(&mut self, l: usize, m: usize, width: usize) -> (Row, bool) {
        let mut row = self.rows.get_mut(l).map(std::mem::take).unwrap_or_default();
        let alone = self.alone >> l & 1 == 1;
        self.alone &= !(1 << l);
        let (had, end) = (row.joints, row.joints.max(self.joints.min(m)));
        if end > had {
            for v in [&mut row.theta, &mut row.rate] {
                v.reserve_exact(2 * (end - had));
            }
            row.weight.reserve_exact(end - had);
            for j in had..end {
                for k in 0..2 {
                    row.theta.push(self.theta[(2 * j + k) * width + l]);
                    row.rate.push(self.rate[(2 * j + k) * width + l]);
                }
                row.weight.push(self.weight[j * width + l]);
            }
            row.joints = end;
        }
        (row, alone)
    }

    /// Give lane `l` the state `taken` by [`Block::take_lane`]: into the group's lane where
    /// the group stores all of it and its palettes are not current, else as the lane's row;
    /// either way at rest (blend weight `rest`) beyond it.
    pub(super) fn put_lane(&mut self, l: usize, taken: (Row, bool), width: usize, rest: f32) {
        let (row, alone) = taken;
        let (joints, stored) = (row.joints, self.joints);
        let in_group = !alone && joints <= stored;
        if in_group {
            for j in 0..joints {
                for k in 0..2 {
                    self.theta[(2 * j + k) * width + l] = row.theta[2 * j + k];
                    self.rate[(2 * j + k) * width + l] = row.rate[2 * j + k];
                }
                self.weight[j * width + l] = row.weight[j];
            }
        }
        for j in joints..stored {
            for k in 0..2 {
                self.theta[(2 * j + k) * width + l] = 0.0;
                self.rate[(2 * j + k) * width + l] = 0.0;
            }
            self.weight[j * width + l] = rest;
        }
        if in_group {
            if let Some(r) = self.rows.get_mut(l) {
                *r = Row::default();
            }
        } else {
            if self.rows.len() < width {
                self.rows.resize_with(width, Row::default);
            }
            self.rows[l] = row;
            self.alone |= (alone as u32) << l;
        }
    }
}

/// Steps a lane group keeps the memory of joints it no longer stores before giving it
/// back (about two seconds at 30 frames a second).
pub const TRIM_STEPS: u32 = 64;

impl Block {
    /// Joints the memory holds, at `width` lanes.
    pub(super) fn reserved(&self, width: usize) -> usize {
        self.weight.len() / width
    }

    /// Store `joints` joints for every lane. Joints it did not store before start at rest
    /// in every lane: angles and rates 0, blend weight `rest` (1 before a batch's first
    /// step, when every joint is shown at rest; 0 after, so that a joint that comes back
    /// blends in). Their palettes are computed by the step that simulates them, and read
    /// only once simulated. Fewer joints than stored: those beyond are no longer stored
    /// (their memory is kept, see [`Block::trim`]).
    pub(super) fn store(&mut self, joints: usize, width: usize, rest: f32) {
        let had = self.joints;
        if joints > had {
            // Joints the memory still holds from before: reset to rest.
            let kept = joints.min(self.reserved(width));
            if kept > had {
                self.theta[2 * had * width..2 * kept * width].fill(0.0);
                self.rate[2 * had * width..2 * kept * width].fill(0.0);
                self.weight[had * width..kept * width].fill(rest);
            }
        }
        if joints > self.reserved(width) {
            // Exactly what is needed, so that the bytes held are the bytes counted; grown in
            // place where the allocator can (a large block is remapped, not copied).
            let grow = |v: &mut Vec<f32>, len: usize, value: f32| {
                v.reserve_exact(len - v.len());
                v.resize(len, value);
            };
            grow(&mut self.theta, 2 * joints * width, 0.0);
            grow(&mut self.rate, 2 * joints * width, 0.0);
            grow(&mut self.pal, 12 * joints * width, 0.0);
            grow(&mut self.weight, joints * width, rest);
        }
        self.joints = joints;
    }

    /// Count a step: memory held beyond the joints stored for [`TRIM_STEPS`] steps in a row
    /// is given back.
    pub(super) fn trim(&mut self, width: usize) {
        if self.reserved(width) <= self.joints {
            self.idle = 0;
            return;
        }
        self.idle += 1;
        if self.idle >= TRIM_STEPS {
            let j = self.joints;
            self.theta.truncate(2 * j * width);
            self.rate.truncate(2 * j * width);
            self.weight.truncate(j * width);
            self.pal.truncate(12 * j * width);
            for v in [&mut self.theta, &mut self.rate, &mut self.weight, &mut self.pal] {
                v.shrink_to_fit();
            }
            self.idle = 0;
        }
    }

    /// Bytes held.
    pub(super) fn bytes(&self) -> usize {
        4 * (self.theta.capacity()
            + self.rate.capacity()
            + self.weight.capacity()
            + self.pal.capacity()
            + self.rows.iter().map(Row::capacity).sum::<usize>())
    }
}

//! A fixed-substep clock for interactive hosts (the viewer, the web page): real time in,
//! whole simulation substeps out, so the sway always advances in the same step however fast
//! the frames come.

/// Simulation substep, s: the sway advances in steps of at most this.
pub const SUBSTEP: f32 = 1.0 / 60.0;
/// Most substeps per frame (0.2 s of simulated time). A frame slower than that (× the time
/// scale) leaves the simulation behind real time (a viewer shows "slow motion").
pub const MAX_SUBSTEPS: u32 = 12;

/// Fixed-substep clock: real time in, whole substeps out, never more than
/// [`MAX_SUBSTEPS`] a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clock {
    /// Simulated time owed and not yet stepped, s (less than one substep).
    carry: f32,
    /// Whether the last frame hit the cap (the simulation runs slower than real time).
    pub slow: bool,
}

impl Default for Clock {
    fn default() -> Self {
        Clock { carry: 0.0, slow: false }
    }
}

impl Clock {
    /// Substeps of [`SUBSTEP`] to run after `real_dt` seconds at `scale` simulated seconds
    /// per second. Time beyond the cap is dropped (and `slow` set), not carried over, so a
    /// slow frame never makes the next one slower.
    pub fn advance(&mut self, real_dt: f32, scale: f32) -> u32 {
        let owed = self.carry + (real_dt.max(0.0) * scale.max(0.0)).min(1e6);
        let whole = (owed / SUBSTEP).floor();
        if whole > MAX_SUBSTEPS as f32 {
            self.slow = true;
            self.carry = 0.0;
            MAX_SUBSTEPS
        } else {
            self.slow = false;
            self.carry = owed - whole * SUBSTEP;
            whole as u32
        }
    }
}

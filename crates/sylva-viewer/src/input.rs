//! Keys and mouse → viewer changes, from plain events (so tests can feed synthetic ones).
//!
//! | input | effect |
//! |---|---|
//! | left drag | orbit the camera |
//! | left click (no drag) | select the tree under the cursor (click on empty ground: none) |
//! | wheel | zoom |
//! | W A S D, Q E | move in the ground plane, down / up |
//! | ↑ ↓ | wind speed ×1.25 / ÷1.25 |
//! | ← → | turn the wind 15° left / right |
//! | Space | pause / run |
//! | . | one substep while paused |
//! | Tab | show / hide the panel |
//! | F1 | show / hide this help |
//! | F12 | screenshot (PNG) |
//! | O | colour overlay: off, geometry level, instance group |
//! | C | record a clip (PNG frames, GIF, MP4) / stop |
//! | R | record the camera / stop and write `camera-path.toml` |
//! | P | replay the camera path / stop |
//! | Esc | quit |

use std::collections::HashSet;

use winit::keyboard::KeyCode;

use super::state::{Action, Viewer};
use sylva_render::Overlay;

/// Help lines: key, what it does (the F1 overlay and the README).
pub const KEYS: [(&str, &str); 18] = [
    ("left drag", "orbit the camera"),
    ("left click", "select the tree under the cursor"),
    ("wheel", "zoom"),
    ("W A S D", "move in the ground plane"),
    ("Q E", "move down / up"),
    ("↑ ↓", "wind speed ×1.25 / ÷1.25"),
    ("← →", "turn the wind 15° left / right"),
    ("Space", "pause / run"),
    (".", "one substep while paused"),
    ("Tab", "show / hide the panel"),
    ("F1", "show / hide this help"),
    ("F12", "screenshot (PNG in the working folder)"),
    ("O", "colour overlay: off, geometry level, instance group"),
    ("C", "record a clip (PNG frames, GIF, MP4 in clip-…/) / stop"),
    ("R", "record the camera / stop and write camera-path.toml"),
    ("P", "replay the camera path (recorded, --camera-path, or the scene's)"),
    ("Esc", "quit"),
    ("panel", "wind, LOD, scene, figures, plots, the selected tree"),
];

/// One input event, as the window delivers it (only what the viewer reads).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input {
    /// A key pressed (or auto-repeated) or released.
    Key {
        /// Physical key.
        code: KeyCode,
        /// Pressed (true) or released.
        pressed: bool,
        /// An auto-repeat of a held key.
        repeat: bool,
    },
    /// Left button pressed (true) or released.
    Left(bool),
    /// Cursor moved to (x, y) pixels.
    Cursor(f64, f64),
    /// Wheel turned by this many lines (positive: away from the user, zoom in).
    Wheel(f32),
}

/// Pointer and held keys between events.
#[derive(Debug, Default)]
pub struct Controls {
    /// Keys held down.
    pub held: HashSet<KeyCode>,
    dragging: bool,
    dragged: f64,
    cursor: Option<(f64, f64)>,
}

/// Pixels the cursor may move between press and release and still count as a click.
const CLICK_SLOP: f64 = 4.0;

impl Controls {
    /// The cursor's last position, pixels from the window's top left (none before it moved).
    pub fn cursor(&self) -> Option<(f64, f64)> {
        self.cursor
    }

    /// Turn `input` into actions on `v` (a `width × height` pixel view).
    pub fn handle(&mut self, v: &mut Viewer, input: Input, width: f32, height: f32) {
        match input {
            Input::Key { code, pressed: false, .. } => {
                self.held.remove(&code);
            }
            Input::Key { code, pressed: true, repeat } => {
                self.held.insert(code);
                if let Some(a) = key_action(v, code, repeat) {
                    v.apply(a);
                }
            }
            Input::Left(true) => {
                self.dragging = true;
                self.dragged = 0.0;
            }
            Input::Left(false) => {
                if self.dragging
                    && self.dragged <= CLICK_SLOP
                    && let Some((x, y)) = self.cursor
                {
                    // The pixel as the unshifted camera sees it (the view is centred
                    // beside the panel: `Viewer::view_shift`).
                    let x = x as f32 - 0.5 * v.view_shift * width;
                    let (o, d) = v.orbit.ray(x, y as f32, width, height);
                    v.apply(Action::Select(v.forest.pick(o, d)));
                }
                self.dragging = false;
            }
            Input::Cursor(x, y) => {
                if let Some((px, py)) = self.cursor
                    && self.dragging
                {
                    self.dragged += (x - px).abs() + (y - py).abs();
                    if self.dragged > CLICK_SLOP {
                        v.orbit.drag((x - px) as f32, (y - py) as f32);
                    }
                }
                self.cursor = Some((x, y));
            }
            Input::Wheel(lines) => {
                v.orbit.zoom(lines);
            }
        }
    }

    /// Move the camera target for the keys held over `dt` seconds of real time.
    pub fn fly(&self, v: &mut Viewer, dt: f32) {
        let (mut forward, mut right, mut up) = (0.0, 0.0, 0.0);
        for k in &self.held {
            match k {
                KeyCode::KeyW => forward += 1.0,
                KeyCode::KeyS => forward -= 1.0,
                KeyCode::KeyA => right -= 1.0,
                KeyCode::KeyD => right += 1.0,
                KeyCode::KeyQ => up -= 1.0,
                KeyCode::KeyE => up += 1.0,
                _ => {}
            }
        }
        v.orbit.travel(forward, right, up, dt);
    }
}

/// Whether a key event goes to the panel before the viewer: only while the panel edits text
/// (`typing`: a text field has the keyboard focus), and never Tab, which shows and hides
/// the panel. Otherwise the panel's keyboard navigation would take the viewer's keys: Tab
/// would move the focus onto a checkbox and Space then tick it instead of pausing.
pub fn panel_takes_key(code: KeyCode, typing: bool) -> bool {
    typing && code != KeyCode::Tab
}

/// Whether a mouse button or wheel event goes to the panel rather than the 3-D view,
/// decided at the event from where the cursor is then: over the panel's strip (the left
/// `panel_px` pixels), or while the panel holds the pointer (a slider being dragged). egui's
/// own answer is the last frame's: at a few frames a second, a cursor moved off the panel
/// and clicked before the next frame would have its click taken by the panel and lost.
pub fn panel_takes_pointer(cursor_x: Option<f64>, panel_px: f32, panel_dragging: bool) -> bool {
    panel_dragging || cursor_x.is_some_and(|x| x < panel_px as f64)
}

/// The action of a key press.
fn key_action(v: &Viewer, code: KeyCode, repeat: bool) -> Option<Action> {
    let (gain, turn) = v.forest.wind_control();
    Some(match code {
        KeyCode::Escape => Action::Quit,
        KeyCode::ArrowUp => Action::WindGain(gain * 1.25),
        KeyCode::ArrowDown => Action::WindGain(gain / 1.25),
        KeyCode::ArrowLeft => Action::WindTurn(turn + 15.0),
        KeyCode::ArrowRight => Action::WindTurn(turn - 15.0),
        KeyCode::Space if !repeat => Action::Pause(!v.settings.paused),
        KeyCode::Period => Action::Step,
        KeyCode::Tab if !repeat => Action::Panel(!v.panel),
        KeyCode::F1 if !repeat => Action::Help(!v.help),
        KeyCode::F12 if !repeat => Action::Screenshot,
        KeyCode::KeyR if !repeat => Action::Record(v.recording.is_none()),
        KeyCode::KeyC if !repeat => Action::Clip(!v.clip),
        KeyCode::KeyO if !repeat => Action::Overlay(match v.overlay {
            Overlay::Off => Overlay::Level,
            Overlay::Level => Overlay::Group,
            Overlay::Group => Overlay::Off,
        }),
        KeyCode::KeyP if !repeat => Action::Replay(v.replaying.is_none()),
        _ => return None,
    })
}

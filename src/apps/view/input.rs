//! The viewer's input, in its own terms: the window layer turns winit's events into
//! these, and tests send them directly, so both go through the same handling
//! ([`super::viewer::Viewer::handle`]).

use crate::io::up::UpAxis;

/// Mouse buttons that drag.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Button {
    Left,
    Middle,
    Right,
}

/// Keys held down for continuous motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Move {
    Forward,
    Back,
    Left,
    Right,
    Up,
    Down,
    TurnLeft,
    TurnRight,
    TurnUp,
    TurnDown,
}

/// Keys that act once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// Frame the whole model from the current direction (F).
    Frame,
    /// Back to the starting view (R).
    Reset,
    /// Next display mode (M).
    NextMode,
    /// Next up axis: z, y, x, −z, −y, −x (U).
    NextUp,
    /// Stand the model on this axis (the panel's "Up").
    SetUp(UpAxis),
    /// ε_px × 2 (+).
    MoreError,
    /// ε_px ÷ 2 (−).
    LessError,
    /// EWA prefilter on/off (X).
    ToggleEwa,
    /// Freeze the level of detail at the current eye, or unfreeze it (L).
    ToggleFreeze,
    /// Show or hide the panel (Tab).
    TogglePanel,
    /// Save a screenshot (F12 or P).
    Screenshot,
    /// Open a model (Ctrl+O).
    Open,
}

/// One input event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input {
    /// The pointer moved by (dx, dy) pixels with `button` held; `shift` makes a left
    /// drag pan.
    Drag {
        button: Button,
        shift: bool,
        dx: f64,
        dy: f64,
    },
    /// Wheel notches (positive: toward the screen, zoom in) with the pointer at (x, y)
    /// pixels from the top left.
    Wheel {
        notches: f64,
        x: f64,
        y: f64,
    },
    /// A motion key pressed or released.
    Hold(Move, bool),
    Command(Command),
}

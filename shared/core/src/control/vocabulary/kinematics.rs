//! How an agent can move: in any direction at once, turning in place, or along curves
//! no tighter than a turning radius.

/// An agent's kinematic model.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Kinematics {
    /// It moves in any direction at once (the paper's agents): a move is any polyline.
    #[default]
    Holonomic,
    /// A differential-drive robot: it turns in place and drives along its heading. In one
    /// step its driving (at most the top speed) and its turning (at most `max_turn_rad`)
    /// share the step's time.
    Unicycle {
        /// The largest heading change in one step, radians.
        max_turn_rad: f64,
        /// Whether it may drive backwards.
        reverse: bool,
    },
    /// A car-like robot: it cannot turn in place; its path bends no tighter than
    /// `turning_radius_m` anywhere, driven at most the top speed per step.
    Car {
        /// The smallest radius its path may bend with, metres.
        turning_radius_m: f64,
        /// Whether it may drive backwards (Reeds-Shepp paths; Dubins without).
        reverse: bool,
    },
}

impl Kinematics {
    /// Whether an agent of this model has a heading that its moves must respect.
    ///
    /// ```
    /// use shared::control::vocabulary::Kinematics;
    /// assert!(!Kinematics::Holonomic.has_heading());
    /// assert!(Kinematics::Unicycle { max_turn_rad: 1.0, reverse: false }.has_heading());
    /// ```
    pub fn has_heading(&self) -> bool {
        !matches!(self, Self::Holonomic)
    }

    /// The model's name in a scenario file.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Holonomic => "holonomic",
            Self::Unicycle { .. } => "unicycle",
            Self::Car { .. } => "car",
        }
    }

    /// Whether it may drive backwards (a holonomic agent has no backwards).
    pub fn reverse(&self) -> bool {
        match self {
            Self::Holonomic => false,
            Self::Unicycle { reverse, .. } | Self::Car { reverse, .. } => *reverse,
        }
    }
}

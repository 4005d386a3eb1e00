//! Colours: the Okabe-Ito palette (Okabe and Ito 2008, "Color Universal Design"), which
//! stays distinguishable under the common forms of colour blindness, plus neutral greys.
//!
//! Every figure takes its colours from the roles below, so a reader who learns them on
//! one plot can read them on every other.

use plotters::style::RGBColor;

/// Okabe-Ito black.
pub const BLACK: RGBColor = RGBColor(0, 0, 0);
/// Okabe-Ito orange (the paper's "marigold" agents).
pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
/// Okabe-Ito sky blue.
pub const SKY_BLUE: RGBColor = RGBColor(86, 180, 233);
/// Okabe-Ito bluish green.
pub const BLUISH_GREEN: RGBColor = RGBColor(0, 158, 115);
/// Okabe-Ito yellow.
pub const YELLOW: RGBColor = RGBColor(240, 228, 66);
/// Okabe-Ito blue.
pub const BLUE: RGBColor = RGBColor(0, 114, 178);
/// Okabe-Ito vermillion.
pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
/// Okabe-Ito reddish purple.
pub const REDDISH_PURPLE: RGBColor = RGBColor(204, 121, 167);
/// Background.
pub const WHITE: RGBColor = RGBColor(255, 255, 255);
/// Obstacle bodies.
pub const OBSTACLE: RGBColor = RGBColor(96, 96, 96);
/// Obstacles' safety margin (obstacle radius plus agent radius), drawn translucent.
pub const SAFETY_MARGIN: RGBColor = RGBColor(150, 150, 150);
/// Grid lines and the field's border.
pub const GRID: RGBColor = RGBColor(225, 225, 225);
/// Secondary text.
pub const TEXT_MUTED: RGBColor = RGBColor(90, 90, 90);

/// The formation centre's Hybrid A* path and its heading arrows.
pub const CENTRE_PATH: RGBColor = BLUE;
/// The start pose.
pub const START: RGBColor = BLUISH_GREEN;
/// The goal pose.
pub const GOAL: RGBColor = VERMILLION;
/// Agents and their safety circles.
pub const AGENT: RGBColor = ORANGE;
/// Outline of an agent's safety circle.
pub const AGENT_EDGE: RGBColor = RGBColor(120, 80, 0);
/// Agents out of the formation (dead: frozen as obstacles).
pub const AGENT_DEAD: RGBColor = RGBColor(60, 60, 60);
/// Ideal formation slots.
pub const SLOT: RGBColor = BLUE;
/// An agent's path to its best point.
pub const MOVE: RGBColor = BLUISH_GREEN;
/// Individual agents' deviation curves.
pub const DEVIATION_AGENT: RGBColor = SKY_BLUE;
/// The formation's mean deviation.
pub const DEVIATION_MEAN: RGBColor = VERMILLION;
/// Agent-agent clearance.
pub const CLEARANCE_AGENTS: RGBColor = BLUE;
/// Agent-obstacle clearance.
pub const CLEARANCE_OBSTACLES: RGBColor = ORANGE;
/// The collision region below zero clearance.
pub const COLLISION: RGBColor = VERMILLION;
/// An agent's sensing radius (drawn faint, on request).
pub const SENSING: RGBColor = REDDISH_PURPLE;
/// Moving obstacles, their routes and where they stood (maps).
pub const MOVING_OBSTACLE: RGBColor = REDDISH_PURPLE;
/// Outline and hatching of obstacles the centre's planner did not know at the start.
pub const UNKNOWN_OBSTACLE: RGBColor = BLACK;
/// Faults marked on a time axis.
pub const FAULT: RGBColor = REDDISH_PURPLE;

/// Every colour the figures draw with (the GIF palette is built from these).
pub const INKS: [RGBColor; 10] = [
    BLACK,
    ORANGE,
    SKY_BLUE,
    BLUISH_GREEN,
    YELLOW,
    BLUE,
    VERMILLION,
    REDDISH_PURPLE,
    OBSTACLE,
    AGENT_EDGE,
];

//! Reeds-Shepp shortest paths: the shortest path between two poses for a car that turns no
//! tighter than a given radius and may drive both forwards and in reverse (Reeds & Shepp,
//! "Optimal paths for a car that goes both forwards and backwards", 1990).
//!
//! # Path words
//!
//! A path is a *word* of at most five segments. Each segment is either an arc of exactly the
//! minimum turning radius (`L` turns left, `R` turns right, `C` is either) or a straight line
//! (`S`), driven forwards (`+`) or in reverse (`-`); `|` marks a cusp, where the car changes
//! between forward and reverse. Reeds and Shepp proved that a shortest path is always one of
//! 48 words. Up to two symmetries they reduce to nine closed-form formulas (numbered as in
//! section 8 of the paper), grouped into five families:
//!
//! - **CSC** (8.1, 8.2): arc, straight, arc, all in the same direction, e.g. `L+ S+ L+`,
//!   `L+ S+ R+`. These are the Dubins words plus their all-reverse mirrors.
//! - **CCC** (8.3, 8.4): three arcs with one or two cusps, `C|C|C`, `C|CC` and `CC|C`.
//! - **CCCC** (8.7, 8.8): four arcs whose two middle arcs have the same length `u`,
//!   `C Cu|Cu C` and `C|Cu Cu|C`.
//! - **CCSC** (8.9, 8.10): `C|C(pi/2) S C` and its reverse `C S C(pi/2)|C`, where `C(pi/2)` is a
//!   quarter turn.
//! - **CCSCC** (8.11): `C|C(pi/2) S C(pi/2)|C`.
//!
//! Each formula solves for the base word (starting with `L+`) and is applied to the goal
//! under the two symmetries of the problem: *time-flip* (drive the word in reverse, which
//! negates every segment length) and *reflection* (mirror across the start heading, which
//! swaps `L` and `R`). The `CCC` and `CCSC` formulas are also applied *backwards* (the word
//! read from the goal to the start). That is 44 evaluations covering the 48 words.
//!
//! The solver follows OMPL's `ReedsSheppStateSpace` step by step (same formulas, same
//! acceptance tolerances, same evaluation order), so lengths agree with OMPL to rounding;
//! `tests/it/oracle_reeds_shepp.rs` checks this against OMPL 2.0.1. Two shortcuts make a
//! length 2.5 times cheaper (the Hybrid A* search computes one for every pose it reaches)
//! and change no result: the sine and cosine of the heading change are computed once, not
//! per formula; and a formula stops before its arc tangents when the part of its word
//! already known (the middle) reaches the family's bound (the best word so far less the
//! family's fixed arcs).
//!
//! Paths are [`CurvePath`]s (module [`crate::paths::curve`], shared with the Dubins solver); the
//! types are re-exported here, so `shared::paths::reeds_shepp::CurvePath` names the same type.
//!
//! # Files
//!
//! - `shortest_path.rs`: [`shortest_path()`] and [`shortest_length_m`], the entry points;
//! - `word.rs`: the candidate words and the search over the families and symmetries;
//! - `formulas.rs`: the nine closed-form formulas of section 8.

mod formulas;
mod shortest_path;
mod word;

pub use crate::paths::curve::{CurvePath, Segment, Steer};
pub use shortest_path::{shortest_length_m, shortest_path};

//! The search: A* over cells of (x, y, heading bin), expanding each cell's cheapest
//! continuous pose with the motion primitives, trying the analytic expansion on Smac's
//! schedule.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::TAU;

use super::analytic::analytic_expansion;
use super::collision::Checker;
use super::error::PlanError;
use super::heuristic::Holonomic;
use super::primitive::{Piece, Primitive, dense_path};
use super::resample::path_length_m;
use super::settings::HybridAStarSettings;
use crate::geometry::{Field, Pose};
use crate::ordered::TotalF64;
use crate::paths::dubins;
use crate::paths::reeds_shepp;
use rustc_hash::FxHashMap;

/// Figures of one successful search.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanStats {
    /// Nodes expanded.
    pub expansions: usize,
    /// Analytic expansions tried (the last one succeeded).
    pub analytic_attempts: usize,
    /// Length of the returned path (sum of the distances between its poses), in metres.
    pub length_m: f64,
}

const NO_PARENT: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Node {
    pose: Pose,
    g_m: f64,
    parent: u32,
    /// Index of the primitive that led here (unused for the start).
    primitive: u8,
    /// +1 forwards, -1 backwards, 0 for the start.
    direction: i8,
    closed: bool,
}

/// An entry of the open list: lowest `f` first, then highest `g` (deeper), then oldest.
/// `BinaryHeap` pops the greatest, so `f` and the node index are reversed; the fields
/// compare in this order.
///
/// A child enters with a provisional `f` from the obstacle-aware bound alone, a lower
/// bound of its full heuristic (which adds the Reeds-Shepp or Dubins length, the costly
/// part); the full one is computed only if the entry comes up, and the node is expanded
/// only from an entry with its full `f` that still comes first. Every expansion is
/// therefore the one an eager search would make: the same node, in the same order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Entry {
    f_m: Reverse<TotalF64>,
    g_m: TotalF64,
    node: Reverse<u32>,
    /// Whether `f_m` is provisional (the obstacle-aware bound only).
    provisional: bool,
}

impl Entry {
    fn new(f_m: f64, g_m: f64, node: u32) -> Self {
        Self {
            f_m: Reverse(TotalF64(f_m)),
            g_m: TotalF64(g_m),
            node: Reverse(node),
            provisional: false,
        }
    }

    fn provisional(f_m: f64, g_m: f64, node: u32) -> Self {
        Self {
            provisional: true,
            ..Self::new(f_m, g_m, node)
        }
    }
}

/// The search over cells of (x, y, heading bin), one continuous pose per cell.
pub(super) struct Search<'a> {
    checker: Checker,
    holonomic: &'a mut Holonomic,
    start: Pose,
    goal: Pose,
    settings: &'a HybridAStarSettings,
    primitives: Vec<Primitive>,
    rows: u64,
    nodes: Vec<Node>,
    cells: FxHashMap<u64, u32>,
    open: BinaryHeap<Entry>,
}

impl<'a> Search<'a> {
    pub(super) fn new(
        field: &Field,
        checker: Checker,
        holonomic: &'a mut Holonomic,
        start: &Pose,
        goal: &Pose,
        settings: &'a HybridAStarSettings,
    ) -> Self {
        let primitives = Primitive::set(settings);
        Self {
            checker,
            holonomic,
            start: *start,
            goal: *goal,
            settings,
            primitives,
            rows: (field.height_m / settings.cell_m).ceil() as u64 + 1,
            nodes: Vec::new(),
            cells: FxHashMap::default(),
            open: BinaryHeap::new(),
        }
    }

    fn cell_key(&self, pose: &Pose) -> u64 {
        let bins = self.settings.heading_bins;
        let bin_rad = TAU / bins as f64;
        let bin = ((pose.heading_rad.rem_euclid(TAU) / bin_rad + 0.5).floor() as usize) % bins;
        // Poses reaching here are inside the field, so the cell coordinates are >= 0.
        let ix = (pose.x_m / self.settings.cell_m).floor().max(0.0) as u64;
        let iy = (pose.y_m / self.settings.cell_m).floor().max(0.0) as u64;
        (ix * self.rows + iy) * bins as u64 + bin as u64
    }

    fn shortest_length_m(&self, from: &Pose) -> f64 {
        if self.settings.allow_reverse {
            reeds_shepp::shortest_length_m(from, &self.goal, self.settings.turning_radius_m)
        } else {
            dubins::shortest_length_m(from, &self.goal, self.settings.turning_radius_m)
        }
    }

    fn heuristic_m(&mut self, pose: &Pose) -> f64 {
        let holonomic_m = self.holonomic.lower_bound_m(&pose.position());
        if holonomic_m.is_infinite() {
            return holonomic_m;
        }
        self.shortest_length_m(pose).max(holonomic_m)
    }

    pub(super) fn run(mut self) -> Result<(Vec<Pose>, PlanStats), PlanError> {
        let start = self.start;
        let h_m = self.heuristic_m(&start);
        if h_m.is_infinite() {
            return Err(PlanError::NoPath);
        }
        self.nodes.push(Node {
            pose: self.start,
            g_m: 0.0,
            parent: NO_PARENT,
            primitive: 0,
            direction: 0,
            closed: false,
        });
        let start_key = self.cell_key(&self.start);
        self.cells.insert(start_key, 0);
        self.open.push(Entry::new(h_m, 0.0, 0));

        let cell_m = self.settings.cell_m;
        let ratio = self.settings.analytic_expansion_ratio;
        let mut closest_cells = f64::INFINITY;
        // The start's shot was tried in `plan_with_stats`.
        let mut countdown = i64::MAX;
        let mut expansions = 0usize;
        let mut analytic_attempts = 1usize;

        while let Some(mut entry) = self.open.pop() {
            let index = entry.node.0 as usize;
            let node = self.nodes[index];
            if node.closed || node.g_m != entry.g_m.0 {
                continue; // stale entry
            }
            if entry.provisional {
                entry = Entry::new(
                    node.g_m + self.heuristic_m(&node.pose),
                    node.g_m,
                    entry.node.0,
                );
                if self.open.peek().is_some_and(|next| *next > entry) {
                    self.open.push(entry); // another comes first now
                    continue;
                }
            }
            let (entry_f_m, entry_g_m) = (entry.f_m.0.0, entry.g_m.0);
            if expansions >= self.settings.max_expansions {
                return Err(PlanError::ExpansionLimit { expansions });
            }
            self.nodes[index].closed = true;
            expansions += 1;

            // Analytic expansion, more often as the search closes in (Smac's schedule).
            let h_m = entry_f_m - entry_g_m;
            closest_cells = closest_cells.min(h_m / cell_m);
            let desired = (closest_cells / ratio).floor().max(ratio.ceil()) as i64;
            countdown = countdown.min(desired);
            if countdown <= 0 {
                countdown = desired;
                analytic_attempts += 1;
                if let Some(tail) =
                    analytic_expansion(&mut self.checker, self.settings, &node.pose, &self.goal)
                {
                    let path = self.reconstruct(index, tail);
                    let length_m = path_length_m(&path);
                    return Ok((
                        path,
                        PlanStats {
                            expansions,
                            analytic_attempts,
                            length_m,
                        },
                    ));
                }
            }
            countdown -= 1;

            for p in 0..self.primitives.len() {
                let primitive = self.primitives[p];
                let piece = Piece {
                    start: node.pose,
                    curvature_per_m: primitive.curvature_per_m,
                    length_m: primitive.length_m,
                };
                let child = piece.end();
                if !self.checker.in_field(&child.position()) {
                    continue;
                }
                let direction: i8 = if primitive.length_m < 0.0 { -1 } else { 1 };
                let mut g_m = node.g_m + primitive.cost_m;
                if node.direction != 0 && node.direction != direction {
                    g_m += self.settings.direction_change_penalty_m;
                }
                let key = self.cell_key(&child);
                let existing = self.cells.get(&key).copied();
                if let Some(other) = existing {
                    let other = &self.nodes[other as usize];
                    if other.closed || other.g_m <= g_m {
                        continue;
                    }
                }
                if !self.checker.piece_free(&piece) {
                    continue;
                }
                let holonomic_m = self.holonomic.lower_bound_m(&child.position());
                if holonomic_m.is_infinite() {
                    continue;
                }
                let new_node = Node {
                    pose: child,
                    g_m,
                    parent: index as u32,
                    primitive: p as u8,
                    direction,
                    closed: false,
                };
                let slot = match existing {
                    Some(other) => {
                        self.nodes[other as usize] = new_node;
                        other
                    }
                    None => {
                        let slot = self.nodes.len() as u32;
                        self.nodes.push(new_node);
                        self.cells.insert(key, slot);
                        slot
                    }
                };
                self.open
                    .push(Entry::provisional(g_m + holonomic_m, g_m, slot));
            }
        }
        Err(PlanError::NoPath)
    }

    /// The dense path: the primitives from the start to node `last`, then `tail`.
    fn reconstruct(&self, last: usize, tail: Vec<Piece>) -> Vec<Pose> {
        let mut chain = Vec::new();
        let mut index = last;
        while self.nodes[index].parent != NO_PARENT {
            chain.push(index);
            index = self.nodes[index].parent as usize;
        }
        chain.reverse();
        let primitives = chain.iter().map(|&i| {
            let node = &self.nodes[i];
            let primitive = &self.primitives[node.primitive as usize];
            let piece = Piece {
                start: self.nodes[node.parent as usize].pose,
                curvature_per_m: primitive.curvature_per_m,
                length_m: primitive.length_m,
            };
            (piece, node.pose)
        });
        let tail = tail.into_iter().map(|p| (p, p.end()));
        dense_path(
            &self.start,
            &self.goal,
            primitives.chain(tail),
            self.settings.sample_spacing_m,
        )
    }
}

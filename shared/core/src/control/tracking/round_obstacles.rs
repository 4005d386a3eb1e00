//! Tracking a slot whose way ahead crosses an obstacle: the first move of the best track
//! round it, found on a lattice over the look-ahead.
//!
//! An agent that chases the free point nearest its slot slides round an obstacle the
//! slot passes through and may come out on the wrong side, far behind. Knowing where its
//! slot will be over the next steps, it can instead take the first move of the track of
//! least summed deviation over them that keeps out of the obstacles: round the side the
//! slot comes out of, early.

use std::cell::RefCell;

use rustc_hash::FxHashMap;

use crate::control::best_point::nearest_free_point;
use crate::geometry::{FreeSpace, Point};

use super::lattice::{Lattice, best_track_on_lattice};

/// The spacing of the lattice of the first move's end, in agent radii: the move the agent
/// takes, so fine.
pub const ROUND_FIRST_SPACING_RADII: f64 = 1.0 / 3.0;

/// The spacing of the lattice of the later moves' ends, in agent radii: they only tell
/// which way round is best.
pub const ROUND_SPACING_RADII: f64 = 1.0;

/// How far from its slot (or the slot's nearest free point), in agent radii, a point of
/// the search's lattice may lie.
pub const ROUND_WINDOW_RADII: f64 = 10.0;

/// The lattice an agent of radius `radius_m` searches round the obstacles
/// ([`first_move_round_obstacles`]), whatever its top speed. Measured on the paper,
/// dense, narrow and large scenarios capped at twice the centre's step (agents of radius
/// 0.25 and 0.3 m): a first lattice 0.2 m apart instead of 0.1 m left agents further from their slots
/// (mean deviation up to 1.3 times); a later one 0.25 m apart instead of 0.35 m took
/// twice the time and did no better; a window of 2 m instead of 3 m left narrow's agents
/// behind its walls. The first lattice's spacing does not grow with the top speed: with
/// a top speed of 1 m (large, agents of radius 0.3 m) a first lattice a sixth of the top
/// speed apart (0.17 m) instead of a third of the radius (0.1 m) left the mean deviation
/// 7 % to 50 % higher on six of seven fields, for 7 % to 20 % less time.
pub fn round_lattice_for(radius_m: f64) -> Lattice {
    Lattice {
        spacing_m: ROUND_SPACING_RADII * radius_m,
        first_spacing_m: ROUND_FIRST_SPACING_RADII * radius_m,
        window_m: ROUND_WINDOW_RADII * radius_m,
    }
}

/// The first move of the best track round the obstacles for an agent standing at `me`
/// with top speed `max_step_m`, its slot at `slots[j]` after `j + 1` moves: the end of
/// that move, or `None` when no track through the lattice exists.
///
/// - `now`: the free space of this turn's move (the mates standing where they are).
/// - `later`: the free space of the later moves (the static obstacles only: the mates
///   move on too). It must hold every point `now` holds.
/// - `firsts`: more candidates for the first move's end (such as where the agent's
///   usual move would take it).
///
/// The track is the least summed deviation from the slots among the tracks through
/// `lattice` ([`round_lattice_for`]), the slots themselves and their nearest free points
/// ([`best_track_on_lattice`]): every position free, every move a free straight segment
/// within the top speed. So the move returned is free in `now` and within the top speed.
///
/// ```
/// use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};
/// use shared::control::tracking::{first_move_round_obstacles, round_lattice_for};
/// // The slot runs along y = 5 through a disk of radius 1 at (5, 5); the agent (0.5 m a
/// // step) stands at the disk's edge, (3.9, 5): it sets off round the disk at once.
/// let obstacles = DiskGrid::new(vec![Disk { centre: Point::new(5.0, 5.0), radius_m: 1.0 }]);
/// let layers = [&obstacles];
/// let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
/// let slots: Vec<Point> = (1..=8).map(|j| Point::new(3.9 + 0.4 * j as f64, 5.0)).collect();
/// let me = Point::new(3.9, 5.0);
/// let lattice = round_lattice_for(0.3);
/// let first = first_move_round_obstacles(&space, &space, &me, &slots, &[], 0.5, lattice)
///     .expect("a move");
/// assert!((first - me).norm() <= 0.5 + 1e-9);
/// assert!(space.is_segment_free(&me, &first, 0.0));
/// assert!((first.y - 5.0).abs() > 0.1, "it leaves the slot's line: {first}");
/// ```
pub fn first_move_round_obstacles(
    now: &FreeSpace<'_>,
    later: &FreeSpace<'_>,
    me: &Point,
    slots: &[Point],
    firsts: &[Point],
    max_step_m: f64,
    lattice: Lattice,
) -> Option<Point> {
    let later = LaterSpaces::Shared(later);
    let track = track_round_obstacles(now, later, me, slots, firsts, max_step_m, lattice)?;
    track.first().copied()
}

/// The free spaces of a search's later moves ([`track_round_obstacles`]).
#[derive(Clone, Copy, Debug)]
pub enum LaterSpaces<'a, 's> {
    /// One free space for every later move (the static obstacles only: the mates move
    /// on too).
    Shared(&'a FreeSpace<'s>),
    /// A free space of its own for each later move: `[k - 1]` for the move to
    /// `slots[k]` (bodies that stand only for some moves, such as a mate's predicted
    /// way). Each must hold every point the next one holds at the same place (a node's
    /// clearance serves the move out of it too): a body of move `k + 1` belongs to move
    /// `k`'s space as well.
    PerMove(&'a [FreeSpace<'s>]),
}

/// The best track round the obstacles, as [`first_move_round_obstacles`] searches it,
/// with the later moves' free spaces `later`. Returns the whole track (its first point
/// the first move's end), or `None` when no track through the lattice exists or `later`
/// holds fewer spaces than later moves.
pub fn track_round_obstacles(
    now: &FreeSpace<'_>,
    later: LaterSpaces<'_, '_>,
    me: &Point,
    slots: &[Point],
    firsts: &[Point],
    max_step_m: f64,
    lattice: Lattice,
) -> Option<Vec<Point>> {
    let enough = match later {
        LaterSpaces::Shared(_) => true,
        LaterSpaces::PerMove(spaces) => spaces.len() + 1 >= slots.len(),
    };
    if !(max_step_m.is_finite() && max_step_m > 0.0 && enough) {
        return None;
    }
    let space = |k: usize| match (k, later) {
        (0, _) => now,
        (_, LaterSpaces::Shared(shared)) => shared,
        (_, LaterSpaces::PerMove(spaces)) => &spaces[k - 1],
    };
    let clearance_in = |space: &FreeSpace<'_>, p: &Point| {
        space
            .is_free(p, 0.0)
            .then(|| space.clearance_m(p, max_step_m).max(0.0))
    };
    // A shared later space is asked about each point once: the lattices of consecutive
    // steps overlap. (A cheap hash: the default one, built against hostile keys, took
    // about 5 % of a capped run; these keys are the search's own points.)
    let shared_clearances: RefCell<FxHashMap<(u64, u64), Option<f64>>> = RefCell::default();
    let clearance_m = |k: usize, p: &Point| match (k, later) {
        (1.., LaterSpaces::Shared(shared)) => *shared_clearances
            .borrow_mut()
            .entry((p.x.to_bits(), p.y.to_bits()))
            .or_insert_with(|| clearance_in(shared, p)),
        _ => clearance_in(space(k), p),
    };
    let segment_free = |k: usize, a: &Point, b: &Point| space(k).is_segment_free(a, b, 0.0);
    // The slots and their nearest free points are candidates too: the lattice alone
    // would round every position by up to half its spacing.
    let anchors = anchors_of(space, slots, firsts);
    best_track_on_lattice(
        me,
        slots,
        &anchors,
        max_step_m,
        lattice,
        clearance_m,
        segment_free,
    )
    .map(|(_, track)| track)
}

/// The extra candidates of each step of the search: the slot `slots[k]` and its nearest
/// free point in `space(k)`, and `firsts` for the first move.
fn anchors_of<'s>(
    space: impl Fn(usize) -> &'s FreeSpace<'s>,
    slots: &[Point],
    firsts: &[Point],
) -> Vec<Vec<Point>> {
    slots
        .iter()
        .enumerate()
        .map(|(k, s)| {
            std::iter::once(*s)
                .chain(nearest_free_point(space(k), s).ok())
                .chain(firsts.iter().copied().filter(|_| k == 0))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Disk, DiskGrid, Field};

    /// On random fields, with mates that stand only for the first move: the first move,
    /// when there is one, is a free straight segment of `now` within the top speed.
    #[test]
    fn the_first_move_is_free_and_within_the_top_speed() {
        let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let field = Field::new(12.0, 12.0);
        let mut moved = 0;
        for _ in 0..150 {
            let disk = |next: &mut dyn FnMut() -> f64, r: f64| Disk {
                centre: Point::new(1.0 + 10.0 * next(), 1.0 + 10.0 * next()),
                radius_m: r,
            };
            let statics = DiskGrid::new(
                (0..6)
                    .map(|_| {
                        let r = 0.6 + next();
                        disk(&mut next, r)
                    })
                    .collect(),
            );
            let mates = DiskGrid::new((0..4).map(|_| disk(&mut next, 0.55)).collect());
            let (now_layers, later_layers) = ([&statics, &mates], [&statics]);
            let now = FreeSpace::new(field, &now_layers);
            let later = FreeSpace::new(field, &later_layers);
            let me = Point::new(1.0 + 10.0 * next(), 1.0 + 10.0 * next());
            if !now.is_free(&me, 0.0) {
                continue;
            }
            let (heading, speed) = (std::f64::consts::TAU * next(), 0.2 + 0.5 * next());
            let slots: Vec<Point> = (1..=10)
                .map(|j| {
                    me + nalgebra::Vector2::new(heading.cos(), heading.sin()) * speed * j as f64
                })
                .collect();
            let Some(first) = first_move_round_obstacles(
                &now,
                &later,
                &me,
                &slots,
                &[],
                0.5,
                round_lattice_for(0.3),
            ) else {
                continue;
            };
            assert!((first - me).norm() <= 0.5 + 1e-9, "{me} -> {first}");
            assert!(now.is_segment_free(&me, &first, 0.0), "{me} -> {first}");
            moved += usize::from(first != me);
        }
        assert!(moved > 50, "only {moved} moves");
    }
}

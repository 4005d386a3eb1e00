//! A lower bound that knows the way round: the cone programme lets an agent stand inside
//! an obstacle (only its deviation has a floor there), so where a slot's track crosses a
//! wall the bound is loose. This one keeps every position out of the obstacles, at the
//! price of a grid: dynamic programming over square cells, each step from a cell to one
//! that some point of it can reach within the top speed, each cell counted at the least
//! deviation any point of it can have.
//!
//! Every relaxation makes it smaller, never larger, so it is a lower bound for any track
//! whose positions are free and whose steps are at most the top speed:
//! - a cell is kept if a free point may lie in it (the caller's test is conservative:
//!   `least_deviation_on_grid`'s `may_be_free`), so a track's cells are all kept;
//! - a step is allowed between two cells if the nearest points of the two squares lie
//!   within the top speed, so a track's steps are all allowed;
//! - a cell costs the distance from the slot to its nearest point (and at least the
//!   step's floor), no more than any point of it;
//! - every position outside the window of cells round the slot counts as one place,
//!   "out", costing the window's half-width, reached from every cell and reaching every
//!   cell within a step of the window's edge.
//!
//! A step across a thin obstacle between two free cells is still allowed (a segment's
//! freedom is not asked), so it is a bound, not the optimum.

use shared::geometry::Point;

/// The grid of `least_deviation_on_grid`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// The side of a cell, in metres.
    pub cell_m: f64,
    /// The half-width of the square window of cells round each step's slot, in metres;
    /// farther positions cost at least this much.
    pub window_m: f64,
}

impl Grid {
    /// The grid for an agent with top speed `max_step_m`: cells a tenth of it, a window of
    /// ten top-speed steps, at most 5 m (a hundred cells each way at most, whatever the
    /// scale). Out is one place, so a track could leave the window and come back anywhere
    /// near its edge, on the far side of a wall too; with 5 m that costs more than 9 m of
    /// deviation in two steps, more than any agent alone strays in the capped scenarios
    /// measured (2.6 m at most, for ten steps).
    pub fn for_speed(max_step_m: f64) -> Self {
        Self {
            cell_m: max_step_m / 10.0,
            window_m: (10.0 * max_step_m).min(5.0),
        }
    }
}

/// A lower bound of the summed deviation (metres) over every track that starts at
/// `start` (anywhere if `None`), moves at most `max_step_m` a step, and stands at step
/// `k + 1` where `may_be_free` allows, its slot there being `slots[k]` and its deviation
/// at least `floors_m[k]` (none where the slice ends).
///
/// - `grid`: the cells and the window ([`Grid::for_speed`]).
/// - `may_be_free(centre, radius_m)`: whether a free position may lie within `radius_m`
///   of `centre`; it must say `true` whenever one does (saying `true` when unsure only
///   loosens the bound). `FreeSpace::is_free(centre, radius_m)` is such a test: a free
///   point within the radius is clear of every obstacle there by at least minus it.
///
/// `f64::INFINITY` when no track can follow (every cell in reach is blocked and the slots
/// stay near).
pub fn least_deviation_on_grid(
    start: Option<&Point>,
    slots: &[Point],
    floors_m: &[f64],
    max_step_m: f64,
    grid: Grid,
    mut may_be_free: impl FnMut(&Point, f64) -> bool,
) -> f64 {
    let h = grid.cell_m;
    if slots.is_empty() || !(h > 0.0 && max_step_m > 0.0) {
        return 0.0;
    }
    let half = (grid.window_m / h).ceil().max(1.0) as i64;
    let side = (2 * half + 1) as usize;
    let cell_of = |p: &Point| ((p.x / h).floor() as i64, (p.y / h).floor() as i64);
    let reach = Reach::new(max_step_m / h);
    let mut free_cells = FreeCells::new(h);
    let mut scratch = (Vec::new(), Vec::new());

    // Step 0: the start's cell, nothing else (out is unreachable yet); or anywhere.
    let (mut centre, mut before, mut before_out) = match start {
        Some(start) => {
            let mut before = vec![f64::INFINITY; side * side];
            before[half as usize * side + half as usize] = 0.0;
            (cell_of(start), before, f64::INFINITY)
        }
        None => (cell_of(&slots[0]), vec![0.0; side * side], 0.0),
    };
    let mut filtered = vec![vec![f64::INFINITY; side * side]; reach.widths.len()];
    let mut now = vec![f64::INFINITY; side * side];
    for (k, slot) in slots.iter().enumerate() {
        let floor_m = floor_at(floors_m, k);
        // Each row of the last step, its least value within each width.
        for (w, rows) in reach.widths.iter().zip(filtered.iter_mut()) {
            for (row_in, row_out) in before.chunks(side).zip(rows.chunks_mut(side)) {
                sliding_min(row_in, *w, row_out, &mut scratch);
            }
        }
        let least_before = before.iter().copied().fold(before_out, f64::min);
        let next = cell_of(slot);
        let (shift_i, shift_j) = (next.0 - centre.0, next.1 - centre.1);
        for j in 0..side {
            for i in 0..side {
                let cell = (next.0 - half + i as i64, next.1 - half + j as i64);
                let free = free_cells.is_free(cell, &mut may_be_free);
                // Within a step of the last window's edge (or beyond): out reaches it.
                let (bi, bj) = (i as i64 + shift_i, j as i64 + shift_j);
                let edge = bi.min(bj).min(side as i64 - 1 - bi.max(bj));
                now[j * side + i] = if free {
                    let mut best = if edge <= reach.rows {
                        before_out
                    } else {
                        f64::INFINITY
                    };
                    for (dj, width) in reach.rows() {
                        let bj = bj + dj;
                        if (0..side as i64).contains(&bi) && (0..side as i64).contains(&bj) {
                            best = best.min(filtered[width][bj as usize * side + bi as usize]);
                        }
                    }
                    distance_to_cell_m(slot, cell, h).max(floor_m) + best
                } else {
                    f64::INFINITY
                };
            }
        }
        before_out = (half as f64 * h).max(floor_m) + least_before;
        std::mem::swap(&mut before, &mut now);
        centre = next;
    }
    before.iter().copied().fold(before_out, f64::min)
}

/// `least_deviation_on_grid` where it matters: over each stretch of steps whose slots
/// lie where the agent does not fit (a floor above 0), from `grid.window_m` of the slot's
/// way before the stretch (free to start anywhere there: standing on the far side of an
/// obstacle that early costs more than the window) to twice that after it (the catching
/// up); every other step counts its floor. Each part bounds its steps' deviation from
/// below, so their sum bounds the whole; the arguments are `least_deviation_on_grid`'s,
/// `start` being where the agent is at step 0.
pub fn least_deviation_round_obstacles(
    start: &Point,
    slots: &[Point],
    floors_m: &[f64],
    max_step_m: f64,
    grid: Grid,
    mut may_be_free: impl FnMut(&Point, f64) -> bool,
) -> f64 {
    let floor = |k: usize| floor_at(floors_m, k);
    // The slot's way from step 0 to each step.
    let way_m: Vec<f64> = std::iter::once(start)
        .chain(slots)
        .collect::<Vec<_>>()
        .windows(2)
        .scan(0.0, |way_m, pair| {
            *way_m += (pair[1] - pair[0]).norm();
            Some(*way_m)
        })
        .collect();
    let mut stretches: Vec<(usize, usize)> = Vec::new();
    for k in (0..slots.len()).filter(|k| floor(*k) > 0.0) {
        let first = way_m[..k]
            .iter()
            .rposition(|w| way_m[k] - w >= grid.window_m)
            .map_or(0, |before| before + 1);
        let last = (k..slots.len())
            .find(|j| way_m[*j] - way_m[k] >= 2.0 * grid.window_m)
            .unwrap_or(slots.len() - 1);
        match stretches.last_mut() {
            Some(stretch) if first <= stretch.1 + 1 => stretch.1 = stretch.1.max(last),
            _ => stretches.push((first, last)),
        }
    }
    let mut sum_m = 0.0;
    let mut next = 0;
    for (first, last) in stretches {
        sum_m += (next..first).map(floor).sum::<f64>();
        sum_m += least_deviation_on_grid(
            (first == 0).then_some(start),
            &slots[first..=last],
            &floors_m[first.min(floors_m.len())..],
            max_step_m,
            grid,
            &mut may_be_free,
        );
        next = last + 1;
    }
    sum_m + (next..slots.len()).map(floor).sum::<f64>()
}

/// The floor of step `k` (none, 0, where the slice ends).
fn floor_at(floors_m: &[f64], k: usize) -> f64 {
    floors_m.get(k).copied().unwrap_or(0.0).max(0.0)
}

/// Which cells a step reaches, in cells: for each row offset `dj`, the column offsets
/// `-w ..= w` whose squares come within the top speed of the centre cell's square.
struct Reach {
    /// The distinct widths `w`.
    widths: Vec<usize>,
    /// Per row offset `dj` (from `-rows` to `rows`), the index of its width.
    width_of_row: Vec<usize>,
    rows: i64,
}

impl Reach {
    /// The reach of a step of `cells` cells.
    fn new(cells: f64) -> Self {
        // The squares' nearest points are `max(|d| - 1, 0)` cells apart on each axis; a
        // hair of slack keeps a step exactly at the top speed in.
        let limit = cells + 1e-9;
        let rows = 1 + limit.floor() as i64;
        let mut widths = Vec::new();
        let width_of_row = (-rows..=rows)
            .map(|dj| {
                let gap = (dj.abs() - 1).max(0) as f64;
                let w = 1 + (limit * limit - gap * gap).max(0.0).sqrt().floor() as usize;
                match widths.iter().position(|x| *x == w) {
                    Some(index) => index,
                    None => {
                        widths.push(w);
                        widths.len() - 1
                    }
                }
            })
            .collect();
        Self {
            widths,
            width_of_row,
            rows,
        }
    }

    /// Each row offset with the index of its width.
    fn rows(&self) -> impl Iterator<Item = (i64, usize)> + '_ {
        (-self.rows..=self.rows).zip(self.width_of_row.iter().copied())
    }
}

/// Which cells may hold a free point, asked once each: tiles of 64 x 64 cells, made as
/// the windows reach them (memory follows the ground the windows cover, not the box
/// round the whole track).
struct FreeCells {
    /// Per tile, per cell: 0 not asked yet, 1 may be free, 2 blocked.
    tiles: std::collections::HashMap<(i64, i64), Vec<u8>>,
    /// The tile asked last, and a copy of its key (most cells of a row share one).
    last: Option<((i64, i64), Vec<u8>)>,
    cell_m: f64,
}

/// Cells along a tile's side.
const TILE: i64 = 64;

impl FreeCells {
    /// No cell asked yet, cells of `cell_m`.
    fn new(cell_m: f64) -> Self {
        Self {
            tiles: std::collections::HashMap::new(),
            last: None,
            cell_m,
        }
    }

    /// Whether `cell` may hold a free point, asking `may_be_free` the first time.
    fn is_free(
        &mut self,
        cell: (i64, i64),
        may_be_free: &mut impl FnMut(&Point, f64) -> bool,
    ) -> bool {
        let key = (cell.0.div_euclid(TILE), cell.1.div_euclid(TILE));
        let index = (cell.1.rem_euclid(TILE) * TILE + cell.0.rem_euclid(TILE)) as usize;
        if self.last.as_ref().is_none_or(|(k, _)| *k != key) {
            if let Some((k, tile)) = self.last.take() {
                self.tiles.insert(k, tile);
            }
            let tile = self
                .tiles
                .remove(&key)
                .unwrap_or_else(|| vec![0; (TILE * TILE) as usize]);
            self.last = Some((key, tile));
        }
        let Some((_, tile)) = self.last.as_mut() else {
            return true;
        };
        if tile[index] == 0 {
            let h = self.cell_m;
            let centre = Point::new((cell.0 as f64 + 0.5) * h, (cell.1 as f64 + 0.5) * h);
            let free = may_be_free(&centre, h * std::f64::consts::FRAC_1_SQRT_2);
            tile[index] = if free { 1 } else { 2 };
        }
        tile[index] == 1
    }
}

/// `out[i]`: the least of `row[i - w ..= i + w]` (those in the row): two passes of
/// blocks of `2w + 1` (van Herk, Gil and Werman), three comparisons a cell whatever `w`;
/// `scratch` holds the passes.
fn sliding_min(row: &[f64], w: usize, out: &mut [f64], scratch: &mut (Vec<f64>, Vec<f64>)) {
    let n = row.len();
    let block = 2 * w + 1;
    let (prefix, suffix) = scratch;
    prefix.clear();
    prefix.extend_from_slice(row);
    suffix.clear();
    suffix.extend_from_slice(row);
    for i in 1..n {
        if i % block != 0 {
            prefix[i] = prefix[i].min(prefix[i - 1]);
        }
    }
    for i in (0..n.saturating_sub(1)).rev() {
        if (i + 1) % block != 0 {
            suffix[i] = suffix[i].min(suffix[i + 1]);
        }
    }
    for (i, o) in out.iter_mut().enumerate() {
        let lo = i.saturating_sub(w);
        let hi = (i + w).min(n - 1);
        // [lo, hi] spans at most two blocks: the end of lo's and the start of hi's. In one
        // block, it starts the block (a whole window, or cut by the row's start) or ends
        // the row.
        *o = if lo / block != hi / block {
            suffix[lo].min(prefix[hi])
        } else if lo % block == 0 {
            prefix[hi]
        } else {
            suffix[lo]
        };
    }
}

/// The distance from `p` to the nearest point of square `cell` of side `h`.
fn distance_to_cell_m(p: &Point, cell: (i64, i64), h: f64) -> f64 {
    let gap = |x: f64, index: i64| {
        let (lo, hi) = (index as f64 * h, (index + 1) as f64 * h);
        (lo - x).max(x - hi).max(0.0)
    };
    let (dx, dy) = (gap(p.x, cell.0), gap(p.y, cell.1));
    (dx * dx + dy * dy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sliding minimum agrees with the plain one on every width and length.
    #[test]
    fn the_sliding_minimum_is_the_plain_one() {
        let row: Vec<f64> = (0..23).map(|i| ((i * 7919) % 31) as f64).collect();
        for n in [1, 2, 5, 23] {
            for w in 0..6 {
                let mut out = vec![0.0; n];
                sliding_min(&row[..n], w, &mut out, &mut (Vec::new(), Vec::new()));
                for (i, o) in out.iter().enumerate() {
                    let plain = row[i.saturating_sub(w)..=(i + w).min(n - 1)]
                        .iter()
                        .copied()
                        .fold(f64::INFINITY, f64::min);
                    assert_eq!(*o, plain, "n {n} w {w} i {i}");
                }
            }
        }
    }

    /// The table of free cells answers as the test it asks, once a cell, across tiles
    /// and on both sides of zero.
    #[test]
    fn each_cell_is_asked_once() {
        let mut cells = FreeCells::new(0.1);
        let mut asked = std::collections::HashSet::new();
        let mut test = |p: &Point, r: f64| {
            assert!((r - 0.1 * std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
            assert!(asked.insert(((p.x * 20.0).round() as i64, (p.y * 20.0).round() as i64)));
            (p.x + p.y).sin() > 0.0
        };
        for _ in 0..2 {
            for j in -70..70 {
                for i in (-130..130).step_by(3) {
                    let centre = Point::new((i as f64 + 0.5) * 0.1, (j as f64 + 0.5) * 0.1);
                    let want = (centre.x + centre.y).sin() > 0.0;
                    assert_eq!(cells.is_free((i, j), &mut test), want, "({i}, {j})");
                }
            }
        }
    }

    /// A step's reach holds every cell with a point within the top speed, and no other.
    #[test]
    fn a_step_reaches_the_cells_within_the_top_speed() {
        let h = 0.1;
        for cells in [0.5, 1.0, 3.0, 4.5, 10.0] {
            let reach = Reach::new(cells);
            let reached = |di: i64, dj: i64| {
                reach
                    .rows()
                    .any(|(r, w)| r == dj && di.unsigned_abs() as usize <= reach.widths[w])
            };
            for dj in -15i64..=15 {
                for di in -15i64..=15 {
                    // From the centre cell's nearest corner to the other square.
                    let near = |d: i64| (d.abs() - 1).max(0) as f64 * h;
                    let within = near(di).hypot(near(dj)) <= cells * h + 1e-12;
                    assert_eq!(reached(di, dj), within, "cells {cells} at ({di}, {dj})");
                }
            }
        }
    }

    /// In the open, a slot that moves no faster than the agent costs nothing (to a cell).
    #[test]
    fn a_followable_slot_costs_nothing() {
        let slots: Vec<Point> = (1..=40).map(|k| Point::new(0.2 * k as f64, 1.0)).collect();
        let start = Point::new(0.0, 1.0);
        let got = least_deviation_on_grid(
            Some(&start),
            &slots,
            &[],
            0.5,
            Grid::for_speed(0.5),
            |_, _| true,
        );
        assert_eq!(got, 0.0);
    }

    /// A wall across the slot's way: a band `x` in [2, 3] m, 100 m long. The slot walks
    /// through it at 0.2 m a step and on, to 1.6 m past its near side (so going out of
    /// the window never pays); the agent (top speed 0.5 m) cannot cross, so
    /// once the slot is past the wall's near side its deviation is at least the slot's
    /// distance from that side: the bound must say so, less a cell's diagonal a step.
    /// (The cone programme's floors only count the distance to the far side.)
    #[test]
    fn a_wall_across_the_way_is_counted() {
        let slots: Vec<Point> = (1..=18).map(|k| Point::new(0.2 * k as f64, 0.0)).collect();
        let grid = Grid::for_speed(0.5);
        // A free point within `r` of `p` unless `p` lies deeper than `r` in the band.
        let may_be_free =
            |p: &Point, r: f64| !(p.x > 2.0 + r && p.x < 3.0 - r && p.y.abs() < 50.0 - r);
        let floors: Vec<f64> = slots
            .iter()
            .map(|s| {
                if s.x > 2.0 && s.x < 3.0 {
                    (s.x - 2.0).min(3.0 - s.x)
                } else {
                    0.0
                }
            })
            .collect();
        let got = least_deviation_on_grid(
            Some(&Point::origin()),
            &slots,
            &floors,
            0.5,
            grid,
            may_be_free,
        );
        let slack = grid.cell_m * std::f64::consts::SQRT_2;
        let least: f64 = slots.iter().map(|s| (s.x - 2.0 - slack).max(0.0)).sum();
        let floors_sum: f64 = floors.iter().sum();
        assert!(got >= least, "{got} against at least {least}");
        assert!(
            got > 3.0 * floors_sum,
            "{got} against the floors' {floors_sum}"
        );
        // And no more than standing at the near side does.
        let standing: f64 = slots.iter().map(|s| (s.x - 2.0).max(0.0)).sum();
        assert!(got <= standing + 1e-9, "{got} against {standing}");
    }

    /// On random fields of disks across a straight slot track, the bound is never above a
    /// track the lattice search finds (an achievable one: every position free, every
    /// step a free segment within the top speed), never below the floors, and above them
    /// by more than a metre over the fields (going round costs more than the floors say).
    #[test]
    fn the_bound_is_below_every_track_found() {
        use rand::{Rng, SeedableRng};
        use shared::control::tracking::{Lattice, best_track_on_lattice};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(29);
        let max_step_m = 0.5;
        let (mut counted, mut round_m) = (0, 0.0);
        for _ in 0..12 {
            let disks: Vec<(Point, f64)> = (0..4)
                .map(|_| {
                    let centre =
                        Point::new(rng.random_range(2.0..8.0), rng.random_range(-1.0..1.0));
                    (centre, rng.random_range(0.3..1.0))
                })
                .collect();
            let depth_m = |p: &Point| {
                disks
                    .iter()
                    .map(|(c, r)| r - (p - c).norm())
                    .fold(f64::NEG_INFINITY, f64::max)
            };
            let slots: Vec<Point> = (1..=40).map(|k| Point::new(0.25 * k as f64, 0.0)).collect();
            if depth_m(&Point::origin()) > 0.0 {
                continue;
            }
            // Distance to free space: at least the depth in the deepest disk.
            let floors: Vec<f64> = slots.iter().map(|s| depth_m(s).max(0.0)).collect();
            let clearance_m = |_: usize, p: &Point| (depth_m(p) <= 0.0).then_some(0.0);
            let segment_free = |_: usize, a: &Point, b: &Point| {
                (0..=20).all(|i| depth_m(&(a + (b - a) * (i as f64 / 20.0))) <= 0.0)
            };
            let anchors = vec![Vec::new(); slots.len()];
            let lattice = Lattice {
                spacing_m: 0.1,
                first_spacing_m: 0.1,
                window_m: 3.0,
            };
            let Some((found_m, _)) = best_track_on_lattice(
                &Point::origin(),
                &slots,
                &anchors,
                max_step_m,
                lattice,
                clearance_m,
                segment_free,
            ) else {
                continue;
            };
            let bound_m = least_deviation_round_obstacles(
                &Point::origin(),
                &slots,
                &floors,
                max_step_m,
                Grid::for_speed(max_step_m),
                |p, r| depth_m(p) <= r,
            );
            let floors_m: f64 = floors.iter().sum();
            assert!(
                bound_m <= found_m + 1e-9,
                "{bound_m} above a track of {found_m}"
            );
            assert!(
                bound_m >= floors_m - 1e-9,
                "{bound_m} below the floors {floors_m}"
            );
            counted += 1;
            round_m += bound_m - floors_m;
        }
        assert!(counted >= 8, "only {counted} fields had a track");
        // And it knows the way round: over the fields it is well above the floors.
        assert!(round_m > 1.0, "the way round adds only {round_m} m");
    }
}

//! The best track through the obstacles that a search over a lattice finds: every
//! position free, every step a free straight segment within the top speed, the summed
//! deviation from the slots least among the tracks through the lattice's points, by
//! dynamic programming over the steps.
//!
//! An agent with a look-ahead takes the first move of such a track when its slot's way
//! ahead crosses an obstacle ([`super::first_move_round_obstacles`]); `coordinator bound
//! --alone` searches a whole run's track with it (an achievable track, so its deviation
//! bounds the least deviation of an agent alone from above).

use crate::geometry::{Point, Vector};

/// How much longer than the top speed a step between two lattice points may come out
/// from rounding their coordinates (`i * spacing`), in metres.
const STEP_ROUNDING_M: f64 = 1e-9;

/// How the search lays its lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Distance between neighbouring lattice points, in metres.
    pub spacing_m: f64,
    /// The same for the first move's end, in metres (finer, where it matters most: the
    /// first move is the one an agent takes).
    pub first_spacing_m: f64,
    /// How far from its slot the agent may be at a step, in metres: the lattice points
    /// of a step are those within this distance of the slot or of one of the step's
    /// anchors.
    pub window_m: f64,
}

/// A candidate position at one step: where, how far it is from every obstacle (capped),
/// its lattice cell (none for an anchor), the least summed deviation of a track reaching
/// it, and the candidate of the step before that track comes from.
#[derive(Clone, Copy, Debug)]
struct Node {
    at: Point,
    clearance_m: f64,
    cell: Option<(i64, i64)>,
    cost_m: f64,
    from: usize,
}

/// Which node of a step lies on each lattice cell, and its cost: a dense table over the
/// cells' bounding box (a step's cells fill the disk of its window, so little of it is
/// empty). The costs sit apart from the nodes, so that the search's scan of a
/// neighbourhood reads one small array.
struct CellIndex {
    first: (i64, i64),
    columns: i64,
    rows: i64,
    node: Vec<Option<usize>>,
    /// The cost of the node on each cell (infinite where none).
    cost_m: Vec<f64>,
}

impl CellIndex {
    /// The index of `nodes`' cells.
    fn of(nodes: &[Node]) -> Self {
        let cells = || nodes.iter().filter_map(|n| n.cell);
        let (Some(lo_i), Some(hi_i), Some(lo_j), Some(hi_j)) = (
            cells().map(|c| c.0).min(),
            cells().map(|c| c.0).max(),
            cells().map(|c| c.1).min(),
            cells().map(|c| c.1).max(),
        ) else {
            return Self {
                first: (0, 0),
                columns: 0,
                rows: 0,
                node: Vec::new(),
                cost_m: Vec::new(),
            };
        };
        let (columns, rows) = (hi_i - lo_i + 1, hi_j - lo_j + 1);
        let mut node = vec![None; (columns * rows) as usize];
        let mut cost_m = vec![f64::INFINITY; (columns * rows) as usize];
        for (k, n) in nodes.iter().enumerate() {
            if let Some((i, j)) = n.cell {
                let at = ((i - lo_i) * rows + (j - lo_j)) as usize;
                node[at] = Some(k);
                cost_m[at] = n.cost_m;
            }
        }
        Self {
            first: (lo_i, lo_j),
            columns,
            rows,
            node,
            cost_m,
        }
    }

    /// The places in the tables of the cells `(i, j_lo) ..= (i, j_hi)` inside them, in
    /// order (`None`: none is).
    fn chord(&self, i: i64, j_lo: i64, j_hi: i64) -> Option<std::ops::RangeInclusive<usize>> {
        let di = i - self.first.0;
        let (lo, hi) = (
            (j_lo - self.first.1).max(0),
            (j_hi - self.first.1).min(self.rows - 1),
        );
        if di < 0 || di >= self.columns || lo > hi {
            return None;
        }
        let base = di * self.rows;
        Some((base + lo) as usize..=(base + hi) as usize)
    }

    /// The node on cell `(i, j)`, if any.
    fn get(&self, i: i64, j: i64) -> Option<usize> {
        self.node[*self.chord(i, j, j)?.start()]
    }
}

/// The track of least summed deviation that an agent starting at `start` can follow with
/// steps of at most `max_step_m` (straight segments), its slot at step `k + 1` being
/// `slots[k]`, its positions at each step taken from `lattice` around the slot and the
/// step's anchors (within `k + 1` top-speed steps of `start`) and from `anchors[k]`
/// themselves (extra candidates, such as the slot itself and its nearest free point).
///
/// - `clearance_m(k, p)`: `None` where the agent does not fit at `p` at the end of move
///   `k` (the move to `x_(k+1)`; `start` is asked with `k` = 0), else a distance within
///   which every point is free of the obstacles of that move (it may be an
///   underestimate, such as 0; the space is also assumed convex apart from the
///   obstacles, like a rectangular field). The obstacles of a move must include those of
///   the next (bodies that stand only for the first moves), as a node's clearance serves
///   the move out of it too.
/// - `segment_free(k, a, b)`: whether the straight segment from `a` to `b` is free for
///   move `k`; asked only when the two clearances do not already cover it.
///
/// A step is at most `max_step_m` up to the rounding of the lattice's coordinates
/// (1e-9 m). Returns the summed deviation (metres) and the track `x_1 .. x_T`, or `None` when no
/// track through the candidates exists (a step none of whose candidates can be reached).
pub fn best_track_on_lattice(
    start: &Point,
    slots: &[Point],
    anchors: &[Vec<Point>],
    max_step_m: f64,
    lattice: Lattice,
    clearance_m: impl Fn(usize, &Point) -> Option<f64>,
    segment_free: impl Fn(usize, &Point, &Point) -> bool,
) -> Option<(f64, Vec<Point>)> {
    let spacing_of = |k: usize| match k {
        0 => lattice.first_spacing_m,
        _ => lattice.spacing_m,
    };
    if !(lattice.spacing_m > 0.0
        && lattice.first_spacing_m > 0.0
        && max_step_m > 0.0
        && lattice.window_m >= 0.0)
    {
        return None;
    }
    let chords = reach_chords(max_step_m, lattice.spacing_m);
    let reachable = |k: usize, from: &Node, to: &Node| {
        let gap = to.at - from.at;
        norm_within(&gap, max_step_m + STEP_ROUNDING_M)
            && (norm_within(&gap, from.clearance_m + to.clearance_m)
                || segment_free(k, &from.at, &to.at))
    };
    let mut steps: Vec<Vec<Node>> = Vec::with_capacity(slots.len() + 1);
    steps.push(vec![Node {
        at: *start,
        clearance_m: clearance_m(0, start).map_or(0.0, |c| c.min(max_step_m).max(0.0)),
        cell: None,
        cost_m: 0.0,
        from: 0,
    }]);
    for (k, slot) in slots.iter().enumerate() {
        let (h, h_before) = (spacing_of(k), spacing_of(k.saturating_sub(1)));
        let point_of = |(i, j): (i64, i64)| Point::new(i as f64 * h, j as f64 * h);
        let previous = &steps[k];
        let by_cell = CellIndex::of(previous);
        let loose: Vec<usize> = (0..previous.len())
            .filter(|&i| previous[i].cell.is_none())
            .collect();
        let mut candidates = Vec::new();
        // No point farther than k + 1 moves from the start can be reached.
        let within_m = (k + 1) as f64 * (max_step_m + STEP_ROUNDING_M);
        // Lattice points within the window of the slot or of one of the step's anchors.
        let step_anchors = anchors.get(k).map_or(&[][..], Vec::as_slice);
        let centres = || std::iter::once(slot).chain(step_anchors);
        let w = lattice.window_m;
        let lo = |c: fn(&Point) -> f64| {
            let least = centres().map(c).fold(f64::INFINITY, f64::min);
            ((least - w) / h).floor() as i64
        };
        let hi = |c: fn(&Point) -> f64| {
            let most = centres().map(c).fold(f64::NEG_INFINITY, f64::max);
            ((most + w) / h).ceil() as i64
        };
        for i in lo(|p| p.x)..=hi(|p| p.x) {
            for j in lo(|p| p.y)..=hi(|p| p.y) {
                let at = point_of((i, j));
                if norm_within(&(at - start), within_m)
                    && centres().any(|c| norm_within(&(at - c), w))
                {
                    candidates.push((at, Some((i, j))));
                }
            }
        }
        candidates.extend(anchors.get(k).into_iter().flatten().map(|a| (*a, None)));
        let mut nodes = Vec::with_capacity(candidates.len());
        for (at, cell) in candidates {
            let Some(clear) = clearance_m(k, &at) else {
                continue;
            };
            let mut node = Node {
                at,
                clearance_m: clear.min(max_step_m).max(0.0),
                cell,
                cost_m: f64::INFINITY,
                from: 0,
            };
            let relax = |node: &mut Node, from: usize| {
                let q = &previous[from];
                if q.cost_m < node.cost_m && reachable(k, q, node) {
                    node.cost_m = q.cost_m;
                    node.from = from;
                }
            };
            match cell {
                // The step before on the same lattice: its cells within reach.
                Some((i, j)) if k > 0 && h_before == h => {
                    for &(di, m) in &chords {
                        let Some(row) = by_cell.chord(i + di, j - m, j + m) else {
                            continue;
                        };
                        let (costs, nodes) = (&by_cell.cost_m[row.clone()], &by_cell.node[row]);
                        for (cost_m, from) in costs.iter().zip(nodes) {
                            // Only a cheaper node can change the answer: its cost first.
                            if *cost_m < node.cost_m
                                && let Some(from) = *from
                            {
                                relax(&mut node, from);
                            }
                        }
                    }
                }
                _ => {
                    let (lo_i, hi_i) = (
                        ((at.x - max_step_m) / h_before).floor() as i64,
                        ((at.x + max_step_m) / h_before).ceil() as i64,
                    );
                    let (lo_j, hi_j) = (
                        ((at.y - max_step_m) / h_before).floor() as i64,
                        ((at.y + max_step_m) / h_before).ceil() as i64,
                    );
                    for i in lo_i..=hi_i {
                        for j in lo_j..=hi_j {
                            if let Some(from) = by_cell.get(i, j) {
                                relax(&mut node, from);
                            }
                        }
                    }
                }
            }
            for &from in &loose {
                relax(&mut node, from);
            }
            if node.cost_m.is_finite() {
                node.cost_m += (at - slot).norm();
                nodes.push(node);
            }
        }
        if nodes.is_empty() {
            return None;
        }
        steps.push(nodes);
    }
    // The cheapest end, and the way back to it.
    let last = steps.last()?;
    let (mut at, end) = last
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.cost_m.total_cmp(&b.1.cost_m))?;
    let total_m = end.cost_m;
    let mut track = Vec::with_capacity(slots.len());
    for k in (1..steps.len()).rev() {
        let node = &steps[k][at];
        track.push(node.at);
        at = node.from;
    }
    track.reverse();
    Some((total_m, track))
}

/// The lattice offsets `(di, dj)` a step of at most `max_step_m` between two points
/// `spacing_m` apart can take, as chords of the disk: for each column offset `di`
/// (ascending), the row offsets `-m ..= m`, given as `(di, m)`.
fn reach_chords(max_step_m: f64, spacing_m: f64) -> Vec<(i64, i64)> {
    let reach = (max_step_m / spacing_m).floor() as i64;
    let within = |di: i64, dj: i64| ((di * di + dj * dj) as f64).sqrt() * spacing_m <= max_step_m;
    (-reach..=reach)
        .filter_map(|di| {
            let m = (0..=reach).take_while(|&dj| within(di, dj)).last()?;
            Some((di, m))
        })
        .collect()
}

/// Whether `v.norm() <= r`, bit for bit, mostly without the square root: the squared
/// length is compared with `r * r` and the root taken only within a relative 1e-12 of it
/// (where rounding could decide).
fn norm_within(v: &Vector, r: f64) -> bool {
    let (squared, r_squared) = (v.norm_squared(), r * r);
    if r < 0.0 {
        false
    } else if squared <= r_squared * (1.0 - 1e-12) {
        true
    } else if squared >= r_squared * (1.0 + 1e-12) {
        false
    } else {
        squared.sqrt() <= r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LATTICE: Lattice = Lattice {
        spacing_m: 0.1,
        first_spacing_m: 0.1,
        window_m: 1.5,
    };

    /// The chords hold exactly the offsets within a step, in column-then-row order.
    #[test]
    fn the_chords_are_the_offsets_within_a_step() {
        let cases: [(f64, f64); 5] = [(0.5, 0.1), (1.0, 0.3), (0.5, 0.3), (0.6, 0.25), (0.2, 0.3)];
        for (max_step_m, spacing_m) in cases {
            let reach = (max_step_m / spacing_m).floor() as i64;
            let plain: Vec<(i64, i64)> = (-reach..=reach)
                .flat_map(|di| (-reach..=reach).map(move |dj| (di, dj)))
                .filter(|&(di, dj)| ((di * di + dj * dj) as f64).sqrt() * spacing_m <= max_step_m)
                .collect();
            let chorded: Vec<(i64, i64)> = reach_chords(max_step_m, spacing_m)
                .into_iter()
                .flat_map(|(di, m)| (-m..=m).map(move |dj| (di, dj)))
                .collect();
            assert_eq!(chorded, plain, "step {max_step_m}, spacing {spacing_m}");
        }
    }

    /// The test without the root answers as the root does, on random lengths and on
    /// lengths a rounding away from the radius.
    #[test]
    fn norm_within_agrees_with_the_norm() {
        let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..20_000 {
            let v = Vector::new(4.0 * next() - 2.0, 4.0 * next() - 2.0);
            let exact = v.norm();
            let nudged = [
                exact,
                f64::from_bits(exact.to_bits() + 1),
                f64::from_bits(exact.to_bits().saturating_sub(1)),
                3.0 * next(),
                -next(),
            ];
            for r in nudged {
                assert_eq!(norm_within(&v, r), v.norm() <= r, "{v} against {r}");
            }
        }
    }

    /// The search in open space (every point free, every segment free), top speed 0.5 m.
    fn in_open_space(
        start: &Point,
        slots: &[Point],
        anchors: &[Vec<Point>],
        lattice: Lattice,
    ) -> Option<(f64, Vec<Point>)> {
        best_track_on_lattice(
            start,
            slots,
            anchors,
            0.5,
            lattice,
            |_, _| Some(f64::INFINITY),
            |_, _, _| true,
        )
    }

    /// A slot the agent can follow in open space, the slots as anchors: it tracks them
    /// exactly.
    #[test]
    fn a_followable_slot_is_tracked_exactly() {
        let start = Point::new(0.03, 0.01);
        let slots: Vec<Point> = (1..=6)
            .map(|k| Point::new(0.03 + 0.37 * k as f64, 0.01))
            .collect();
        let anchors: Vec<Vec<Point>> = slots.iter().map(|s| vec![*s]).collect();
        let (sum, track) = in_open_space(&start, &slots, &anchors, LATTICE).expect("a track");
        assert!(sum < 1e-12, "{sum}");
        assert_eq!(track, slots);
    }

    /// A slot running away at 1 m a step from an agent that makes 0.5 m, along a lattice
    /// line: it falls behind by 0.5 m a step whatever it does, so the summed deviation
    /// is 0.5 (1 + 2 + ... + T), as the cone programme's closed form says.
    #[test]
    fn a_runaway_slot_gives_the_closed_form() {
        let t = 6;
        let slots: Vec<Point> = (1..=t).map(|k| Point::new(k as f64, 0.0)).collect();
        let lattice = Lattice {
            spacing_m: 0.1,
            first_spacing_m: 0.1,
            window_m: 4.0,
        };
        let (sum, track) = in_open_space(&Point::origin(), &slots, &[], lattice).expect("a track");
        let exact = 0.5 * (t * (t + 1) / 2) as f64;
        assert!((sum - exact).abs() < 1e-9, "{sum} vs {exact}");
        for (k, p) in track.iter().enumerate() {
            assert!((p.x - 0.5 * (k + 1) as f64).abs() < 1e-9, "{p:?}");
        }
    }

    /// A wall across the slot's way with one gap: every step of the track is free and
    /// within the top speed, and the track is never better than the cone bound (the
    /// bound without the wall) nor worse than standing still.
    #[test]
    fn the_track_goes_round_a_wall_and_stays_between_the_bounds() {
        // The wall: x in [1.0, 1.2], y outside [1.5, 2.0] is blocked.
        let blocked = |p: &Point| p.x > 1.0 && p.x < 1.2 && !(p.y > 1.5 && p.y < 2.0);
        let clearance = |_: usize, p: &Point| (!blocked(p)).then_some(0.0);
        let segment_free = |_: usize, a: &Point, b: &Point| {
            (0..=200).all(|i| !blocked(&(a + (b - a) * (i as f64 / 200.0))))
        };
        // Long enough that staying behind the wall costs more than the way round.
        let slots: Vec<Point> = (1..=16).map(|k| Point::new(0.3 * k as f64, 0.0)).collect();
        let start = Point::origin();
        let lattice = Lattice {
            spacing_m: 0.1,
            first_spacing_m: 0.1,
            window_m: 2.5,
        };
        let (sum, track) =
            best_track_on_lattice(&start, &slots, &[], 0.5, lattice, clearance, segment_free)
                .expect("a track");
        let mut from = start;
        for p in &track {
            assert!(!blocked(p), "{p:?}");
            assert!((p - from).norm() <= 0.5 + 1e-12);
            assert!(segment_free(0, &from, p), "{from:?} -> {p:?}");
            from = *p;
        }
        let summed: f64 = track.iter().zip(&slots).map(|(p, s)| (p - s).norm()).sum();
        assert!((summed - sum).abs() < 1e-9);
        let standing: f64 = slots.iter().map(|s| (s - start).norm()).sum();
        assert!(sum < standing, "{sum} vs {standing}");
        // Without the wall the slot (0.3 m a step) is followed exactly from step 1 on,
        // but for the lattice's rounding: going round costs more.
        assert!(sum > 0.5, "{sum}");
        // It crossed the wall through the gap.
        assert!(track.iter().any(|p| p.x >= 1.2));
    }

    /// No candidate within reach: no track.
    #[test]
    fn an_unreachable_step_gives_none() {
        let slots = vec![Point::new(10.0, 0.0)];
        let lattice = Lattice {
            spacing_m: 0.1,
            first_spacing_m: 0.1,
            window_m: 1.0,
        };
        let found = in_open_space(&Point::origin(), &slots, &[], lattice);
        assert!(found.is_none());
    }
}

//! For how many turns an agent can keep out of the moving obstacles' reach, moving as it
//! likes: a backward sweep over a lattice of points round the agent, one layer a turn.
//!
//! A point that stays outside every reach disk while the agent stands there is one way to
//! stay clear; a gap the obstacles are closing may need several moves in a row, each
//! within the top speed, each ending outside that turn's reach disks. [`SurvivalGrid`]
//! answers that question for every lattice point at once: `V_n(c)`, the number of turns
//! from turn `n` on that an agent at lattice point `c` can go on ending outside the
//! obstacles' reach, is 0 where `c` is not free at turn `n`, and otherwise one more than
//! the best `V_{n+1}` of the points within a move of `c` (itself included). A move's end
//! `q` is then scored by the best `V_1` within a move of `q`.
//!
//! The lattice only weighs where to go; every move an agent takes is still checked
//! exactly, where it is planned.

use crate::geometry::{Disk, Point, Vector};

/// How many turns, from the first after this one on, an agent can keep to free points
/// (each turn's end at most a move from the last), for every point of a square lattice
/// round the agent.
#[derive(Clone, Debug)]
pub struct SurvivalGrid {
    /// The lattice point of index (0, 0).
    corner: Point,
    /// The spacing of the lattice, in metres.
    cell_m: f64,
    /// Points on a side of the lattice.
    side: usize,
    /// The longest move in a turn, in metres.
    move_m: f64,
    /// `V_1`, row by row: for how many turns from the first after this one an agent at
    /// that point can keep to free points (at most the horizon).
    first: Vec<u8>,
}

impl SurvivalGrid {
    /// The lattice round `me` (spacing `cell_m`) over every point an agent moving at most
    /// `move_m` a turn can reach in `turns + 1` turns, swept back from turn `turns`
    /// (at most 255) to turn 1. A point is free at turn `n` (counted from this one) when
    /// `stays_free` holds there (the field, what stands still) and it is outside every
    /// disk of `blocked_at(n)` (distance at least the radius).
    ///
    /// ```
    /// use shared::geometry::{Disk, Point};
    /// use shared::control::survival_grid::SurvivalGrid;
    /// // A wall of reach (a disk 100 m across) coming east at 0.4 m a turn, its edge
    /// // 0.5 m behind an agent at the origin: moving 0.5 m a turn the agent stays ahead
    /// // of it for good; moving 0.25 m a turn it is caught.
    /// let reach = |n: usize| vec![Disk::new(-100.5 + 0.4 * n as f64, 0.0, 100.0)];
    /// let me = Point::new(0.0, 0.0);
    /// let fast = SurvivalGrid::new(&me, 0.5, 0.125, 10, |_| true, reach);
    /// assert_eq!(fast.turns_clear(&me), 10);
    /// let slow = SurvivalGrid::new(&me, 0.25, 0.0625, 10, |_| true, reach);
    /// assert!(slow.turns_clear(&me) < 10);
    /// ```
    pub fn new(
        me: &Point,
        move_m: f64,
        cell_m: f64,
        turns: usize,
        stays_free: impl Fn(&Point) -> bool,
        blocked_at: impl Fn(usize) -> Vec<Disk>,
    ) -> Self {
        let turns = turns.min(usize::from(u8::MAX));
        // The lattice is the world's (points at whole multiples of `cell_m`), so the
        // lattices of an agent's successive turns share their points. Half the side, in
        // cells, round the point nearest `me`: the farthest reach (turns + 1 moves, from
        // up to a cell away) and a move more, so every neighbour looked at is on the
        // lattice.
        let half = (((turns + 2) as f64 * move_m + cell_m) / cell_m).ceil() as usize;
        let side = 2 * half + 1;
        let nearest = Point::new(
            (me.x / cell_m).round() * cell_m,
            (me.y / cell_m).round() * cell_m,
        );
        let corner = nearest - Vector::new(half as f64 * cell_m, half as f64 * cell_m);
        let reach = (move_m / cell_m).floor() as isize;
        // Standing still first: where that is best, nothing else is looked at.
        let mut offsets: Vec<(isize, isize)> = (-reach..=reach)
            .flat_map(|di| (-reach..=reach).map(move |dj| (di, dj)))
            .filter(|&(di, dj)| ((di * di + dj * dj) as f64).sqrt() * cell_m <= move_m)
            .collect();
        offsets.sort_by_key(|&(di, dj)| di * di + dj * dj);
        let offsets: Vec<isize> = offsets
            .into_iter()
            .map(|(di, dj)| di * side as isize + dj)
            .collect();
        let point = |i: usize, j: usize| corner + Vector::new(j as f64 * cell_m, i as f64 * cell_m);
        let mut open = vec![false; side * side];
        for (k, open) in open.iter_mut().enumerate() {
            *open = stays_free(&point(k / side, k % side));
        }
        let mut free = vec![false; side * side];
        let mut next = vec![0u8; side * side];
        let mut this = vec![0u8; side * side];
        for n in (1..=turns).rev() {
            // Where an agent can be at the end of turn n: within n + 1 moves of `me`.
            let r = ((((n + 1) as f64 * move_m + cell_m) / cell_m).ceil() as usize).min(half);
            let (lo, hi) = (half - r, half + r);
            free.copy_from_slice(&open);
            for disk in blocked_at(n) {
                // The lattice points of the disk's bounding box within this turn's square.
                let rel = disk.centre - corner;
                let span = |mid_m: f64| {
                    let from = ((mid_m - disk.radius_m) / cell_m).floor().max(lo as f64);
                    let to = ((mid_m + disk.radius_m) / cell_m).ceil().min(hi as f64);
                    (from <= to).then_some((from as usize, to as usize))
                };
                let (Some((i0, i1)), Some((j0, j1))) = (span(rel.y), span(rel.x)) else {
                    continue;
                };
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        if (point(i, j) - disk.centre).norm() < disk.radius_m {
                            free[i * side + j] = false;
                        }
                    }
                }
            }
            let most = (turns - n) as u8;
            // Out of reach from `me` (never read, but never stale either).
            this.fill(0);
            for i in lo..=hi {
                for j in lo..=hi {
                    let k = i * side + j;
                    this[k] = if !free[k] {
                        0
                    } else if n == turns {
                        1
                    } else {
                        let mut best = 0;
                        for &o in &offsets {
                            best = best.max(next[(k as isize + o) as usize]);
                            if best == most {
                                break;
                            }
                        }
                        1 + best
                    };
                }
            }
            std::mem::swap(&mut this, &mut next);
        }
        Self {
            corner,
            cell_m,
            side,
            move_m,
            first: next,
        }
    }

    /// For how many turns after this one an agent ending this turn at `q` can keep to free
    /// points: the best of the lattice points within a move of `q`.
    pub fn turns_clear(&self, q: &Point) -> usize {
        self.indices_within(q, self.move_m)
            .map(|k| usize::from(self.first[k]))
            .max()
            .unwrap_or(0)
    }

    /// The indices of the lattice points within `dist_m` of `q` (those the lattice holds).
    fn indices_within(&self, q: &Point, dist_m: f64) -> impl Iterator<Item = usize> + '_ {
        let rel = q - self.corner;
        let reach = (dist_m / self.cell_m).ceil() as isize + 1;
        let (ci, cj) = (
            (rel.y / self.cell_m).round() as isize,
            (rel.x / self.cell_m).round() as isize,
        );
        let side = self.side as isize;
        let q = *q;
        (ci - reach..=ci + reach)
            .flat_map(move |i| (cj - reach..=cj + reach).map(move |j| (i, j)))
            .filter(move |&(i, j)| i >= 0 && j >= 0 && i < side && j < side)
            .filter(move |&(i, j)| {
                let p = self.corner + Vector::new(j as f64 * self.cell_m, i as f64 * self.cell_m);
                (p - q).norm() <= dist_m
            })
            .map(|(i, j)| i as usize * self.side + j as usize)
    }
}

//! The candidate words, and the search for the shortest over the five families, each
//! formula applied under time-flip and reflection (and the `CCC` and `CCSC` ones also read
//! backwards).
//!
//! Everything here works in the start pose's frame, scaled so that the turning radius is
//! 1: the goal is (x, y, phi) and lengths are in units of the turning radius.

use std::f64::consts::PI;

use super::formulas::{
    Formula, Goal, lp_rm_l, lp_rm_s_lm_rp, lp_rm_sm_lm, lp_rm_sm_rm, lp_rum_lum_rp, lp_rup_lum_rm,
    lp_sp_lp, lp_sp_rp,
};
use crate::geometry::Pose;
use crate::paths::curve::{Segment, Steer, scaled_segment};

/// A candidate word in normalized units: up to five steers with signed lengths.
#[derive(Clone, Copy, Debug)]
pub(super) struct Word {
    steers: [Steer; 5],
    lengths: [f64; 5],
    count: usize,
    /// Sum of absolute lengths.
    pub(super) total: f64,
}

impl Word {
    /// The placeholder before any word is found: infinitely long.
    const NONE: Word = Word {
        steers: [Steer::Straight; 5],
        lengths: [0.0; 5],
        count: 0,
        total: f64::INFINITY,
    };

    fn new<const N: usize>(steers: [Steer; N], lengths: [f64; N]) -> Self {
        let mut word = Word {
            count: N,
            total: 0.0,
            ..Word::NONE
        };
        word.steers[..N].copy_from_slice(&steers);
        word.lengths[..N].copy_from_slice(&lengths);
        word.total = word.lengths.iter().map(|l| l.abs()).sum();
        word
    }

    /// Time-flip: the same steers driven in the opposite direction.
    fn time_flipped(mut self) -> Self {
        for length in &mut self.lengths[..self.count] {
            *length = -*length;
        }
        self
    }

    /// Reflection across the start heading: left and right swapped.
    fn reflected(mut self) -> Self {
        for steer in &mut self.steers[..self.count] {
            *steer = steer.mirrored();
        }
        self
    }

    /// The word's non-negligible segments, scaled to metres.
    pub(super) fn segments(&self, turning_radius_m: f64) -> impl Iterator<Item = Segment> + '_ {
        self.steers[..self.count]
            .iter()
            .zip(&self.lengths[..self.count])
            .filter_map(move |(steer, length)| scaled_segment(*steer, *length, turning_radius_m))
    }
}

/// Finds the shortest word from `from` to `to`; `None` only for non-finite input.
pub(super) fn solve(from: &Pose, to: &Pose, turning_radius_m: f64) -> Option<Word> {
    let dx_m = to.x_m - from.x_m;
    let dy_m = to.y_m - from.y_m;
    let (sin, cos) = from.heading_rad.sin_cos();
    let x = (cos * dx_m + sin * dy_m) / turning_radius_m;
    let y = (-sin * dx_m + cos * dy_m) / turning_radius_m;
    let phi = to.heading_rad - from.heading_rad;
    let word = solve_normalized(x, y, phi);
    word.total.is_finite().then_some(word)
}

/// Minimum over all families, in OMPL's order (which only decides ties).
fn solve_normalized(x: f64, y: f64, phi: f64) -> Word {
    use Steer::{Left as L, Right as R, Straight as S};
    const HALF_PI: f64 = 0.5 * PI;
    let mut best = Word::NONE;
    let goal = Goal::new(x, y, phi);
    let back = goal.backwards();

    // CSC: L+S+L+ and L+S+R+.
    let mut search = Search::new(&mut best, 0.0);
    search.all_symmetries(&goal, lp_sp_lp, |t, u, v| Word::new([L, S, L], [t, u, v]));
    search.all_symmetries(&goal, lp_sp_rp, |t, u, v| Word::new([L, S, R], [t, u, v]));

    // CCC: L+R-L(+/-), and the same read backwards.
    let mut search = Search::new(&mut best, 0.0);
    search.all_symmetries(&goal, lp_rm_l, |t, u, v| Word::new([L, R, L], [t, u, v]));
    search.all_symmetries(&back, lp_rm_l, |t, u, v| Word::new([L, R, L], [v, u, t]));

    // CCCC: L+R+u L-u R- and L+R-u L-u R+ (the cost counts the middle length u twice).
    let mut search = Search::new(&mut best, 0.0).with_double_middle();
    search.all_symmetries(&goal, lp_rup_lum_rm, |t, u, v| {
        Word::new([L, R, L, R], [t, u, -u, v])
    });
    search.all_symmetries(&goal, lp_rum_lum_rp, |t, u, v| {
        Word::new([L, R, L, R], [t, u, u, v])
    });

    // CCSC: L+R-(pi/2) S- L- and L+R-(pi/2) S- R-, and both read backwards.
    let mut search = Search::new(&mut best, HALF_PI);
    search.all_symmetries(&goal, lp_rm_sm_lm, |t, u, v| {
        Word::new([L, R, S, L], [t, -HALF_PI, u, v])
    });
    search.all_symmetries(&goal, lp_rm_sm_rm, |t, u, v| {
        Word::new([L, R, S, R], [t, -HALF_PI, u, v])
    });
    search.all_symmetries(&back, lp_rm_sm_lm, |t, u, v| {
        Word::new([L, S, R, L], [v, u, -HALF_PI, t])
    });
    search.all_symmetries(&back, lp_rm_sm_rm, |t, u, v| {
        Word::new([R, S, R, L], [v, u, -HALF_PI, t])
    });

    // CCSCC: L+R-(pi/2) S- L-(pi/2) R+.
    let mut search = Search::new(&mut best, PI);
    search.all_symmetries(&goal, lp_rm_s_lm_rp, |t, u, v| {
        Word::new([L, R, S, L, R], [t, -HALF_PI, u, -HALF_PI, v])
    });

    best
}

/// One family's search state, mirroring OMPL: a candidate replaces the best word when its
/// formula cost `|t| + |u| + |v|` (or `|t| + 2|u| + |v|` for CCCC) is below `bound`, which
/// starts at the best total minus the family's fixed arc lengths.
struct Search<'a> {
    best: &'a mut Word,
    bound: f64,
    double_middle: bool,
}

impl<'a> Search<'a> {
    fn new(best: &'a mut Word, fixed_arcs: f64) -> Self {
        let bound = best.total - fixed_arcs;
        Search {
            best,
            bound,
            double_middle: false,
        }
    }

    fn with_double_middle(mut self) -> Self {
        self.double_middle = true;
        self
    }

    /// Tries `formula` on the goal and on its time-flipped, reflected, and time-flipped and
    /// reflected images; `build` turns a base solution into its word.
    fn all_symmetries(&mut self, goal: &Goal, formula: Formula, build: fn(f64, f64, f64) -> Word) {
        for (time_flip, reflect) in [(false, false), (true, false), (false, true), (true, true)] {
            let turn_flip = if time_flip != reflect { -1.0 } else { 1.0 };
            let image = Goal {
                x: if time_flip { -goal.x } else { goal.x },
                y: if reflect { -goal.y } else { goal.y },
                phi: turn_flip * goal.phi,
                sin_phi: turn_flip * goal.sin_phi,
                cos_phi: goal.cos_phi,
            };
            let Some((t, u, v)) = formula(&image, self.bound) else {
                continue;
            };
            let middle_weight = if self.double_middle { 2.0 } else { 1.0 };
            let cost = t.abs() + middle_weight * u.abs() + v.abs();
            if self.bound > cost {
                let mut word = build(t, u, v);
                if time_flip {
                    word = word.time_flipped();
                }
                if reflect {
                    word = word.reflected();
                }
                *self.best = word;
                self.bound = cost;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every formula under every symmetry (and read backwards where the search reads it
    /// so), without a bound: the least total of all the words they give.
    fn least_total_unpruned(x: f64, y: f64, phi: f64) -> f64 {
        let goal = Goal::new(x, y, phi);
        let back = goal.backwards();
        // (formula, its fixed arcs, the weight of its middle length, read backwards too)
        let formulas: [(Formula, f64, f64, bool); 8] = [
            (lp_sp_lp, 0.0, 1.0, false),
            (lp_sp_rp, 0.0, 1.0, false),
            (lp_rm_l, 0.0, 1.0, true),
            (lp_rup_lum_rm, 0.0, 2.0, false),
            (lp_rum_lum_rp, 0.0, 2.0, false),
            (lp_rm_sm_lm, 0.5 * PI, 1.0, true),
            (lp_rm_sm_rm, 0.5 * PI, 1.0, true),
            (lp_rm_s_lm_rp, PI, 1.0, false),
        ];
        let mut least = f64::INFINITY;
        for (formula, fixed, middle, backwards) in formulas {
            let goals: &[&Goal] = if backwards { &[&goal, &back] } else { &[&goal] };
            for g in goals {
                for (flip_x, flip_y) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                    let turn = flip_x * flip_y;
                    let image = Goal {
                        x: flip_x * g.x,
                        y: flip_y * g.y,
                        phi: turn * g.phi,
                        sin_phi: turn * g.sin_phi,
                        cos_phi: g.cos_phi,
                    };
                    if let Some((t, u, v)) = formula(&image, f64::INFINITY) {
                        least = least.min(t.abs() + middle * u.abs() + v.abs() + fixed);
                    }
                }
            }
        }
        least
    }

    #[test]
    fn the_bound_never_drops_the_shortest_word() {
        // Goals on a grid round the start with every heading, near ones included (where
        // the cusped words are shortest).
        let mut checked = 0;
        for i in -12..=12 {
            for j in -12..=12 {
                for k in 0..24 {
                    let (x, y) = (0.37 * i as f64, 0.41 * j as f64);
                    let phi = k as f64 * std::f64::consts::TAU / 24.0 - PI + 0.01;
                    let pruned = solve_normalized(x, y, phi).total;
                    let least = least_total_unpruned(x, y, phi);
                    assert!(
                        (pruned - least).abs() <= 1e-12,
                        "({x}, {y}, {phi}): pruned {pruned}, unpruned {least}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 25 * 25 * 24);
    }
}

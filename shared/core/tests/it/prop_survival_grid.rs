//! `SurvivalGrid` (a backward sweep) against a plain forward search over the same
//! lattice: from a move's end, the set of lattice points an agent can be at after each
//! turn, kept to free points, until it is empty.

use proptest::prelude::*;
use shared::control::survival_grid::SurvivalGrid;
use shared::geometry::{Disk, Point, Vector};

/// A disk moving in a straight line: centre at turn 0, velocity per turn, radius.
type Mover = ((f64, f64), (f64, f64), f64);

/// The disks of `movers` at turn `n`.
fn disks_at(movers: &[Mover], n: usize) -> Vec<Disk> {
    movers
        .iter()
        .map(|&((x, y), (vx, vy), r)| Disk::new(x + n as f64 * vx, y + n as f64 * vy, r))
        .collect()
}

/// For how many turns after this one an agent ending it at `q` can keep to free points,
/// moving at most `move_m` a turn between the lattice points `me + (a, b) cell_m`:
/// searched forward, turn by turn.
fn turns_clear_forward(
    me: &Point,
    q: &Point,
    move_m: f64,
    cell_m: f64,
    turns: usize,
    free: &dyn Fn(usize, &Point) -> bool,
) -> usize {
    let half = ((turns + 2) as f64 * move_m / cell_m).ceil() as i64;
    let lattice: Vec<Point> = (-half..=half)
        .flat_map(|a| (-half..=half).map(move |b| (a, b)))
        .map(|(a, b)| me + Vector::new(a as f64 * cell_m, b as f64 * cell_m))
        .collect();
    let mut now: Vec<Point> = lattice
        .iter()
        .filter(|p| (*p - q).norm() <= move_m && free(1, p))
        .copied()
        .collect();
    let mut n = 0;
    while !now.is_empty() {
        n += 1;
        if n == turns {
            break;
        }
        now = lattice
            .iter()
            .filter(|p| free(n + 1, p) && now.iter().any(|s| (*p - s).norm() <= move_m))
            .copied()
            .collect();
    }
    n
}

fn mover() -> impl Strategy<Value = Mover> {
    (
        (-3.0..3.0f64, -3.0..3.0f64),
        (-0.45..0.45f64, -0.45..0.45f64),
        0.3..1.5f64,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// The backward sweep and the forward search agree on every move's end, among moving
    /// disks and a standing one, and standing where the move ends is never better than
    /// the sweep's answer.
    #[test]
    fn the_sweep_agrees_with_a_forward_search(
        movers in prop::collection::vec(mover(), 1..=4),
        ((sx, sy), sr) in ((-3.0..3.0f64, -3.0..3.0f64), 0.3..1.5f64),
        (qx, qy) in (-0.5..0.5f64, -0.5..0.5f64),
        turns in 1..=6usize,
    ) {
        let (me, move_m, cell_m) = (Point::new(0.0, 0.0), 0.5, 0.25);
        let q = me + Vector::new(qx, qy);
        prop_assume!((q - me).norm() <= move_m);
        let standing = Disk::new(sx, sy, sr);
        let stays_free = |p: &Point| (p - standing.centre).norm() >= standing.radius_m;
        let free = |n: usize, p: &Point| {
            stays_free(p) && disks_at(&movers, n).iter().all(|d| (p - d.centre).norm() >= d.radius_m)
        };
        let grid = SurvivalGrid::new(&me, move_m, cell_m, turns, stays_free, |n| disks_at(&movers, n));
        let swept = grid.turns_clear(&q);
        prop_assert_eq!(swept, turns_clear_forward(&me, &q, move_m, cell_m, turns, &free));
        // Standing on the nearest lattice point within a move of q is one way to go.
        let a = (q.x / cell_m).round();
        let b = (q.y / cell_m).round();
        let p = me + Vector::new(a * cell_m, b * cell_m);
        if (p - q).norm() <= move_m {
            let standing = (1..=turns).take_while(|&n| free(n, &p)).count();
            prop_assert!(swept >= standing, "swept {} < standing {}", swept, standing);
        }
    }
}

/// An obstacle's reach closing in from the east at 0.4 m a turn, a wall of it north and
/// south too (a gap closing round the agent), open to the west: standing, the agent is
/// caught within a few turns; moving west every turn, it never is.
#[test]
fn a_closing_gap_is_left_by_moving_on() {
    // The east wall: a disk 200 m across whose west edge is at x = 1 - 0.4 n.
    let east = |n: usize| vec![Disk::new(101.0 - 0.4 * n as f64, 0.0, 100.0)];
    let corridor = |p: &Point| p.y.abs() < 3.0;
    let me = Point::new(0.0, 0.0);
    let grid = SurvivalGrid::new(&me, 0.5, 0.125, 10, corridor, east);
    let standing = (1..=10)
        .take_while(|&n| east(n).iter().all(|d| (me - d.centre).norm() >= d.radius_m))
        .count();
    assert!(standing < 3, "standing clear for {standing} turns");
    assert_eq!(grid.turns_clear(&me), 10);
    // Moving only 0.25 m a turn, the agent falls behind.
    let slow = SurvivalGrid::new(&me, 0.25, 0.125, 10, corridor, east);
    assert!(slow.turns_clear(&me) < 10);
}

/// Disks wholly beyond the lattice, on every side, change nothing; a disk over all of it
/// leaves the agent no free point.
#[test]
fn disks_beyond_the_lattice_change_nothing_and_one_over_it_blocks_all() {
    let me = Point::new(0.3, -0.2);
    let far = |_: usize| {
        vec![
            Disk::new(40.0, 0.0, 5.0),
            Disk::new(-40.0, 3.0, 5.0),
            Disk::new(0.0, 40.0, 5.0),
            Disk::new(1.0, -40.0, 5.0),
        ]
    };
    let grid = SurvivalGrid::new(&me, 0.5, 0.125, 10, |_: &Point| true, far);
    assert_eq!(grid.turns_clear(&me), 10);
    let over = |_: usize| vec![Disk::new(0.0, 0.0, 100.0)];
    let grid = SurvivalGrid::new(&me, 0.5, 0.125, 10, |_: &Point| true, over);
    assert_eq!(grid.turns_clear(&me), 0);
}

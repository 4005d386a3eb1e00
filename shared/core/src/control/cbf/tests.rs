//! Tests of the QP and the barrier controllers.

use super::*;

#[test]
fn degenerate_rows_are_ignored_or_infeasible() {
    let u = Vector::new(1.0, -2.0);
    let ok = [HalfPlane::new(Vector::zeros(), 0.0)];
    assert_eq!(solve_qp_2d(&u, &ok), Ok(u));
    let bad = [HalfPlane::new(Vector::zeros(), -1e-300)];
    assert_eq!(solve_qp_2d(&u, &bad), Err(QpError::Infeasible));
    let nan = [HalfPlane::new(Vector::new(f64::NAN, 1.0), 0.0)];
    assert_eq!(solve_qp_2d(&u, &nan), Err(QpError::NotFinite));
}

#[test]
fn parallel_rows_and_single_point_sets() {
    let u = Vector::new(3.0, 3.0);
    // 1 <= x <= 1 and y <= 0: the set is a half-line.
    let rows = [
        HalfPlane::new(Vector::new(1.0, 0.0), 1.0),
        HalfPlane::new(Vector::new(-2.0, 0.0), -2.0),
        HalfPlane::new(Vector::new(0.0, 5.0), 0.0),
    ];
    assert_eq!(solve_qp_2d(&u, &rows), Ok(Vector::new(1.0, 0.0)));
    let empty = [
        HalfPlane::new(Vector::new(1.0, 0.0), 1.0),
        HalfPlane::new(Vector::new(-1.0, 0.0), -1.5),
    ];
    assert_eq!(solve_qp_2d(&u, &empty), Err(QpError::Infeasible));
}

mod unicycle {
    use super::*;
    use crate::control::formation::Slot;
    use crate::control::kinematics::{UnicycleLimits, unicycle_step_share};
    use crate::control::vocabulary::AgentSpec;
    use crate::geometry::{Disk, Field, Pose};

    /// A GRITSbot-like agent (radius 0.055 m) whose slot is the centre itself, so the
    /// slot is wherever the centre pose puts it.
    fn controller(obstacles: &[Disk]) -> CbfController {
        let spec = AgentSpec::new(Slot::new(0.0, 0.0), 0.055);
        CbfController::new(
            Field::new(3.2, 2.0),
            obstacles,
            &spec,
            CbfSettings::default(),
        )
        .expect("settings")
    }

    const LIMITS: UnicycleLimits = UnicycleLimits {
        max_step_m: 0.0066,
        max_turn_rad: 0.1188,
        reverse: false,
    };

    #[test]
    fn the_arc_lies_on_its_circle_and_ends_turned_by_its_turn() {
        let from = Point::new(1.0, 2.0);
        let (h, d, a) = (0.4_f64, 0.9, -1.3);
        let arc = unicycle_arc(&from, h, d, a);
        // Round the centre a radius d / a to the left of the heading (right for a < 0).
        let radius_m = d / a;
        let centre = from + Vector::new(-h.sin(), h.cos()) * radius_m;
        assert_eq!(
            arc.len(),
            1 + (a.abs() / ARC_CHORD_TURN_RAD).ceil() as usize
        );
        for p in &arc {
            assert!(((p - centre).norm() - radius_m.abs()).abs() < 1e-12, "{p}");
        }
        // The last chord's direction is the end heading less half a chord's turn.
        let k = arc.len();
        let last = arc[k - 1] - arc[k - 2];
        let chord_turn = a / (k - 1) as f64;
        let want = h + a - 0.5 * chord_turn;
        assert!((last.y.atan2(last.x) - want).abs() < 1e-9);
        // Straight, and standing still.
        let straight = unicycle_arc(&from, h, 0.5, 0.0);
        assert_eq!(straight.len(), 2);
        assert!((straight[1] - (from + 0.5 * Vector::new(h.cos(), h.sin()))).norm() < 1e-15);
        assert_eq!(unicycle_arc(&from, h, 0.0, 1.0), vec![from]);
    }

    #[test]
    fn a_robot_with_its_slot_ahead_to_the_left_drives_and_turns_in_the_same_step() {
        let c = controller(&[]);
        let me = Point::new(1.0, 1.0);
        // The slot is ahead and to the left; the robot faces +x.
        let centre = Pose::new(1.2, 1.4, 0.0);
        let mv = c.plan_unicycle_move(&centre, &me, 0.0, &[], &LIMITS, None);
        let end_rad = mv.end_heading_rad.expect("a heading");
        let driven_m = crate::geometry::polyline_length_m(&mv.waypoints);
        assert!(driven_m > 1e-4, "it drives: {driven_m}");
        assert!(end_rad > 1e-3, "it turns towards the slot: {end_rad}");
        let share = unicycle_step_share(0.0, &mv.waypoints, end_rad, &LIMITS);
        assert!(share <= 1.0 + 1e-9, "within one step: {share}");
        assert!(share > 0.99, "at the top of its limits: {share}");
        assert!(mv.waypoints.windows(2).all(|w| (w[1] - w[0]).x > 0.0));
    }

    #[test]
    fn with_align_heading_a_robot_at_its_slot_turns_in_place_to_the_centres_heading() {
        let c = controller(&[]);
        let me = Point::new(1.0, 1.0);
        // The slot 0.02 m ahead (within the projection distance), the centre facing +y.
        let centre = Pose::new(1.02, 1.0, std::f64::consts::FRAC_PI_2);
        let (mut heading_rad, mut steps) = (0.0_f64, 0);
        while (heading_rad - centre.heading_rad).abs() > 1e-12 {
            let mv = c.plan_unicycle_move(
                &centre,
                &me,
                heading_rad,
                &[],
                &LIMITS,
                Some(centre.heading_rad),
            );
            assert_eq!(mv.waypoints, vec![me], "it turns in place");
            let end_rad = mv.end_heading_rad.expect("a heading");
            assert!(
                (end_rad - heading_rad).abs() <= LIMITS.max_turn_rad,
                "within a step's turn"
            );
            heading_rad = end_rad;
            steps += 1;
            assert!(steps <= 14, "a quarter turn takes 14 steps of 0.1188 rad");
        }
        assert_eq!(steps, 14);
        // Without it, the barrier steers the point ahead to the slot: the robot drives.
        let mv = c.plan_unicycle_move(&centre, &me, 0.0, &[], &LIMITS, None);
        assert!(
            mv.waypoints.len() > 1 && mv.end_heading_rad == Some(0.0),
            "{mv:?}"
        );
        // Farther than the projection distance, align_heading changes nothing.
        let far = Pose::new(1.2, 1.0, std::f64::consts::FRAC_PI_2);
        assert_eq!(
            c.plan_unicycle_move(&far, &me, 0.0, &[], &LIMITS, Some(far.heading_rad)),
            c.plan_unicycle_move(&far, &me, 0.0, &[], &LIMITS, None)
        );
    }

    #[test]
    fn a_robot_with_its_slot_behind_turns_in_place_or_backs_up_if_it_may() {
        let c = controller(&[]);
        let me = Point::new(1.0, 1.0);
        let centre = Pose::new(0.8, 1.1, 0.0);
        // Forwards only: it turns in place, towards the slot (left).
        let mv = c.plan_unicycle_move(&centre, &me, 0.0, &[], &LIMITS, None);
        assert_eq!(mv.waypoints, vec![me]);
        assert!(mv.end_heading_rad.expect("a heading") > 0.1);
        // With reverse it backs towards the slot while it turns.
        let limits = UnicycleLimits {
            reverse: true,
            ..LIMITS
        };
        let mv = c.plan_unicycle_move(&centre, &me, 0.0, &[], &limits, None);
        let end = mv.waypoints.last().expect("a point");
        assert!(end.x < me.x - 1e-4, "{end}");
        let end_rad = mv.end_heading_rad.expect("a heading");
        let share = unicycle_step_share(0.0, &mv.waypoints, end_rad, &limits);
        assert!(share <= 1.0 + 1e-9, "within one step: {share}");
        // The point ahead of it (what the barrier steers) comes nearer its nominal goal,
        // the slot's offset from the centre carried to it: it swings left.
        assert!(end_rad > 0.0, "{end_rad}");
        let ahead = |p: &Point, h: f64| p + 0.055 * Vector::new(h.cos(), h.sin());
        let goal = Point::new(0.8, 1.1) + 0.055 * Vector::new(1.0, 0.0);
        assert!((ahead(end, end_rad) - goal).norm() < (ahead(&me, 0.0) - goal).norm());
    }

    #[test]
    fn the_barrier_holds_the_projected_disk_off_an_obstacle_ahead() {
        // An obstacle right ahead, the slot beyond it: the robot must not drive on.
        let post = Disk::new(1.3, 1.0, 0.1);
        let c = controller(&[post]);
        let mut me = Point::new(1.0, 1.0);
        let mut heading_rad = 0.0;
        let centre = Pose::new(1.8, 1.0, 0.0);
        // The projected disk (radius + projection = 0.11 m round the point 0.055 m ahead)
        // is kept off the post for a thousand steps, and so is the robot.
        for _ in 0..1000 {
            let mv = c.plan_unicycle_move(&centre, &me, heading_rad, &[], &LIMITS, None);
            for p in &mv.waypoints {
                let clearance_m = (p - post.centre).norm() - post.radius_m - 0.055;
                assert!(clearance_m > 0.0, "{p}: {clearance_m}");
            }
            me = mv.best;
            heading_rad = mv.end_heading_rad.expect("a heading");
        }
        let ahead = me + 0.055 * Vector::new(heading_rad.cos(), heading_rad.sin());
        assert!((ahead - post.centre).norm() >= post.radius_m + 0.11 - 1e-6);
    }
}

mod substeps {
    use super::*;
    use crate::control::formation::Slot;
    use crate::control::vocabulary::AgentSpec;
    use crate::geometry::{Field, Pose};

    /// An agent at the origin of a 20 x 20 m field (shifted to its middle) whose slot is
    /// 1.5 m ahead, a mate standing just off the straight line to it.
    fn controller(substeps: u32) -> CbfController {
        let spec = AgentSpec::new(Slot::new(0.0, 0.0), 0.3);
        let settings = CbfSettings {
            substeps,
            ..CbfSettings::default()
        };
        CbfController::new(Field::new(20.0, 20.0), &[], &spec, settings).expect("settings")
    }

    fn me() -> Point {
        Point::new(10.0, 10.0)
    }

    /// The centre pose that puts the slot at (11.5, 10).
    fn centre() -> Pose {
        Pose::new(11.5, 10.0, 0.0)
    }

    fn mate() -> Body {
        Body {
            position: Point::new(10.9, 10.15),
            radius_m: 0.3,
        }
    }

    #[test]
    fn one_piece_is_the_one_straight_step_of_the_qp_velocity() {
        let c = controller(1);
        let others = [mate()];
        let mv = c.plan_move(&centre(), &me(), &others);
        let u = c
            .velocity(&Point::new(11.5, 10.0), &me(), &others)
            .expect("safe start");
        assert_eq!(mv.best, me() + c.settings().dt_s * u);
        assert_eq!(mv.waypoints, vec![me(), mv.best]);
    }

    #[test]
    fn more_pieces_slide_round_a_mate_and_end_nearer_the_slot() {
        let others = [mate()];
        let slot = Point::new(11.5, 10.0);
        let one = controller(1).plan_move(&centre(), &me(), &others);
        let three = controller(3).plan_move(&centre(), &me(), &others);
        assert_eq!(three.waypoints.len(), 4);
        assert_eq!(three.waypoints[0], me());
        // Each piece clear of the mate, and no longer than a third of the step.
        for piece in three.waypoints.windows(2) {
            assert!((piece[1] - piece[0]).norm() <= 1.0 / 3.0 + 1e-12);
            let d =
                crate::geometry::distance_point_segment(&others[0].position, &piece[0], &piece[1]);
            assert!(d >= 0.6, "a piece within {d} m of the mate");
        }
        assert!(
            (three.best - slot).norm() < (one.best - slot).norm(),
            "three pieces end {} m from the slot, one {} m",
            (three.best - slot).norm(),
            (one.best - slot).norm()
        );
    }
}

mod deadlock_escape {
    use super::*;
    use crate::control::formation::Slot;
    use crate::control::vocabulary::AgentSpec;
    use crate::geometry::{Disk, Field, Pose};

    /// The obstacle's centre.
    const OBSTACLE: Point = Point::new(12.0, 10.0);

    /// An agent of radius 0.3 m with one obstacle of radius 0.5 m at [`OBSTACLE`], with or
    /// without the escape.
    fn controller(deadlock_escape: bool) -> CbfController {
        let spec = AgentSpec::new(Slot::new(0.0, 0.0), 0.3);
        let settings = CbfSettings {
            deadlock_escape,
            ..CbfSettings::default()
        };
        let obstacle = [Disk::new(OBSTACLE.x, OBSTACLE.y, 0.5)];
        CbfController::new(Field::new(20.0, 20.0), &obstacle, &spec, settings).expect("settings")
    }

    /// `turns` turns from (10, 10) towards the fixed `slot`, every piece checked clear of
    /// the obstacle (radii sum 0.8 m), `after` called with each turn's end: where the
    /// agent ends.
    fn drive(
        c: &CbfController,
        slot: Point,
        turns: usize,
        mut after: impl FnMut(usize, Point),
    ) -> Point {
        let centre = Pose::new(slot.x, slot.y, 0.0);
        let mut me = Point::new(10.0, 10.0);
        for turn in 0..turns {
            let mv = c.plan_move(&centre, &me, &[]);
            for piece in mv.waypoints.windows(2) {
                let d = crate::geometry::distance_point_segment(&OBSTACLE, &piece[0], &piece[1]);
                assert!(
                    d >= 0.8,
                    "turn {turn}: a piece within {d} m of the obstacle's centre"
                );
            }
            me = mv.best;
            after(turn, me);
        }
        me
    }

    /// The slot, (14, 10), lies straight behind the obstacle from (10, 10): the nominal
    /// velocity points at the obstacle's centre, so the barrier alone cancels it.
    #[test]
    fn a_stalled_agent_goes_round_the_body_in_its_way_and_reaches_its_slot() {
        let slot = Point::new(14.0, 10.0);
        let stuck = drive(&controller(false), slot, 20, |_, _| {});
        assert!(
            stuck.x < 12.0 && (stuck - slot).norm() > 2.0,
            "without the escape the barrier holds it in front of the obstacle: {stuck}"
        );
        let round = drive(&controller(true), slot, 20, |_, _| {});
        assert!(
            (round - slot).norm() < 0.05,
            "with it the agent goes round and reaches its slot: {round}"
        );
    }

    /// A slot at an obstacle's centre can never be reached: with the escape the agent
    /// keeps sliding round the obstacle at its edge (it is never stalled for good), never
    /// nearer than the radii sum and, once there, never farther beyond it than one piece
    /// of its turn (a third of its 1 m step) takes it.
    #[test]
    fn an_agent_whose_slot_lies_inside_an_obstacle_keeps_to_its_edge_safely() {
        drive(&controller(true), OBSTACLE, 60, |turn, me| {
            if turn >= 10 {
                let off_m = (me - OBSTACLE).norm() - 0.8;
                assert!(
                    (0.0..1.0 / 3.0).contains(&off_m),
                    "turn {turn}: {off_m} m off the obstacle's edge"
                );
            }
        });
    }
}

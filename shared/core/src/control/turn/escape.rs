//! A turn among moving obstacles: the escape of an agent that starts its turn inside an
//! obstacle's reach, and the plan round the reach disks with a step to spare.

use crate::control::vocabulary::{Body, MAX_WAYPOINTS, Move, MoveStatus};
use crate::geometry::{
    Disk, DiskGrid, Field, FreeSpace, InflatedPolygon, Point, PolygonLayer, Pose, Vector,
    distance_point_segment, polyline_length_m,
};
use crate::paths::disk_path;
use crate::world::moving_obstacle::MovingObstacle;

use super::{Aim, PLANNING_MARGIN_M, TurnController};

impl TurnController {
    /// [`Self::plan`] before looking ahead: the escape, if any, and the plan round
    /// the reach disks `reach` (with a step to spare) of the `sensed` moving obstacles;
    /// `others` are the sensed bodies; the best point is taken for `aim` when given
    /// (`TurnController::plan`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn plan_turn_around(
        &self,
        step: usize,
        centre: &Pose,
        aim: Option<&Aim>,
        me: &Point,
        others: &[Body],
        sensed: &[&MovingObstacle],
        reach: &[Disk],
    ) -> Move {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let spares_m: Vec<f64> = sensed.iter().map(|m| m.speed_m_per_step).collect();
        let inside = reach
            .iter()
            .any(|d| (me - d.centre).norm() < d.radius_m + keep_m);
        let escape: Option<Vec<Point>> = if inside {
            // Every moving obstacle where it stands, sensed or not (an escape is checked
            // against the true bodies).
            let now: Vec<Disk> = self.moving.iter().map(|m| m.disk_at(step)).collect();
            self.escape_point(me, others, &now, reach, &spares_m)
                .map(|q| vec![*me, q])
                .or_else(|| self.escape_path(me, others, &now, reach, &spares_m))
                .or_else(|| {
                    self.flee_point(me, others, &now, reach)
                        .map(|q| vec![*me, q])
                })
        } else {
            None
        };
        let start = escape
            .as_ref()
            .and_then(|e| e.last().copied())
            .unwrap_or(*me);
        // Planned around with a second step to spare where there is room, so that an
        // obstacle coming closer seldom catches the agent inside its reach.
        let mut bodies = others.to_vec();
        for (m, d) in sensed.iter().zip(reach) {
            let d = d.inflated(m.speed_m_per_step);
            let room_m = (start - d.centre).norm() - keep_m;
            let radius_m = d.radius_m.min(room_m);
            if radius_m > 0.0 {
                bodies.push(Body {
                    position: d.centre,
                    radius_m,
                });
            }
        }
        let Some(escape) = escape else {
            return self.plan_move_within(centre, aim, me, &bodies, self.spec.max_step_m);
        };
        let used_m = polyline_length_m(&escape);
        let left_m = self.spec.max_step_m.map(|s| (s - used_m).max(0.0));
        let mut mv = self.plan_move_within(centre, aim, &start, &bodies, left_m);
        // The escape, then the rest (which begins where the escape ends).
        let mut waypoints = escape;
        waypoints.extend(mv.waypoints.iter().skip(1));
        mv.waypoints = waypoints;
        if mv.waypoints.len() > MAX_WAYPOINTS {
            mv.waypoints.truncate(MAX_WAYPOINTS);
            mv.best = mv.end();
            mv.status = MoveStatus::UnderWay;
        }
        mv
    }

    /// When no straight motion gets out ([`Self::escape_point`]): the shortest path among
    /// every body, the static obstacles and the moving ones where they stand, within the
    /// top speed, to a point just outside every disk of `reach` (grown by the agent's
    /// radius), tried every 10 degrees round the disk it is deepest in, nearest the
    /// straight way out first, a step to spare beyond it before just outside it. A
    /// polyline from `me` to that point.
    fn escape_path(
        &self,
        me: &Point,
        others: &[Body],
        now: &[Disk],
        reach: &[Disk],
        spares_m: &[f64],
    ) -> Option<Vec<Point>> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let budget_m = self.spec.max_step_m.unwrap_or(f64::INFINITY);
        let (i, away_rad) = deepest_of(me, reach, keep_m)?;
        let (deepest, spare_m) = (reach[i], spares_m.get(i).copied().unwrap_or(0.0));
        let big_r = deepest.radius_m + keep_m + PLANNING_MARGIN_M;
        // Planning frame as in BestPointController: the agent a point, every body grown by
        // its radius and the margin, the field inset by as much.
        let grow_m = self.spec.radius_m + PLANNING_MARGIN_M;
        let offset = Vector::new(grow_m, grow_m);
        let field = Field::new(
            (self.field.width_m - 2.0 * grow_m).max(0.0),
            (self.field.height_m - 2.0 * grow_m).max(0.0),
        );
        let near_m = budget_m.min(2.0 * big_r) + grow_m;
        let mut statics = Vec::new();
        let _ = self
            .statics
            .visit_near(me, near_m + self.statics.max_radius_m(), |_, d| {
                statics.push(Disk {
                    centre: d.centre - offset,
                    radius_m: d.radius_m + grow_m,
                });
                std::ops::ControlFlow::<()>::Continue(())
            });
        let bodies: Vec<Disk> = others
            .iter()
            .map(|b| Disk {
                centre: b.position - offset,
                radius_m: b.radius_m + grow_m,
            })
            .chain(now.iter().map(|d| Disk {
                centre: d.centre - offset,
                radius_m: d.radius_m + grow_m,
            }))
            .collect();
        let (statics, bodies) = (DiskGrid::new(statics), DiskGrid::new(bodies));
        let layers = [&statics, &bodies];
        // The polygons near enough to matter, grown and moved into the planning frame.
        let mut polygons = Vec::new();
        let near = Vector::repeat(near_m);
        let _ = self.polygons.visit_box(&(me - near), &(me + near), |_, p| {
            polygons.push(InflatedPolygon::from_polygon(
                p.polygon().translated(&-offset),
                grow_m,
            ));
            std::ops::ControlFlow::<()>::Continue(())
        });
        let polygons = PolygonLayer::new(polygons);
        let space = FreeSpace::new(field, &layers).with_polygons(&polygons);
        let me_p = me - offset;
        // A step to spare beyond the disk first, then just outside it.
        for (off_deg, out_r) in offsets_deg(180)
            .map(|off| (off, big_r + spare_m))
            .chain(offsets_deg(180).map(|off| (off, big_r)))
        {
            let rad = away_rad + off_deg.to_radians();
            let q = deepest.centre + out_r * Vector::new(rad.cos(), rad.sin());
            if (q - me).norm() > budget_m
                || reach
                    .iter()
                    .any(|d| (q - d.centre).norm() < d.radius_m + keep_m)
            {
                continue;
            }
            let q_p = q - offset;
            if !space.is_free(&q_p, 0.0) {
                continue;
            }
            let Ok(path) = disk_path::shortest_path(&space, &me_p, &q_p) else {
                continue;
            };
            if path.length_m() > budget_m {
                continue;
            }
            let mut points: Vec<Point> = path
                .polyline(0.5 * PLANNING_MARGIN_M)
                .iter()
                .map(|p| p + offset)
                .collect();
            if points.len() < 2 || points.len() > MAX_WAYPOINTS / 2 {
                continue;
            }
            // Exactly from the agent to the escape point.
            points[0] = *me;
            if let Some(last) = points.last_mut() {
                *last = q;
            }
            return Some(points);
        }
        None
    }

    /// A point just outside every disk of `reach` (grown by the agent's radius), reached
    /// from `me` by a straight motion clear of every body, the static obstacles, the
    /// moving ones where they stand and the field's edges, within the top speed.
    fn escape_point(
        &self,
        me: &Point,
        others: &[Body],
        now: &[Disk],
        reach: &[Disk],
        spares_m: &[f64],
    ) -> Option<Point> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        // The disk it is deepest in, and that obstacle's speed: how far beyond the disk
        // the agent goes if it can, to keep a step to spare.
        let (i, away_rad) = deepest_of(me, reach, keep_m)?;
        let (deepest, spare_m) = (reach[i], spares_m.get(i).copied().unwrap_or(0.0));
        let away = me - deepest.centre;
        let budget_m = self.spec.max_step_m.unwrap_or(f64::INFINITY);
        for off_deg in offsets_deg(150) {
            let rad = away_rad + off_deg.to_radians();
            let v = Vector::new(rad.cos(), rad.sin());
            // |me + t v - c| = R, the larger root (leaving the disk).
            let leave = |big_r: f64| {
                let b = v.dot(&away);
                let disc = b * b - (away.norm_squared() - big_r * big_r);
                (disc >= 0.0).then(|| -b + disc.sqrt())
            };
            let Some(t_out) = leave(deepest.radius_m + keep_m + PLANNING_MARGIN_M) else {
                continue;
            };
            if !(t_out > 0.0 && t_out <= budget_m) {
                continue;
            }
            // As far as a step to spare, or the top speed, allows; else just out.
            let t_far = leave(deepest.radius_m + spare_m + keep_m + PLANNING_MARGIN_M)
                .map_or(t_out, |t| t.min(budget_m));
            for t in [t_far, t_out] {
                if let Some(q) = self.escape_to(me, v, t, others, reach, now, true) {
                    return Some(q);
                }
            }
        }
        None
    }

    /// When there is no way out of the obstacle's reach within the top speed (it came
    /// too close, or struck the agent): a straight motion as far from it as the top speed
    /// allows, radially or up to 90 degrees off, clear of everything.
    fn flee_point(
        &self,
        me: &Point,
        others: &[Body],
        now: &[Disk],
        reach: &[Disk],
    ) -> Option<Point> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let budget_m = self.spec.max_step_m?;
        let (i, away_rad) = deepest_of(me, reach, keep_m)?;
        let deepest = reach[i];
        for off_deg in offsets_deg(90) {
            let rad = away_rad + off_deg.to_radians();
            let v = Vector::new(rad.cos(), rad.sin());
            if let Some(q) = self.escape_to(me, v, budget_m, others, reach, now, false)
                && (q - deepest.centre).norm() > (me - deepest.centre).norm()
            {
                return Some(q);
            }
        }
        None
    }

    /// `me + t v` if the straight motion there is clear of every body, the static
    /// obstacles, the moving ones where they stand (`now`) and the field's edges, and,
    /// with `leave_reach`, it ends outside every disk of `reach` (grown by the agent's
    /// radius).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn escape_to(
        &self,
        me: &Point,
        v: Vector,
        t: f64,
        others: &[Body],
        reach: &[Disk],
        now: &[Disk],
        leave_reach: bool,
    ) -> Option<Point> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let clear_m = self.spec.radius_m + PLANNING_MARGIN_M;
        {
            let q = me + t * v;
            let outside_reach = !leave_reach
                || reach
                    .iter()
                    .all(|d| (q - d.centre).norm() >= d.radius_m + keep_m);
            let in_field = self.field.signed_inset_m(&q) >= clear_m;
            // The motion keeps half the planning margin from every body (the agent may
            // start its turn touching one, at the margin); its end the whole margin, so
            // the rest of the turn is planned from a free point.
            let segment_clear = |d: &Disk| {
                d.signed_distance_to_segment_m(me, &q)
                    >= self.spec.radius_m + 0.5 * PLANNING_MARGIN_M
                    && d.signed_distance_m(&q) >= clear_m
            };
            let clear_of_bodies = others.iter().all(|b| {
                segment_clear(&Disk {
                    centre: b.position,
                    radius_m: b.radius_m,
                })
            });
            // An agent a moving obstacle struck (it overlaps it) may leave it, never
            // coming closer to its centre.
            let clear_of_moving = now.iter().all(|d| {
                let start_m = (me - d.centre).norm();
                if start_m < d.radius_m + self.spec.radius_m {
                    distance_point_segment(&d.centre, me, &q) >= start_m
                        && d.signed_distance_m(&q) >= clear_m
                } else {
                    segment_clear(d)
                }
            });
            let clear_of_statics =
                self.statics
                    .all_near(me, t + clear_m + self.statics.max_radius_m(), segment_clear);
            let grow = Vector::repeat(clear_m);
            let (lo, hi) = (
                Point::new(me.x.min(q.x), me.y.min(q.y)) - grow,
                Point::new(me.x.max(q.x), me.y.max(q.y)) + grow,
            );
            let clear_of_polygons = self
                .polygons
                .visit_box(&lo, &hi, |_, p| {
                    let clear = p.signed_distance_to_segment_m(me, &q)
                        >= self.spec.radius_m + 0.5 * PLANNING_MARGIN_M
                        && p.signed_distance_m(&q) >= clear_m;
                    match clear {
                        true => std::ops::ControlFlow::Continue(()),
                        false => std::ops::ControlFlow::Break(()),
                    }
                })
                .is_continue();
            (outside_reach
                && in_field
                && clear_of_bodies
                && clear_of_moving
                && clear_of_statics
                && clear_of_polygons)
                .then_some(q)
        }
    }
}

/// The disk of `reach` that `me` is deepest in (each grown by `keep_m`), by index, and the
/// direction straight away from its centre, in radians.
fn deepest_of(me: &Point, reach: &[Disk], keep_m: f64) -> Option<(usize, f64)> {
    let depth = |d: &Disk| d.radius_m + keep_m - (me - d.centre).norm();
    let (i, d) = reach
        .iter()
        .enumerate()
        .max_by(|(_, a), (_, b)| depth(a).total_cmp(&depth(b)))?;
    let away = me - d.centre;
    let away_rad = if away.norm() > 0.0 {
        away.y.atan2(away.x)
    } else {
        0.0
    };
    Some((i, away_rad))
}

/// Turns off the straight way out, in degrees, nearest first: 0, 10, -10, 20, -20, ...,
/// `max_deg`, `-max_deg` (`max_deg` a multiple of 10).
fn offsets_deg(max_deg: i32) -> impl Iterator<Item = f64> {
    (0..=max_deg / 5).map(|k: i32| f64::from(10 * ((k + 1) / 2) * if k % 2 == 0 { 1 } else { -1 }))
}

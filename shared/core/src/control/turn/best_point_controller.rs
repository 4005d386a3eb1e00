//! The paper's controller for one agent: the exact best point, then the shortest path to
//! it.

use crate::control::best_point::{self, BestPointError};
use crate::control::formation::Slot;
use crate::control::tracking;
use crate::control::vocabulary::{AgentSpec, Body, MAX_WAYPOINTS, Move, MoveStatus};
use crate::geometry::{
    Disk, DiskGrid, Field, FreeSpace, InflatedPolygon, Point, Polygon, PolygonLayer, Pose,
    RegionGrid, Vector,
};
use crate::paths::disk_path::{self, DiskPath};
use crate::world::scenario::ScenarioMap;

use super::PLANNING_MARGIN_M;
#[cfg(doc)]
use super::TurnController;
use super::give_way::{self, LaggingMate, Planning};

/// The paper's controller for one agent (exact best point, then the shortest path to it):
/// everything the agent needs to take its turns; built once, reused every step.
///
/// The agent is planned as a point: every other body is inflated by the agent's radius
/// plus [`PLANNING_MARGIN_M`], and the field is shrunk by the same amount on every side.
/// The controllers take a field anchored at the origin, so planning happens in a frame
/// shifted by that inset; results are mapped back (exactly for the slot and the agent's
/// own position).
#[derive(Clone, Debug)]
pub struct BestPointController {
    /// The field the agent's centre may use, in the planning frame.
    field: Field,
    /// Planning frame origin in world coordinates (the inset on both axes).
    offset: Vector,
    slot: Slot,
    radius_m: f64,
    /// Static obstacles inflated by this agent's radius and the planning margin, in the
    /// planning frame.
    obstacles: DiskGrid,
    /// With limited sensing: the obstacles with their true radii in world coordinates
    /// (same order as `obstacles`), to pick the ones the agent senses each turn.
    sensed_from: Option<DiskGrid>,
    /// Static polygon obstacles (boxed: most runs have none).
    polygons: Box<PolygonObstacles>,
    spec: AgentSpec,
}

/// Where an agent with a top speed and a look-ahead is heading
/// ([`BestPointController::plan_move_aiming`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Aim {
    /// The first point of its least-deviation track, at most its top speed away
    /// ([`crate::control::tracking::lead_point`]); its slot now when it can follow its slot.
    pub lead: Point,
    /// Its slot over the look-ahead, world coordinates: `slots[0]` this turn's (where it
    /// should stand after this move), `slots[j]` the one after `j + 1` moves.
    pub slots: Vec<Point>,
    /// The mates near it that lag far behind their slots, which it gives way to: it
    /// predicts the track each would search round the obstacles (the first move round
    /// the bodies standing, this agent's included) and keeps its own later moves off it.
    pub lagging: Vec<LaggingMate>,
}

/// The best point for a goal and the path there (`None`: the agent stands on it).
type Found = Result<(Point, Option<DiskPath>), BestPointError>;

/// The polygon obstacles of one agent's controller.
#[derive(Clone, Debug, Default)]
struct PolygonObstacles {
    /// Grown by the agent's radius and the planning margin, in the planning frame.
    grown: PolygonLayer,
    /// As given, in world coordinates (same order as `grown`), to pick the ones the agent
    /// senses each turn.
    given: Vec<Polygon>,
    /// The regions the map's blocked cells close off, for this agent's clearance, in the
    /// planning frame (with a map only).
    regions: Option<RegionGrid>,
}

/// The move an agent would make anyway, and what it was made from
/// ([`BestPointController::plan_move_aiming`]).
#[derive(Clone, Copy)]
struct Followed<'m> {
    /// Its path to the best point, cut at its top speed.
    mv: &'m Move,
    /// The best point (planning frame) when the agent is not on it.
    best_p: Option<Point>,
    /// Where the agent stands (world coordinates).
    me: &'m Point,
    /// Its top speed, metres per step.
    max_step_m: f64,
}

impl BestPointController {
    /// The controller of agent `spec` in `field` among `obstacles` (true radii).
    pub fn new(field: Field, obstacles: &[Disk], spec: &AgentSpec) -> Self {
        let grow_m = spec.radius_m + PLANNING_MARGIN_M;
        let offset = Vector::new(grow_m, grow_m);
        Self {
            field: Field::new(
                (field.width_m - 2.0 * grow_m).max(0.0),
                (field.height_m - 2.0 * grow_m).max(0.0),
            ),
            offset,
            slot: spec.slot,
            radius_m: spec.radius_m,
            obstacles: DiskGrid::new(
                obstacles
                    .iter()
                    .map(|o| Disk {
                        centre: o.centre - offset,
                        radius_m: o.radius_m + grow_m,
                    })
                    .collect(),
            ),
            sensed_from: spec
                .sensing_radius_m
                .map(|_| DiskGrid::new(obstacles.to_vec())),
            polygons: Box::default(),
            spec: *spec,
        }
    }

    /// The same controller also planning round the static `polygons` (world
    /// coordinates). With limited sensing, a polygon is planned round whole from the turn
    /// any part of it comes within the sensing radius.
    pub fn with_polygons(mut self, polygons: &[Polygon]) -> Self {
        let grow_m = self.radius_m + PLANNING_MARGIN_M;
        self.polygons = Box::new(PolygonObstacles {
            grown: PolygonLayer::new(
                polygons
                    .iter()
                    .map(|p| InflatedPolygon::from_polygon(p.translated(&-self.offset), grow_m))
                    .collect(),
            ),
            given: polygons.to_vec(),
            regions: None,
        });
        self
    }

    /// The same controller knowing that the polygons from `map.first_piece` on are the
    /// blocked cells of `map`: it proves goals in regions the map closes off unreachable
    /// at once ([`RegionGrid`]). Call after [`Self::with_polygons`].
    pub fn with_map(mut self, map: &ScenarioMap) -> Self {
        let clearance_m = self.radius_m + PLANNING_MARGIN_M - disk_path::FREE_TOLERANCE_M;
        let regions = map
            .grid
            .regions(|c| map.blocks(c), clearance_m, -self.offset);
        self.polygons.regions = Some(regions);
        self
    }

    /// The grown polygons (planning frame) the agent senses from `me`, in polygon order;
    /// `None` when it senses everything.
    fn sensed_polygons(&self, me: &Point) -> Option<PolygonLayer> {
        let sensing_m = self.spec.sensing_radius_m?;
        let grow_m = self.radius_m + PLANNING_MARGIN_M;
        let here = me - self.offset;
        let reach = Vector::repeat(sensing_m + grow_m);
        let mut seen = Vec::new();
        let _ = self
            .polygons
            .grown
            .visit_box(&(here - reach), &(here + reach), |i, _| {
                if self.polygons.given[i].distance_m(me) <= sensing_m {
                    seen.push(i);
                }
                std::ops::ControlFlow::<()>::Continue(())
            });
        seen.sort_unstable();
        let grown = self.polygons.grown.polygons();
        Some(PolygonLayer::new(
            seen.iter().map(|&i| grown[i].clone()).collect(),
        ))
    }

    /// The inflated obstacles (planning frame) the agent senses from `me`, in obstacle
    /// order; `None` when it senses everything.
    fn sensed_obstacles(&self, me: &Point) -> Option<DiskGrid> {
        let (grid, sensing_m) = (self.sensed_from.as_ref()?, self.spec.sensing_radius_m?);
        let mut seen = Vec::new();
        let _ = grid.visit_near(me, sensing_m + grid.max_radius_m(), |i, d| {
            if self.spec.senses(me, &d.centre, d.radius_m) {
                seen.push(i);
            }
            std::ops::ControlFlow::<()>::Continue(())
        });
        seen.sort_unstable();
        let inflated = self.obstacles.disks();
        Some(DiskGrid::new(seen.iter().map(|&i| inflated[i]).collect()))
    }

    /// This agent's radius, in metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The ideal slot when the centre is at `centre`.
    pub fn slot_position(&self, centre: &Pose) -> Point {
        self.slot.ideal_position(centre)
    }

    /// Plan this agent's move while every `other` body stands still: the reachable free
    /// point nearest to the slot and the shortest path there. With limited sensing, only
    /// the obstacles it senses are planned around (`others` are taken as given: see
    /// [`TurnController::plan`], which picks the sensed ones); the top speed is
    /// [`TurnController`]'s business too.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        self.plan_move_within(centre, me, others, self.spec.max_step_m)
    }

    /// [`Self::plan_move`] with the path cut at `max_step_m` (absent: not cut) instead of
    /// the agent's top speed: what is left of a turn that began with another motion.
    pub fn plan_move_within(
        &self,
        centre: &Pose,
        me: &Point,
        others: &[Body],
        max_step_m: Option<f64>,
    ) -> Move {
        self.plan_move_with_chords(centre, me, others, max_step_m, f64::INFINITY)
    }

    /// [`Self::plan_move_within`] with every chord drawn for an arc of the path at most
    /// `max_chord_m` long ([`DiskPath::polyline_with_chords`]; infinite: no limit), for a
    /// unicycle, which can stop inside a chord only where it is clear.
    pub fn plan_move_with_chords(
        &self,
        centre: &Pose,
        me: &Point,
        others: &[Body],
        max_step_m: Option<f64>,
        max_chord_m: f64,
    ) -> Move {
        self.plan_move_aiming(centre, None, me, others, max_step_m, max_chord_m)
    }

    /// [`Self::plan_move_with_chords`] for an agent that knows where its slot is going
    /// (`aim`: see [`Aim`]; `None`: it chases its slot as usual).
    ///
    /// When mates far behind their slots would pass where the agent goes
    /// ([`Aim::lagging`]), it takes the first move of the best track round the obstacles
    /// whose later moves keep off their predicted tracks: it gives way (`give_way.rs`;
    /// the move is free of every body standing this turn and within the top speed).
    ///
    /// Else, when one of the aim's slots lies where the agent does not fit among the static
    /// obstacles (its slot's way ahead crosses an obstacle), the agent takes the first
    /// move of the best track round them that a lattice search over the aim's slots finds
    /// ([`tracking::first_move_round_obstacles`]; the mates stand where they are for that
    /// move only): a straight move, free of every body standing this turn and within the
    /// top speed (status [`MoveStatus::UnderWay`], its best point the move's end), unless
    /// that move is the one the agent would make anyway. Measured on the paper, dense,
    /// narrow and large scenarios capped at twice the centre's step, it lowered the mean
    /// deviation by 11 % to 50 % and the largest by 23 % to 61 %
    /// (`docs/measurements.md`).
    ///
    /// Otherwise, when the agent cannot follow its slot (the aim's lead point is not its
    /// slot), no obstacle stands between the agent and its best point (mates may) and the
    /// straight move to the lead point is clear, the agent takes that move (status
    /// [`MoveStatus::UnderWay`], its best point the lead point). Otherwise something
    /// stands in the way, and the agent follows its path as usual, round the obstacle,
    /// rather than pressing against it towards a lead point behind it. (Taking the lead
    /// whenever its own segment was clear made agents turn back and forth in front of
    /// an obstacle, between the lead and a path round the far side: in
    /// swarm200-parallel one agent fell 12.8 m behind that way. Judging by the path
    /// alone, mates included, gave up most of the gain in large: mean deviation 0.130 m
    /// against 0.109 m with mates left out of the test. Heading for the best point of a
    /// slot some steps ahead when the lead point is blocked, an intercept, did worse:
    /// the shortest path to a far slot's best point may start the other way round an
    /// obstacle, and the agent then turns back and forth between the two.)
    pub fn plan_move_aiming(
        &self,
        centre: &Pose,
        aim: Option<&Aim>,
        me: &Point,
        others: &[Body],
        max_step_m: Option<f64>,
        max_chord_m: f64,
    ) -> Move {
        let slot = self.slot_position(centre);
        let grow_m = self.radius_m + PLANNING_MARGIN_M;
        let agents = DiskGrid::new(
            others
                .iter()
                .map(|b| Disk {
                    centre: b.position - self.offset,
                    radius_m: b.radius_m + grow_m,
                })
                .collect(),
        );
        let sensed = self.sensed_obstacles(me);
        let layers = [sensed.as_ref().unwrap_or(&self.obstacles), &agents];
        let sensed_polygons = match self.polygons.grown.is_empty() {
            true => None,
            false => self.sensed_polygons(me),
        };
        let polygons = sensed_polygons.as_ref().unwrap_or(&self.polygons.grown);
        let space = FreeSpace::new(self.field, &layers)
            .with_polygons(polygons)
            .with_regions(self.polygons.regions.as_ref());
        let me_p = me - self.offset;
        let mut paths = disk_path::PathsFrom::new(&space, &me_p);
        let found = self.best_and_path(&space, &mut paths, &slot, me);
        let (Some(aim), Some(max_step_m)) = (aim, max_step_m) else {
            return self.follow(slot, me, found, max_step_m, max_chord_m);
        };
        let obstacles_only = [layers[0]];
        let statics = FreeSpace::new(self.field, &obstacles_only)
            .with_polygons(polygons)
            .with_regions(self.polygons.regions.as_ref());
        // The best point, when the agent is not on it.
        let best_p = match &found {
            Ok((best_p, Some(_))) => Some(*best_p),
            _ => None,
        };
        let followed = self.follow(slot, me, found, Some(max_step_m), max_chord_m);
        let planning = Planning {
            field: self.field,
            offset: self.offset,
            radius_m: self.radius_m,
            obstacles: layers[0],
            polygons,
            regions: self.polygons.regions.as_ref(),
            others,
        };
        let anyway = Followed {
            mv: &followed,
            best_p,
            me,
            max_step_m,
        };
        self.aimed_move(aim, &space, &statics, &planning, anyway)
            .unwrap_or(followed)
    }

    /// The move an agent with `aim` takes instead of the one it would make `anyway` (its
    /// path to the best point, cut at its top speed), if any: see
    /// [`Self::plan_move_aiming`]. `space` is this turn's free space (mates included),
    /// `statics` the same without the mates.
    fn aimed_move(
        &self,
        aim: &Aim,
        space: &FreeSpace<'_>,
        statics: &FreeSpace<'_>,
        planning: &Planning<'_>,
        anyway: Followed<'_>,
    ) -> Option<Move> {
        let Followed {
            mv: followed,
            best_p,
            me,
            max_step_m,
        } = anyway;
        let slot = followed.slot;
        // The straight move to `best` (world coordinates).
        let straight_to = |best: Point| Move {
            end_heading_rad: None,
            slot,
            best,
            status: if (best - slot).norm() <= 1e-9 {
                MoveStatus::AtSlot
            } else {
                MoveStatus::UnderWay
            },
            waypoints: if best == *me {
                vec![*me]
            } else {
                vec![*me, best]
            },
        };
        let me_p = me - self.offset;
        // Mates far behind whose way comes near: the agent keeps its later moves off
        // their predicted tracks.
        let yields = give_way::predicted_tracks(planning, &aim.lagging, statics, me);
        if let Some(end_p) = give_way::first_move_giving_way(
            planning, &aim.slots, aim.lead, space, &yields, followed, me, max_step_m,
        ) {
            let follows = matches!(followed.waypoints[..], [_, end] if end - self.offset == end_p);
            let end = if end_p == me_p {
                *me
            } else {
                end_p + self.offset
            };
            return (!follows).then(|| straight_to(end));
        }
        // The slot's way ahead crosses a static obstacle: the first move of the best
        // track round it.
        if aim
            .slots
            .iter()
            .any(|s| !statics.is_free(&(s - self.offset), 0.0))
        {
            let slots_p: Vec<Point> = aim.slots.iter().map(|s| s - self.offset).collect();
            // The followed move and the lead are candidates too, when straight.
            let firsts: Vec<Point> = match followed.waypoints[..] {
                [_, end] => vec![end - self.offset, aim.lead - self.offset],
                _ => vec![aim.lead - self.offset],
            };
            let end_p = tracking::first_move_round_obstacles(
                space,
                statics,
                &me_p,
                &slots_p,
                &firsts,
                max_step_m,
                tracking::round_lattice_for(self.radius_m),
            )?;
            let follows = matches!(followed.waypoints[..], [_, end] if end - self.offset == end_p);
            let end = if end_p == me_p {
                *me
            } else {
                end_p + self.offset
            };
            return (!follows).then(|| straight_to(end));
        }
        if aim.slots.first() == Some(&aim.lead) {
            return None;
        }
        // Only where no obstacle stands between the agent and its best point (mates
        // may: they move on): round an obstacle the path decides, or the agent would
        // turn back and forth between the two.
        let lead_p = aim.lead - self.offset;
        let open = best_p.is_some_and(|b| statics.is_segment_free(&me_p, &b, 0.0));
        (open && space.is_free(&lead_p, 0.0) && space.is_segment_free(&me_p, &lead_p, 0.0))
            .then(|| straight_to(aim.lead))
    }

    /// The best point for `goal` (world coordinates) seen from `me`, and the shortest path
    /// there (`None`: the agent stands on it), `paths` holding the searches from `me`.
    fn best_and_path(
        &self,
        space: &FreeSpace<'_>,
        paths: &mut disk_path::PathsFrom<'_, '_>,
        goal: &Point,
        me: &Point,
    ) -> Found {
        let (goal_p, me_p) = (goal - self.offset, me - self.offset);
        let mut found: Option<(Point, DiskPath)> = None;
        let best_p =
            best_point::nearest_reachable_free_point(space, &goal_p, &me_p, |p| {
                match paths.shortest_path(p) {
                    Ok(path) => {
                        found = Some((*p, path));
                        true
                    }
                    Err(_) => false,
                }
            })?;
        if best_p == me_p {
            return Ok((best_p, None));
        }
        // The closure accepted `best` last, so `found` holds its path.
        match found {
            Some((p, path)) if p == best_p => Ok((best_p, Some(path))),
            _ => Ok((me_p, None)),
        }
    }

    /// The move along `found` (the best point for `slot`, in the planning frame, and the
    /// path there), cut at `max_step_m`, for an agent at `me`.
    fn follow(
        &self,
        slot: Point,
        me: &Point,
        found: Found,
        max_step_m: Option<f64>,
        max_chord_m: f64,
    ) -> Move {
        let (slot_p, me_p) = (slot - self.offset, me - self.offset);
        // Back to world coordinates, keeping the slot and the start bit-exact.
        let to_world = |p: &Point| -> Point {
            if *p == slot_p {
                slot
            } else if *p == me_p {
                *me
            } else {
                p + self.offset
            }
        };
        let stay = |status| Move {
            end_heading_rad: None,
            slot,
            best: *me,
            status,
            waypoints: vec![*me],
        };
        let (best_p, path) = match found {
            Ok(found) => found,
            Err(BestPointError::NoFreePoint) => return stay(MoveStatus::NoFreePoint),
        };
        let best = to_world(&best_p);
        let Some(path) = path else {
            let status = if best_p == me_p && (slot - best).norm() <= 1e-9 {
                MoveStatus::AtSlot
            } else {
                MoveStatus::Stayed
            };
            return stay(status);
        };
        // With a top speed the agent follows the path that far: cut on the path itself
        // (on an arc's circle, not on a chord), so it stops at a free point.
        let under_way = max_step_m.and_then(|s| path.prefix(s));
        let followed = under_way.as_ref().unwrap_or(&path);
        let mut waypoints: Vec<Point> = followed
            .polyline_with_chords(0.5 * PLANNING_MARGIN_M, max_chord_m)
            .iter()
            .map(to_world)
            .collect();
        if waypoints.len() > MAX_WAYPOINTS {
            return stay(MoveStatus::PathTooLong);
        }
        // The polyline starts at the agent and ends at the best point (or the cut),
        // exactly.
        if let Some(first) = waypoints.first_mut() {
            *first = *me;
        }
        if under_way.is_none()
            && let Some(last) = waypoints.last_mut()
        {
            *last = best;
        }
        let status = if under_way.is_some() {
            MoveStatus::UnderWay
        } else if (slot - best).norm() <= 1e-9 {
            MoveStatus::AtSlot
        } else {
            MoveStatus::Deviated
        };
        Move {
            end_heading_rad: None,
            slot,
            best,
            status,
            waypoints,
        }
    }
}

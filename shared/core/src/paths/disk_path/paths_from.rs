//! Shortest paths from one start to many goals, sharing one barrier graph.

use super::barrier_graph::BarrierGraph;
use super::error::PathError;
use super::path::DiskPath;
use super::shortest_path::search_path;
use super::tolerance::FREE_TOLERANCE_M;
use crate::geometry::{FreeSpace, Point};

/// Shortest paths from one start to many goals in the same free space: the reachability
/// test of one agent's turn, where the candidate best points are tried one after another.
///
/// [`PathsFrom::shortest_path`] answers exactly what
/// [`shortest_path`](super::shortest_path()) answers (the same path, bit for bit, or the
/// same error). It is faster when the goal lies in another free component than the start,
/// as when the agent stands in a pocket closed by overlapping disks and its slot lies
/// outside: [`shortest_path`](super::shortest_path()) has to exhaust the pocket before it
/// may give up, while here a barrier graph of the disks around the start, built once and
/// shared by every goal, shows most such goals unreachable in one pass over its edges. The
/// barrier test is sound (a goal it rejects is unreachable, so no answer changes); a goal
/// it does not reject goes to the search.
#[derive(Debug)]
pub struct PathsFrom<'a, 's> {
    space: &'a FreeSpace<'s>,
    from: Point,
    from_is_free: bool,
    /// Built on the first goal that needs it; rebuilt larger for a goal it does not cover.
    barriers: Option<BarrierGraph>,
}

impl<'a, 's> PathsFrom<'a, 's> {
    /// Paths from `from` in `space` (already inflated disks, as for
    /// [`shortest_path`](super::shortest_path())).
    pub fn new(space: &'a FreeSpace<'s>, from: &Point) -> Self {
        Self {
            space,
            from: *from,
            from_is_free: space.is_free(from, FREE_TOLERANCE_M),
            barriers: None,
        }
    }

    /// The common start of every path.
    pub fn start(&self) -> Point {
        self.from
    }

    /// `shortest_path(space, from, to)`, the same answer bit for bit.
    pub fn shortest_path(&mut self, to: &Point) -> Result<DiskPath, PathError> {
        if !self.from_is_free {
            return Err(PathError::StartNotFree);
        }
        if !self.space.is_free(to, FREE_TOLERANCE_M) {
            return Err(PathError::GoalNotFree);
        }
        let from = self.from;
        if from == *to || self.space.is_segment_free(&from, to, FREE_TOLERANCE_M) {
            return Ok(DiskPath::straight(from, *to));
        }
        if self.barriers_for(to).separates(&from, to) {
            return Err(PathError::Unreachable);
        }
        search_path(self.space, &from, to)
    }

    /// The barrier graph, covering the disks near the start and near `to`.
    fn barriers_for(&mut self, to: &Point) -> &mut BarrierGraph {
        // Pockets are small: a few of the largest disks around the start or the goal.
        let pad_m = BARRIER_PAD_RADII * self.space.max_radius_m();
        let needed_m = (to - self.from).norm() + pad_m;
        let reach_m = match &self.barriers {
            Some(graph) if graph.reach_m >= needed_m => None,
            Some(graph) => Some(needed_m.max(2.0 * graph.reach_m)),
            None => Some(needed_m),
        };
        if let Some(reach_m) = reach_m {
            self.barriers = Some(BarrierGraph::new(self.space, &self.from, reach_m));
        }
        self.barriers.as_mut().expect("built above")
    }
}

/// How far around the start a [`PathsFrom`] barrier graph reaches beyond its farthest goal,
/// in largest disk radii.
const BARRIER_PAD_RADII: f64 = 4.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DiskGrid;
    use crate::paths::disk_path::shortest_path::shortest_path;
    use crate::paths::disk_path::tests::packed_block;

    #[test]
    fn paths_from_a_pocket_match_shortest_path() {
        let (field, disks) = packed_block();
        let grid = DiskGrid::new(disks.clone());
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        // An agent's position in the block: a pocket.
        let me = Point::new(5.5, 4.5);
        let mut paths = PathsFrom::new(&space, &me);
        let goals = [
            Point::new(5.6, 4.3),   // same pocket, straight
            Point::new(6.5, 4.5),   // a neighbouring pocket
            Point::new(1.0, 1.0),   // outside the block
            Point::new(20.0, 1.0),  // outside the field
            Point::new(5.0, 6.0),   // inside a disk
            Point::new(13.0, 11.0), // far outside the block
        ];
        let mut unreachable = 0;
        for goal in &goals {
            let fast = paths.shortest_path(goal);
            let slow = shortest_path(&space, &me, goal);
            assert_eq!(format!("{fast:?}"), format!("{slow:?}"), "{goal:?}");
            unreachable += usize::from(fast == Err(PathError::Unreachable));
        }
        assert_eq!(unreachable, 3);
        // The barrier graph alone shows the pocket closed.
        let graph = paths
            .barriers
            .as_mut()
            .expect("built for the blocked goals");
        assert!(graph.separates(&me, &Point::new(1.0, 1.0)));
        assert!(!graph.separates(&me, &Point::new(5.4, 4.6)));
        // From outside the block, a path around it.
        let mut outside = PathsFrom::new(&space, &Point::new(1.0, 1.0));
        let around = outside.shortest_path(&Point::new(13.0, 11.0));
        assert_eq!(
            around,
            shortest_path(&space, &Point::new(1.0, 1.0), &Point::new(13.0, 11.0))
        );
        assert!(around.is_ok());
    }
}

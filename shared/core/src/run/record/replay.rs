//! The centre's course rebuilt from a run's record ([`replay_course`]), to go on with a
//! run that was stopped.

use super::Step;
use crate::geometry::Pose;
use crate::world::course::Course;
use crate::world::scenario::Scenario;

/// The course of `scenario` along `first_plan`, advanced through the recorded `steps`
/// (from step 0, in order) as the run advanced it: before step `k`, with every agent
/// where step `k - 1` left it, alive or not as it was then. Every decision of a course
/// depends on that geometry alone, so the course comes out as the run's was, with its
/// replans, waits and obstacles found (only the planning times differ).
///
/// Each step's centre is checked against the one recorded: `Err(k)` names the first step
/// `k` whose recorded centre is not the one the course gives (a record of another
/// scenario or plan), or the first step after the course's end.
pub fn replay_course<'a>(
    scenario: &'a Scenario,
    first_plan: &[Pose],
    steps: &[Step],
) -> Result<Course<'a>, usize> {
    let mut course = Course::new(scenario, first_plan);
    for pair in steps.windows(2) {
        let (before, step) = (&pair[0], &pair[1]);
        let bodies = before.bodies(scenario);
        let alive: Vec<bool> = before.agents.iter().map(|a| a.alive).collect();
        match course.advance(step.step, &bodies, &alive) {
            Some(centre) if centre == step.centre => {}
            _ => return Err(step.step),
        }
    }
    Ok(course)
}

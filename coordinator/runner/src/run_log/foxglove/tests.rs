//! The scene's JSON and what it draws.

use super::*;
use shared::run::simulate::{plan_centre_path, simulate_along};

/// The scenes of a run with moving obstacles, sensing and unknown obstacles: the
/// template's JSON is the value `serde_json` writes of the same message.
#[test]
fn the_scene_written_from_the_template_is_the_one_serde_writes() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    for name in ["moving-field.toml", "discovered-wall.toml", "paper.toml"] {
        let scenario = Scenario::load(&file.join(name)).expect("scenario");
        let path = plan_centre_path(&scenario).expect("path");
        let run = simulate_along(&scenario, &path).expect("run");
        let known = vec![true; scenario.unknown.len()];
        for step in run.steps.iter().step_by(7) {
            let slots = slots_in_formation(step);
            let scene = scene_update(&scenario, step, &known, step.step == 0, Some(&slots), 0);
            // Appended after what the buffer held, as the writer's reused buffer does.
            let mut buffer = b"left over".to_vec();
            scene.write_json(&mut buffer);
            let fast: Value = serde_json::from_slice(&buffer[9..]).expect("JSON");
            let serde = serde_json::to_value(&scene).expect("JSON");
            assert_eq!(fast, serde, "{name}, step {}", step.step);
        }
    }
}

/// The slots drawn in the formation frame land on the field's slots once the frame
/// is placed at the centre; the polygons are drawn as closed loops with the obstacles;
/// a best point is drawn only off its slot.
#[test]
fn slots_follow_the_formation_frame_and_polygons_are_drawn() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let scenario = Scenario::load(&file.join("polygon-corridor.toml")).expect("scenario");
    assert!(!scenario.polygons.is_empty());
    let path = plan_centre_path(&scenario).expect("path");
    let run = simulate_along(&scenario, &path).expect("run");
    for step in &run.steps {
        let slots = slots_in_formation(step);
        let (sin, cos) = step.centre.heading_rad.sin_cos();
        for (local, agent) in slots.iter().zip(&step.agents) {
            let field = step.centre.position()
                + shared::geometry::Vector::new(
                    cos * local.x - sin * local.y,
                    sin * local.x + cos * local.y,
                );
            assert!(
                (field - agent.slot).norm() < SCENE_RESOLUTION_M,
                "step {}",
                step.step
            );
        }
        let scene = serde_json::to_value(scene_update(
            &scenario,
            step,
            &[],
            step.step == 0,
            Some(&slots),
            0,
        ))
        .expect("JSON");
        let entities = scene["entities"].as_array().expect("entities");
        let named = |id: &str| entities.iter().find(|e| e["id"] == id);
        let drawn_slots = named("slots").expect("slots");
        assert_eq!(drawn_slots["frame_id"], FORMATION_FRAME);
        assert_eq!(drawn_slots["frame_locked"], true);
        let off_slot = step
            .agents
            .iter()
            .filter(|a| shown(&a.best) != shown(&a.slot))
            .count();
        let best = named("best_points").expect("best points");
        assert_eq!(best["cylinders"].as_array().map(Vec::len), Some(off_slot));
        if step.step == 0 {
            let loops = named("obstacles").expect("obstacles")["lines"]
                .as_array()
                .expect("lines")
                .iter()
                .filter(|l| l["type"] == LINE_LOOP)
                .count();
            assert_eq!(loops, scenario.polygons.len());
        }
    }
}

//! The order of the turns within a step (`[turns] order`): safety never depends on it,
//! the deviation under a top speed does.

use shared::control::vocabulary::TurnOrder;
use shared::run::simulate::simulate;
use shared::world::scenario::Scenario;

/// Three agents in a column driving east, 0.7 m apart with radii of 0.3 m, numbered from
/// the back; each step the centre moves 0.25 m, within the top speed.
fn column(order: &str) -> Scenario {
    column_with(&format!("[turns]\norder = \"{order}\"\n"), "")
}

/// The column of [`column`] with `turns` as its `[turns]` table (or none) and `formation`
/// added to its `[formation]` table.
fn column_with(turns: &str, formation: &str) -> Scenario {
    let text = format!(
        r#"
name = "column"
[field]
width_m = 30.0
height_m = 10.0
[formation]
agent_radius_m = 0.3
max_step_m = 0.5
{formation}
slots = [
  {{ r_m = 1.4, theta_deg = 180.0 }},
  {{ r_m = 0.7, theta_deg = 180.0 }},
  {{ r_m = 0.0, theta_deg = 0.0 }},
]
[path]
start = {{ x_m = 3.0, y_m = 5.0, heading_deg = 0.0 }}
goal = {{ x_m = 27.0, y_m = 5.0, heading_deg = 0.0 }}
turning_radius_m = 2.0
step_m = 0.25
centre_clearance_m = 0.5
{turns}
"#
    );
    Scenario::parse(&text, "column.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// Front to back, each agent's new slot is free when its turn comes (the mate in front,
/// 0.7 m ahead, moved already): every agent stays exactly on its slot. In agent order the
/// agent behind moves first, while the mate in front still stands where it was, at most
/// 0.7 - 0.25 = 0.45 m from its new slot, less than the radii sum: it stops 0.6 m behind
/// that mate, at least 0.15 m short.
#[test]
fn a_column_taking_its_turns_front_to_back_keeps_every_slot() {
    let front_first = column("front-first");
    assert_eq!(front_first.turn_order, TurnOrder::FrontFirst);
    let run = simulate(&front_first).expect("simulate");
    let s = run.summary();
    assert!(s.completed);
    assert_eq!(s.collisions, 0);
    assert!(s.max_deviation_m < 1e-9, "{}", s.max_deviation_m);

    let agent_order = column("agent");
    assert_eq!(agent_order.turn_order, TurnOrder::Agent);
    let s = simulate(&agent_order).expect("simulate").summary();
    assert_eq!(s.collisions, 0);
    assert!(s.max_deviation_m >= 0.15 - 1e-9, "{}", s.max_deviation_m);
}

/// Omitted, the order is front to back when every agent has a top speed and looks ahead
/// (the column then keeps every slot, as with the order written out), and agent order
/// with `horizon_steps = 0` (chasing the slot as before the look-ahead; without a top
/// speed likewise, in the next test) and for cars. The resolved file writes the order
/// out, so it loads back the same.
#[test]
fn omitted_the_order_is_front_first_with_a_top_speed_and_a_look_ahead() {
    let capped = column_with("", "");
    assert_eq!(capped.turn_order, TurnOrder::FrontFirst);
    let s = simulate(&capped).expect("simulate").summary();
    assert_eq!(s.collisions, 0);
    assert!(s.max_deviation_m < 1e-9, "{}", s.max_deviation_m);
    let text = capped.to_resolved_toml("column.toml").expect("resolved");
    let again = Scenario::parse(&text, "resolved.toml").expect("resolved loads");
    assert_eq!(again.turn_order, TurnOrder::FrontFirst);

    let chasing = column_with("", "horizon_steps = 0");
    assert_eq!(chasing.turn_order, TurnOrder::Agent);
    let s = simulate(&chasing).expect("simulate").summary();
    assert!(s.max_deviation_m >= 0.15 - 1e-9, "{}", s.max_deviation_m);
    let text = chasing.to_resolved_toml("column.toml").expect("resolved");
    let again = Scenario::parse(&text, "resolved.toml").expect("resolved loads");
    assert_eq!(again.turn_order, TurnOrder::Agent);

    // Cars keep agent order: the shipped car scenario names no order.
    let cars =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-car.toml");
    let text = std::fs::read_to_string(&cars).expect("paper-car.toml");
    assert!(!text.contains("order ="), "the file names no order");
    let cars = Scenario::parse(&text, "paper-car.toml").expect("paper-car");
    assert!(
        cars.agents
            .iter()
            .all(|a| a.max_step_m.is_some() && a.horizon_steps > 0)
    );
    assert_eq!(cars.turn_order, TurnOrder::Agent);
}

/// Without a top speed the order defaults to agent order (the paper's); `order` refuses
/// a name it does not know, naming the key.
#[test]
fn without_a_top_speed_the_order_is_the_agents_and_an_unknown_name_is_refused() {
    let text = shared::world::scenario::PAPER_SCENARIO_TOML;
    let paper = Scenario::parse(text, "paper.toml").expect("paper");
    assert_eq!(paper.turn_order, TurnOrder::Agent);
    let bad = format!("{text}\n[turns]\norder = \"back-first\"\n");
    let err = Scenario::parse(&bad, "bad.toml")
        .expect_err("unknown order")
        .to_string();
    assert!(
        err.contains("bad.toml") && err.contains("back-first"),
        "{err}"
    );
}

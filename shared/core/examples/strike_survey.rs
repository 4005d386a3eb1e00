//! How often are agents struck by moving obstacles slower than they are?
//!
//! Draws `FIELDS` random open fields (30 x 20 m, no static obstacle, a formation of four
//! agents of radius 0.3 m with a top speed of 0.5 m per step crossing it, one to six
//! moving obstacles of radius 0.4 to 1 m on two or three random waypoints, back and forth
//! or round a loop) with obstacle speeds drawn from `[MIN, MAX)` metres per step, runs
//! the reference simulation on each and counts the fields where a moving obstacle's
//! motion came within reach of an agent (a strike). Field `k` is drawn from seed `k`, so
//! two builds can be compared field by field.
//!
//! ```text
//! cargo run --release -p formation-shared --example strike_survey -- 0.35 0.45 300
//! ```

use rand::{Rng, SeedableRng};
use shared::geometry::Point;
use shared::run::simulate::simulate;
use shared::world::moving_obstacle::{MovingObstacle, Route};
use shared::world::scenario::{Scenario, moving_obstacle_table};

/// The field, formation and path of every field: four agents crossing from west to east.
const OPEN_FIELD: &str = include_str!("../../../tests/data/open-field.toml");

/// The scenario text of field `seed`, its obstacles at `min..max` metres per step.
fn random_field(seed: u64, min: f64, max: f64) -> String {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut text = String::from(OPEN_FIELD);
    let movers = rng.random_range(1..=6);
    let mut drawn = 0;
    while drawn < movers {
        let radius_m: f64 = rng.random_range(0.4..1.0);
        let corners = rng.random_range(2..=3);
        let waypoints: Vec<(f64, f64)> = (0..corners)
            .map(|_| (rng.random_range(1.0..29.0), rng.random_range(1.0..19.0)))
            .collect();
        let speed: f64 = rng.random_range(min..max);
        let looped = rng.random_bool(0.5);
        // Clear of the formation's start and of the goal.
        let (x, y) = waypoints[0];
        if (x - 3.0f64).hypot(y - 10.0) <= radius_m + 2.5
            || (x - 27.0f64).hypot(y - 10.0) <= radius_m + 1.5
        {
            continue;
        }
        let route = if looped {
            Route::Loop
        } else {
            Route::BackAndForth
        };
        let points = waypoints.iter().map(|&(x, y)| Point::new(x, y)).collect();
        text += &moving_obstacle_table(&MovingObstacle::new(radius_m, points, speed, route));
        drawn += 1;
    }
    text
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [min, max, fields] = args.as_slice() else {
        return Err(
            "usage: strike_survey MIN MAX FIELDS (obstacle speeds in m per step, at most 0.5)"
                .into(),
        );
    };
    let (min, max, fields): (f64, f64, u64) = (min.parse()?, max.parse()?, fields.parse()?);
    if !(0.0 < min && min < max && max <= 0.5) {
        return Err("MIN and MAX: 0 < MIN < MAX <= 0.5 (the agents' top speed)".into());
    }
    let (mut struck_fields, mut strikes, mut incomplete) = (0, 0, 0);
    for seed in 0..fields {
        let scenario = Scenario::parse(&random_field(seed, min, max), "open-field.toml")?;
        let run = simulate(&scenario)?;
        let struck: usize = run.steps.iter().map(|s| s.struck.len()).sum();
        if struck > 0 {
            struck_fields += 1;
            strikes += struck;
            println!("field {seed}: {struck} strikes");
        }
        if !run.completed {
            incomplete += 1;
        }
    }
    println!(
        "obstacles at {min}-{max} m per step: {struck_fields} of {fields} fields with a strike ({strikes} strikes), {incomplete} not completed"
    );
    Ok(())
}

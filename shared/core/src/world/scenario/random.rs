//! The obstacles drawn from the scenario's seed (`[obstacles.random]`): uniform over the
//! field, clear of the start and goal, the same for the same seed on every machine.

use rand::{Rng, SeedableRng};

use super::PathSpec;
use crate::geometry::{Disk, Field, Point};

/// Fewer obstacles than asked could be placed clear of the start and goal (the field is
/// too crowded for the attempts allowed: a thousand per obstacle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Crowded {
    /// How many were placed.
    pub(super) placed: usize,
}

/// Uniformly placed obstacles whose disks stay `keep_clear_m` away from the start and
/// goal positions, drawn from a ChaCha8 stream seeded with the scenario's seed.
pub(super) fn random_obstacles(
    count: usize,
    radius_m: f64,
    keep_clear_m: f64,
    field: &Field,
    path: &PathSpec,
    seed: u64,
) -> Result<Vec<Disk>, Crowded> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let keep = [path.start.position(), path.goal.position()];
    let mut disks = Vec::with_capacity(count);
    let max_attempts = 1000 * count.max(1);
    let mut attempts = 0;
    while disks.len() < count {
        attempts += 1;
        if attempts > max_attempts {
            return Err(Crowded {
                placed: disks.len(),
            });
        }
        let c = Point::new(
            rng.random_range(0.0..=field.width_m),
            rng.random_range(0.0..=field.height_m),
        );
        if keep
            .iter()
            .all(|k| (c - k).norm() >= radius_m + keep_clear_m)
        {
            disks.push(Disk {
                centre: c,
                radius_m,
            });
        }
    }
    Ok(disks)
}

#[cfg(test)]
mod tests {
    use crate::world::scenario::{MINIMAL, Scenario};

    #[test]
    fn random_obstacles_are_reproducible_and_keep_clear_of_start_and_goal() {
        let text = MINIMAL.replace(
            "[formation]",
            "[obstacles.random]\ncount = 25\nkeep_clear_m = 2.0\n[formation]",
        );
        let a = Scenario::parse(&text, "r.toml").unwrap();
        let b = Scenario::parse(&text, "r.toml").unwrap();
        assert_eq!(a.obstacles, b.obstacles);
        assert_eq!(a.obstacles.len(), 25);
        for o in &a.obstacles {
            for p in [a.path.start.position(), a.path.goal.position()] {
                assert!(o.signed_distance_m(&p) >= 2.0 - 1e-12);
            }
        }
        let c = Scenario::parse(
            &text.replace("name = \"t\"", "name = \"t\"\nseed = 9"),
            "r.toml",
        )
        .unwrap();
        assert_ne!(a.obstacles, c.obstacles, "the seed drives the field");
    }
}

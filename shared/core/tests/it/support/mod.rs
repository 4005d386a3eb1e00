//! Helpers shared by the property tests of `shared`.

use rand::Rng;
use shared::control::vocabulary::Body;
use shared::geometry::{Disk, Field, Point, Vector};

/// Draw a start for an agent of radius `radius_m` where controllers are put to the test:
/// touching an obstacle or another agent, on the field's left edge, or anywhere, until
/// `clear(p)` accepts one; `None` after 2000 draws.
pub fn draw_start(
    rng: &mut impl Rng,
    field: &Field,
    obstacles: &[Disk],
    others: &[Body],
    radius_m: f64,
    clear: impl Fn(&Point) -> bool,
) -> Option<Point> {
    for _ in 0..2000 {
        let angle = rng.random_range(0.0..std::f64::consts::TAU);
        let towards = Vector::new(angle.cos(), angle.sin());
        let p = match rng.random_range(0..4) {
            0 if !obstacles.is_empty() => {
                let d = obstacles[rng.random_range(0..obstacles.len())];
                d.centre + (d.radius_m + radius_m) * towards
            }
            1 if !others.is_empty() => {
                let o = others[rng.random_range(0..others.len())];
                o.position + (o.radius_m + radius_m) * towards
            }
            2 => Point::new(
                radius_m,
                rng.random_range(radius_m..field.height_m - radius_m),
            ),
            _ => Point::new(
                rng.random_range(0.0..field.width_m),
                rng.random_range(0.0..field.height_m),
            ),
        };
        if clear(&p) {
            return Some(p);
        }
    }
    None
}

/// Up to 24 obstacles (radius 0.2 to 2.5 m) and up to 6 other agents (radius 0.1 to
/// 1 m) placed at random in `field`; they may overlap one another.
pub fn random_bodies(rng: &mut impl Rng, field: &Field) -> (Vec<Disk>, Vec<Body>) {
    let obstacles: Vec<Disk> = (0..rng.random_range(0..25))
        .map(|_| {
            Disk::new(
                rng.random_range(0.0..field.width_m),
                rng.random_range(0.0..field.height_m),
                rng.random_range(0.2..2.5),
            )
        })
        .collect();
    let others: Vec<Body> = (0..rng.random_range(0..7))
        .map(|_| Body {
            position: Point::new(
                rng.random_range(0.0..field.width_m),
                rng.random_range(0.0..field.height_m),
            ),
            radius_m: rng.random_range(0.1..1.0),
        })
        .collect();
    (obstacles, others)
}

//! Formation slots: where each agent ideally stands (the paper's equation 2).

use crate::geometry::{Point, Pose, Vector};

/// An agent's place in the formation, in polar form in the formation frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slot {
    /// Distance from the formation centre, in metres.
    pub r_m: f64,
    /// Angle from the formation's heading, counter-clockwise, in radians.
    pub theta_rad: f64,
}

impl Slot {
    /// A slot at distance `r_m` and angle `theta_rad` from the centre.
    pub fn new(r_m: f64, theta_rad: f64) -> Self {
        Self { r_m, theta_rad }
    }

    /// The ideal position of the agent when the centre is at `centre` (equation 2):
    /// `x* = r (cos(theta + gamma), sin(theta + gamma)) + x0`.
    ///
    /// ```
    /// use shared::control::formation::Slot;
    /// use shared::geometry::Pose;
    /// let slot = Slot::new(2.0, std::f64::consts::FRAC_PI_2);
    /// let p = slot.ideal_position(&Pose::new(10.0, 5.0, std::f64::consts::FRAC_PI_2));
    /// assert!((p.x - 8.0).abs() < 1e-12 && (p.y - 5.0).abs() < 1e-12);
    /// ```
    pub fn ideal_position(&self, centre: &Pose) -> Point {
        let angle_rad = self.theta_rad + centre.heading_rad;
        centre.position() + self.r_m * Vector::new(angle_rad.cos(), angle_rad.sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotating_the_centre_rotates_every_slot_rigidly() {
        let slots = [
            Slot::new(1.0, 0.0),
            Slot::new(1.5, 0.7),
            Slot::new(2.0, -2.1),
        ];
        let a = Pose::new(3.0, 4.0, 0.0);
        let b = Pose::new(3.0, 4.0, 1.1);
        for i in 0..slots.len() {
            for j in 0..slots.len() {
                let da = (slots[i].ideal_position(&a) - slots[j].ideal_position(&a)).norm();
                let db = (slots[i].ideal_position(&b) - slots[j].ideal_position(&b)).norm();
                assert!(
                    (da - db).abs() < 1e-12,
                    "distances between slots are preserved"
                );
            }
            let d = (slots[i].ideal_position(&b) - b.position()).norm();
            assert!((d - slots[i].r_m).abs() < 1e-12);
        }
    }
}

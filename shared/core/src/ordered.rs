//! A total order on `f64`, for priority queues and A* costs.

use std::cmp::Ordering;
use std::ops::Add;

use pathfinding::num_traits::Zero;

/// An `f64` ordered by [`f64::total_cmp`]: `-0.0 < +0.0`, and NaNs sort by their sign bit
/// beyond the infinities. Equality follows the same order (`-0.0 != +0.0`), consistent with
/// `Ord`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TotalF64(pub(crate) f64);

impl PartialEq for TotalF64 {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for TotalF64 {}

impl PartialOrd for TotalF64 {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for TotalF64 {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0)
    }
}

impl Add for TotalF64 {
    type Output = Self;
    fn add(self, other: Self) -> Self {
        Self(self.0 + other.0)
    }
}

impl Zero for TotalF64 {
    fn zero() -> Self {
        Self(0.0)
    }
    fn is_zero(&self) -> bool {
        self.0 == 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_like_total_cmp() {
        let mut v = [
            TotalF64(1.0),
            TotalF64(-0.0),
            TotalF64(f64::INFINITY),
            TotalF64(0.0),
            TotalF64(-2.5),
        ];
        v.sort();
        let bits: Vec<u64> = v.iter().map(|x| x.0.to_bits()).collect();
        let expected: Vec<u64> = [-2.5, -0.0, 0.0, 1.0, f64::INFINITY]
            .iter()
            .map(|x: &f64| x.to_bits())
            .collect();
        assert_eq!(bits, expected);
        assert_ne!(TotalF64(-0.0), TotalF64(0.0));
        assert_eq!(TotalF64(1.0) + TotalF64(2.0), TotalF64(3.0));
        assert!(TotalF64::zero().is_zero());
    }
}

//! The barrier-function controllers' settings ([`crate::control::cbf`]) and their validation: part
//! of a [`ControllerSpec`](crate::control::vocabulary::ControllerSpec), so of every scenario, whichever
//! controller runs it.

/// Extra inflation of every barrier, in metres: the CBF keeps each body at least this
/// much (minus rounding) away from every other body and from the field edges, so that
/// floating-point rounding never breaks the true invariant.
pub const CBF_MARGIN_M: f64 = 1e-6;

/// Default sharpness of the LogSumExp smooth max, in 1/m: with `n` terms the smooth max
/// over-approximates the max by at most `ln(n) / k` metres (0.069 m for two terms).
pub const DEFAULT_LSE_SHARPNESS_PER_M: f64 = 10.0;

/// The most substeps a barrier turn may be cut into ([`CbfSettings::substeps`]).
pub const MAX_CBF_SUBSTEPS: u32 = 100;

/// The substeps of a `cbf` turn by default, chosen by measurement on the paper, dense,
/// narrow and large scenarios given a top speed (docs/measurements.md): with 3, large's
/// mean and largest deviation are less than half and nine tenths of one piece's, and no
/// other scenario's mean or largest deviation grows.
pub const DEFAULT_CBF_SUBSTEPS: u32 = 3;

/// Why CBF settings (or a controller built from them) are unusable.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum CbfSettingsError {
    /// A setting is NaN, infinite, zero or negative.
    #[error("{name} must be finite and positive, got {value}")]
    NotPositive {
        /// Name of the setting.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// `gamma_per_s * dt_s > 1`: a straight step could cross the barrier.
    #[error("gamma_per_s * dt_s = {product} exceeds 1: a straight step could cross the barrier")]
    GammaDtAboveOne {
        /// The product `gamma_per_s * dt_s`.
        product: f64,
    },
    /// `substeps` is 0 or above [`MAX_CBF_SUBSTEPS`].
    #[error("substeps must be 1 to {MAX_CBF_SUBSTEPS}, got {substeps}")]
    Substeps {
        /// The number given.
        substeps: u32,
    },
    /// The sensing radius is shorter than the agent's radius plus one step at maximum
    /// speed: a body could be hit before it is sensed.
    #[error(
        "sensing_radius_m = {sensing_radius_m} is shorter than the agent radius plus one step at maximum speed ({required_m} m)"
    )]
    SensingTooShort {
        /// The sensing radius, in metres.
        sensing_radius_m: f64,
        /// The least sensing radius that is safe for this agent, in metres.
        required_m: f64,
    },
}

/// Settings of the CBF-QP controllers (shared by [`CbfController`](crate::control::cbf::CbfController) and
/// [`ZcbfLogSumExpController`](crate::control::cbf::ZcbfLogSumExpController) so that the comparison is
/// like for like).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CbfSettings {
    /// Class-K gain of the barrier condition `h' >= -gamma h`, in 1/s.
    pub gamma_per_s: f64,
    /// Duration of one move (one turn), in seconds.
    pub dt_s: f64,
    /// Proportional gain of the nominal controller `u_nom = gain (slot - x)`, in 1/s.
    pub gain_per_s: f64,
    /// Saturation of the nominal velocity (and cap of the chosen one), in m/s.
    pub max_speed_m_per_s: f64,
    /// A neighbour is sensed (gets a constraint) when some point of its body lies within
    /// this distance of the agent's centre, in metres. Must be at least the agent's
    /// radius plus one step at maximum speed.
    pub sensing_radius_m: f64,
    /// How many straight pieces of `dt_s / substeps` a `cbf` turn is made of, each with
    /// its own QP at the point the last one reached (the mates still standing where the
    /// turn found them): the agent slides round a body within the turn instead of
    /// stopping at it for the turn. The gains are per piece (`gain_per_s` and
    /// `gamma_per_s` times `substeps`), so `gain * dt` and `gamma * dt` mean per piece
    /// what they mean per turn with one. 1 is one straight step a turn. Holonomic agents
    /// only: a unicycle's barrier turn is one arc.
    pub substeps: u32,
    /// Whether a `cbf` agent stalled at a barrier tries the way round it: when the
    /// filtered velocity of a piece is under [`CBF_STALL_SHARE`] of the nominal one, the
    /// QP is solved again for the nominal turned a quarter turn clockwise (the right-hand
    /// rule of multi-robot deadlock resolution), and that velocity is taken if it is
    /// faster. Both solve the same constraints, so safety is unchanged; without it an
    /// agent whose slot lies straight behind a body stops there for good. Holonomic agents
    /// only, as `substeps`.
    pub deadlock_escape: bool,
}

/// Below this share of its nominal speed a `cbf` piece counts as stalled
/// ([`CbfSettings::deadlock_escape`]).
pub const CBF_STALL_SHARE: f64 = 0.2;

impl Default for CbfSettings {
    /// `gamma = 1 /s`, `dt = 1 s` (`gamma * dt = 1`, the largest safe value: the barrier
    /// may be approached as fast as the whole-segment guarantee allows),
    /// `gain = 1 /s` (`gain * dt = 1`: an unobstructed slot within one step's reach is
    /// reached in one turn), maximum speed 1 m/s (one metre per turn, four times the
    /// example scenario's centre step of 0.25 m, so agents catch up after a detour), and a
    /// sensing radius of 5 m (safe for agent radii up to 4 m), and
    /// [`DEFAULT_CBF_SUBSTEPS`] pieces a turn, with the deadlock escape.
    fn default() -> Self {
        Self {
            gamma_per_s: 1.0,
            dt_s: 1.0,
            gain_per_s: 1.0,
            max_speed_m_per_s: 1.0,
            sensing_radius_m: 5.0,
            substeps: DEFAULT_CBF_SUBSTEPS,
            deadlock_escape: true,
        }
    }
}

impl CbfSettings {
    /// Check that every setting is finite and positive, that `gamma * dt <= 1` and that
    /// `substeps` is 1 to [`MAX_CBF_SUBSTEPS`].
    pub fn validate(&self) -> Result<(), CbfSettingsError> {
        if !(1..=MAX_CBF_SUBSTEPS).contains(&self.substeps) {
            return Err(CbfSettingsError::Substeps {
                substeps: self.substeps,
            });
        }
        for (name, value) in [
            ("gamma_per_s", self.gamma_per_s),
            ("dt_s", self.dt_s),
            ("gain_per_s", self.gain_per_s),
            ("max_speed_m_per_s", self.max_speed_m_per_s),
            ("sensing_radius_m", self.sensing_radius_m),
        ] {
            positive(name, value)?;
        }
        let product = self.gamma_per_s * self.dt_s;
        if product > 1.0 {
            return Err(CbfSettingsError::GammaDtAboveOne { product });
        }
        Ok(())
    }

    /// Longest move of one turn, in metres (`max_speed * dt`).
    pub fn max_step_m(&self) -> f64 {
        self.max_speed_m_per_s * self.dt_s
    }

    /// Check these settings for an agent of radius `radius_m`: [`CbfSettings::validate`]
    /// plus a sensing radius of at least `radius_m + max_step_m()`.
    ///
    /// ```
    /// use shared::control::vocabulary::{CbfSettings, CbfSettingsError};
    /// // The defaults sense 5 m around an agent that moves at most 1 m a turn.
    /// let settings = CbfSettings::default();
    /// assert_eq!(settings.validate_for_agent(0.3), Ok(()));
    /// assert!(matches!(
    ///     settings.validate_for_agent(4.5),
    ///     Err(CbfSettingsError::SensingTooShort { .. })
    /// ));
    /// ```
    pub fn validate_for_agent(&self, radius_m: f64) -> Result<(), CbfSettingsError> {
        self.validate()?;
        positive("agent radius_m", radius_m)?;
        let required_m = radius_m + self.max_step_m() + CBF_MARGIN_M;
        if self.sensing_radius_m < required_m {
            return Err(CbfSettingsError::SensingTooShort {
                sensing_radius_m: self.sensing_radius_m,
                required_m,
            });
        }
        Ok(())
    }
}

fn positive(name: &'static str, value: f64) -> Result<(), CbfSettingsError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(CbfSettingsError::NotPositive { name, value })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_validation() {
        assert_eq!(CbfSettings::default().validate(), Ok(()));
        let fast = CbfSettings {
            gamma_per_s: 3.0,
            ..CbfSettings::default()
        };
        assert!(matches!(
            fast.validate(),
            Err(CbfSettingsError::GammaDtAboveOne { .. })
        ));
        let blind = CbfSettings {
            sensing_radius_m: 1.0,
            ..CbfSettings::default()
        };
        assert!(matches!(
            blind.validate_for_agent(0.3),
            Err(CbfSettingsError::SensingTooShort { .. })
        ));
        for substeps in [0, MAX_CBF_SUBSTEPS + 1] {
            let cut = CbfSettings {
                substeps,
                ..CbfSettings::default()
            };
            assert_eq!(cut.validate(), Err(CbfSettingsError::Substeps { substeps }));
        }
        let nan = CbfSettings {
            dt_s: f64::NAN,
            ..CbfSettings::default()
        };
        assert!(matches!(
            nan.validate(),
            Err(CbfSettingsError::NotPositive { name: "dt_s", .. })
        ));
    }
}

//! From the daemon's units (N at the fingertip, rad/s at the joint) to a drive's
//! (per mille of rated torque, rpm at the motor) and back: settings validated once, then
//! conversions that cannot fail (they saturate at the configured limits).

use thiserror::Error;

/// The scaling settings of one finger drive, as configured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScalingSettings {
    /// Motor rated torque (0x6076), mNm.
    pub rated_torque_mnm: f64,
    /// Gear ratio, motor turns per joint turn (> 0).
    pub gear_ratio: f64,
    /// Moment arm from joint to fingertip, m (> 0).
    pub moment_arm_m: f64,
    /// The largest torque target sent, per mille of rated torque (1..=32767).
    pub max_torque_permille: u16,
    /// The largest velocity target sent, rpm at the motor (> 0).
    pub max_speed_rpm: u32,
}

/// A scaling setting that cannot work.
#[derive(Clone, Copy, Debug, PartialEq, Error)]
pub enum ScalingError {
    /// Not finite or not > 0.
    #[error("scaling field `{field}` must be finite and > 0 (is {value})")]
    NotPositive {
        /// The field's name.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A limit of zero or beyond the object's range.
    #[error("scaling limit `{0}` is 0 or beyond the drive object's range")]
    Limit(&'static str),
}

/// Validated scaling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaling {
    /// Per mille of rated torque per newton at the fingertip.
    permille_per_n: f64,
    /// Motor rpm per rad/s at the joint.
    rpm_per_rad_s: f64,
    max_torque_permille: i16,
    max_speed_rpm: i32,
}

impl ScalingSettings {
    /// Checks every field once.
    pub fn validate(&self) -> Result<Scaling, ScalingError> {
        for (field, value) in [
            ("rated_torque_mnm", self.rated_torque_mnm),
            ("gear_ratio", self.gear_ratio),
            ("moment_arm_m", self.moment_arm_m),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ScalingError::NotPositive { field, value });
            }
        }
        let max_torque_permille = i16::try_from(self.max_torque_permille)
            .ok()
            .filter(|v| *v > 0)
            .ok_or(ScalingError::Limit("max_torque_permille"))?;
        let max_speed_rpm = i32::try_from(self.max_speed_rpm)
            .ok()
            .filter(|v| *v > 0)
            .ok_or(ScalingError::Limit("max_speed_rpm"))?;
        // F [N] * arm [m] = joint torque [Nm]; / gear = motor torque [Nm];
        // / (rated [mNm] / 1000) * 1000 = per mille.
        let permille_per_n = self.moment_arm_m / self.gear_ratio * 1e6 / self.rated_torque_mnm;
        let rpm_per_rad_s = self.gear_ratio * 60.0 / core::f64::consts::TAU;
        Ok(Scaling {
            permille_per_n,
            rpm_per_rad_s,
            max_torque_permille,
            max_speed_rpm,
        })
    }
}

impl Scaling {
    /// Target torque (0x6071) for a fingertip force, saturated at the limit; NaN gives 0.
    pub fn torque_permille(&self, force_n: f64) -> i16 {
        let lim = f64::from(self.max_torque_permille);
        let v = (force_n * self.permille_per_n).clamp(-lim, lim);
        if v.is_nan() {
            0
        } else {
            v.round() as i16
        }
    }

    /// Max torque (0x6072) for a fingertip force limit: the force's magnitude in per mille,
    /// saturated at the limit; NaN gives 0 (no torque).
    pub fn max_torque_permille(&self, force_n: f64) -> u16 {
        self.torque_permille(force_n).unsigned_abs()
    }

    /// Fingertip force for a max torque (0x6072) in per mille.
    pub fn limit_force_n(&self, permille: u16) -> f64 {
        f64::from(permille) / self.permille_per_n
    }

    /// Fingertip force for a torque (0x6077) in per mille.
    pub fn force_n(&self, permille: i16) -> f64 {
        f64::from(permille) / self.permille_per_n
    }

    /// Target velocity (0x60FF, rpm) for a joint speed, saturated; NaN gives 0.
    pub fn velocity_rpm(&self, rad_s: f64) -> i32 {
        let lim = f64::from(self.max_speed_rpm);
        let v = (rad_s * self.rpm_per_rad_s).clamp(-lim, lim);
        if v.is_nan() {
            0
        } else {
            v.round() as i32
        }
    }

    /// Joint speed for a motor velocity (0x606C, rpm).
    pub fn rad_s(&self, rpm: i32) -> f64 {
        f64::from(rpm) / self.rpm_per_rad_s
    }
}

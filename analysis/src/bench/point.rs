//! One measured point of the work-precision charts and the CSV status of a
//! refused fixed-step run: the types [`super::work_precision`] and
//! [`super::across_lift_off`] both produce, kept apart from either so that
//! neither module imports the other's internals.

/// One measured point.
#[derive(Debug, Clone)]
pub struct Point {
    /// Scene name.
    pub scene: &'static str,
    /// Method name.
    pub method: String,
    /// Steps per period (fixed-step only).
    pub steps: Option<u32>,
    /// |Δμ|/μ0 against the scene's reference (the exact f64 solver, or the
    /// across-lift-off references), or `None` on failure.
    pub error: Option<f64>,
    /// Seconds per evaluation.
    pub time_s: f64,
    /// The method's stated error bound, units of μ0.
    pub bound: Option<f64>,
    /// "ok" or the failure.
    pub status: String,
}

/// The CSV `status` of a refused fixed-step run: the refusal's kind.
pub fn refusal_kind<T>(e: &model_core::fixed_step::FixedStepError<T>) -> &'static str {
    use model_core::fixed_step::FixedStepError as E;
    match e {
        E::TooFewSteps { .. } => "TooFewSteps",
        E::PrecisionLimit { .. } => "PrecisionLimit",
        E::IllConditioned => "IllConditioned",
        E::BadConfig => "BadConfig",
        E::BadVelocity(_) => "BadVelocity",
        E::ZeroVelocity => "ZeroVelocity",
        E::BadStart => "BadStart",
        E::BadDrive => "BadDrive",
        E::NotConverged { .. } => "NotConverged",
    }
}

//! Drive periods per update of the μ loop (`--periods`).

/// Drive periods per update: a number, or as many as fit one half-buffer
/// at the drive frequency (`auto`, the default).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Periods {
    /// `board::device::periods_in_half_buffer` at the drive frequency.
    Auto,
    /// This many, 1 … `CONTROL_MAX_PERIODS`.
    Fixed(u32),
}

impl Periods {
    /// The periods at `freq_hz` with `sample_rate_hz`.
    pub fn at(self, freq_hz: f64, sample_rate_hz: f64) -> u32 {
        match self {
            Periods::Auto => board::device::periods_in_half_buffer(freq_hz, sample_rate_hz),
            Periods::Fixed(n) => n,
        }
    }
}

impl std::fmt::Display for Periods {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Periods::Auto => f.write_str("auto"),
            Periods::Fixed(n) => write!(f, "{n}"),
        }
    }
}

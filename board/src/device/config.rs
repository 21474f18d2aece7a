//! The board's fixed configuration: sample rate, transducer (DAC) and force
//! (ADC) calibrations, lift-off margin, frequency range, slew rates — and the
//! limits that follow from it, each written once here.

use super::error::ConfigError;
use crate::dds::DAC_MAX;
use crate::estimator::Calibration;
use crate::protocol::framing::BYTE_TIMEOUT_US;
use crate::protocol::messages::{Info, PROTOCOL_VERSION};

/// Transducer calibration of one DAC channel: displacement
/// `= (code − zero_code) · metres_per_code`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DacCal {
    /// Metres of displacement per DAC code (> 0).
    pub metres_per_code: f32,
    /// DAC code of zero displacement.
    pub zero_code: f32,
}

impl DacCal {
    /// Codes from `zero_code` up to the top of the DAC ([`DAC_MAX`]).
    pub fn codes_above_zero(&self) -> f32 {
        f32::from(DAC_MAX) - self.zero_code
    }

    /// Codes from `zero_code` to the nearer end of the DAC range.
    pub fn codes_to_nearer_end(&self) -> f32 {
        self.zero_code.min(self.codes_above_zero())
    }
}

/// Fixed configuration of a board.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceConfig {
    /// DAC/ADC sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Channel 1 (normal transducer) calibration.
    pub dac_z: DacCal,
    /// Channel 2 (tangential transducer) calibration.
    pub dac_x: DacCal,
    /// ADC calibration of the tangential force.
    pub adc_x: Calibration,
    /// ADC calibration of the normal force.
    pub adc_z: Calibration,
    /// ADC full scale (4095 for 12 bits).
    pub adc_full_scale: u16,
    /// Lift-off margin: Δu_z ≤ (1 − margin)·u_z0 (0 ≤ margin < 1).
    pub liftoff_margin: f32,
    /// Lowest and highest drive frequency, Hz.
    pub freq_range_hz: (f64, f64),
    /// Amplitude and offset slew, m/s; phase slew, rad/s.
    pub slew_m_per_s: f32,
    /// Phase slew, rad/s.
    pub slew_rad_per_s: f32,
    /// ADC calibration of the normal transducer's motion pickup (a pickup
    /// patch or a vibrometer's output): `gain` m per count, `offset` the
    /// count at rest. Pin PA6 (ADC12_IN6) on the board.
    pub pickup_z: Calibration,
    /// ADC calibration of the tangential transducer's motion pickup, m per
    /// count. Pin PA7 (ADC12_IN7) on the board.
    pub pickup_x: Calibration,
    /// ADC sample `k` sees the DAC word `k − lag` (the STM32 DAC moves its
    /// holding register to the output on the trigger and only then requests
    /// the next word by DMA: lag 1). The phase of each ADC sample is shifted
    /// accordingly.
    pub adc_lag_samples: u32,
    /// How long after a sample's force conversion its motion pickups are
    /// converted, s (0 ≤ δ < one sample period). On the board ADC1 and ADC2
    /// run in dual regular-simultaneous mode, each scanning two inputs per
    /// trigger (ADC1: IN0 normal force, then IN6 normal pickup; ADC2: IN1
    /// tangential force, then IN7 tangential pickup), so each pickup is
    /// converted one conversion after its force: (SMP + 12) ADC clocks /
    /// f_ADC (RM0090 §13.5: sampling time plus 12 cycles of successive
    /// approximation), with SMP = 3 cycles at f_ADC = 21 MHz
    /// ([`PICKUP_DELAY_S`] = 15/21 MHz = 0.714 µs, 0.357 of a 2 µs sample
    /// at 500 kS/s: 10.3° of a 40 kHz drive). The device demodulates each
    /// pickup sample at its own instant, the force sample's drive phase
    /// advanced by δ ([`DeviceConfig::pickup_reference_word`]), and the
    /// simulated plant samples the pickups δ after the forces.
    pub pickup_delay_s: f64,
}

/// The driver board's pickup delay ([`DeviceConfig::pickup_delay_s`]):
/// (3 + 12) ADC clocks at 21 MHz (PCLK2 84 MHz / 4), s.
pub const PICKUP_DELAY_S: f64 = 15.0 / 21e6;

/// Samples per DAC/ADC half-buffer of the driver board (and of the virtual
/// device, which runs the same pipeline): 64 = 128 µs at 500 kS/s. The DMA
/// refills one half while the other is output, so a command computed from
/// ADC block `n` reaches the output at fill `n + 3` (see
/// [`crate::device`]'s closed loop): three half-buffers of dead time,
/// 384 µs. With 256-sample halves (the first boards' value) that was
/// 1.536 ms, and the closed loop could not settle within 2 ms.
/// Interrupt cost per half: two DMA interrupts every 128 µs, each a few
/// hundred cycles of 21 504 at 168 MHz.
pub const HALF_BUFFER: usize = 64;

/// Allowed drive periods of a measurement or a streamed estimate, inclusive.
pub const PERIODS_RANGE: (u32, u32) = (1, 1_000_000);

/// Largest |φ| of a drive, rad (a phase beyond is surely a unit mistake).
pub const MAX_PHASE_RAD: f32 = 1_000.0;

/// The contact stiffnesses k_z, k_x the device's f32 model takes, N/m: a
/// contact softer than 1 N/m or stiffer than 10¹² N/m is no probe's, and
/// inside this range every quantity of the model (W₀ = μ₀k_z u_z0/k_x,
/// the forces) stays well inside f32's (a k_x of 10⁻³⁰ was accepted and
/// then made every prediction fail). Host front ends check it by flag.
pub const STIFFNESS_RANGE_N_PER_M: (f64, f64) = (1.0, 1e12);

/// Largest |v₀| of a prediction, m/s.
pub const MAX_VELOCITY_M_S: f32 = 1_000.0;

impl DeviceConfig {
    /// The driver board's configuration, shared by the firmware and the
    /// virtual device: 500 kS/s, 2 nm/code normal and 1 nm/code tangential
    /// (around mid-scale) transducer calibration, 0.02 N/count (f_z) and
    /// 0.01 N/count around mid-scale (f_x) force calibration, 5 % lift-off
    /// margin, 1–100 kHz, 1 mm/s and 100 rad/s slew. Replace the calibrations
    /// with a board's measured values. `adc_lag_samples` is 1 on the chip (the
    /// DAC moves its holding register to the output on the trigger, the ADC
    /// converts on the same trigger) and 0 for a plant that samples at the
    /// drive phase of the sample itself. The pickups are converted
    /// [`PICKUP_DELAY_S`] after the forces (the ADCs' scan order, on the chip
    /// and in the simulated plant alike).
    pub const fn driver_board(adc_lag_samples: u32) -> Self {
        DeviceConfig {
            sample_rate_hz: 500_000.0,
            dac_z: DacCal {
                metres_per_code: 2e-9,
                zero_code: 0.0,
            },
            dac_x: DacCal {
                metres_per_code: 1e-9,
                zero_code: 2048.0,
            },
            adc_x: Calibration {
                gain: 0.01,
                offset: 2048.0,
            },
            adc_z: Calibration {
                gain: 0.02,
                offset: 0.0,
            },
            adc_full_scale: 4095,
            // ±10 µm over the ADC's range around mid-scale (AC-coupled).
            pickup_z: Calibration {
                gain: 5e-9,
                offset: 2048.0,
            },
            pickup_x: Calibration {
                gain: 5e-9,
                offset: 2048.0,
            },
            liftoff_margin: 0.05,
            freq_range_hz: (1_000.0, 100_000.0),
            slew_m_per_s: 1e-3,
            slew_rad_per_s: 100.0,
            adc_lag_samples,
            pickup_delay_s: PICKUP_DELAY_S,
        }
    }

    /// The DDS accumulator word of the drive phase at which ADC sample 0 of
    /// a block was taken (the forces): the block's fill started at
    /// accumulator `acc0` with tuning word `tw`, and the ADC sees the DAC
    /// word `adc_lag_samples` earlier. Sample `k` is `k·tw` words on.
    pub fn adc_reference_word(&self, acc0: u32, tw: u32) -> u32 {
        acc0.wrapping_sub(tw.wrapping_mul(self.adc_lag_samples))
    }

    /// The drive's phase advance over the pickups' delay, in accumulator
    /// words: `tw·δ·f_s` (the DDS advances `tw` words per sample), rounded
    /// to the nearest word (½ word = 7.3e-10 rad). 0 for a delay that is not
    /// finite or not > 0 ([`DeviceConfig::check_pickup_delay`] refuses the
    /// non-finite and the negative ones).
    pub fn pickup_delay_words(&self, tw: u32) -> u32 {
        let samples = self.pickup_delay_s * self.sample_rate_hz;
        if !(samples.is_finite() && samples > 0.0) {
            return 0;
        }
        // tw < 2³² and δ·f_s < 1: in u32 range; `as` saturates otherwise.
        (f64::from(tw) * samples + 0.5) as u32
    }

    /// [`DeviceConfig::pickup_delay_s`]·[`DeviceConfig::sample_rate_hz`] in
    /// units of 2⁻³², rounded: the factor `K` of
    /// [`pickup_delay_words_of`] (0 where [`DeviceConfig::pickup_delay_words`]
    /// gives 0; a delay of a whole sample or more saturates). Formed once
    /// (soft-float f64 on the M4), so that a window's close, which follows
    /// every retune of the tracker, needs no f64 (issue 35).
    pub fn pickup_delay_factor(&self) -> u64 {
        let samples = self.pickup_delay_s * self.sample_rate_hz;
        if !(samples.is_finite() && samples > 0.0) {
            return 0;
        }
        (samples * 4_294_967_296.0 + 0.5).min(4_294_967_295.0) as u64
    }

    /// The accumulator word of the drive phase at which the pickups of ADC
    /// sample 0 of a block were taken: [`DeviceConfig::adc_reference_word`]
    /// advanced by [`DeviceConfig::pickup_delay_words`]. Everything that
    /// demodulates the pickups starts its reference here (sample `k` is
    /// `k·tw` words on).
    pub fn pickup_reference_word(&self, acc0: u32, tw: u32) -> u32 {
        self.adc_reference_word(acc0, tw)
            .wrapping_add(self.pickup_delay_words(tw))
    }

    /// Checks [`DeviceConfig::pickup_delay_s`]: finite, ≥ 0 and below one
    /// sample period `1/sample_rate_hz` (a pickup converted a whole sample
    /// late would belong to the next sample).
    ///
    /// # Errors
    /// [`ConfigError::PickupDelay`].
    pub fn check_pickup_delay(&self) -> Result<(), ConfigError> {
        let d = self.pickup_delay_s;
        if d.is_finite() && d >= 0.0 && d * self.sample_rate_hz < 1.0 {
            Ok(())
        } else {
            Err(ConfigError::PickupDelay)
        }
    }

    /// Largest normal offset u_z0, m: `(DAC_MAX − zero_code)·metres_per_code`
    /// of the normal channel (computed in f32).
    pub fn max_offset_z_m(&self) -> f32 {
        self.dac_z.codes_above_zero() * self.dac_z.metres_per_code
    }

    /// Largest tangential amplitude Δu_x, m: the codes from `zero_code` to the
    /// nearer end of the DAC, times `metres_per_code` (computed in f32).
    pub fn max_amp_x_m(&self) -> f32 {
        self.dac_x.codes_to_nearer_end() * self.dac_x.metres_per_code
    }

    /// How far below the surface the normal transducer reaches, m:
    /// `zero_code·metres_per_code` of the normal channel (computed in f32).
    pub fn retract_z_m(&self) -> f32 {
        self.dac_z.zero_code * self.dac_z.metres_per_code
    }

    /// The lift-off limit of Δu_z at offset `offset_z_m`:
    /// `(1 − liftoff_margin)·offset_z_m`, computed in f32 (inclusive: Δu_z
    /// equal to it is accepted).
    pub fn liftoff_limit_m(&self, offset_z_m: f32) -> f32 {
        (1.0 - self.liftoff_margin) * offset_z_m
    }
}

impl Info {
    /// The `Info` of a device with configuration `cfg`, board name `board`
    /// (ASCII, truncated to 16 bytes) and firmware version `firmware`.
    pub fn for_config(cfg: &DeviceConfig, board: &str, firmware: [u8; 3]) -> Self {
        let mut name = [0u8; 16];
        for (d, s) in name.iter_mut().zip(board.bytes()) {
            *d = s;
        }
        Info {
            firmware,
            protocol: PROTOCOL_VERSION,
            board: name,
            sample_rate_hz: cfg.sample_rate_hz,
            freq_range_hz: cfg.freq_range_hz,
            max_amp_x_m: cfg.max_amp_x_m(),
            max_offset_z_m: cfg.max_offset_z_m(),
            liftoff_margin: cfg.liftoff_margin,
            max_phase_rad: MAX_PHASE_RAD,
            max_velocity_m_s: MAX_VELOCITY_M_S,
            periods_range: PERIODS_RANGE,
            byte_timeout_us: BYTE_TIMEOUT_US,
            retract_z_m: cfg.retract_z_m(),
            self_test: crate::protocol::messages::SelfTest::NOT_RUN,
        }
    }
}

/// [`DeviceConfig::pickup_delay_words`] in integers from the factor `k` of
/// [`DeviceConfig::pickup_delay_factor`]: `⌊(tw·k + 2³¹)/2³²⌋`. `k` is
/// within ½ of `2³²·δ·f_s`, so `tw·k/2³²` is within `tw/2³³ < ½` word of
/// `tw·δ·f_s`, and the result within one word of it (the f64 form's
/// rounding, ½ word, and this): 1.5e-9 rad, `tests/tests/pickup_delay.rs`.
pub fn pickup_delay_words_of(k: u64, tw: u32) -> u32 {
    // tw·k ≤ (2³² − 1)² = 2⁶⁴ − 2³³ + 1: the half word added stays in u64.
    ((u64::from(tw) * k + (1 << 31)) >> 32) as u32
}

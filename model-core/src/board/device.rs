//! The driver board's logic, free of hardware types so that the host runs the
//! very same code (native tests, the virtual device): drive settings in
//! physical units with the transducer calibration, the lift-off guard, start /
//! ramped stop, faults with a safe state, the DAC refill and ADC intake
//! bookkeeping (which drive phase each ADC sample belongs to), the friction
//! measurement and the model's prediction for the current drive.
//!
//! Every setter validates its whole input before touching anything: a
//! refused command leaves the running state exactly as it was.

use crate::board::dds::{phase_word, Achieved, Dds, DdsError, Level, SineTable, Slew};
use crate::board::estimator::{Calibration, Estimate, EstimateError, Estimator};
use crate::model::exact::{self, ExactError, Solution};
use crate::model::float::Libm;
use crate::model::regime::{classify, ClassifyOptions, Regime};
use crate::model::scene::{Scene, SceneError, SceneParams};

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
    /// ADC sample `k` sees the DAC word `k − lag` (the STM32 DAC moves its
    /// holding register to the output on the trigger and only then requests
    /// the next word by DMA: lag 1). The phase of each ADC sample is shifted
    /// accordingly.
    pub adc_lag_samples: u32,
}

impl DeviceConfig {
    /// The driver board's configuration, shared by the firmware and the
    /// virtual device: 500 kS/s, 2 nm/code normal and 1 nm/code tangential
    /// (around mid-scale) transducer calibration, 0.02 N/count (f_z) and
    /// 0.01 N/count around mid-scale (f_x) force calibration, 5 % lift-off
    /// margin, 1–100 kHz, 1 mm/s and 100 rad/s slew. Replace the calibrations
    /// with a board's measured values. `adc_lag_samples` is 1 on the chip (the
    /// DAC moves its holding register to the output on the trigger, the ADC
    /// converts on the same trigger) and 0 for a plant that samples at the
    /// drive phase of the sample itself.
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
            liftoff_margin: 0.05,
            freq_range_hz: (1_000.0, 100_000.0),
            slew_m_per_s: 1e-3,
            slew_rad_per_s: 100.0,
            adc_lag_samples,
        }
    }
}

/// The drive as commanded, physical units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveSetting {
    /// Drive frequency, Hz.
    pub freq_hz: f64,
    /// Normal amplitude Δu_z, m (≥ 0).
    pub amp_z_m: f32,
    /// Tangential amplitude Δu_x, m (≥ 0).
    pub amp_x_m: f32,
    /// Normal offset = mean indentation u_z0, m (> 0).
    pub offset_z_m: f32,
    /// Phase φ of the tangential drive, rad.
    pub phase_rad: f32,
}

/// The contact the device predicts with (the drive supplies u_z0, Δu_z, Δu_x, ω, φ).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Contact {
    /// μ₀.
    pub mu0: f32,
    /// k_z, N/m.
    pub kz: f32,
    /// k_x, N/m.
    pub kx: f32,
}

/// Which drive parameter an error names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DriveParam {
    /// Frequency.
    Freq,
    /// Normal amplitude.
    AmpZ,
    /// Tangential amplitude.
    AmpX,
    /// Normal offset.
    OffsetZ,
    /// Phase.
    Phase,
    /// Measurement periods.
    Periods,
    /// Velocity of a prediction.
    Velocity,
}

/// Why a command was refused (nothing changed).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceError {
    /// A parameter is not finite or outside `[min, max]`.
    OutOfRange {
        /// The parameter.
        param: DriveParam,
        /// Smallest allowed value.
        min: f32,
        /// Largest allowed value.
        max: f32,
    },
    /// Δu_z would exceed `(1 − margin)·u_z0`: the contact would lift off.
    LiftOff {
        /// Commanded Δu_z, m.
        amp_z_m: f32,
        /// Largest allowed Δu_z, m.
        limit_m: f32,
    },
    /// A measurement is already running.
    Busy,
    /// A fault is latched: reset it first.
    Faulted(u32),
    /// The contact and drive do not form a valid scene.
    Scene(SceneError),
    /// The model solver failed.
    Model(ExactError),
    /// No finished measurement.
    Estimate(EstimateError),
}

/// Latched fault bits.
pub mod faults {
    /// An ADC sample hit the rail during a measurement.
    pub const ADC_SATURATED: u32 = 1 << 0;
    /// The DAC buffer was refilled late (the DMA read a stale half).
    pub const DAC_UNDERRUN: u32 = 1 << 1;
    /// The previous reset was by the watchdog.
    pub const WATCHDOG_RESET: u32 = 1 << 2;
    /// An external fault input (e.g. an amplifier alarm).
    pub const EXTERNAL: u32 = 1 << 3;
}

/// What a drive command achieved (exact frequency and phase of the DDS).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Applied {
    /// The DDS frequency.
    pub achieved: Achieved,
    /// Exact phase between the channels' waveforms (φ as produced), rad.
    pub phase_rad: f64,
}

/// A model prediction for the current drive.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Prediction {
    /// μ/μ₀ at the velocity (at v₀ = 0: μ(0⁺)).
    pub mu_over_mu0: f32,
    /// μ.
    pub mu: f32,
    /// Forward and backward critical velocity, m/s.
    pub vc: (f32, f32),
}

/// Status snapshot.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Drive running (amplitudes at or ramping to the setting).
    pub running: bool,
    /// All ramps finished.
    pub settled: bool,
    /// Latched fault bits ([`faults`]).
    pub faults: u32,
    /// A measurement is in progress.
    pub measuring: bool,
    /// Received bytes dropped because the link's receive queue was full, since
    /// power-up (saturating). Never a silent drop: a host that sees this grow
    /// pipelined more than the device can hold.
    pub rx_overflows: u32,
}

/// The device.
pub struct Device<'t, const N: usize> {
    cfg: DeviceConfig,
    table: &'t SineTable<N>,
    dds: Dds<'t, N>,
    drive: DriveSetting,
    applied: Applied,
    contact: Contact,
    running: bool,
    faults: u32,
    rx_overflows: u32,
    est: Estimator,
    /// Accumulator and tuning word at the start of each DAC half-buffer.
    half: [(u32, u32); 2],
}

fn range(x: f32, min: f32, max: f32, param: DriveParam) -> Result<f32, DeviceError> {
    if x.is_finite() && x >= min && x <= max {
        Ok(x)
    } else {
        Err(DeviceError::OutOfRange { param, min, max })
    }
}

impl<'t, const N: usize> Device<'t, N> {
    /// A stopped device with a zero drive.
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`] / [`DeviceError::Estimate`] for an invalid configuration.
    pub fn new(
        cfg: DeviceConfig,
        table: &'t SineTable<N>,
        contact: Contact,
    ) -> Result<Self, DeviceError> {
        let slew = Self::slew(&cfg)?;
        let dds =
            Dds::new(table, cfg.sample_rate_hz, slew).map_err(|_| DeviceError::OutOfRange {
                param: DriveParam::Freq,
                min: 0.0,
                max: f32::MAX,
            })?;
        let est = Estimator::new(cfg.adc_x, cfg.adc_z, cfg.adc_full_scale)
            .map_err(DeviceError::Estimate)?;
        range(cfg.liftoff_margin, 0.0, 0.99, DriveParam::AmpZ)?;
        for c in [cfg.dac_z, cfg.dac_x] {
            range(
                c.metres_per_code,
                f32::MIN_POSITIVE,
                f32::MAX,
                DriveParam::AmpZ,
            )?;
            range(c.zero_code, 0.0, 4095.0, DriveParam::OffsetZ)?;
        }
        let drive = DriveSetting {
            freq_hz: cfg.freq_range_hz.0,
            amp_z_m: 0.0,
            amp_x_m: 0.0,
            offset_z_m: 0.0,
            phase_rad: 0.0,
        };
        let mut d = Device {
            cfg,
            table,
            dds,
            drive,
            applied: Applied {
                achieved: Achieved {
                    tuning_word: 0,
                    freq_hz: 0.0,
                },
                phase_rad: 0.0,
            },
            contact,
            running: false,
            faults: 0,
            rx_overflows: 0,
            est,
            half: [(0, 0); 2],
        };
        d.check_contact(&contact)?;
        let a = d
            .dds
            .set_frequency(cfg.freq_range_hz.0)
            .map_err(|_| DeviceError::OutOfRange {
                param: DriveParam::Freq,
                min: cfg.freq_range_hz.0 as f32,
                max: cfg.freq_range_hz.1 as f32,
            })?;
        d.applied.achieved = a;
        // Rest levels: zero displacement on both channels.
        let _ = d.dds.set_level(
            0,
            Level {
                amp: 0.0,
                dc: cfg.dac_z.zero_code,
            },
        );
        let _ = d.dds.set_level(
            1,
            Level {
                amp: 0.0,
                dc: cfg.dac_x.zero_code,
            },
        );
        Ok(d)
    }

    fn slew(cfg: &DeviceConfig) -> Result<Slew, DeviceError> {
        let codes_per_s =
            cfg.slew_m_per_s / cfg.dac_z.metres_per_code.min(cfg.dac_x.metres_per_code);
        Slew::from_rates(
            cfg.sample_rate_hz as f32,
            codes_per_s,
            codes_per_s,
            cfg.slew_rad_per_s,
        )
        .map_err(|_| DeviceError::OutOfRange {
            param: DriveParam::Phase,
            min: 0.0,
            max: f32::MAX,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &DeviceConfig {
        &self.cfg
    }

    /// The drive as last accepted.
    pub fn drive(&self) -> DriveSetting {
        self.drive
    }

    /// What the DDS produces for the accepted drive.
    pub fn applied(&self) -> Applied {
        self.applied
    }

    /// The contact parameters.
    pub fn contact(&self) -> Contact {
        self.contact
    }

    /// The DDS (read-only).
    pub fn dds(&self) -> &Dds<'t, N> {
        &self.dds
    }

    /// Status snapshot.
    pub fn status(&self) -> Status {
        Status {
            running: self.running,
            settled: self.dds.settled(),
            faults: self.faults,
            measuring: self.est.busy(),
            rx_overflows: self.rx_overflows,
        }
    }

    /// Counts `n` received bytes the link had to drop (receive queue full);
    /// reported in [`Status::rx_overflows`].
    pub fn count_rx_overflow(&mut self, n: u32) {
        self.rx_overflows = self.rx_overflows.saturating_add(n);
    }

    fn check_contact(&self, c: &Contact) -> Result<(), DeviceError> {
        // Validate with a nominal drive so that only the contact is judged.
        Scene::new(SceneParams {
            mu0: c.mu0,
            kz: c.kz,
            kx: c.kx,
            uz0: 1e-6,
            duz: 0.0,
            dux: 0.0,
            omega: 1.0,
            phi: 0.0,
        })
        .map(|_| ())
        .map_err(DeviceError::Scene)
    }

    /// Sets the contact parameters.
    ///
    /// # Errors
    /// [`DeviceError::Scene`]; nothing changes on error.
    pub fn set_contact(&mut self, c: Contact) -> Result<(), DeviceError> {
        self.check_contact(&c)?;
        self.contact = c;
        Ok(())
    }

    /// DDS levels for a drive (validated, nothing applied).
    fn plan(&self, d: &DriveSetting) -> Result<(Achieved, [Level; 2], [u32; 2]), DeviceError> {
        let (fmin, fmax) = self.cfg.freq_range_hz;
        if !(d.freq_hz.is_finite() && d.freq_hz >= fmin && d.freq_hz <= fmax) {
            return Err(DeviceError::OutOfRange {
                param: DriveParam::Freq,
                min: fmin as f32,
                max: fmax as f32,
            });
        }
        let (z, x) = (self.cfg.dac_z, self.cfg.dac_x);
        let max_off = (4095.0 - z.zero_code) * z.metres_per_code;
        let off = range(d.offset_z_m, 0.0, max_off, DriveParam::OffsetZ)?;
        let limit = (1.0 - self.cfg.liftoff_margin) * off;
        if !(d.amp_z_m.is_finite() && d.amp_z_m >= 0.0) {
            return Err(DeviceError::OutOfRange {
                param: DriveParam::AmpZ,
                min: 0.0,
                max: limit,
            });
        }
        if d.amp_z_m > limit || (d.amp_z_m > 0.0 && off == 0.0) {
            return Err(DeviceError::LiftOff {
                amp_z_m: d.amp_z_m,
                limit_m: limit,
            });
        }
        let max_x = x.zero_code.min(4095.0 - x.zero_code) * x.metres_per_code;
        let amp_x = range(d.amp_x_m, 0.0, max_x, DriveParam::AmpX)?;
        let phase = range(d.phase_rad, -1e3, 1e3, DriveParam::Phase)?;
        let achieved = self
            .dds
            .plan_frequency(d.freq_hz)
            .map_err(|_| DeviceError::OutOfRange {
                param: DriveParam::Freq,
                min: fmin as f32,
                max: fmax as f32,
            })?;
        let lz = Level {
            amp: d.amp_z_m / z.metres_per_code,
            dc: z.zero_code + off / z.metres_per_code,
        };
        let lx = Level {
            amp: amp_x / x.metres_per_code,
            dc: x.zero_code,
        };
        // Both waveforms must stay inside the DAC range (the normal one by the
        // lift-off guard and offset range, but check both exactly).
        lz.check().map_err(|_| DeviceError::OutOfRange {
            param: DriveParam::AmpZ,
            min: 0.0,
            max: (4095.0 - lz.dc).min(lz.dc) * z.metres_per_code,
        })?;
        lx.check().map_err(|_| DeviceError::OutOfRange {
            param: DriveParam::AmpX,
            min: 0.0,
            max: max_x,
        })?;
        // −cos θ = sin(θ − π/2);  cos(θ + φ) = sin(θ + φ + π/2).
        let pz = phase_word(-core::f64::consts::FRAC_PI_2);
        let px = phase_word(f64::from(phase) + core::f64::consts::FRAC_PI_2);
        Ok((achieved, [lz, lx], [pz, px]))
    }

    /// Sets the drive. While running the DDS ramps to it; while stopped it is
    /// stored and used at the next start.
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`], [`DeviceError::LiftOff`], [`DeviceError::Faulted`];
    /// nothing changes on error.
    pub fn set_drive(&mut self, d: DriveSetting) -> Result<Applied, DeviceError> {
        if self.faults != 0 && self.running {
            return Err(DeviceError::Faulted(self.faults));
        }
        let (achieved, levels, phases) = self.plan(&d)?;
        self.drive = d;
        self.dds.set_frequency(d.freq_hz).map_err(dds_err)?;
        self.dds.set_phase(0, phases[0]);
        self.dds.set_phase(1, phases[1]);
        self.applied = Applied {
            achieved,
            phase_rad: crate::board::dds::phase_rad(
                phases[1].wrapping_sub(phases[0]).wrapping_sub(1 << 31),
            ),
        };
        if self.running {
            self.dds.set_level(0, levels[0]).map_err(dds_err)?;
            self.dds.set_level(1, levels[1]).map_err(dds_err)?;
        } else {
            // Stopped: the normal offset (preload) is applied, amplitudes stay 0.
            self.dds
                .set_level(
                    0,
                    Level {
                        amp: 0.0,
                        dc: levels[0].dc,
                    },
                )
                .map_err(dds_err)?;
        }
        Ok(self.applied)
    }

    /// Starts the drive (soft start at the slew rate).
    ///
    /// # Errors
    /// [`DeviceError::Faulted`] while a fault is latched.
    pub fn start(&mut self) -> Result<(), DeviceError> {
        if self.faults != 0 {
            return Err(DeviceError::Faulted(self.faults));
        }
        let (_, levels, _) = self.plan(&self.drive)?;
        self.dds.set_level(0, levels[0]).map_err(dds_err)?;
        self.dds.set_level(1, levels[1]).map_err(dds_err)?;
        self.running = true;
        Ok(())
    }

    /// Stops the drive: amplitudes ramp to zero, the normal offset stays.
    pub fn stop(&mut self) {
        self.dds.ramp_down();
        self.running = false;
    }

    /// Latches a fault and enters the safe state: amplitudes and offsets ramp
    /// to zero displacement.
    pub fn fault(&mut self, bits: u32) {
        self.faults |= bits;
        self.running = false;
        let _ = self.dds.set_level(
            0,
            Level {
                amp: 0.0,
                dc: self.cfg.dac_z.zero_code,
            },
        );
        let _ = self.dds.set_level(
            1,
            Level {
                amp: 0.0,
                dc: self.cfg.dac_x.zero_code,
            },
        );
    }

    /// Clears latched faults (the drive stays stopped).
    pub fn reset_faults(&mut self) {
        self.faults = 0;
    }

    /// Refills DAC half-buffer `half` (0 or 1) with packed words and records
    /// the drive phase of its first sample for the ADC intake.
    pub fn fill_dac(&mut self, half: usize, buf: &mut [u32]) {
        self.half[half & 1] = (self.dds.accumulator(), self.dds.tuning_word());
        self.dds.fill(buf);
    }

    /// Takes the ADC samples `(f_x, f_z)` of the DAC half-buffer `half`
    /// (same timer ticks, same indices).
    pub fn adc_block(&mut self, half: usize, samples: &[(u16, u16)]) {
        let (acc0, tw) = self.half[half & 1];
        let mut acc = acc0.wrapping_sub(tw.wrapping_mul(self.cfg.adc_lag_samples));
        for &(x, z) in samples {
            if self.est.push(self.table, acc, x, z) {
                if let Ok(e) = self.est.estimate() {
                    if e.saturated {
                        self.faults |= faults::ADC_SATURATED;
                    }
                }
            }
            acc = acc.wrapping_add(tw);
        }
    }

    /// Starts a measurement over `periods` drive periods.
    ///
    /// # Errors
    /// [`DeviceError::Busy`] if one is running; [`DeviceError::OutOfRange`] for 0 or
    /// more than 10⁶ periods.
    pub fn measure(&mut self, periods: u32) -> Result<(), DeviceError> {
        if self.est.busy() {
            return Err(DeviceError::Busy);
        }
        if periods == 0 || periods > 1_000_000 {
            return Err(DeviceError::OutOfRange {
                param: DriveParam::Periods,
                min: 1.0,
                max: 1e6,
            });
        }
        self.est.start(periods).map_err(DeviceError::Estimate)
    }

    /// The last finished measurement.
    ///
    /// # Errors
    /// [`DeviceError::Estimate`] (`NotReady` while running).
    pub fn estimate(&self) -> Result<Estimate, DeviceError> {
        self.est.estimate().map_err(DeviceError::Estimate)
    }

    /// The scene of the contact with the accepted drive (f32).
    ///
    /// # Errors
    /// [`DeviceError::Scene`] (e.g. zero offset).
    pub fn scene(&self) -> Result<Scene<f32>, DeviceError> {
        let d = &self.drive;
        Scene::new(SceneParams {
            mu0: self.contact.mu0,
            kz: self.contact.kz,
            kx: self.contact.kx,
            uz0: d.offset_z_m,
            duz: d.amp_z_m,
            dux: d.amp_x_m,
            omega: (core::f64::consts::TAU * self.applied.achieved.freq_hz) as f32,
            phi: self.applied.phase_rad as f32,
        })
        .map_err(DeviceError::Scene)
    }

    /// The model's μ at sliding velocity `v0` (m/s) for the current drive
    /// (f32, exact solver).
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`] for a non-finite velocity, [`DeviceError::Scene`], [`DeviceError::Model`].
    pub fn predict(&self, v0: f32) -> Result<Prediction, DeviceError> {
        predict(&self.scene()?, v0)
    }

    /// The regime of the current drive.
    ///
    /// # Errors
    /// As [`Device::predict`].
    pub fn regime(&self) -> Result<Regime, DeviceError> {
        regime(&self.scene()?)
    }
}

/// The model's μ at `v0` (m/s) for a scene (what [`Device::predict`] computes;
/// callable on a snapshot outside the device's critical section).
///
/// # Errors
/// [`DeviceError::OutOfRange`] for a non-finite velocity, [`DeviceError::Model`].
pub fn predict(s: &Scene<f32>, v0: f32) -> Result<Prediction, DeviceError> {
    range(v0, -1e3, 1e3, DriveParam::Velocity)?;
    let vc = crate::model::analytic::CriticalVelocity::of(s);
    let m = match exact::solve_with::<f32, Libm>(s, v0).map_err(DeviceError::Model)? {
        Solution::Sliding { mu_over_mu0 } | Solution::StickSlip { mu_over_mu0 } => mu_over_mu0,
        Solution::AtRest { mu_0plus, .. } => mu_0plus,
    };
    Ok(Prediction {
        mu_over_mu0: m,
        mu: m * s.mu0(),
        vc: (vc.forward, vc.backward),
    })
}

/// The regime of a scene (what [`Device::regime`] computes).
///
/// # Errors
/// [`DeviceError::Model`].
pub fn regime(s: &Scene<f32>) -> Result<Regime, DeviceError> {
    classify(s, &ClassifyOptions::default())
        .map(|c| c.regime)
        .map_err(DeviceError::Model)
}

fn dds_err(_: DdsError) -> DeviceError {
    DeviceError::OutOfRange {
        param: DriveParam::AmpZ,
        min: 0.0,
        max: 0.0,
    }
}

//! The driver board's logic, free of hardware types so that the host runs the
//! very same code (native tests, the virtual device), in named steps:
//!
//! * [`config`] — the board's configuration and the limits it implies;
//! * `drive` — drive settings in physical units with the transducer
//!   calibration, the lift-off guard, start / ramped stop;
//! * `fault` — the latched faults and the one path into the safe state
//!   (every fault source, and where it is raised);
//! * `measure` — the DAC refill and ADC intake bookkeeping (which drive phase
//!   each ADC sample belongs to) and the friction measurement;
//! * `motion` — the transducers' measured motion (the pickups' lock-ins);
//! * [`displacement`] — the displacement mode: identified transducers as
//!   feed-forward, dead-beat transitions within a voltage headroom, a
//!   complex loop per channel on the measured motion;
//! * [`tracking`] — the resonance tracking (a PLL on one mode's phase);
//! * `predict` — the model's prediction for the current drive;
//! * `load` — the board's own measure of its DSP time per half-buffer;
//! * `closed_loop` — the closed loop's timing (which samples each update
//!   uses, when its command reaches the DAC);
//! * [`error`] — why a command was refused.
//!
//! The wire types the device answers with ([`DriveSetting`], [`Contact`],
//! [`Prediction`], [`Status`], [`Applied`], [`DriveParam`]) live in
//! [`crate::protocol::messages`] and are re-exported here.
//!
//! Every setter validates its whole input before touching anything: a
//! refused command leaves the running state exactly as it was.
//!
//! # Contexts
//!
//! Where each piece runs on the board (issue 35; the firmware's priorities
//! in `hardware::nvic`, the work per half-buffer measured by `predict_cost`'s
//! "worst half-buffer, everything on" and reported as
//! [`Status::cpu_load_pct`]):
//!
//! | context | priority | work | bound |
//! |---|---|---|---|
//! | the DAC handler, per half-buffer | `DSP` | [`Device::dac_half_done`]: the μ loop's command in force, the dead-beat levels (D4–D6, the pole D8 only when c moved), the DDS refill | one half-buffer with the ADC handler's work |
//! | the ADC handler, per half-buffer | `DSP` | [`Device::adc_half_done_with_pickups`]: one reference and the integer sums of every signal ([`crate::reference`]); when a lock-in window closes (every fourth block while the loop holds), its fit, the lift-off guard, D3 and the tracking step (T1–T3); when the μ loop's estimate closes, [`crate::estimator::Estimator::estimate_mu`] and the update (C1–C7) | the same |
//! | the server, in the main loop | thread | every request; the scene and the prediction (≈ 4 200 and 1 300 instructions), the μ loop's plan (≈ 61 000, once per setpoint), a measurement's whole estimate (on a copy of the estimator), the measured motion's report ([`Device::measured_drive`]) — all with the device released | none (preempted by the handlers) |
//! | the server's critical sections ([`crate::server::DeviceAccess::with`]) | masks `DSP` | copies in and out of the device, the checks of a request | 10 % of a half-buffer; the drive-planning requests a stated 8 000 instructions |

mod closed_loop;
pub mod config;
pub mod displacement;
mod drive;
pub mod error;
mod fault;
mod load;
mod measure;
mod motion;
mod predict;
pub mod tracking;

pub use closed_loop::{estimate_samples, periods_in_half_buffer, MIN_GAIN};
pub use config::{
    DacCal, DeviceConfig, HALF_BUFFER, MAX_PHASE_RAD, MAX_VELOCITY_M_S, PERIODS_RANGE,
    STIFFNESS_RANGE_N_PER_M,
};
pub use error::{ConfigError, DeviceError};
pub use fault::faults;
pub use load::CpuLoad;
pub use measure::{check_periods, estimate};
pub use motion::{MeasuredDrive, WINDOW_MIN_SAMPLES, WINDOW_SPAN_RAD};
pub use predict::{predict, regime};

pub use crate::protocol::messages::{
    Applied, Contact, DisplacementOptions, DriveMode, DriveParam, DriveSetting, Prediction, Status,
    Track, TransducerModel, Transducers,
};

use crate::dds::{Achieved, Dds, Level, SineTable, Slew};
use crate::estimator::Estimator;
use crate::reference::BLOCK;
use model_core::scene::{self, ContactMode, Scene, SceneParams};

/// The device.
pub struct Device<'t, const N: usize> {
    cfg: DeviceConfig,
    table: &'t SineTable<N>,
    dds: Dds<'t, N>,
    drive: DriveSetting,
    applied: Applied,
    contact: Contact,
    /// Drives above the lift-off limit are accepted (`SetLiftOff`).
    allow_liftoff: bool,
    /// The scene parameters of the contact with the accepted drive, taken
    /// whenever one of them changes (a copy: the scene itself is formed
    /// where it is used, outside the critical sections of the firmware).
    scene: SceneInputs,
    running: bool,
    latch: fault::Latch,
    rx_overflows: u32,
    est: Estimator,
    /// Accumulator and tuning word at the start of the last fills (by fill
    /// number modulo `measure::FILL_RING`).
    half: [(u32, u32); measure::FILL_RING],
    /// Estimate reasons that held while those fills were made.
    half_conditions: [u32; measure::FILL_RING],
    /// Per ADC block (same slots): its reference words (eq. R1) as the DAC
    /// fills formed them for their codes, laid out as the ADC sees them:
    /// `L` = [`DeviceConfig::adc_lag_samples`] words from the end of fill
    /// `n − 1`, then fill `n`'s first `BLOCK − L` (`measure.rs`,
    /// `kept_reference`).
    fill_refs: [[u32; BLOCK]; measure::FILL_RING],
    /// Which fills wrote each slot's two parts: `(n − 1, n)` when block
    /// `n`'s words are whole.
    fill_refs_by: [(u32, u32); measure::FILL_RING],
    /// ADC blocks whose reference the ADC handler formed itself (their
    /// fills' words not kept: `measure.rs`, `kept_reference`).
    references_formed: u32,
    /// +1 per command that sets new DDS targets (accepted `set_drive`,
    /// `start`, `stop`, `fault`).
    ramp_generation: u32,
    /// The closed loop (`None` until first switched on).
    control: Option<closed_loop::Loop>,
    /// DAC fills since power-up (the number of the next fill).
    fills: u32,
    /// ADC blocks since power-up (the number of the next block).
    adc_blocks: u32,
    /// The motion pickups' lock-ins and last result.
    motion: motion::Motion,
    /// The identified transducers (`SetTransducers`; kept by `Reset`).
    transducers: Option<Transducers>,
    /// Voltage or displacement mode.
    mode: DriveMode,
    /// The displacement loops.
    loops: displacement::Loops,
    /// (v6) Tracking and headroom.
    options: displacement::DisplacementOptions,
    /// (v6) The resonance tracking.
    tracker: tracking::Tracker,
    /// (v8) The DSP handlers' cycles per half-buffer, as the firmware
    /// counted them.
    load: CpuLoad,
}

/// `x` if finite and in `[min, max]`, else [`DeviceError::OutOfRange`].
fn in_range(x: f32, min: f32, max: f32, param: DriveParam) -> Result<f32, DeviceError> {
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
    /// [`DeviceError::Config`] for a configuration that cannot work,
    /// [`DeviceError::Scene`] for an invalid contact.
    pub fn new(
        cfg: DeviceConfig,
        table: &'t SineTable<N>,
        contact: Contact,
    ) -> Result<Self, DeviceError> {
        let dds = Dds::new(table, cfg.sample_rate_hz, Self::slew(&cfg)?)
            .map_err(|_| DeviceError::Config(ConfigError::SampleRate))?;
        let est = Estimator::new(cfg.adc_x, cfg.adc_z, cfg.adc_full_scale)
            .map_err(|_| DeviceError::Config(ConfigError::AdcCal))?;
        check_config(&cfg)?;
        let mut d = Device {
            cfg,
            table,
            dds,
            drive: DriveSetting {
                freq_hz: cfg.freq_range_hz.0,
                amp_z_m: 0.0,
                amp_x_m: 0.0,
                offset_z_m: 0.0,
                phase_rad: 0.0,
            },
            applied: Applied {
                achieved: Achieved {
                    tuning_word: 0,
                    freq_hz: 0.0,
                },
                phase_rad: 0.0,
            },
            contact,
            allow_liftoff: false,
            scene: SceneInputs::UNSET,
            running: false,
            latch: fault::Latch::new(),
            rx_overflows: 0,
            est,
            half: [(0, 0); measure::FILL_RING],
            half_conditions: [0; measure::FILL_RING],
            fill_refs: [[0; BLOCK]; measure::FILL_RING],
            fill_refs_by: [(1, 1); measure::FILL_RING],
            references_formed: 0,
            ramp_generation: 0,
            control: None,
            fills: 0,
            adc_blocks: 0,
            motion: motion::Motion::default(),
            transducers: None,
            mode: DriveMode::OpenLoop,
            loops: displacement::Loops::default(),
            options: displacement::DisplacementOptions::default(),
            tracker: tracking::Tracker::default(),
            load: CpuLoad::new(),
        };
        check_contact(&contact)?;
        d.applied.achieved = d
            .dds
            .set_frequency(cfg.freq_range_hz.0)
            .map_err(|_| DeviceError::Config(ConfigError::FreqRange))?;
        d.rest_levels()?;
        d.refresh_scene();
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
        .map_err(|_| DeviceError::Config(ConfigError::Slew))
    }

    /// Targets zero displacement on both channels (amplitudes 0, DC at the
    /// calibrations' zero codes).
    fn rest_levels(&mut self) -> Result<(), DeviceError> {
        let (z, x) = (self.cfg.dac_z.zero_code, self.cfg.dac_x.zero_code);
        self.dds.set_level(0, Level { amp: 0.0, dc: z })?;
        self.dds.set_level(1, Level { amp: 0.0, dc: x })?;
        Ok(())
    }

    /// The configuration.
    pub fn config(&self) -> &DeviceConfig {
        &self.cfg
    }

    /// The drive as last accepted (the setting; see [`Status`] for the output).
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
        let ch = self.dds.channels();
        let (z, x) = (self.cfg.dac_z, self.cfg.dac_x);
        let mut s = Status {
            running: self.running,
            settled: self.dds.settled(),
            faults: self.latch.bits(),
            measuring: self.est.busy(),
            rx_overflows: self.rx_overflows,
            out_amp_z_m: ch[0].amp.abs() * z.metres_per_code,
            out_amp_x_m: ch[1].amp.abs() * x.metres_per_code,
            out_offset_z_m: (ch[0].dc - z.zero_code) * z.metres_per_code,
            liftoff_allowed: self.allow_liftoff,
            measured: self.measured_drive(),
            mode: self.mode,
            frequency_hz: 0.0,
            options: self.options,
            tracking_error_hz: None,
            locked: false,
            cpu_load_pct: self.load.last_pct(),
            cpu_load_max_pct: self.load.max_pct(),
        };
        self.displacement_status(&mut s);
        s
    }

    /// (v8) Records the cycles the DSP handlers took for one half-buffer
    /// (the DAC refill and the ADC block of the same half) out of `budget`
    /// cycles per half-buffer: [`Status::cpu_load_pct`] and
    /// [`Status::cpu_load_max_pct`] (eq. L1 of `device::load`). Called by
    /// the firmware's ADC handler at the end of its work, once per
    /// half-buffer; a device that never calls it reports neither.
    pub fn record_cpu_load(&mut self, cycles: u32, budget: core::num::NonZeroU32) {
        self.load.record(cycles, budget);
    }

    /// (v8) Forgets the largest load (`Reset`): [`Status::cpu_load_max_pct`]
    /// is `None` until the next recorded half-buffer.
    pub fn clear_cpu_load_max(&mut self) {
        self.load.clear_max();
    }

    /// (v8) The recorded DSP load.
    pub fn cpu_load(&self) -> &CpuLoad {
        &self.load
    }

    /// Counts the commands that set new DDS targets (accepted `set_drive`,
    /// `start`, `stop`, `fault`), wrapping: the server sends one `RampDone`
    /// when the DDS has settled after the count changed.
    pub fn ramp_generation(&self) -> u32 {
        self.ramp_generation
    }

    /// Counts `n` received bytes the link had to drop (receive queue full);
    /// reported in [`Status::rx_overflows`].
    pub fn count_rx_overflow(&mut self, n: u32) {
        self.rx_overflows = self.rx_overflows.saturating_add(n);
    }

    /// The received bytes dropped by a full receive queue since power-up
    /// ([`Status::rx_overflows`]).
    pub fn rx_overflow_count(&self) -> u32 {
        self.rx_overflows
    }

    /// A measurement's window is open or pending ([`Status::measuring`]).
    pub fn measuring(&self) -> bool {
        self.est.busy()
    }

    /// Sets the contact parameters.
    ///
    /// # Errors
    /// [`DeviceError::Scene`]; nothing changes on error.
    pub fn set_contact(&mut self, c: Contact) -> Result<(), DeviceError> {
        check_contact(&c)?;
        self.contact = c;
        self.refresh_scene();
        Ok(())
    }

    /// Whether drives above the lift-off limit are accepted.
    pub fn liftoff_allowed(&self) -> bool {
        self.allow_liftoff
    }

    /// Allows drives whose normal amplitude exceeds the lift-off limit
    /// [`DeviceConfig::liftoff_limit_m`] (the contact lifts off once per
    /// period when `Δu_z ≥ u_z0`; [`Device::predict`] then uses the lift-off
    /// model), or refuses them again (the power-up state). The DAC range
    /// still bounds `Δu_z` (see `set_drive`).
    ///
    /// # Errors
    /// [`DeviceError::LiftOff`] when refusing while the accepted drive is
    /// above the limit (set a smaller `Δu_z` first); nothing changes on error.
    pub fn set_liftoff_allowed(&mut self, allow: bool) -> Result<(), DeviceError> {
        if !allow {
            self.check_liftoff(&self.drive)?;
        }
        self.allow_liftoff = allow;
        self.refresh_scene();
        Ok(())
    }

    /// The scene parameters of the contact with the accepted drive (f32) and
    /// its contact mode: intermittent ([`ContactMode::Intermittent`]) while
    /// lift-off is allowed, else permanent. A copy, taken when the drive, the
    /// contact or the lift-off setting changed: what the server takes out of
    /// the device's critical section to form the scene with the device
    /// released ([`SceneInputs::scene`]).
    pub fn scene_inputs(&self) -> SceneInputs {
        self.scene
    }

    /// The scene of the contact with the accepted drive (f32), formed from
    /// [`Device::scene_inputs`] on each call (`Scene::new`: validation, W₀,
    /// libm's `sincosf` of φ — thousands of instructions on the Cortex-M4F;
    /// a convenience for host code, not for a critical section).
    ///
    /// # Errors
    /// [`DeviceError::Scene`] (e.g. zero offset).
    pub fn scene(&self) -> Result<Scene<f32>, DeviceError> {
        self.scene.scene()
    }

    /// Takes [`Device::scene_inputs`] anew: after every change of the drive,
    /// its applied frequency and phase, the contact or the lift-off setting.
    pub(super) fn refresh_scene(&mut self) {
        self.scene = self.live_scene_inputs();
    }

    /// The scene parameters of the contact with the accepted drive at the
    /// frequency and phase the DDS applies now (while tracking, the tracked
    /// frequency; [`Device::scene_inputs`] holds the one of the last change).
    pub(super) fn live_scene_inputs(&self) -> SceneInputs {
        let d = &self.drive;
        self.scene_inputs_with(SceneParams {
            mu0: self.contact.mu0,
            kz: self.contact.kz,
            kx: self.contact.kx,
            uz0: d.offset_z_m,
            duz: d.amp_z_m,
            dux: d.amp_x_m,
            omega: (core::f64::consts::TAU * self.applied.achieved.freq_hz) as f32,
            phi: self.applied.phase_rad as f32,
        })
    }

    /// `params` with the contact mode of the lift-off setting.
    pub(super) fn scene_inputs_with(&self, params: SceneParams<f32>) -> SceneInputs {
        let contact = if self.allow_liftoff {
            ContactMode::Intermittent
        } else {
            ContactMode::Permanent
        };
        SceneInputs { params, contact }
    }
}

/// The parameters of a scene and its contact mode, unvalidated: cheap to
/// copy out of the device (no scene is formed inside the firmware's critical
/// sections: `Scene::new` would hold the DMA handlers off for longer than a
/// half-buffer). Form the scene with [`SceneInputs::scene`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneInputs {
    /// The physical parameters (SI units).
    pub params: SceneParams<f32>,
    /// Permanent, or intermittent while lift-off is allowed.
    pub contact: ContactMode,
}

impl SceneInputs {
    /// Before the device first took its scene parameters.
    const UNSET: SceneInputs = SceneInputs {
        params: SceneParams {
            mu0: 0.0,
            kz: 0.0,
            kx: 0.0,
            uz0: 0.0,
            duz: 0.0,
            dux: 0.0,
            omega: 0.0,
            phi: 0.0,
        },
        contact: ContactMode::Permanent,
    };

    /// The scene (`Scene::new_with_contact`).
    ///
    /// # Errors
    /// [`DeviceError::Scene`].
    pub fn scene(&self) -> Result<Scene<f32>, DeviceError> {
        Scene::new_with_contact(self.params, self.contact).map_err(DeviceError::Scene)
    }
}

/// The configuration checks the DDS and the estimator do not make themselves.
fn check_config(cfg: &DeviceConfig) -> Result<(), DeviceError> {
    cfg.check_pickup_delay().map_err(DeviceError::Config)?;
    let m = cfg.liftoff_margin;
    if !(m.is_finite() && (0.0..=0.99).contains(&m)) {
        return Err(DeviceError::Config(ConfigError::LiftoffMargin));
    }
    for c in [cfg.dac_z, cfg.dac_x] {
        let ok = c.metres_per_code.is_finite()
            && c.metres_per_code > 0.0
            && c.zero_code.is_finite()
            && (0.0..=f32::from(crate::dds::DAC_MAX)).contains(&c.zero_code);
        if !ok {
            return Err(DeviceError::Config(ConfigError::DacCal));
        }
    }
    let (lo, hi) = cfg.freq_range_hz;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi && hi < cfg.sample_rate_hz / 2.0)
    {
        return Err(DeviceError::Config(ConfigError::FreqRange));
    }
    Ok(())
}

/// Validates a contact as `Scene::new` judges it with a nominal drive
/// (`u_z0` = 1 µm, no oscillation, `ω` = 1), so that only the contact is
/// judged: μ₀, k_z, k_x finite, > 0 and normal, and W₀ at 1 µm in range
/// ([`scene::check_contact_params`]: the scene's own checks, without forming
/// one — a few comparisons).
fn check_contact(c: &Contact) -> Result<(), DeviceError> {
    scene::check_contact_params(c.mu0, c.kz, c.kx, 1e-6)
        .map(|_| ())
        .map_err(DeviceError::Scene)
}

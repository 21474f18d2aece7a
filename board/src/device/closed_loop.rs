//! The closed loop inside the device ([`crate::control`]): which
//! samples each update's estimate covers and when its command reaches the DAC.
//!
//! **Timing.** DAC fill `n` (the `n`-th call of `fill_dac` since power-up)
//! is the output that ADC block `n` (the `n`-th call of `adc_block`) samples
//! — on the board the two DMA buffers of one timer, in the virtual device
//! the same order. A command is applied at the next fill after its update (a
//! DDS level change, ramped at the slew rate, without a new ramp
//! generation), and the command in force at each fill is recorded. An
//! estimate covers the *last* `periods` drive periods of a block (the slew
//! ramp and the plant's transient have the rest of the block to pass), or
//! of the `k` blocks they need when they do not fit in one (at 20 kHz,
//! 4 periods + 1 for the wait for a period start are 125 samples: two
//! 64-sample blocks); one update follows when it closes.
//!
//! **Dead time.** On the board block `n` is handled after fill `n + 2` (the
//! DAC's refill of the same boundary runs first), so a command computed from
//! block `n` reaches the output at fill `n + 3`; in the virtual device (by
//! default) at fill `n + 1`. An estimate is used only if *every* block it
//! covers had the latest command with the normal channel's amplitude
//! already at it (`u_n = u_latest`, not ramping at the slew rate nor in a
//! dead-beat transition: "fresh"); it opens only in a fresh block, and is
//! dropped if a block it covers is not, so no update acts on an error its
//! predecessor already corrected, nor on a transition's partial response.
//! (Checking only the block where a two-block estimate closed let the
//! transition block in at 20 kHz: the estimate saw ≈ 85 % of a step's
//! response, and the loop's effective gain fell by as much.) The update
//! interval is therefore at least one half-buffer in the virtual device
//! and three on the board (3 × 128 µs with
//! [`super::HALF_BUFFER`] = 64), longer while a large change ramps (1 µm per
//! ms): with 128 µs blocks, estimates taken mid-ramp made the integral
//! overshoot a setpoint step by 24 % (`fricctl device control-bench`).
//! (A Smith predictor `μ̂ + s·(u_latest − u_n)` was tried instead: with the
//! plant's gain about half the model's it over-corrected and settled slower.)
//! The estimator is the loop's while it runs (`Measure`, `Stream` and
//! `SetDrive` answer `Busy`).

use super::config::MAX_VELOCITY_M_S;
use super::measure::FILL_RING;
use super::{Device, DeviceError, DriveParam};
use crate::control::{self, Controller, Gains, Plan};
use crate::estimator::reasons;
use crate::protocol::messages::{ControlSetting, ControlState, ControlUpdate, CONTROL_MAX_PERIODS};

/// Smallest κ accepted.
pub const MIN_GAIN: f32 = 0.01;

/// The loop's state in the device.
#[derive(Debug, Clone, Copy)]
pub(super) struct Loop {
    ctl: Controller,
    setting: ControlSetting,
    on: bool,
    /// A command to apply at the next fill.
    pending: Option<f32>,
    /// The first fill made with the loop on (estimates start at its block).
    first_fill: u32,
    /// The command in force at the last fills, by fill number modulo
    /// [`FILL_RING`] (eq. C5).
    at_fill: [f32; FILL_RING],
    /// A block of the open estimate ran an older command, or one still
    /// being reached: the estimate is not used.
    spoiled: bool,
    /// Samples since the last update.
    samples_since: u32,
    /// Samples between the last two updates (the retarget's rate-limit
    /// interval: one update's worth of travel).
    interval: u32,
    last: ControlUpdate,
}

/// Samples a loop estimate of `periods` drive periods may need at DDS
/// tuning word `tw` (> 0): the periods and one more for the wait for a
/// period start, `(periods + 1)·2³²/tw`, + 2 for the rounding.
pub fn estimate_samples(periods: u32, tw: u32) -> u64 {
    (u64::from(periods) + 1) * (1u64 << 32) / u64::from(tw.max(1)) + 2
}

/// The most drive periods whose loop estimate fits one half-buffer of
/// [`super::HALF_BUFFER`] samples at `freq_hz` and `sample_rate_hz` ([`estimate_samples`]),
/// at least 1 (the host's `--periods auto`): at 500 kHz, 1 at 20 kHz and
/// 4 at 40 kHz. A window that fits one half-buffer keeps the update
/// interval at its least, 4 half-buffers on the board (3 of dead time and
/// one of transition); one that needs two adds a half-buffer to every
/// update (at 20 kHz, 4 periods: 0.64 ms instead of 0.512 ms).
pub fn periods_in_half_buffer(freq_hz: f64, sample_rate_hz: f64) -> u32 {
    let tw = freq_hz / sample_rate_hz * 4_294_967_296.0;
    if !(1.0..4_294_967_296.0).contains(&tw) {
        return 1;
    }
    let tw = tw as u32;
    let len = super::HALF_BUFFER as u64;
    let mut p = 1;
    while p < CONTROL_MAX_PERIODS && estimate_samples(p + 1, tw) <= len {
        p += 1;
    }
    p
}

impl Loop {
    /// Block (fill) `block` ran the latest command, reached, and no newer
    /// one waits.
    fn fresh(&self, block: u32) -> bool {
        self.at_fill[block as usize % FILL_RING] == self.ctl.output().command_m
            && self.pending.is_none()
    }
}

/// The state reported when the loop never ran.
fn idle_state() -> ControlState {
    ControlState {
        setting: ControlSetting {
            on: false,
            target_mu: 0.0,
            v0_m_s: 0.0,
            gain: 0.0,
            periods: 0,
            rate_m_per_s: 0.0,
        },
        feedforward_m: 0.0,
        slope_per_m: 0.0,
        limit_m: 0.0,
        last: ControlUpdate {
            update: 0,
            target_mu: 0.0,
            measured_mu: 0.0,
            std_error: 0.0,
            amp_z_m: 0.0,
            integral_m: 0.0,
            saturated: false,
            held: false,
        },
    }
}

impl<const N: usize> Device<'_, N> {
    /// Checks a closed-loop setting, in this order: a latched fault; the
    /// target within `±μ₀` (inclusive) of the device's contact; v₀ finite,
    /// ≠ 0, within `±MAX_VELOCITY_M_S`; κ in `[MIN_GAIN, 1]`; periods in
    /// `1..=CONTROL_MAX_PERIODS`; rate in `(0, slew_m_per_s]`; the drive
    /// running; no host measurement or stream running (`busy`). Nothing is
    /// checked for `on: false`.
    ///
    /// # Errors
    /// [`DeviceError::Faulted`], [`DeviceError::OutOfRange`],
    /// [`DeviceError::NotRunning`], [`DeviceError::Busy`].
    pub fn check_control(&self, s: &ControlSetting, busy: bool) -> Result<(), DeviceError> {
        if !s.on {
            return Ok(());
        }
        if self.latch.any() {
            return Err(DeviceError::Faulted(self.latch.bits()));
        }
        let mu0 = self.contact.mu0;
        let out = |param, min, max| DeviceError::OutOfRange { param, min, max };
        if !(s.target_mu.is_finite() && s.target_mu.abs() <= mu0) {
            return Err(out(DriveParam::TargetMu, -mu0, mu0));
        }
        if !(s.v0_m_s.is_finite() && s.v0_m_s != 0.0 && s.v0_m_s.abs() <= MAX_VELOCITY_M_S) {
            return Err(out(
                DriveParam::Velocity,
                -MAX_VELOCITY_M_S,
                MAX_VELOCITY_M_S,
            ));
        }
        if !(s.gain.is_finite() && (MIN_GAIN..=1.0).contains(&s.gain)) {
            return Err(out(DriveParam::Gain, MIN_GAIN, 1.0));
        }
        if !(1..=CONTROL_MAX_PERIODS).contains(&s.periods) {
            return Err(out(DriveParam::Periods, 1.0, CONTROL_MAX_PERIODS as f32));
        }
        let slew = self.cfg.slew_m_per_s;
        if !(s.rate_m_per_s.is_finite() && s.rate_m_per_s > 0.0 && s.rate_m_per_s <= slew) {
            return Err(out(DriveParam::Rate, 0.0, slew));
        }
        if !self.running {
            return Err(DeviceError::NotRunning);
        }
        let loop_measures = self.control.is_some_and(|l| l.on);
        if busy || (self.est.busy() && !loop_measures) {
            return Err(DeviceError::Busy);
        }
        Ok(())
    }

    /// What the plan of an accepted setting needs (the model's feedforward
    /// and gain, [`control::plan`]: slow, the inverse search): the scene's
    /// parameters (while tracking, at the frequency that runs), the Δu_z
    /// commanded now and the largest Δu_z the loop may command. Copies: the
    /// server forms the scene ([`super::SceneInputs::scene`]) and plans with
    /// the device released.
    pub fn control_plan_inputs(&self) -> (super::SceneInputs, f32, f32) {
        let scene = if self.tracking_active() {
            self.live_scene_inputs()
        } else {
            self.scene_inputs()
        };
        let limit = self
            .cfg
            .liftoff_limit_m(self.drive.offset_z_m)
            .min(self.cfg.max_offset_z_m() - self.drive.offset_z_m);
        let now = self
            .control
            .filter(|l| l.on)
            .map_or(self.drive.amp_z_m, |l| l.ctl.output().command_m);
        (scene, now, limit)
    }

    /// Switches the loop on with `plan` (or retargets a running loop), after
    /// [`Device::check_control`] accepted `s`; or off for `s.on == false`
    /// (the last command stays as the drive's Δu_z).
    ///
    /// # Errors
    /// As [`Device::check_control`] (judged again: the device may have
    /// changed since).
    pub fn set_control(
        &mut self,
        s: ControlSetting,
        plan: Option<Plan>,
    ) -> Result<(), DeviceError> {
        if !s.on {
            self.control_off();
            return Ok(());
        }
        self.check_control(&s, false)?;
        let Some(plan) = plan else {
            return Err(DeviceError::Control(control::ControlError::NoOffset));
        };
        let gains = Gains {
            kappa: s.gain,
            rate_m_per_s: s.rate_m_per_s,
        };
        let fs = self.cfg.sample_rate_hz as f32;
        match self.control.as_mut().filter(|l| l.on) {
            Some(l) => {
                let dt = l.interval.max(l.samples_since) as f32 / fs;
                let out = l.ctl.retarget(plan, gains, dt);
                l.setting = s;
                l.pending = Some(out.command_m);
                l.last.target_mu = plan.target_mu;
            }
            None => {
                let ctl = Controller::new(plan, gains, self.drive.amp_z_m);
                let out = ctl.output();
                let mut last = idle_state().last;
                last.target_mu = plan.target_mu;
                last.amp_z_m = out.command_m;
                last.integral_m = out.integral_m;
                // The loop owns the estimator from now on.
                self.est.abort();
                self.control = Some(Loop {
                    ctl,
                    setting: s,
                    on: true,
                    pending: Some(out.command_m),
                    first_fill: self.fills,
                    at_fill: [out.command_m; FILL_RING],
                    spoiled: false,
                    samples_since: 0,
                    interval: 0,
                    last,
                });
            }
        }
        Ok(())
    }

    /// Switches the loop off: the last command stays (a command not yet
    /// applied is applied now; stopped, it becomes the setting's Δu_z);
    /// aborts the loop's estimate. Nothing if it is off.
    pub fn control_off(&mut self) {
        if let Some(l) = self.control.as_mut().filter(|l| l.on) {
            l.on = false;
            l.setting.on = false;
            // The last command (reported in `last.amp_z_m`) is the one held:
            // one not yet applied is applied now (ramped, while running).
            let pending = l.pending.take();
            if let Some(u) = pending {
                // Stopped, it only becomes the setting (applied at `Start`).
                if !self.running || self.command_normal(u) {
                    self.drive.amp_z_m = u;
                }
            }
            self.est.abort();
        }
    }

    /// The loop runs.
    pub fn control_on(&self) -> bool {
        self.control.is_some_and(|l| l.on)
    }

    /// The loop's state.
    pub fn control_state(&self) -> ControlState {
        match &self.control {
            None => idle_state(),
            Some(l) => {
                let p = l.ctl.plan();
                ControlState {
                    setting: l.setting,
                    feedforward_m: p.feedforward_m,
                    slope_per_m: p.slope_per_m,
                    limit_m: p.limit_m,
                    last: l.last,
                }
            }
        }
    }

    /// At fill `fill`: applies a pending command to the normal channel's
    /// DDS level (ramped) and the drive setting, and records the command in
    /// force.
    pub(super) fn control_fill(&mut self, fill: u32) {
        if !self.control_on() {
            return;
        }
        if !self.running {
            self.control_off();
            return;
        }
        let Some(pending) = self.control.as_mut().map(|l| l.pending.take()) else {
            return;
        };
        if let Some(u) = pending {
            // Inside [0, lift-off limit] by (C3): the DDS accepts it (in
            // displacement mode unless its steady voltage leaves the DAC:
            // then the controller goes back to the amplitude in force, its
            // trim with it — anti-windup — and the update says so).
            if self.command_normal(u) {
                self.drive.amp_z_m = u;
            } else {
                let now = self.drive.amp_z_m;
                if let Some(l) = self.control.as_mut() {
                    let out = l.ctl.refused(now);
                    l.last.amp_z_m = out.command_m;
                    l.last.integral_m = out.integral_m;
                    l.last.saturated = true;
                }
            }
        }
        // The command in force, if the normal channel has reached it (a level
        // settled before a fill stays settled through it); NaN while it
        // still ramps at the slew rate: that block's estimate is not fresh.
        // In displacement mode "reached" is the model's envelope at the
        // command (`displacement`, D4–D5: the dead-beat fills reach it
        // within the headroom; the measurement corrects the model through c,
        // so the model's envelope is the motion up to c's residual).
        let reached = if self.displacement_mode() {
            self.model_reached()
        } else {
            self.dds.channels()[0].settled()
        };
        let Some(l) = self.control.as_mut() else {
            return;
        };
        l.at_fill[fill as usize % FILL_RING] = if reached {
            self.drive.amp_z_m
        } else {
            f32::NAN
        };
    }

    /// Before ADC block `block` of `len` samples is pushed: where the loop's
    /// estimate starts in it (the sample index), if one starts here. It
    /// needs `periods` drive periods (+ 1 for the wait for a period start):
    /// `k` blocks if they do not fit in one, and it starts as late as lets
    /// them close at the end of the `k`-th block (at index 0 … `len − 1`
    /// of this one). None before the loop's first fill, while the last
    /// estimate is still open, or while this block does not run the latest
    /// command, reached (an estimate opened there would be dropped, and
    /// would keep the estimator from the first block that does).
    pub(super) fn control_block_start(&mut self, block: u32, len: usize) -> Option<usize> {
        let tw = self.dds.tuning_word();
        let l = self.control.as_ref().filter(|l| l.on)?;
        if (block.wrapping_sub(l.first_fill) as i32) < 0 || self.est.busy() || !l.fresh(block) {
            return None;
        }
        let (len, need) = (len.max(1) as u64, estimate_samples(l.setting.periods, tw));
        let blocks = need.div_ceil(len);
        usize::try_from(blocks * len - need).ok()
    }

    /// Opens the loop's estimate (at the index [`Device::control_block_start`] gave).
    pub(super) fn control_open(&mut self) {
        if let Some(l) = self.control.as_mut().filter(|l| l.on) {
            l.spoiled = false;
            let _ = self.est.start(l.setting.periods);
        }
    }

    /// After ADC block `block` of `samples` samples: counts them and, if the
    /// loop's estimate closed in it and the block ran the latest command,
    /// runs one update (eqs. C1–C4; the command is applied at the next fill).
    pub(super) fn control_block_end(&mut self, block: u32, samples: usize, closed: bool) {
        let fs = self.cfg.sample_rate_hz as f32;
        let Some(l) = self.control.as_mut().filter(|l| l.on) else {
            return;
        };
        l.samples_since = l.samples_since.saturating_add(samples as u32);
        // Every block the estimate covers must run the latest command; one
        // that did not spoils it: aborted at once, so that the next fresh
        // block can open a new one (the railed-sample check covers the gap:
        // `measure.rs`).
        if (closed || self.est.busy()) && !l.fresh(block) {
            l.spoiled = true;
            if !closed {
                self.est.abort();
            }
        }
        if !closed {
            return;
        }
        let Ok(e) = self.est.estimate_mu() else {
            return;
        };
        let unusable = reasons::SATURATED | reasons::FAULT | reasons::NOT_RUNNING;
        let held = e.reasons & unusable != 0 || !e.mu.is_finite();
        if l.spoiled {
            // A block of an older command (dead time), or of the
            // transition to the latest: not used.
            return;
        }
        let out = if held {
            l.ctl.output()
        } else {
            l.ctl.update(e.mu, l.samples_since as f32 / fs)
        };
        l.interval = l.samples_since;
        l.samples_since = 0;
        l.pending = Some(out.command_m);
        l.last = ControlUpdate {
            update: l.last.update.wrapping_add(1),
            target_mu: l.ctl.plan().target_mu,
            measured_mu: e.mu,
            std_error: e.std_error,
            amp_z_m: out.command_m,
            integral_m: out.integral_m,
            saturated: out.saturated,
            held,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The documented values at 500 kHz: 25 samples a period at 20 kHz fit
    /// one period (2·25 + 2 = 52 ≤ 64, 3·25 + 2 > 64); 12.5 at 40 kHz fit
    /// four (⌊5·2³²/tw⌋ + 2 = 64 with tw = ⌊0.08·2³²⌋); and at every
    /// frequency the answer is the largest p whose estimate fits the half
    /// (or the cap), at least 1; outside the tuning word's range, 1.
    #[test]
    fn the_periods_are_the_most_whose_estimate_fits_one_half_buffer() {
        let fs = 500_000.0;
        assert_eq!(periods_in_half_buffer(20_000.0, fs), 1);
        assert_eq!(periods_in_half_buffer(40_000.0, fs), 4);
        let len = super::super::HALF_BUFFER as u64;
        for k in 1..=500 {
            let f = 500.0 * f64::from(k);
            let p = periods_in_half_buffer(f, fs);
            let tw = (f / fs * 4_294_967_296.0) as u32;
            assert!((1..=CONTROL_MAX_PERIODS).contains(&p), "{f} Hz: {p}");
            assert!(p == 1 || estimate_samples(p, tw) <= len, "{f} Hz: {p}");
            assert!(
                p == CONTROL_MAX_PERIODS || estimate_samples(p + 1, tw) > len,
                "{f} Hz: {p}"
            );
        }
        for f in [0.0, -1.0, fs, 2.0 * fs, f64::NAN] {
            assert_eq!(periods_in_half_buffer(f, fs), 1, "{f} Hz");
        }
    }
}

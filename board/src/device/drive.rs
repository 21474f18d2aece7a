//! Drive settings in physical units → DDS levels: validation in a fixed
//! order (the first failing check is reported), the lift-off guard, start,
//! ramped stop (faults and their safe state: `fault`).

use super::config::MAX_PHASE_RAD;
use super::{in_range, Applied, Device, DeviceError, DriveParam, DriveSetting};
use crate::dds::{phase_rad, phase_word, Achieved, Level};

/// A validated drive, ready for the DDS.
struct Plan {
    achieved: Achieved,
    /// Normal and tangential channel levels, codes.
    levels: [Level; 2],
    /// Phase words of the two channels.
    phases: [u32; 2],
    /// The frequency changes: the displacement loops' corrections start over.
    fresh_loops: bool,
}

impl<const N: usize> Device<'_, N> {
    /// The lift-off guard: `Δu_z ≤ (1 − margin)·u_z0` (f32, inclusive) — so
    /// no normal amplitude on a zero offset, whose limit is 0.
    pub(super) fn check_liftoff(&self, d: &DriveSetting) -> Result<(), DeviceError> {
        let limit = self.cfg.liftoff_limit_m(d.offset_z_m);
        if d.amp_z_m > limit {
            return Err(DeviceError::LiftOff {
                amp_z_m: d.amp_z_m,
                limit_m: limit,
            });
        }
        Ok(())
    }

    /// DDS levels for a drive (validated, nothing applied). The checks, in
    /// order (the first failing one is reported): frequency; normal offset
    /// in `[0, max_offset_z_m]`; normal amplitude finite and ≥ 0, then
    /// ≤ `(1 − margin)·offset` (lift-off, f32, inclusive; skipped while
    /// lift-off is allowed, except that a zero offset takes no amplitude),
    /// then ≤ `max_offset_z_m − offset` (DAC headroom above, f32, inclusive),
    /// then ≤ `offset + retract_z_m` (`zero_code·metres_per_code`: the DAC's reach below the
    /// surface, f32, inclusive: with the driver board's `zero_code` 0 the
    /// transducer cannot retract past the surface, so `Δu_z ≤ u_z0`, `a ≤ 1`);
    /// tangential amplitude in `[0, max_amp_x_m]`; phase in
    /// `[−MAX_PHASE_RAD, MAX_PHASE_RAD]`.
    fn plan(&self, d: &DriveSetting) -> Result<Plan, DeviceError> {
        let (fmin, fmax) = self.cfg.freq_range_hz;
        let freq_err = DeviceError::OutOfRange {
            param: DriveParam::Freq,
            min: fmin as f32,
            max: fmax as f32,
        };
        if !(d.freq_hz.is_finite() && d.freq_hz >= fmin && d.freq_hz <= fmax) {
            return Err(freq_err);
        }
        let (z, x) = (self.cfg.dac_z, self.cfg.dac_x);
        let off = in_range(
            d.offset_z_m,
            0.0,
            self.cfg.max_offset_z_m(),
            DriveParam::OffsetZ,
        )?;
        // DAC headroom above the offset and reach below the surface, in f32
        // like the lift-off limit.
        let headroom = (self.cfg.max_offset_z_m() - off).max(0.0);
        let reach = off + self.cfg.retract_z_m();
        let limit = if self.allow_liftoff {
            reach.min(headroom)
        } else {
            self.cfg.liftoff_limit_m(off)
        };
        if !(d.amp_z_m.is_finite() && d.amp_z_m >= 0.0) {
            return Err(DeviceError::OutOfRange {
                param: DriveParam::AmpZ,
                min: 0.0,
                max: limit,
            });
        }
        if !self.allow_liftoff {
            self.check_liftoff(d)?;
        } else if d.amp_z_m > 0.0 && off == 0.0 {
            return Err(DeviceError::LiftOff {
                amp_z_m: d.amp_z_m,
                limit_m: 0.0,
            });
        }
        if d.amp_z_m > headroom {
            return Err(DeviceError::OutOfRange {
                param: DriveParam::AmpZ,
                min: 0.0,
                max: headroom,
            });
        }
        // Reach below the surface (only binding while lift-off is allowed).
        if d.amp_z_m > reach {
            return Err(DeviceError::OutOfRange {
                param: DriveParam::AmpZ,
                min: 0.0,
                max: reach.min(headroom),
            });
        }
        let amp_x = in_range(d.amp_x_m, 0.0, self.cfg.max_amp_x_m(), DriveParam::AmpX)?;

        let phase = in_range(
            d.phase_rad,
            -MAX_PHASE_RAD,
            MAX_PHASE_RAD,
            DriveParam::Phase,
        )?;
        // While tracking, the same setting frequency keeps the tracked one.
        let achieved = if self.options.track != super::Track::None
            && self.running
            && d.freq_hz == self.drive.freq_hz
        {
            self.applied.achieved
        } else {
            self.dds.plan_frequency(d.freq_hz).map_err(|_| freq_err)?
        };
        let lz = Level {
            amp: d.amp_z_m / z.metres_per_code,
            dc: z.zero_code + off / z.metres_per_code,
        };
        let lx = Level {
            amp: amp_x / x.metres_per_code,
            dc: x.zero_code,
        };
        // Displacement mode: the identified transducers give the voltages
        // (`displacement`, eq. D2), checked against the DAC there.
        let fresh_loops = achieved.tuning_word != self.applied.achieved.tuning_word;
        let c = if fresh_loops {
            super::displacement::Loops::default().c
        } else {
            self.loops.c
        };
        let d_checked = DriveSetting {
            amp_x_m: amp_x,
            phase_rad: phase,
            ..*d
        };
        if let Some((levels, phases)) =
            self.voltage_plan(&d_checked, &achieved, [lz.dc, lx.dc], c)?
        {
            return Ok(Plan {
                achieved,
                levels,
                phases,
                fresh_loops,
            });
        }
        // Both waveforms must stay inside the DAC range (the normal one by the
        // lift-off guard and offset range, but check both exactly).
        lz.check().map_err(|_| DeviceError::OutOfRange {
            param: DriveParam::AmpZ,
            min: 0.0,
            max: headroom,
        })?;
        lx.check().map_err(|_| DeviceError::OutOfRange {
            param: DriveParam::AmpX,
            min: 0.0,
            max: self.cfg.max_amp_x_m(),
        })?;
        // −cos θ = sin(θ − π/2);  cos(θ + φ) = sin(θ + φ + π/2).
        Ok(Plan {
            achieved,
            levels: [lz, lx],
            phases: [self.ideal_phase_word(0, d), self.ideal_phase_word(1, d)],
            fresh_loops,
        })
    }

    /// The voltage-mode phase word of channel `ch` (0 normal, 1 tangential)
    /// for drive `d`: `−cos θ = sin(θ − π/2)`, `cos(θ + φ) = sin(θ + φ + π/2)`.
    pub(super) fn ideal_phase_word(&self, ch: usize, d: &DriveSetting) -> u32 {
        if ch == 0 {
            phase_word(-core::f64::consts::FRAC_PI_2)
        } else {
            phase_word(f64::from(d.phase_rad) + core::f64::consts::FRAC_PI_2)
        }
    }

    /// In displacement mode with tracking on, the tracked mode's setting
    /// is at least [`super::tracking::TRACK_MIN_AMP_M`] (below it no window
    /// gives an estimate: the tracking would never lock, or lose its lock).
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`] naming the tracked channel's amplitude,
    /// from that least value to the channel's largest.
    fn check_tracked_amplitude(&self, d: &DriveSetting) -> Result<(), DeviceError> {
        if !self.displacement_mode() {
            return Ok(());
        }
        let least = super::tracking::TRACK_MIN_AMP_M;
        let (param, amp, max) = match self.options.track {
            super::Track::Z => (
                DriveParam::AmpZ,
                d.amp_z_m,
                self.cfg.liftoff_limit_m(d.offset_z_m),
            ),
            super::Track::X => (DriveParam::AmpX, d.amp_x_m, self.cfg.max_amp_x_m()),
            super::Track::None => return Ok(()),
        };
        if amp < least {
            return Err(DeviceError::OutOfRange {
                param,
                min: least,
                max,
            });
        }
        Ok(())
    }

    /// Sets the drive. While running the DDS ramps to it; while stopped it is
    /// stored and used at the next start (the normal offset is ramped to at
    /// once, unless a fault is latched: then nothing moves).
    ///
    /// # Errors
    /// [`DeviceError::Faulted`] while running with a latched fault, then
    /// [`DeviceError::OutOfRange`], [`DeviceError::LiftOff`] in the order of
    /// `plan`, then [`DeviceError::Busy`] while the closed loop runs (switch
    /// it off first); nothing changes on error.
    pub fn set_drive(&mut self, d: DriveSetting) -> Result<Applied, DeviceError> {
        if self.latch.any() && self.running {
            return Err(DeviceError::Faulted(self.latch.bits()));
        }
        if self.control_on() {
            self.plan(&d)?;
            return Err(DeviceError::Busy);
        }
        let plan = self.plan(&d)?;
        self.check_tracked_amplitude(&d)?;
        // The plan validated everything the DDS checks: none of these fail.
        if plan.achieved.tuning_word != self.dds.tuning_word() {
            self.dds.set_frequency(d.freq_hz)?;
            self.restart_tracking();
        }
        self.drive = d;
        self.dds.set_phase(0, plan.phases[0]);
        self.dds.set_phase(1, plan.phases[1]);
        // Displacement mode: φ is what the loops hold between the measured
        // modes, not the phase between the voltages.
        let phase = if self.displacement_mode() {
            f64::from(d.phase_rad)
        } else {
            phase_rad(
                plan.phases[1]
                    .wrapping_sub(plan.phases[0])
                    .wrapping_sub(1 << 31),
            )
        };
        self.applied = Applied {
            achieved: plan.achieved,
            phase_rad: phase,
        };
        if plan.fresh_loops {
            self.loops = self.fresh_loops();
        }
        self.loops.good = 0.0;
        self.loops.avg = None;
        self.refresh_scene();
        self.ramp_generation = self.ramp_generation.wrapping_add(1);
        self.reset_motion_peak();
        if self.running {
            self.ramp_slew();
            self.dds.set_level(0, plan.levels[0])?;
            self.dds.set_level(1, plan.levels[1])?;
        } else if !self.latch.any() {
            // Stopped: the normal offset (preload) is applied, amplitudes stay 0.
            let dc = plan.levels[0].dc;
            self.dds.set_level(0, Level { amp: 0.0, dc })?;
        }
        // Faulted (and so stopped): only stored; the outputs stay in the
        // safe state until `reset_faults` and `start`.
        Ok(self.applied)
    }

    /// Starts the drive (soft start at the slew rate).
    ///
    /// # Errors
    /// [`DeviceError::Faulted`] while a fault is latched.
    pub fn start(&mut self) -> Result<(), DeviceError> {
        if self.latch.any() {
            return Err(DeviceError::Faulted(self.latch.bits()));
        }
        let plan = self.plan(&self.drive)?;
        self.ramp_slew();
        self.dds.set_level(0, plan.levels[0])?;
        self.dds.set_level(1, plan.levels[1])?;
        self.dds.set_phase(0, plan.phases[0]);
        self.dds.set_phase(1, plan.phases[1]);
        self.loops
            .restart(self.motion_phasors(), self.output_volts());
        self.running = true;
        self.restart_tracking();
        self.loops.model = None;
        self.ramp_generation = self.ramp_generation.wrapping_add(1);
        self.reset_motion_peak();
        Ok(())
    }

    /// Stops the drive: amplitudes ramp to zero, the normal offset stays.
    pub fn stop(&mut self) {
        self.loops.good = 0.0;
        self.loops.avg = None;
        self.control_off();
        self.dds.ramp_down();
        self.running = false;
        self.ramp_generation = self.ramp_generation.wrapping_add(1);
    }
}

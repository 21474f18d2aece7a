//! Latched faults and the one path into the safe state.
//!
//! Every fault source reaches the board through [`Device::fault`], and only
//! through it: the latch's bits are private to this module, so no other part
//! of the device can set one without entering the safe state. The sources:
//!
//! | bit | source | where it is raised |
//! |---|---|---|
//! | [`faults::ADC_SATURATED`] | a finished estimate saw a sample at an ADC rail; in the displacement mode while running, a pickup sample at a rail | `Device::adc_block`, `Device::adc_block_with_pickups` |
//! | [`faults::DAC_UNDERRUN`] | the DAC refill came a half-buffer late | [`Device::dac_half_done`] |
//! | [`faults::WATCHDOG_RESET`] | the previous reset was by the watchdog | the firmware at power-up |
//! | [`faults::EXTERNAL`] | the external fault input (amplifier alarm) | the firmware's input interrupt |
//! | [`faults::ADC_OVERRUN`] | the ADC intake came a half-buffer late | [`Device::adc_half_done`] |
//! | [`faults::MEASURED_LIFTOFF`] | the normal pickup measured Δu_z above u_z0 (lift-off not allowed) | `Device::adc_block_with_pickups` (the motion window) |
//! | [`faults::LOSS_OF_LOCK`] | the resonance tracking lost (or never found) its lock | the motion window (`tracking`) |
//! | [`faults::PICKUP_OPEN`] | a driven channel's pickup reads nothing | the motion window (`displacement`) |
//! | [`faults::SELF_TEST`] | the power-up self-test failed a clock or DMA check | the firmware at power-up, and again at once after every `ResetFaults` |
//!
//! **The safe state** ([`Device::fault`]): the closed loop off (its running
//! estimate aborted), the drive stopped, both channels ramped at the slew
//! rate to zero displacement (amplitudes 0, the normal offset 0 too), one new
//! ramp generation (so the server sends exactly one `RampDone` when the ramps
//! end); `Start`, `Measure`, `SetControl` and (while running) `SetDrive` are
//! refused with `Faulted(bits)` until [`Device::reset_faults`].

use super::Device;

/// Latched fault bits (the protocol's `Status.faults`, `Fault` telemetry).
pub mod faults {
    /// An ADC sample hit the rail during a measurement, or a pickup's in the
    /// displacement mode.
    pub const ADC_SATURATED: u32 = 1 << 0;
    /// The DAC buffer was refilled late (the DMA read a stale half).
    pub const DAC_UNDERRUN: u32 = 1 << 1;
    /// The previous reset was by the watchdog.
    pub const WATCHDOG_RESET: u32 = 1 << 2;
    /// An external fault input (e.g. an amplifier alarm).
    pub const EXTERNAL: u32 = 1 << 3;
    /// The ADC intake was late by a half-buffer (a block was overwritten
    /// before it was read; the drive phase of later samples is unknown).
    pub const ADC_OVERRUN: u32 = 1 << 4;
    /// (v5) The normal pickup measured an amplitude Δu_z above the offset
    /// u_z0 (the contact lifted off) while lift-off is not allowed: the
    /// guard on the *measured* motion (the setting's guard keeps a margin
    /// below u_z0; a resonant transducer can still ring above it).
    pub const MEASURED_LIFTOFF: u32 = 1 << 5;
    /// (v6) The resonance tracking lost its lock (or never locked, or the
    /// resonance left the tracking range): the drive would otherwise go on
    /// off resonance.
    pub const LOSS_OF_LOCK: u32 = 1 << 6;
    /// (v6) A driven channel's pickup reads nothing (an open wire): its
    /// measured amplitude stayed below a tenth of the model's while driven.
    pub const PICKUP_OPEN: u32 = 1 << 7;
    /// (v7) The power-up self-test failed a check the drive depends on
    /// (clock or DMA: `Info.self_test` names it,
    /// [`crate::protocol::SelfTest`]); the firmware latches it again
    /// at once after `ResetFaults`, so the drive can never start on such a
    /// board.
    pub const SELF_TEST: u32 = 1 << 8;
    /// Every bit defined above.
    pub const ALL: u32 = ADC_SATURATED
        | DAC_UNDERRUN
        | WATCHDOG_RESET
        | EXTERNAL
        | ADC_OVERRUN
        | MEASURED_LIFTOFF
        | LOSS_OF_LOCK
        | PICKUP_OPEN
        | SELF_TEST;
}

/// The latched bits; set only by [`Device::fault`], cleared only by
/// [`Device::reset_faults`] (both in this module).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Latch {
    bits: u32,
}

impl Latch {
    /// Nothing latched.
    pub(super) const fn new() -> Self {
        Latch { bits: 0 }
    }

    /// The latched bits.
    pub(super) fn bits(self) -> u32 {
        self.bits
    }

    /// Any bit latched.
    pub(super) fn any(self) -> bool {
        self.bits != 0
    }
}

impl<const N: usize> Device<'_, N> {
    /// Latches `bits` and enters the safe state (module documentation): the
    /// loop off, the drive stopped, amplitudes and offsets ramped to zero
    /// displacement, one new ramp generation. The one path by which any
    /// fault source reaches the board. `bits == 0` changes nothing.
    pub fn fault(&mut self, bits: u32) {
        if bits == 0 {
            return;
        }
        self.control_off();
        self.abort_measurement();
        self.latch.bits |= bits;
        self.running = false;
        self.ramp_generation = self.ramp_generation.wrapping_add(1);
        // At the board's slew, also in displacement mode (whose fills jump
        // to D5's voltages): a resonant mode whose drive ramps down rings
        // down with it, without overshoot. The tracking lets go.
        self.loops.good = 0.0;
        self.loops.avg = None;
        self.restart_tracking();
        self.loops.model = None;
        if let Ok(s) = Self::slew(&self.cfg) {
            self.dds.set_slew(s);
        }
        // The rest levels were accepted by `new`: they cannot fail now.
        let _ = self.rest_levels();
    }

    /// The latched fault bits ([`faults`]; `Status.faults` without forming
    /// a status).
    pub fn faults(&self) -> u32 {
        self.latch.bits()
    }

    /// Clears latched faults (the drive stays stopped, at rest).
    pub fn reset_faults(&mut self) {
        self.latch.bits = 0;
    }
}

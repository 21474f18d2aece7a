//! QEMU only (`--features qemu`): the analog side the emulated chip lacks.
//!
//! QEMU's netduinoplus2 models the STM32F405's USART, TIM2–5 and ADC
//! registers, but its DMA controllers and DAC are stubs that never transfer
//! nor interrupt, so on the emulated chip neither the DDS refill nor the ADC
//! intake (both run from DMA half-transfer interrupts on the board) would
//! ever happen, and no measurement could close. This module stands in for
//! the DMA streams and the analog world:
//! * SysTick interrupts once per half-buffer, `HALF/FS_HZ` = 128 µs of
//!   emulated time, and counts a half as due;
//! * the main loop then refills the next DAC half through the same
//!   [`Device::fill_dac`](board::device::Device::fill_dac) the DMA
//!   interrupt calls on the board, runs the plant of
//!   [`board::plant`] (the same code as the host's virtual
//!   device) on what that half drives, and hands the samples to
//!   [`Device::adc_block`](board::device::Device::adc_block) as the
//!   ADC interrupt does. Device time (the protocol's clock, ramps,
//!   measurement windows) counts the halves so processed: when the emulated
//!   core cannot keep up with 128 µs per half, device time runs slower than
//!   the host's clock and nothing is skipped. While the device is quiescent
//!   (drive stopped and settled, nothing measuring) a due half only moves
//!   device time on: no refill, no plant, no ADC block (the emulator idles).
//! * the refill and the ADC block of each half are timed (module `cycles`,
//!   SysTick extended by [`crate::systick::ticks`]); the plant is not: it stands for the
//!   world outside the chip.
//!
//! The plant is the true contact, deliberately *not* the device's model
//! (μ₀ 0.3, k_z = k_x = 10⁷ N/m at power-up): μ₀ = [`PLANT_MU0`],
//! k_z = k_x = 10⁷ N/m, the stage sliding at [`PLANT_V0`], ideal transducers
//! (with the feature `qemu-resonant` the bench's resonant ones,
//! `board::plant::bench`; with `qemu-drift` its normal mode at
//! 20 100 Hz drifting by −20 Hz/s),
//! ADC noise uniform in ±[`ADC_NOISE_COUNTS`] (as the virtual device's
//! default), rounded to whole counts. It runs in
//! `f32` with the FastF32 sine, [`SUB`] sub-steps per sample.

use core::sync::atomic::{AtomicU32, Ordering};

use board::device::DeviceConfig;
#[cfg(feature = "qemu-resonant")]
use board::plant::ResonantOptions;
use board::plant::{HalfDrive, Noise, Plant, SampleConditions};
use cortex_m::peripheral::SYST;
use cortex_m_rt::exception;
use model_core::float::FastF32;

/// `qemu-drift`: the normal resonance at power-up, Hz.
#[cfg(feature = "qemu-drift")]
const DRIFT_RESONANCE_Z_HZ: f32 = 20_100.0;
/// `qemu-drift`: its drift, Hz per second of device time.
#[cfg(feature = "qemu-drift")]
const DRIFT_HZ_PER_S: f32 = -20.0;

use crate::{cycles, ADC_BLOCKS, DEVICE, FS_HZ, HALF, HALVES};

/// The plant's true friction coefficient (the device's model says 0.3 until
/// `scene set` changes it).
pub const PLANT_MU0: f32 = 0.24;
/// The plant's true normal and tangential stiffness, N/m.
pub const PLANT_K: f32 = 1e7;
/// Stage velocity v₀, m/s (`sweep --v0 0.004` predicts at the same).
pub const PLANT_V0: f32 = 0.004;
/// ADC noise, ± counts (uniform; the virtual device's default).
pub const ADC_NOISE_COUNTS: f32 = 1.0;
/// Plant sub-steps per ADC sample: 8·12.5 = 100 steps per 40 kHz period,
/// whose fixed-step error ≈ 10·(1+b)/100² = 1e-3·(1+b) of μ₀.
pub const SUB: u32 = 8;
/// The core clock of QEMU's netduinoplus2 (`hw/arm/netduinoplus2.c`:
/// SYSCLK_FRQ = 168 MHz), which SysTick counts. QEMU's model of TIM2 is not
/// used: its update rate did not follow PSC/ARR here (QEMU 10.0, ≈ 14 times
/// slower than programmed).
pub const QEMU_SYSCLK_HZ: u32 = 168_000_000;
/// Half-buffers whose 128 µs have passed and that are not yet processed.
static DUE: AtomicU32 = AtomicU32::new(0);

/// Whether a half-buffer is waiting (the main loop must not sleep).
pub fn due() -> bool {
    DUE.load(Ordering::Relaxed) > 0
}

/// SysTick on the core clock: one exception per half-buffer
/// ([`crate::systick::start`]).
pub fn tick(syst: &mut SYST) {
    crate::systick::start(syst, QEMU_SYSCLK_HZ / FS_HZ * HALF as u32);
}

#[exception]
fn SysTick() {
    crate::systick::wrapped();
    // At most two halves queued: a core that falls behind slows device time
    // rather than bursting through a backlog.
    let _ = DUE.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
        (n < 2).then_some(n + 1)
    });
}

/// The emulated analog side: the DAC half being refilled and the plant.
pub struct Analog {
    plant: Plant<f32>,
    dac: [u32; HALF],
    samples: [(u16, u16); HALF],
    /// The motion pickups' readings (z, x) of the same half (noise-free
    /// but for the ADC's rounding).
    pickups: [(u16, u16); HALF],
    noise: Noise,
    half: usize,
    cfg: DeviceConfig,
    /// The two halves filled but not yet output, oldest first: as on the
    /// board, where the DMA outputs one half while the other waits, and
    /// `main` fills both before the DMA starts, so ADC block `n` samples
    /// the output of fill `n` while fill `n + 2` is being made. (Running
    /// the plant on the fill just made would pair ADC block `n` with fill
    /// `n + 2`: every phase the device references to its fills — the
    /// forces' harmonics, the pickups' lock-ins — off by two half-buffers.)
    pending: [Option<HalfDrive>; 2],
}

impl Analog {
    /// The plant at rest.
    pub fn new(cfg: DeviceConfig) -> Self {
        #[allow(unused_mut)]
        let mut plant = Plant::new(PLANT_MU0, PLANT_K, PLANT_K);
        // `qemu-resonant`: the bench's resonant transducers, advanced with
        // the exact update over each sub-step.
        #[cfg(feature = "qemu-resonant")]
        {
            let h = 1.0 / (FS_HZ as f32 * SUB as f32);
            #[allow(unused_mut)]
            let mut opts = ResonantOptions::bench(&cfg);
            // `qemu-drift`: the tracking bench's normal mode, drifting.
            #[cfg(feature = "qemu-drift")]
            {
                opts.modes[0].resonance_hz = DRIFT_RESONANCE_Z_HZ;
                opts.drift_hz_per_s[0] = DRIFT_HZ_PER_S;
            }
            plant.resonant = board::plant::Resonant::new(opts, h).ok();
        }
        Analog {
            plant,
            dac: [0; HALF],
            samples: [(0, 0); HALF],
            pickups: [(0, 0); HALF],
            noise: Noise::new(0x9E37_79B9_7F4A_7C15),
            half: 0,
            cfg,
            pending: [None, None],
        }
    }

    /// `main`'s pre-fill of DAC half `half` before the DMA starts, recorded
    /// as a half waiting to be output.
    pub fn prefill(&mut self, dev: &mut crate::Dev, half: usize, buf: &mut [u32]) {
        let d = HalfDrive::fill(dev, half, buf);
        self.pending = [self.pending[1], Some(d)];
    }

    /// Processes one due half-buffer, if any: DAC refill, plant, ADC block.
    pub fn step(&mut self) {
        if DUE
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1))
            .is_err()
        {
            return;
        }
        // Drive stopped and settled, nothing measuring: the DAC would repeat
        // its DC level and the samples reach nothing, so neither the refill
        // nor the plant is run (the emulator idles) — only device time moves
        // on. (The board refills regardless; its DMA costs no CPU.)
        let quiescent = DEVICE.lock(|d| {
            d.as_ref().is_none_or(|dev| {
                let s = dev.status();
                !s.running && s.settled && !s.measuring
            })
        });
        HALVES.fetch_add(1, Ordering::Relaxed);
        if quiescent {
            return;
        }
        let half = self.half;
        self.half ^= 1;
        let dac = &mut self.dac;
        // Timed as the DAC handler's work on the board (with the plant's
        // record of the drive, a copy of the DDS state).
        let t0 = cycles::now();
        let Some(made) = DEVICE.lock(|d| d.as_mut().map(|dev| HalfDrive::fill(dev, half, dac)))
        else {
            return;
        };
        cycles::fill_done(cycles::since(t0));
        // The half output now is the oldest waiting one (`pending`).
        let out = self.pending[0];
        self.pending = [self.pending[1], Some(made)];
        let Some(d) = out else {
            return;
        };
        // With interrupts enabled: the link stays served meanwhile.
        self.run_plant(&d);
        let (samples, pickups) = (&self.samples, &self.pickups);
        ADC_BLOCKS.fetch_add(1, Ordering::Relaxed);
        let t0 = cycles::now();
        crate::with_device(|dev| {
            dev.adc_block_with_pickups(half, samples, pickups);
            cycles::record(dev, cycles::since(t0));
        });
    }

    fn run_plant(&mut self, d: &HalfDrive) {
        let noise = &mut self.noise;
        self.plant.run_half_with_pickups::<FastF32>(
            &self.cfg,
            d,
            SUB,
            0.0,
            |_| SampleConditions {
                mu0: PLANT_MU0,
                v0: PLANT_V0,
                counts_z: noise.uniform(ADC_NOISE_COUNTS),
                counts_x: noise.uniform(ADC_NOISE_COUNTS),
            },
            &mut self.samples,
            &mut self.pickups,
        );
    }
}

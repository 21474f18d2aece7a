//! The virtual device: the firmware's own device logic and protocol server
//! (model-core `device`, `server`) plus a simulated plant. The plant is the
//! paper's spring contact integrated in physical units with 32 sub-steps per
//! ADC sample, driven by the DDS channels' *current* levels (so ramps act on
//! it), loaded by a stage sliding at `v0`; its forces go through the ADC
//! calibrations with optional noise, sample by sample, into the device's
//! estimator — the same path as on the board.

use std::f64::consts::TAU;

use model_core::dds::{phase_rad, SineTable};
use model_core::device::{Contact, Device, DeviceConfig, DriveSetting};
use model_core::fixed_step::SpringContact;
use model_core::protocol::Info;
use model_core::server::Server;

/// Table size of the virtual device (as the firmware).
pub const TABLE_N: usize = 1024;
/// Samples per half-buffer (as the firmware).
pub const HALF: usize = 512;
/// Sub-steps of the plant per ADC sample.
const SUB: usize = 32;

/// The virtual board's configuration: the driver board's (model-core), with
/// the plant sampled at each sample's own drive phase (no DAC lag).
pub fn config() -> DeviceConfig {
    DeviceConfig::driver_board(0)
}

/// `Info` of the virtual board.
pub fn info(cfg: &DeviceConfig) -> Info {
    Info::for_config(cfg, "virtual device", [0, 1, 0])
}

/// What `fricctl device --sim` keeps between invocations.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct SimState {
    /// The accepted drive.
    pub drive: DriveSetting,
    /// The contact parameters.
    pub contact: Contact,
    /// Started.
    pub running: bool,
}

/// Plant options.
#[derive(Debug, Clone, Copy)]
pub struct PlantOptions {
    /// Stage velocity v0, m/s.
    pub v0: f64,
    /// ADC noise, counts (uniform ± this).
    pub noise_counts: f64,
    /// Uncalibrated ADC offset error, counts (added to both channels).
    pub offset_counts: f64,
}

/// A virtual device with its plant.
pub struct VirtualDevice {
    dev: Device<'static, TABLE_N>,
    server: Server,
    plant: Plant,
    dac: Vec<u32>,
    half: usize,
    rng: u64,
    opts: PlantOptions,
    /// Samples produced since the device was made.
    samples: u64,
}

struct Plant {
    /// The contact (model-core's scheme in physical units).
    contact: SpringContact<f64>,
    /// Stage position v0·t, m.
    stage: f64,
}

impl VirtualDevice {
    /// A stopped virtual device with contact μ0 = 0.3, k_z = k_x = 10⁷ N/m.
    pub fn new(opts: PlantOptions) -> Self {
        let table: &'static SineTable<TABLE_N> = Box::leak(Box::new(SineTable::libm()));
        let cfg = config();
        let dev = Device::new(
            cfg,
            table,
            Contact {
                mu0: 0.3,
                kz: 1e7,
                kx: 1e7,
            },
        )
        .expect("valid virtual configuration");
        let mut v = VirtualDevice {
            dev,
            server: Server::new(info(&cfg)),
            plant: Plant {
                contact: SpringContact::new(0.3, 1e7, 1e7),
                stage: 0.0,
            },
            dac: vec![0; HALF],
            half: 0,
            rng: 0x9E37_79B9_7F4A_7C15,
            opts,
            samples: 0,
        };
        let _ = v.dev.set_drive(DriveSetting {
            freq_hz: 40_000.0,
            amp_z_m: 0.0,
            amp_x_m: 0.0,
            offset_z_m: 0.0,
            phase_rad: 0.0,
        });
        v
    }

    /// The drive, contact and run state, to carry the in-process virtual
    /// device from one `fricctl device --sim` invocation to the next.
    pub fn snapshot(&self) -> SimState {
        SimState {
            drive: self.dev.drive(),
            contact: self.dev.contact(),
            running: self.dev.status().running,
        }
    }

    /// Restores a snapshot (settling the ramps and the plant for 20 ms of
    /// device time). Invalid snapshots are ignored.
    pub fn restore(&mut self, st: &SimState) {
        let _ = self.dev.set_contact(st.contact);
        if self.dev.set_drive(st.drive).is_ok() && st.running && self.dev.start().is_ok() {
            let mut n = 0;
            while !self.dev.status().settled && n < 10_000 {
                self.step_half();
                n += 1;
            }
            self.advance((self.sample_rate() / 50.0) as usize);
        }
    }

    /// Feeds received bytes (arriving now, in device time); returns the
    /// bytes to send back.
    pub fn receive(&mut self, bytes: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        let now_us = self.now_us();
        self.server
            .receive(&mut self.dev, bytes, now_us, |b| out.extend_from_slice(b));
        out
    }

    /// Device time, µs since the virtual device was made (wrapping): the
    /// samples produced so far over the sample rate.
    pub fn now_us(&self) -> u32 {
        (self.samples as f64 * 1e6 / self.sample_rate()) as u64 as u32
    }

    /// Advances the simulation by whole half-buffers covering `samples`;
    /// returns telemetry bytes produced meanwhile.
    pub fn advance(&mut self, samples: usize) -> Vec<u8> {
        let mut out = Vec::new();
        let halves = samples.div_ceil(HALF).max(1);
        for _ in 0..halves {
            self.step_half();
            self.server
                .poll(&mut self.dev, |b| out.extend_from_slice(b));
        }
        out
    }

    /// Drive stopped and settled, no measurement (nor stream): the plant's
    /// samples reach nothing, so a server loop may [`VirtualDevice::skip`]
    /// instead of simulating them.
    pub fn quiescent(&self) -> bool {
        let s = self.dev.status();
        !s.running && s.settled && !s.measuring
    }

    /// Moves the device clock on by `samples` without simulating the plant
    /// (for a [`VirtualDevice::quiescent`] device); returns the telemetry due.
    pub fn skip(&mut self, samples: u64) -> Vec<u8> {
        self.samples += samples;
        let mut out = Vec::new();
        self.server
            .poll(&mut self.dev, |b| out.extend_from_slice(b));
        out
    }

    /// Samples per second.
    pub fn sample_rate(&self) -> f64 {
        self.dev.config().sample_rate_hz
    }

    fn noise(&mut self) -> f64 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        let u = (self.rng >> 11) as f64 / (1u64 << 53) as f64;
        (2.0 * u - 1.0) * self.opts.noise_counts
    }

    fn step_half(&mut self) {
        let cfg = *self.dev.config();
        let contact = self.dev.contact();
        // Drive levels now (metres) from the DDS channel states.
        let ch = *self.dev.dds().channels();
        let acc0 = self.dev.dds().accumulator();
        let tw = self.dev.dds().tuning_word();
        let half = self.half;
        let mut buf = std::mem::take(&mut self.dac);
        self.dev.fill_dac(half, &mut buf);
        self.dac = buf;
        let (mz, mx) = (
            f64::from(cfg.dac_z.metres_per_code),
            f64::from(cfg.dac_x.metres_per_code),
        );
        let uz0 = (f64::from(ch[0].dc) - f64::from(cfg.dac_z.zero_code)) * mz;
        let duz = f64::from(ch[0].amp) * mz;
        let dux = f64::from(ch[1].amp) * mx;
        // ch1 = dc + amp·sin(θ + p1), ch2 = zero + amp·sin(θ + p2): u_z = u_z0 + Δu_z sin(θ + p1),
        // u_x = Δu_x sin(θ + p2) (the device sets p1 = −π/2, p2 = φ + π/2).
        let (p1, p2) = (phase_rad(ch[0].phase), phase_rad(ch[1].phase));
        let dt = 1.0 / cfg.sample_rate_hz / SUB as f64;
        self.plant.contact.mu0 = f64::from(contact.mu0);
        self.plant.contact.kz = f64::from(contact.kz);
        self.plant.contact.kx = f64::from(contact.kx);
        let dtheta = TAU * f64::from(tw) / 4_294_967_296.0;
        let mut samples = Vec::with_capacity(HALF);
        let mut th = phase_rad(acc0);
        for _ in 0..HALF {
            // The sample is taken at θ; then the plant advances to the next tick.
            let uz = uz0 + duz * (th + p1).sin();
            let ux = dux * (th + p2).sin() + self.plant.stage;
            let (fx, fz) = self.plant.contact.step(ux, uz);
            let z = (fz / f64::from(cfg.adc_z.gain)
                + f64::from(cfg.adc_z.offset)
                + self.opts.offset_counts
                + self.noise())
            .round()
            .clamp(0.0, 4095.0);
            let x = (fx / f64::from(cfg.adc_x.gain)
                + f64::from(cfg.adc_x.offset)
                + self.opts.offset_counts
                + self.noise())
            .round()
            .clamp(0.0, 4095.0);
            samples.push((x as u16, z as u16));
            // Sub-steps to the next sample (the paper's scheme on a finer grid).
            for k in 1..=SUB {
                let t = th + dtheta * k as f64 / SUB as f64;
                self.plant.stage += self.opts.v0 * dt;
                self.plant.contact.step(
                    dux * (t + p2).sin() + self.plant.stage,
                    uz0 + duz * (t + p1).sin(),
                );
            }
            th += dtheta;
        }
        self.dev.adc_block(half, &samples);
        self.half ^= 1;
        self.samples += HALF as u64;
    }
}

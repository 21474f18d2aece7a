//! A device in displacement mode on resonant transducers (`plant::Resonant`),
//! driven half-buffer by half-buffer, with the true motion read from the
//! plant's own state — not from the device's lock-in: for a motion
//! `x = A cos(ωt + ψ)`, `A = √(x² + (ẋ/ω)²)` and `ωt + ψ = atan2(−ẋ/ω, x)`,
//! so φ between the modes is `ψ_x − ψ_z + π` (eq. M1) with the common time
//! cancelling. Shared by the displacement, tracking and fast-loop tests.
//!
//! The bench's transducers: 20 300 Hz, Q 300 normal; 19 700 Hz, Q 200
//! tangential; contact load Q 2000; pickups without noise (the ADC's
//! rounding only).

use board::dds::SineTable;
use board::device::{
    Contact, Device, DeviceConfig, DriveMode, DriveSetting, TransducerModel, Transducers,
    HALF_BUFFER,
};
use board::plant::{HalfDrive, Plant, Resonant, ResonantOptions, SampleConditions};
use board::resonator::ModeParams;
use model_core::Libm;
use std::f64::consts::{PI, TAU};

/// The plant's true μ₀ (and the device's).
pub const MU0: f64 = 0.3;
/// Sub-steps per sample of the plant.
pub const SUB: u32 = 4;
/// The contact's load: 1/Q_eff = 1/Q + 1/LOAD_Q.
pub const LOAD_Q: f64 = 2000.0;

/// The bench's drive at 20 kHz with Δu_z = `amp_z`: Δu_x = 0.3 µm,
/// u_z0 = 4 µm, φ = 40°.
pub fn setting(amp_z: f32) -> DriveSetting {
    DriveSetting {
        freq_hz: 20_000.0,
        amp_z_m: amp_z,
        amp_x_m: 0.3e-6,
        offset_z_m: 4e-6,
        phase_rad: 40f32.to_radians(),
    }
}

/// The true modes at rest (unloaded Q).
pub fn true_modes() -> [ModeParams<f64>; 2] {
    [
        ModeParams {
            resonance_hz: 20_300.0,
            q: 300.0,
            gain_m_per_v: 8e-8,
        },
        ModeParams {
            resonance_hz: 19_700.0,
            q: 200.0,
            gain_m_per_v: 4e-8,
        },
    ]
}

/// Q with the contact's load.
pub fn loaded(q: f64) -> f64 {
    1.0 / (1.0 / q + 1.0 / LOAD_Q)
}

/// The device's model of a true mode: f_r shifted by `df`, Q and gain scaled
/// (the loaded Q; the phase lag of the DAC's hold, half a sample at 20 kHz).
pub fn model_of(m: ModeParams<f64>, df: f64, q_scale: f64, g_scale: f64) -> TransducerModel {
    TransducerModel {
        resonance_hz: (m.resonance_hz + df) as f32,
        q: (loaded(m.q) * q_scale) as f32,
        gain_m_per_v: (m.gain_m_per_v * g_scale) as f32,
        phase_lag_rad: (PI * 20_000.0 / 500_000.0) as f32,
    }
}

/// The exact model of modes `m` (an exact identification at rest).
pub fn exact_model(m: [ModeParams<f64>; 2]) -> Transducers {
    Transducers {
        z: model_of(m[0], 0.0, 1.0, 1.0),
        x: model_of(m[1], 0.0, 1.0, 1.0),
    }
}

/// The plant's options: the true modes, no drift, heating or cross-talk.
pub fn opts() -> ResonantOptions<f64> {
    ResonantOptions {
        modes: true_modes(),
        drift_hz_per_s: [0.0; 2],
        thermal_hz_per_um2: 0.0,
        crosstalk: 0.0,
        load_q: LOAD_Q,
    }
}

/// A device in displacement mode with its resonant plant.
pub struct Bench<'t> {
    /// The board's configuration.
    pub cfg: DeviceConfig,
    /// The device.
    pub dev: Device<'t, 1024>,
    /// The plant.
    pub plant: Plant<f64>,
    /// Pickup samples forced to these counts (an open wire), per channel.
    pub pickup_stuck: [Option<u16>; 2],
    /// Pickup gain errors: each sample's counts from the calibration's zero
    /// are scaled by this, per channel (1: the calibrated pickup).
    pub pickup_gain: [f64; 2],
    half: usize,
    /// Half-buffers run.
    pub halves: usize,
}

/// The true motion after a half: (A_z, A_x, φ).
#[derive(Debug, Clone, Copy)]
pub struct Truth {
    /// Normal amplitude, m.
    pub amp_z: f64,
    /// Tangential amplitude, m.
    pub amp_x: f64,
    /// φ between the modes, rad.
    pub phi: f64,
}

impl<'t> Bench<'t> {
    /// A bench with the plant `opts` and the device's transducer `model`.
    pub fn new(table: &'t SineTable<1024>, opts: ResonantOptions<f64>, model: Transducers) -> Self {
        let cfg = DeviceConfig::driver_board(0);
        let contact = Contact {
            mu0: MU0 as f32,
            kz: 1e7,
            kx: 1e7,
        };
        let mut dev = Device::new(cfg, table, contact).expect("valid device");
        dev.set_transducers(Some(model)).expect("valid model");
        dev.set_drive_mode(DriveMode::Displacement)
            .expect("displacement mode");
        let mut plant = Plant::<f64>::new(MU0, 1e7, 1e7);
        plant.resonant = Some(
            Resonant::new(opts, 1.0 / (cfg.sample_rate_hz * f64::from(SUB))).expect("valid plant"),
        );
        Bench {
            cfg,
            dev,
            plant,
            pickup_stuck: [None; 2],
            pickup_gain: [1.0; 2],
            half: 0,
            halves: 0,
        }
    }

    /// One half-buffer; the true motion at its end.
    pub fn step(&mut self) -> Truth {
        let mut dac = [0u32; HALF_BUFFER];
        let mut forces = [(0u16, 0u16); HALF_BUFFER];
        let mut pickups = [(0u16, 0u16); HALF_BUFFER];
        let d = HalfDrive::fill(&mut self.dev, self.half, &mut dac);
        self.plant.run_half_with_pickups::<Libm>(
            &self.cfg,
            &d,
            SUB,
            0.0,
            |_| SampleConditions {
                mu0: MU0,
                v0: 0.004,
                counts_z: 0.0,
                counts_x: 0.0,
            },
            &mut forces,
            &mut pickups,
        );
        let zero = [
            f64::from(self.cfg.pickup_z.offset),
            f64::from(self.cfg.pickup_x.offset),
        ];
        let scale = |c: u16, ch: usize| {
            let g = self.pickup_gain[ch];
            if g == 1.0 {
                c
            } else {
                (zero[ch] + (f64::from(c) - zero[ch]) * g).round() as u16
            }
        };
        for p in &mut pickups {
            *p = (scale(p.0, 0), scale(p.1, 1));
            if let Some(c) = self.pickup_stuck[0] {
                p.0 = c;
            }
            if let Some(c) = self.pickup_stuck[1] {
                p.1 = c;
            }
        }
        self.dev
            .adc_block_with_pickups(self.half, &forces, &pickups);
        self.half ^= 1;
        self.halves += 1;
        self.truth()
    }

    /// The true motion now, in the frame of the DDS frequency.
    pub fn truth(&self) -> Truth {
        let w = TAU * self.dev.applied().achieved.freq_hz;
        let r = self.plant.resonant.as_ref().expect("resonant plant");
        let motion = |k: usize| {
            let (x, v) = (r.modes[k].x(), r.modes[k].v());
            ((x * x + (v / w) * (v / w)).sqrt(), (-v / w).atan2(x))
        };
        let ((az, pz), (ax, px)) = (motion(0), motion(1));
        let mut phi = px - pz + PI;
        while phi > PI {
            phi -= TAU;
        }
        while phi <= -PI {
            phi += TAU;
        }
        Truth {
            amp_z: az,
            amp_x: ax,
            phi,
        }
    }

    /// Runs until the device says the drive holds (at most `limit` halves);
    /// the halves it took and the largest true normal amplitude on the way.
    ///
    /// # Panics
    /// If it does not hold within `limit` halves.
    pub fn until_settled(&mut self, limit: usize) -> (usize, f64) {
        let mut peak = 0.0f64;
        for k in 1..=limit {
            let t = self.step();
            peak = peak.max(t.amp_z);
            if self.dev.status().settled {
                return (k, peak);
            }
        }
        panic!("not settled within {limit} halves: {:?}", self.dev.status());
    }

    /// Seconds per half-buffer.
    pub fn t_half(&self) -> f64 {
        HALF_BUFFER as f64 / self.cfg.sample_rate_hz
    }
}

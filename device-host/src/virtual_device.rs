//! The virtual device: the firmware's own device logic and protocol server
//! ([`board::device`], [`board::server`]) plus a simulated plant
//! ([`board::plant`], the same code the firmware runs under
//! QEMU): the paper's spring contact integrated in physical units with 32
//! sub-steps per ADC sample, driven by the DDS channels' *current* levels (so
//! ramps act on it), loaded by a stage sliding at `v0`; its forces go through
//! the ADC calibrations with optional noise, sample by sample, into the
//! device's estimator — the same path as on the board.
//!
//! The plant is *not* the device's model: its contact (μ₀, k_z, k_x) is its
//! own ([`PlantOptions`], default equal to the device's power-up contact
//! 0.3, 10⁷ N/m, 10⁷ N/m) and `scene set` does not change it. On top of the
//! true contact the plant has
//! - transducers whose displacement amplitudes Δu_z, Δu_x follow the DAC's
//!   with a first-order lag of time constant τ = `lag_periods`/f
//!   (dA/dt = (A_DAC − A)/τ, advanced exactly per ADC sample);
//! - or, with any of the resonant flags ([`crate::transducers`]), resonant
//!   transducers: second-order modes (f_r, Q, static gain) driven by the DAC
//!   voltages, with resonance drift, self-heating, cross-talk and the
//!   contact's load ([`board::plant::Resonant`]);
//! - a drifting friction coefficient μ₀(t) = μ₀ + `mu0_drift`·t (t = device
//!   time, s; μ₀(t) stops at 0 rather than change sign);
//! - a stage velocity that is constant (`v0`) or follows a piecewise-linear
//!   profile v₀(t) read from a CSV file (`t_s,v0_m_s`; held at the end values
//!   before the first and after the last row);
//! - ADC noise (uniform ± counts) and an uncalibrated ADC offset;
//! - motion pickups on each transducer ([`DeviceConfig::pickup_z`],
//!   `pickup_x`) reading its displacement with the same ADC noise, fed to the
//!   device's lock-ins (`Status.measured`).

use std::f64::consts::TAU;

use board::dds::SineTable;
use board::device::{Contact, Device, DeviceConfig, DriveSetting};
use board::link::{self, RxQueue, TxRing};
use board::plant::{HalfDrive, Noise, Plant, SampleConditions};
use board::protocol::Info;
use board::server::Server;
use model_core::Libm;

use fric_analysis::numbers::{short, Real};

use crate::transducers::TransducerSpec;
use crate::{Error, Result};

/// Table size of the virtual device (as the firmware).
pub const TABLE_N: usize = 1024;
/// Samples per half-buffer (the firmware's, [`board::device::HALF_BUFFER`]).
pub const HALF: usize = board::device::HALF_BUFFER;
/// Seed of the pickups' noise record (xor'ed into a reseed).
const PICKUP_SEED: u64 = 0xD1B5_4A32_D192_ED03;
/// Sub-steps of the plant per ADC sample.
const SUB: u32 = 32;

/// The virtual board's configuration: the driver board's (`board`), with
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
    /// Drives above the lift-off limit allowed (`device config --allow-liftoff`).
    #[serde(default)]
    pub liftoff_allowed: bool,
}

/// The device's power-up contact (and the plant's default): μ₀, k_z (N/m), k_x (N/m).
pub const DEFAULT_CONTACT: (f64, f64, f64) = (0.3, 1e7, 1e7);

/// Plant options.
#[derive(Debug, Clone, PartialEq)]
pub struct PlantOptions {
    /// Stage velocity v0, m/s (used when `v0_profile` is `None`).
    pub v0: f64,
    /// ADC noise, counts (uniform ± this).
    pub noise_counts: f64,
    /// Uncalibrated ADC offset error, counts (added to both channels).
    pub offset_counts: f64,
    /// The true μ₀ at device time 0.
    pub mu0: f64,
    /// The true k_z, N/m.
    pub kz: f64,
    /// The true k_x, N/m.
    pub kx: f64,
    /// Time constant of the transducers' amplitude lag, in drive periods (0 = none).
    pub lag_periods: f64,
    /// dμ₀/dt, 1/s.
    pub mu0_drift: f64,
    /// Stage velocity profile (t s, v₀ m/s), piecewise linear, t strictly increasing.
    pub v0_profile: Option<Vec<(f64, f64)>>,
    /// Steps of μ₀: from device time `t` s on, μ₀ is multiplied by the
    /// factor (a disturbance of the bench; empty for none).
    pub mu0_steps: Vec<(f64, f64)>,
    /// Resonant transducers (`None`: ideal ones, with `lag_periods`).
    pub resonant: Option<board::plant::ResonantOptions<f64>>,
}

impl PlantOptions {
    /// Stage velocity at device time `t` s: the profile interpolated
    /// linearly (held at its end values outside), else `v0`.
    pub fn v0_at(&self, t: f64) -> f64 {
        let Some(p) = self.v0_profile.as_deref() else {
            return self.v0;
        };
        match p {
            [] => self.v0,
            [(t0, v), ..] if t <= *t0 => *v,
            [.., (tn, v)] if t >= *tn => *v,
            _ => {
                // t0 < t < tn: the segment [a, b] with a.t ≤ t < b.t.
                let i = p.partition_point(|(ti, _)| *ti <= t);
                let ((ta, va), (tb, vb)) = (p[i - 1], p[i]);
                va + (vb - va) * (t - ta) / (tb - ta)
            }
        }
    }

    /// μ₀ at device time `t` s (eq. of the module doc; not below 0).
    pub fn mu0_at(&self, t: f64) -> f64 {
        let f: f64 = self
            .mu0_steps
            .iter()
            .filter(|(ts, _)| t >= *ts)
            .map(|(_, k)| k)
            .product();
        ((self.mu0 + self.mu0_drift * t) * f).max(0.0)
    }
}

/// Domain of the plant's stage velocity, m/s (`--v0`, `--sim-v0`, the rows
/// of `--v0-profile`): within the device's ±1000 m/s, a normal `f32` number
/// or 0, as every velocity the device is told.
pub const STAGE_VELOCITY: Real = Real::ANY
    .at_least(-1000.0)
    .at_most(1000.0)
    .because("the device's velocity limit")
    .single_precision();
/// Domain of the plant's ADC noise, counts: within the 12-bit ADC's full scale.
pub const NOISE_COUNTS: Real = Real::non_negative()
    .at_most(4095.0)
    .because("the 12-bit ADC's full scale");
/// Domain of the plant's ADC offset, counts: within the ADC's full scale.
pub const OFFSET_COUNTS: Real = Real::ANY
    .at_least(-4095.0)
    .at_most(4095.0)
    .because("the 12-bit ADC's full scale");
/// Domain of the plant's contact (μ0, k_z, k_x): the scene's domain
/// (the analysis' scene domain), in `f32` as the device's contact.
pub const PLANT_CONTACT: Real = Real::positive().single_precision();
/// Domain of the ideal transducers' lag, drive periods.
pub const LAG_PERIODS: Real = Real::non_negative().single_precision();
/// Domain of the drift of μ₀, 1/s.
pub const MU0_DRIFT: Real = Real::ANY.single_precision();

/// The plant asked for: each field is a flag of `fricctl sim-device` and
/// `fricctl device --sim` (named in errors); [`PlantSpec::options`] checks
/// them and reads the profile.
#[derive(Debug, Clone, PartialEq)]
pub struct PlantSpec {
    /// Virtual plant: true μ0 (the device's model keeps its own, see `scene`)
    pub plant_mu0: f64,
    /// Virtual plant: true k_z, N/m
    pub plant_kz: f64,
    /// Virtual plant: true k_x, N/m
    pub plant_kx: f64,
    /// Virtual plant: ideal transducers whose displacement amplitudes follow with a first-order lag, time constant in drive periods (0 = none; non-zero implies ideal transducers)
    pub plant_lag_periods: f64,
    /// Virtual plant: drift of μ0, per second of device time (μ0 stops at 0)
    pub plant_mu0_drift: f64,
    /// Virtual plant: stage velocity profile, CSV `t_s,v0_m_s` (header line, t strictly increasing), piecewise linear in device time, held outside; replaces the constant velocity
    pub v0_profile: Option<std::path::PathBuf>,
    /// The transducers: ideal or resonant.
    pub transducers: TransducerSpec,
}

impl Default for PlantSpec {
    /// The power-up contact, no lag, no drift, no profile, the default (resonant) transducers.
    fn default() -> Self {
        PlantSpec {
            plant_mu0: DEFAULT_CONTACT.0,
            plant_kz: DEFAULT_CONTACT.1,
            plant_kx: DEFAULT_CONTACT.2,
            plant_lag_periods: 0.0,
            plant_mu0_drift: 0.0,
            v0_profile: None,
            transducers: TransducerSpec::default(),
        }
    }
}

impl PlantSpec {
    /// The checked plant options with the constant velocity `v0` (m/s), ADC
    /// noise and offset (counts); `names` are the flag names of those three.
    ///
    /// # Errors
    /// One line naming the flag for a value out of its domain or an
    /// unreadable profile.
    pub fn options(
        &self,
        v0: f64,
        noise: f64,
        offset: f64,
        names: [&str; 3],
    ) -> Result<PlantOptions> {
        // The flags' parsers checked each value; a caller from elsewhere
        // (Python, a bench) may not have, so every value is checked here.
        for (x, n, d) in [
            (v0, names[0], STAGE_VELOCITY),
            (noise, names[1], NOISE_COUNTS),
            (offset, names[2], OFFSET_COUNTS),
            (self.plant_mu0, "plant-mu0", PLANT_CONTACT),
            (self.plant_kz, "plant-kz", PLANT_CONTACT),
            (self.plant_kx, "plant-kx", PLANT_CONTACT),
            (self.plant_lag_periods, "plant-lag-periods", LAG_PERIODS),
            (self.plant_mu0_drift, "plant-mu0-drift", MU0_DRIFT),
        ] {
            d.check(x, &short(x))
                .map_err(|r| Error::usage(format!("--{n}: {r}")))?;
        }
        let v0_profile = match &self.v0_profile {
            Some(p) => Some(read_profile(p)?),
            None => None,
        };
        let cfg = config();
        // Resonant by default; a first-order lag is a model of ideal
        // transducers, so `--plant-lag-periods` alone keeps them ideal.
        let resonant = self.transducers.options(
            (cfg.dac_z.metres_per_code, cfg.dac_x.metres_per_code),
            self.plant_lag_periods == 0.0,
        )?;
        if resonant.is_some() && self.plant_lag_periods != 0.0 {
            return Err(Error::usage(
                "--plant-lag-periods: is for ideal transducers; a resonant one has its own time constant Q/(pi f_r)",
            ));
        }
        Ok(PlantOptions {
            v0,
            noise_counts: noise,
            offset_counts: offset,
            mu0: self.plant_mu0,
            kz: self.plant_kz,
            kx: self.plant_kx,
            lag_periods: self.plant_lag_periods,
            mu0_drift: self.plant_mu0_drift,
            mu0_steps: Vec::new(),
            v0_profile,
            resonant,
        })
    }
}

/// Reads a velocity profile: CSV with a header line and rows `t_s,v0_m_s`,
/// finite, t strictly increasing, at least one row.
///
/// # Errors
/// One line naming `--v0-profile`, the file and the line.
pub fn read_profile(path: &std::path::Path) -> Result<Vec<(f64, f64)>> {
    let bad = |m: String| Error::usage(format!("--v0-profile: {}: {m}", path.display()));
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (i, rec) in r.records().enumerate() {
        let line = i + 2;
        let rec = rec.map_err(|e| bad(format!("line {line}: {e}")))?;
        if rec.len() != 2 {
            return Err(bad(format!(
                "line {line}: expected 2 columns t_s,v0_m_s, got {}",
                rec.len()
            )));
        }
        let num = |k: usize| -> Result<f64> {
            rec[k]
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(format!("line {line}: '{}' is not a finite number", &rec[k])))
        };
        let (t, v) = (num(0)?, num(1)?);
        STAGE_VELOCITY
            .check(v, &rec[1])
            .map_err(|r| bad(format!("line {line}: v0_m_s {r}")))?;
        if out.last().is_some_and(|(tl, _)| t <= *tl) {
            return Err(bad(format!("line {line}: t_s must increase strictly")));
        }
        out.push((t, v));
    }
    if out.is_empty() {
        return Err(bad("no rows (expected a header and rows t_s,v0_m_s)".into()));
    }
    Ok(out)
}

/// The plant of `opts`: its contact, and resonant transducers updated with
/// the plant's sub-step (`SUB` per sample).
fn plant_of(opts: &PlantOptions, cfg: &DeviceConfig) -> Plant<f64> {
    let mut p = Plant::new(opts.mu0, opts.kz, opts.kx);
    if let Some(r) = opts.resonant {
        let h = 1.0 / (cfg.sample_rate_hz * f64::from(SUB));
        // The options were checked (`TransducerSpec::options`); a bad set
        // from code leaves the transducers ideal rather than panic.
        p.resonant = board::plant::Resonant::new(r, h).ok();
    }
    p
}

/// A virtual device with its plant.
pub struct VirtualDevice {
    dev: Device<'static, TABLE_N>,
    server: Server,
    plant: Plant<f64>,
    dac: Vec<u32>,
    half: usize,
    rng: Noise,
    /// The pickups' ADC noise: its own record, so that adding the pickups
    /// left the forces' noise records (and every result seeded by them) as
    /// they were.
    pickup_rng: Noise,
    opts: PlantOptions,
    /// Samples produced since the device was made.
    samples: u64,
    /// Fills made ahead of the half-buffer being simulated (0: fill, then
    /// simulate it; the board: 2, see [`VirtualDevice::set_fill_lead`]).
    fill_lead: usize,
    /// Filled half-buffers not yet simulated, with their half index.
    filled: std::collections::VecDeque<(HalfDrive, usize)>,
    /// Received bytes not yet served (the firmware's USART queue).
    rx: Box<RxQueue<{ link::RX_CAPACITY }>>,
    /// Answers and telemetry not yet on the wire (the firmware's ring).
    tx: Box<TxRing<{ link::TX_CAPACITY }>>,
}

/// The virtual device's queues as the firmware's loop sees them.
struct QueueIo<'a> {
    rx: &'a mut RxQueue<{ link::RX_CAPACITY }>,
    tx: &'a mut TxRing<{ link::TX_CAPACITY }>,
}

impl link::LinkIo for QueueIo<'_> {
    fn pop_rx(&mut self) -> Option<u8> {
        self.rx.pop()
    }

    fn tx_free(&mut self) -> usize {
        self.tx.free()
    }

    fn send(&mut self, frame: &[u8]) {
        // `link::serve` checked the room first: this cannot fail.
        let _ = self.tx.push_frame(frame);
    }
}

/// Moves everything waiting in `tx` into `out`.
fn drain_all(tx: &mut TxRing<{ link::TX_CAPACITY }>, out: &mut Vec<u8>) {
    while let Some(b) = tx.pop() {
        out.push(b);
    }
}

impl VirtualDevice {
    /// A stopped virtual device whose model has contact μ0 = 0.3,
    /// k_z = k_x = 10⁷ N/m ([`DEFAULT_CONTACT`]), with the plant `opts`.
    pub fn new(opts: PlantOptions) -> Self {
        let table: &'static SineTable<TABLE_N> = Box::leak(Box::new(SineTable::libm()));
        let cfg = config();
        let dev = Device::new(
            cfg,
            table,
            Contact {
                mu0: DEFAULT_CONTACT.0 as f32,
                kz: DEFAULT_CONTACT.1 as f32,
                kx: DEFAULT_CONTACT.2 as f32,
            },
        )
        .expect("valid virtual configuration");
        let mut v = VirtualDevice {
            dev,
            server: Server::new(info(&cfg)),
            plant: plant_of(&opts, &cfg),
            dac: vec![0; HALF],
            half: 0,
            rng: Noise::new(0x9E37_79B9_7F4A_7C15),
            pickup_rng: Noise::new(PICKUP_SEED),
            opts,
            samples: 0,
            fill_lead: 0,
            filled: std::collections::VecDeque::new(),
            rx: Box::default(),
            tx: Box::default(),
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
            liftoff_allowed: self.dev.liftoff_allowed(),
        }
    }

    /// Restores a snapshot (settling the ramps and the plant for 20 ms of
    /// device time). Invalid snapshots are ignored.
    pub fn restore(&mut self, st: &SimState) {
        let _ = self.dev.set_contact(st.contact);
        let _ = self.dev.set_liftoff_allowed(st.liftoff_allowed);
        if self.dev.set_drive(st.drive).is_ok() && st.running && self.dev.start().is_ok() {
            let mut n = 0;
            while !self.dev.status().settled && n < 10_000 {
                self.step_half();
                n += 1;
            }
            self.advance((self.sample_rate() / 50.0) as usize);
        }
    }

    /// Feeds received bytes (arriving now, in device time) and serves them
    /// as a host that reads at once would see it: the bytes enter the
    /// receive queue in pieces that fit, each followed by the firmware's
    /// loop; returns the answers and telemetry (the whole transmit ring).
    /// Nothing is dropped (the in-process link has no wire to overrun).
    pub fn receive(&mut self, bytes: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        for piece in bytes.chunks(link::RX_CAPACITY) {
            self.push_rx(piece);
            loop {
                self.serve_link();
                drain_all(&mut self.tx, &mut out);
                if self.rx.is_empty() {
                    break;
                }
            }
        }
        out
    }

    /// Bytes arriving from the wire into the receive queue, as the USART
    /// interrupt puts them there: a byte that does not fit is dropped and
    /// counted in `Status.rx_overflows` (announced by `RxOverflow`
    /// telemetry). Returns the number dropped.
    pub fn push_rx(&mut self, bytes: &[u8]) -> usize {
        let dropped = bytes.iter().filter(|&&b| self.rx.push(b).is_err()).count();
        if dropped > 0 {
            self.dev
                .count_rx_overflow(u32::try_from(dropped).unwrap_or(u32::MAX));
        }
        dropped
    }

    /// The firmware's main loop ([`link::serve`]) until it has no work: a
    /// request leaves the receive queue only while the transmit ring has
    /// room for its answer, and telemetry is sent only while it has room
    /// for [`link::POLL_FRAMES`] frames.
    pub fn serve_link(&mut self) {
        let now_us = self.now_us();
        let mut io = QueueIo {
            rx: &mut self.rx,
            tx: &mut self.tx,
        };
        loop {
            link::serve(&mut self.server, &mut self.dev, &mut io, now_us);
            if !link::has_work(io.rx.len(), io.tx.free()) {
                break;
            }
        }
    }

    /// The transmit ring (answers and telemetry waiting for the wire).
    pub fn tx(&mut self) -> &mut TxRing<{ link::TX_CAPACITY }> {
        &mut self.tx
    }

    /// Device time, µs since the virtual device was made (wrapping): the
    /// samples produced so far over the sample rate.
    pub fn now_us(&self) -> u32 {
        (self.samples as f64 * 1e6 / self.sample_rate()) as u64 as u32
    }

    /// Advances the simulation by whole half-buffers covering `samples`,
    /// running the firmware's loop after each; returns the bytes sent
    /// meanwhile (the transmit ring drained after each half: a host that
    /// reads at once).
    pub fn advance(&mut self, samples: usize) -> Vec<u8> {
        let mut out = Vec::new();
        self.advance_with(samples, |tx| drain_all(tx, &mut out));
        out
    }

    /// [`VirtualDevice::advance`] with the transmit ring handed to `drain`
    /// after each half, which takes what its wire accepts (the rest waits).
    pub fn advance_with(
        &mut self,
        samples: usize,
        mut drain: impl FnMut(&mut TxRing<{ link::TX_CAPACITY }>),
    ) {
        let halves = samples.div_ceil(HALF).max(1);
        for _ in 0..halves {
            self.step_half();
            self.serve_link();
            drain(&mut self.tx);
        }
    }

    /// Drive stopped and settled, no measurement (nor stream), nothing
    /// waiting in the link: the plant's samples reach nothing, so a server
    /// loop may [`VirtualDevice::skip`] instead of simulating them.
    pub fn quiescent(&self) -> bool {
        let s = self.dev.status();
        !s.running && s.settled && !s.measuring && self.rx.is_empty()
    }

    /// Moves the device clock on by `samples` without simulating the plant
    /// (for a [`VirtualDevice::quiescent`] device) and runs the loop once.
    pub fn skip(&mut self, samples: u64) {
        self.samples += samples;
        self.serve_link();
    }

    /// How many half-buffers the DAC fills run ahead of the output: 0 (the
    /// default) fills each half just before it is output; the board's
    /// firmware fills a half while the other is output and handles the ADC
    /// block after the DAC refill of the same boundary, so a command computed
    /// from ADC block `n` first reaches the output in half `n + 3`: lead 2.
    pub fn set_fill_lead(&mut self, halves: usize) {
        self.fill_lead = halves;
    }

    /// Reseeds the ADC noise (a different, equally likely noise record).
    pub fn set_noise_seed(&mut self, seed: u64) {
        self.rng = Noise::new(seed);
        self.pickup_rng = Noise::new(seed ^ PICKUP_SEED);
    }

    /// The device (read-only: the bench's view of its DDS and status).
    pub fn device(&self) -> &Device<'static, TABLE_N> {
        &self.dev
    }

    /// Latches fault `bits` through the board's one fault path
    /// (`Device::fault`: the safe state, one `Fault` telemetry frame), as
    /// the board's own sources raise them — a late DAC refill, the
    /// watchdog, the external input, a late ADC intake. `sim-device
    /// --fault-listen` feeds it from outside; 0 changes nothing.
    pub fn inject_fault(&mut self, bits: u32) {
        self.dev.fault(bits);
    }

    /// The plant (the bench's view of the true motion).
    pub fn plant(&self) -> &Plant<f64> {
        &self.plant
    }

    /// The plant, to set a bench's excursion limit.
    pub fn plant_mut(&mut self) -> &mut Plant<f64> {
        &mut self.plant
    }

    /// Samples per second.
    pub fn sample_rate(&self) -> f64 {
        self.dev.config().sample_rate_hz
    }

    fn noise(&mut self) -> f64 {
        self.rng.uniform(self.opts.noise_counts)
    }

    /// Makes DAC fills until `fill_lead + 1` halves wait to be simulated.
    fn fill_ahead(&mut self) {
        while self.filled.len() <= self.fill_lead {
            let half = self.half;
            let mut buf = std::mem::take(&mut self.dac);
            let d = HalfDrive::fill(&mut self.dev, half, &mut buf);
            self.dac = buf;
            self.filled.push_back((d, half));
            self.half ^= 1;
        }
    }

    fn step_half(&mut self) {
        self.fill_ahead();
        let Some((d, half)) = self.filled.pop_front() else {
            return;
        };
        // Amplitude lag per sample: exact solution of dA/dt = (A_DAC − A)/τ
        // over one sample with A_DAC constant, τ = lag_periods/f = lag_periods·2π/(dθ·f_s).
        let dtheta = d.dtheta();
        let keep = if self.opts.lag_periods > 0.0 && dtheta > 0.0 {
            (-dtheta / (TAU * self.opts.lag_periods)).exp()
        } else {
            0.0
        };
        let ts = 1.0 / self.sample_rate();
        let t0 = self.samples;
        let offset = self.opts.offset_counts;
        let mut samples = [(0u16, 0u16); HALF];
        let mut pickups = [(0u16, 0u16); HALF];
        let cfg = *self.dev.config();
        let mut plant = self.plant;
        plant.run_half_with_pickups::<Libm>(
            &cfg,
            &d,
            SUB,
            keep,
            |i| {
                let t_s = (t0 + i as u64) as f64 * ts;
                let counts_z = offset + self.noise();
                let counts_x = offset + self.noise();
                SampleConditions {
                    mu0: self.opts.mu0_at(t_s),
                    v0: self.opts.v0_at(t_s),
                    counts_z,
                    counts_x,
                }
            },
            &mut samples,
            &mut pickups,
        );
        self.plant = plant;
        // The pickups' ADC noise, as the forces' (uniform ± counts, on the
        // rounded reading, clamped to the ADC's range).
        let full = f64::from(cfg.adc_full_scale);
        let amp = self.opts.noise_counts;
        for p in pickups.iter_mut() {
            let mut n = |c: u16| {
                (f64::from(c) + self.pickup_rng.uniform(amp))
                    .round()
                    .clamp(0.0, full) as u16
            };
            *p = (n(p.0), n(p.1));
        }
        self.dev.adc_block_with_pickups(half, &samples, &pickups);
        self.samples += HALF as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use board::protocol::{
        decode, encode, Body, Deframed, Deframer, Frame, Request, Response, MAX_FRAME,
        PROTOCOL_VERSION,
    };

    /// The answers to `seq` among the bytes a virtual device sent.
    fn answers_to(seq: u32, out: &[u8]) -> Vec<Response> {
        let mut df = Deframer::default();
        let mut found = Vec::new();
        for &b in out {
            if let Deframed::Frame(f) = df.push(b, 0) {
                if let Ok(fr) = decode(f) {
                    if let (true, Body::Response(r)) = (fr.seq == seq, fr.body) {
                        found.push(r);
                    }
                }
            }
        }
        found
    }

    /// docs/protocol.md, "Inter-byte timeout": measured in device time. A
    /// `GetStatus` split in two with 50 ms of the virtual device's time
    /// between the halves is answered; split by 150 ms (> 100 ms) its first
    /// half is discarded and the request gets no `Status` (wall time between
    /// the two writes is nil in both cases).
    #[test]
    fn the_inter_byte_timeout_counts_device_time() {
        let mut buf = [0u8; MAX_FRAME];
        let frame = |seq: u32, buf: &mut [u8; MAX_FRAME]| {
            encode(
                &Frame {
                    version: PROTOCOL_VERSION,
                    seq,
                    body: Body::Request(Request::GetStatus),
                },
                buf,
            )
            .unwrap()
            .to_vec()
        };
        for (seq, gap_s, answered) in [(9u32, 0.05, true), (10, 0.15, false)] {
            let opts = PlantSpec::default()
                .options(0.0, 0.0, 0.0, ["v0", "noise", "offset"])
                .unwrap();
            let mut v = VirtualDevice::new(opts);
            let bytes = frame(seq, &mut buf);
            let cut = bytes.len() / 2;
            let mut out = v.receive(&bytes[..cut]);
            out.extend(v.advance((gap_s * v.sample_rate()) as usize));
            out.extend(v.receive(&bytes[cut..]));
            let got = answers_to(seq, &out);
            let status = got.iter().any(|r| matches!(r, Response::Status(_)));
            assert_eq!(status, answered, "gap {gap_s} s: {got:?}");
        }
    }
}

//! The motion pickups' conversion delay (issue 42, item 3). On the board
//! ADC1 and ADC2 scan the force, then the pickup of each axis on every
//! trigger, so a pickup is converted δ = (3 + 12) ADC clocks / 21 MHz =
//! 0.714 µs after its force (`DeviceConfig::pickup_delay_s`): 10.3° of a
//! 40 kHz drive. The device demodulates each pickup sample at its own
//! instant, and the simulated plant samples the pickups δ after the forces.
//!
//! * `the_device_measures_the_response_of_delayed_pickups`: hand-made pickup
//!   samples (a pure sinusoid of known amplitude and phase, evaluated in
//!   f64 at t_k + δ) through a real `Device` in voltage mode; the measured
//!   response `X/U` against the known one, and the same samples through a
//!   device that ignores the delay, whose phase is off by ω·δ.
//! * `the_plant_samples_ideal_pickups_after_the_forces`: the plant's pickup
//!   counts (ideal transducers) against the closed form at t_k + δ.
//! * `the_device_measures_resonant_transducers_through_delayed_pickups`: the
//!   plant's resonant modes (the exact partial hold step over δ) through the
//!   device: each mode's measured response is its transfer function with the
//!   DAC's hold, as identification assumes.

use std::f64::consts::{PI, TAU};

use board::dds::SineTable;
use board::dds::DAC_VOLTS_PER_CODE;
use board::device::{
    config::PICKUP_DELAY_S, ConfigError, Contact, Device, DeviceConfig, DriveSetting,
    MeasuredDrive, HALF_BUFFER,
};
use board::plant::{HalfDrive, Plant, Resonant, ResonantOptions, SampleConditions};
use board::resonator::ModeParams;
use integration_tests::lockin_error_gain;
use model_core::Libm;

/// Accumulator words per turn.
const WORDS: f64 = 4_294_967_296.0;

const CONTACT: Contact = Contact {
    mu0: 0.3,
    kz: 1e7,
    kx: 1e7,
};

/// The drive of the device-level test: 40 kHz (the frequency),
/// Δu_z = 1 µm, Δu_x = 0.5 µm, u_z0 = 4 µm, φ = 0.7 rad.
fn drive_40k() -> DriveSetting {
    DriveSetting {
        freq_hz: 40_000.0,
        amp_z_m: 1e-6,
        amp_x_m: 0.5e-6,
        offset_z_m: 4e-6,
        phase_rad: 0.7,
    }
}

/// The pickups' signals of the device-level test: `(A, ψ)` of
/// `x(t) = A cos(θ(t) + ψ)` per channel (z, x), m and rad; A_z below u_z0
/// (the measured lift-off guard), both well inside the pickups' ±10 µm.
const SIGNAL: [(f64, f64); 2] = [(1.5e-6, 1.0), (0.8e-6, -2.0)];

/// `x` wrapped to (−π, π].
fn wrap(x: f64) -> f64 {
    let y = (x + PI).rem_euclid(TAU) - PI;
    if y == -PI {
        PI
    } else {
        y
    }
}

/// The voltage phasor `U` of each channel for the drive `d` (eqs. 1–2:
/// `u_z = −Δu_z cos θ`, `u_x = Δu_x cos(θ + φ)`), from the setting and the
/// calibrations alone: `(|U|, arg U)`, V and rad.
fn volts(cfg: &DeviceConfig, d: &DriveSetting) -> [(f64, f64); 2] {
    let v = |amp: f32, mpc: f32| f64::from(amp) / f64::from(mpc) * DAC_VOLTS_PER_CODE;
    [
        (v(d.amp_z_m, cfg.dac_z.metres_per_code), PI),
        (
            v(d.amp_x_m, cfg.dac_x.metres_per_code),
            f64::from(d.phase_rad),
        ),
    ]
}

/// Runs a device with configuration `cfg` on the drive `d` and feeds it, as
/// pickups, the sinusoids `SIGNAL` sampled at `t_k + true_delay_s`: the
/// drive phase of ADC sample k (the DDS accumulator of DAC word
/// `k − adc_lag_samples` of the block's fill) plus `ω·δ`, all in f64, then
/// converted to counts by the configuration's pickup calibrations. Returns
/// the measured drives of `windows` lock-in windows after the DDS has
/// settled, and ω·δ (rad).
fn run_fed(
    cfg: DeviceConfig,
    d: DriveSetting,
    true_delay_s: f64,
    windows: usize,
) -> (Vec<MeasuredDrive>, f64) {
    let (ms, wd, _) = run_fed_counted(cfg, d, true_delay_s, windows);
    (ms, wd)
}

/// [`run_fed`], with the count of blocks whose reference the ADC formed
/// itself (`Device::adc_references_formed`) and the blocks taken.
fn run_fed_counted(
    cfg: DeviceConfig,
    d: DriveSetting,
    true_delay_s: f64,
    windows: usize,
) -> (Vec<MeasuredDrive>, f64, (u32, u32)) {
    let table = SineTable::<1024>::libm();
    let mut dev = Device::new(cfg, &table, CONTACT).unwrap();
    dev.set_drive(d).unwrap();
    dev.start().unwrap();
    let mut dac = [0u32; HALF_BUFFER];
    // Forces at rest: f_x = 0, f_z = 2 N (the estimator is not asked).
    let forces = [(cfg.adc_x.offset as u16, 100u16); HALF_BUFFER];
    let mut pickups = [(0u16, 0u16); HALF_BUFFER];
    let cal = [cfg.pickup_z, cfg.pickup_x];
    let lag = f64::from(cfg.adc_lag_samples);
    let (mut half, mut settled_for, mut seen) = (0, 0usize, 0u32);
    let mut out = Vec::new();
    let mut wd = 0.0;
    while out.len() < windows {
        let (acc0, tw) = (dev.dds().accumulator(), dev.dds().tuning_word());
        dev.fill_dac(half, &mut dac);
        // ω·δ: the DDS advances tw words per sample, f_s samples per second.
        wd = TAU * f64::from(tw) * cfg.sample_rate_hz * true_delay_s / WORDS;
        for (k, p) in pickups.iter_mut().enumerate() {
            let theta = TAU * (f64::from(acc0) + (k as f64 - lag) * f64::from(tw)) / WORDS + wd;
            let c = |ch: usize| {
                let (a, psi) = SIGNAL[ch];
                let x = a * (theta + psi).cos();
                (x / f64::from(cal[ch].gain) + f64::from(cal[ch].offset)).round() as u16
            };
            *p = (c(0), c(1));
        }
        dev.adc_block_with_pickups(half, &forces, &pickups);
        half ^= 1;
        assert_eq!(dev.status().faults, 0);
        if dev.status().settled {
            settled_for += 1;
        }
        if let Some(m) = dev.measured_drive() {
            // Two windows after settling: the window that closed is wholly
            // at the final levels.
            if settled_for > 2 && m.windows != seen {
                out.push(m);
            }
            seen = m.windows;
        }
    }
    (out, wd, (dev.adc_references_formed(), dev.adc_blocks()))
}

/// The device's measured response `X/U` of channel `ch` as `(|H|, arg H)`.
fn response(m: &MeasuredDrive, ch: usize) -> (f64, f64) {
    let h = if ch == 0 {
        m.response_z_m_per_v
    } else {
        m.response_x_m_per_v
    }
    .expect("a driven channel has a response");
    let (re, im) = (f64::from(h[0]), f64::from(h[1]));
    (re.hypot(im), im.atan2(re))
}

#[test]
fn the_board_converts_its_pickups_15_adc_clocks_after_the_forces() {
    // RM0090 §13.5: T_conv = sampling time + 12 ADC clocks; SMPR = 0 is
    // 3 clocks; f_ADC = 84 MHz / 4 = 21 MHz.
    let cfg = DeviceConfig::driver_board(1);
    assert_eq!(cfg.pickup_delay_s, (3.0 + 12.0) / 21e6);
    assert_eq!(PICKUP_DELAY_S, cfg.pickup_delay_s);
    assert_eq!(cfg.check_pickup_delay(), Ok(()));
    // 0.357 of a sample at 500 kS/s; 10.3° of a 40 kHz drive.
    assert!((cfg.pickup_delay_s * cfg.sample_rate_hz - 0.357).abs() < 1e-3);
    assert!(((TAU * 40e3 * cfg.pickup_delay_s).to_degrees() - 10.29).abs() < 0.01);
    // The check refuses what cannot be a delay within one sample.
    for bad in [-1e-9, 2e-6, 1e-3, f64::NAN, f64::INFINITY] {
        let c = DeviceConfig {
            pickup_delay_s: bad,
            ..cfg
        };
        assert_eq!(
            c.check_pickup_delay(),
            Err(ConfigError::PickupDelay),
            "{bad}"
        ); // And the device refuses to be built on it.
        let table = board::dds::SineTable::<1024>::build::<model_core::Libm>();
        let contact = board::device::Contact {
            mu0: 0.3,
            kz: 1e7,
            kx: 1e7,
        };
        assert!(
            matches!(
                board::device::Device::new(c, &table, contact),
                Err(board::device::DeviceError::Config(ConfigError::PickupDelay))
            ),
            "{bad}"
        );
    }
    let zero = DeviceConfig {
        pickup_delay_s: 0.0,
        ..cfg
    };
    assert_eq!(zero.check_pickup_delay(), Ok(()));
    assert!(ConfigError::PickupDelay
        .to_string()
        .contains("pickup_delay_s"));
    // The reference word: the force's, advanced by round(tw·δ·f_s).
    let tw = 343_597_384u32; // 40 kHz at 500 kS/s
    let want = (f64::from(tw) * 15.0 / 21e6 * 500e3).round() as u32;
    assert_eq!(cfg.pickup_delay_words(tw), want);
    assert_eq!(
        cfg.pickup_reference_word(1000, tw),
        1000u32.wrapping_sub(tw).wrapping_add(want)
    );
    assert_eq!(
        zero.pickup_reference_word(1000, tw),
        1000u32.wrapping_sub(tw)
    );
    // The window's integer form (issue 35): within one word of tw·δ·f_s
    // formed here in f64 (the docs' bound), for the board's delay and a
    // delay of almost a whole sample, over tuning words from 0 to 2³² − 1;
    // zero for no delay.
    let mut worst: f64 = 0.0;
    for c in [
        cfg,
        DeviceConfig {
            pickup_delay_s: 0.999 / 500e3,
            ..cfg
        },
    ] {
        let k = c.pickup_delay_factor();
        let samples = c.pickup_delay_s * c.sample_rate_hz;
        for i in 0..=4096u64 {
            let tw = (i * 1_048_575).min(u64::from(u32::MAX)) as u32;
            let got = board::device::config::pickup_delay_words_of(k, tw);
            let exact = f64::from(tw) * samples;
            let err = (f64::from(got) - exact).abs();
            assert!(err <= 1.0, "tw {tw}: {got} vs {exact}");
            worst = worst.max(err);
        }
    }
    assert!(worst > 0.5, "the rounding is exercised ({worst})");
    assert_eq!(zero.pickup_delay_factor(), 0);
    // A delay the configuration check refuses gives no delay at all, in
    // both forms (documented: 0 for a delay not finite or not > 0).
    for bad in [f64::INFINITY, f64::NAN, -1e-7] {
        let c = DeviceConfig {
            pickup_delay_s: bad,
            ..cfg
        };
        assert_eq!(
            (c.pickup_delay_factor(), c.pickup_delay_words(tw)),
            (0, 0),
            "{bad}"
        );
    }
    assert_eq!(board::device::config::pickup_delay_words_of(0, tw), 0);
}

/// Hand-made pickup samples at `t_k + δ` through the device (voltage mode,
/// the chip's ADC lag 1, 40 kHz): the measured `X/U` of each channel is the
/// known `A·e^{jψ}/U` within the bound below; a device that ignores the
/// delay (`pickup_delay_s = 0`, the state before the fix) measures a phase
/// ω·δ = 10.3° ahead.
///
/// Bound on the phase of one window (one 64-sample block, 5.1 periods at
/// 40 kHz; the lock-in's fit has no leak for a pure sinusoid at the
/// reference frequency, `lockin.rs` eq. L1):
/// * the counts' rounding, ≤ ½ count of `gain` per sample: ≤ ½·gain·G on
///   the phasor, G the window's error gain (`lockin_error_gain`, from the
///   fit's weights), so ≤ ½·gain·G/A on the phase;
/// * the reference words (eq. R1 of `board::reference`, formed by the DAC
///   fill and kept for the ADC): each cosine and sine within ε_r ≤ 3.06e-5
///   (R2), which moves the phasor by ≤ √2·G·ε_r·A: ≤ 8.7e-5 rad with G ≈ 2;
/// * the f32 arithmetic (the lock-in's sums of 64 terms, ≤ 64·2⁻²⁴·2 ≈
///   8e-6 relative; the phase word in f32, 2⁻²⁴·2π = 3.7e-7 rad; fast-f32
///   sin/cos ≤ 1e-7) and the delay rounded to a whole accumulator word
///   (≤ ½·2π/2³² = 7.3e-10 rad): allowed 1e-4 rad, five times their sum.
///
/// The same bound holds for `|H|` relative (the errors are of the phasor).
#[test]
fn the_device_measures_the_response_of_delayed_pickups() {
    let cfg = DeviceConfig::driver_board(1);
    let d = drive_40k();
    let u = volts(&cfg, &d);
    let (ms, wd) = run_fed(cfg, d, cfg.pickup_delay_s, 40);
    let tw = (40e3 / cfg.sample_rate_hz * WORDS).round();
    let g = lockin_error_gain(HALF_BUFFER, TAU * tw / WORDS);
    let cal = [cfg.pickup_z.gain, cfg.pickup_x.gain];
    let bound =
        |ch: usize| 0.5 * f64::from(cal[ch]) * g / SIGNAL[ch].0 + 2f64.sqrt() * g * 3.06e-5 + 1e-4;
    // ω·δ at the DDS's 40 kHz: 10.29°.
    assert!(
        (wd.to_degrees() - 10.29).abs() < 0.01,
        "{}",
        wd.to_degrees()
    );
    let mut worst = [0.0f64; 2];
    for m in &ms {
        for ch in 0..2 {
            let (mag, arg) = response(m, ch);
            let (a, psi) = SIGNAL[ch];
            let (want_mag, want_arg) = (a / u[ch].0, wrap(psi - u[ch].1));
            let e = wrap(arg - want_arg);
            worst[ch] = worst[ch].max(e.abs());
            assert!(e.abs() <= bound(ch), "ch {ch}: {arg} vs {want_arg} ({m:?})");
            assert!(
                (mag / want_mag - 1.0).abs() <= bound(ch),
                "ch {ch}: |H| {mag:e} vs {want_mag:e}"
            );
        }
    }
    // The bound is far below what the delay costs uncorrected.
    assert!(bound(0).max(bound(1)) < wd / 20.0, "{} {wd}", bound(0));
    println!(
        "phase error with the delay corrected: z {:.4}°, x {:.4}° (bounds {:.3}°, {:.3}°)",
        worst[0].to_degrees(),
        worst[1].to_degrees(),
        bound(0).to_degrees(),
        bound(1).to_degrees()
    );

    // The same samples through a device that ignores the delay: every
    // response's phase is ω·δ ahead (the pickups were sampled later than the
    // reference assumes), within the same bound.
    let blind = DeviceConfig {
        pickup_delay_s: 0.0,
        ..cfg
    };
    let (ms, wd0) = run_fed(blind, d, cfg.pickup_delay_s, 10);
    assert_eq!(wd0, wd);
    let mut seen = [0.0f64; 2];
    for m in &ms {
        for ch in 0..2 {
            let (_, arg) = response(m, ch);
            let e = wrap(arg - wrap(SIGNAL[ch].1 - u[ch].1));
            seen[ch] = e;
            assert!(
                (e - wd).abs() <= bound(ch),
                "ch {ch}: error {e} vs ω·δ = {wd}"
            );
        }
    }
    println!(
        "phase error with the delay ignored: z {:.3}°, x {:.3}° (ω·δ = {:.3}°)",
        seen[0].to_degrees(),
        seen[1].to_degrees(),
        wd.to_degrees()
    );
}

/// The plant's pickups with ideal transducers: each count is the closed
/// form `Δu_z sin(θ_k − π/2 + ω·δ)`, `Δu_x sin(θ_k + φ + π/2 + ω·δ)` (eqs.
/// 1–2 as the DDS outputs them), θ_k the drive phase of ADC sample k, in
/// counts by the calibration and rounded: within 1 count (the plant rounds
/// the same value computed in another order: a tie may go either way; the
/// DDS's f32 amplitude codes and its phase words differ from the setting by
/// ≤ 1e-7 relative and ≤ 1.5e-9 rad, ≤ 1e-4 count at ≤ 400 counts). With
/// δ = 0 (a plant whose pickups convert with the forces) the counts are the
/// closed form at θ_k, and the two differ by far more than a count.
#[test]
fn the_plant_samples_ideal_pickups_after_the_forces() {
    for delay in [PICKUP_DELAY_S, 0.0] {
        let cfg = DeviceConfig {
            pickup_delay_s: delay,
            ..DeviceConfig::driver_board(1)
        };
        let table = SineTable::<1024>::libm();
        let mut dev = Device::new(cfg, &table, CONTACT).unwrap();
        let d = DriveSetting {
            amp_z_m: 2e-6,
            ..drive_40k()
        };
        dev.set_drive(d).unwrap();
        dev.start().unwrap();
        let mut plant = Plant::<f64>::new(0.3, 1e7, 1e7);
        let mut dac = [0u32; HALF_BUFFER];
        let mut forces = [(0u16, 0u16); HALF_BUFFER];
        let mut pickups = [(0u16, 0u16); HALF_BUFFER];
        let (mut half, mut settled_for, mut checked) = (0, 0usize, 0usize);
        let (mut worst, mut worst_other) = (0i32, 0i32);
        while checked < 20 {
            let h = HalfDrive::fill(&mut dev, half, &mut dac);
            plant.run_half_with_pickups::<Libm>(
                &cfg,
                &h,
                8,
                0.0,
                |_| SampleConditions {
                    mu0: 0.3,
                    v0: 0.004,
                    counts_z: 0.0,
                    counts_x: 0.0,
                },
                &mut forces,
                &mut pickups,
            );
            dev.adc_block_with_pickups(half, &forces, &pickups);
            half ^= 1;
            // Settled before this fill: its drive is the setting's throughout.
            if settled_for > 1 {
                let lag = f64::from(cfg.adc_lag_samples);
                let closed = |k: usize, dl: f64| {
                    let tw = f64::from(h.tw);
                    let theta = TAU * (f64::from(h.acc0) + (k as f64 - lag) * tw) / WORDS
                        + TAU * tw * cfg.sample_rate_hz * dl / WORDS;
                    let z = f64::from(d.amp_z_m) * (theta - PI / 2.0).sin();
                    let x =
                        f64::from(d.amp_x_m) * (theta + f64::from(d.phase_rad) + PI / 2.0).sin();
                    let c = |v: f64, cal: board::estimator::Calibration| {
                        (v / f64::from(cal.gain) + f64::from(cal.offset)).round() as i32
                    };
                    (c(z, cfg.pickup_z), c(x, cfg.pickup_x))
                };
                for (k, &(pz, px)) in pickups.iter().enumerate() {
                    let (z, x) = closed(k, delay);
                    let e = (i32::from(pz) - z).abs().max((i32::from(px) - x).abs());
                    worst = worst.max(e);
                    let other = if delay > 0.0 { 0.0 } else { PICKUP_DELAY_S };
                    let (z, x) = closed(k, other);
                    let e = (i32::from(pz) - z).abs().max((i32::from(px) - x).abs());
                    worst_other = worst_other.max(e);
                }
                checked += 1;
            }
            if dev.status().settled {
                settled_for += 1;
            }
        }
        assert!(
            worst <= 1,
            "δ = {delay}: {worst} counts from the closed form"
        );
        // 2 µm at 5 nm/count is 400 counts; ω·δ = 0.18 rad moves a sample by
        // up to 0.18·400 = 72 counts.
        assert!(worst_other > 20, "δ = {delay}: {worst_other}");
        println!(
            "δ = {delay:e} s: worst {worst} count(s); against the other instant {worst_other}"
        );
    }
}

/// Resonant transducers (the bench's modes, loaded) through the device:
/// each mode's measured response `X/U` at 20 kHz is its transfer function
/// times the DAC's hold, `H(f)·sinc(πf/f_s)·e^{−jπf/f_s}` — the model
/// identification fits (its extra lag θ = π f_r/f_s,
/// `ResonantOptions::identified`). The plant samples each mode δ after the
/// sample's start by the exact hold update over δ, the device demodulates
/// at that instant: nothing of δ remains (uncorrected on either side it
/// would be ω·δ = 5.1° at 20 kHz).
///
/// Bound per window: the pickups' rounding ½·gain·G over the amplitude, as
/// in the ideal test; and 1e-4: the held waveform's images (≤ 2e-6 of the
/// fundamental, `plant.rs` tests) and the f32 lock-in (≤ 1e-5), with margin.
#[test]
fn the_device_measures_resonant_transducers_through_delayed_pickups() {
    let cfg = DeviceConfig::driver_board(1);
    let table = SineTable::<1024>::libm();
    let mut dev = Device::new(cfg, &table, CONTACT).unwrap();
    let d = DriveSetting {
        freq_hz: 20_000.0,
        amp_z_m: 2e-6,
        amp_x_m: 1e-6,
        offset_z_m: 4e-6,
        phase_rad: 40f32.to_radians(),
    };
    dev.set_drive(d).unwrap();
    dev.start().unwrap();
    let opts = ResonantOptions::<f64>::bench(&cfg);
    let sub = 4;
    let mut plant = Plant::<f64>::new(0.3, 1e7, 1e7);
    plant.resonant =
        Some(Resonant::new(opts, 1.0 / (cfg.sample_rate_hz * f64::from(sub))).unwrap());
    // 30 τ of the slower (normal) mode, τ = Q_eff/(π f_r) = 4.1 ms, in
    // half-buffers of 128 µs, after the DDS has settled.
    let loaded = |p: ModeParams<f64>| {
        let q = 1.0 / (1.0 / p.q + 1.0 / opts.load_q);
        ModeParams { q, ..p }
    };
    let modes = [loaded(opts.modes[0]), loaded(opts.modes[1])];
    let settle = (30.0 * modes[0].tau_s() / 128e-6) as usize;
    let mut dac = [0u32; HALF_BUFFER];
    let mut forces = [(0u16, 0u16); HALF_BUFFER];
    let mut pickups = [(0u16, 0u16); HALF_BUFFER];
    let (mut half, mut settled_for, mut seen) = (0, 0usize, 0u32);
    let mut ms = Vec::new();
    while ms.len() < 30 {
        let h = HalfDrive::fill(&mut dev, half, &mut dac);
        plant.run_half_with_pickups::<Libm>(
            &cfg,
            &h,
            sub,
            0.0,
            |_| SampleConditions {
                mu0: 0.3,
                v0: 0.004,
                counts_z: 0.0,
                counts_x: 0.0,
            },
            &mut forces,
            &mut pickups,
        );
        dev.adc_block_with_pickups(half, &forces, &pickups);
        half ^= 1;
        assert_eq!(dev.status().faults, 0);
        if dev.status().settled {
            settled_for += 1;
        }
        if let Some(m) = dev.measured_drive() {
            if settled_for > settle && m.windows != seen {
                ms.push(m);
            }
            seen = m.windows;
        }
    }
    let f = dev.applied().achieved.freq_hz;
    let hold = PI * f / cfg.sample_rate_hz;
    let sinc = hold.sin() / hold;
    let u = volts(&cfg, &d);
    let g = lockin_error_gain(HALF_BUFFER, TAU * f / cfg.sample_rate_hz);
    let cal = [cfg.pickup_z.gain, cfg.pickup_x.gain];
    let mut worst = [0.0f64; 2];
    for ch in 0..2 {
        let (mag, lag) = modes[ch].response::<Libm>(f);
        let (want_mag, want_arg) = (mag * sinc, wrap(-lag - hold));
        let amp = want_mag * u[ch].0;
        let bound = 0.5 * f64::from(cal[ch]) * g / amp + 1e-4;
        for m in &ms {
            let (hm, ha) = response(m, ch);
            let e = wrap(ha - want_arg);
            worst[ch] = worst[ch].max(e.abs());
            assert!(
                e.abs() <= bound,
                "ch {ch}: arg {ha} vs {want_arg} (bound {bound})"
            );
            assert!(
                (hm / want_mag - 1.0).abs() <= bound,
                "ch {ch}: |H| {hm:e} vs {want_mag:e}"
            );
        }
        let wd = TAU * f * cfg.pickup_delay_s;
        assert!(bound < wd / 5.0, "ch {ch}: bound {bound} vs ω·δ {wd}");
    }
    println!(
        "resonant: worst phase error z {:.4}°, x {:.4}°",
        worst[0].to_degrees(),
        worst[1].to_degrees()
    );
}

/// The plant's look-ahead over δ ([`board::resonator::Mode::
/// update_for`] with `x_after`) is the exact solution of the mode's
/// equation `x'' + 2ζω_r x' + ω_r² x = ω_r² g u` over δ with `u` held, from
/// any state: checked against classical Runge–Kutta (RK4) on the same
/// equation, 1000 steps over δ. RK4's global error is ≈ (ω_r h)⁴·ω_r δ/120
/// of the state's scale, (1.3e5·7.1e-10)⁴·0.09/120 ≈ 6e-20 here, so what is
/// left is the f64 rounding of both (a few hundred ulps of the scale over
/// 1000 steps): allowed 1e-12 of the scale `max(|x₀|, |v₀|/ω_r, |g u|)`.
/// The state is left as it was, and a zero or negative step is refused.
#[test]
fn the_partial_hold_step_is_exact() {
    use board::resonator::{Mode, ModeError};
    let p = ModeParams {
        resonance_hz: 20_300.0,
        q: 260.9,
        gain_m_per_v: 8e-8,
    };
    let mut m = Mode::new(p, 1.0 / 2e6).unwrap();
    let (x0, v0, u) = (1.2e-6, -0.11, 0.7);
    m.set_state(x0, v0);
    let dl = PICKUP_DELAY_S;
    let look = m.update_for(dl).unwrap();
    let x = m.x_after(&look, u);
    assert_eq!((m.x(), m.v()), (x0, v0), "the state moved");
    let wr = TAU * p.resonance_hz;
    let zeta = 0.5 / p.q;
    let f = |x: f64, v: f64| (v, wr * wr * (p.gain_m_per_v * u - x) - 2.0 * zeta * wr * v);
    let n = 1000;
    let h = dl / f64::from(n);
    let (mut xr, mut vr) = (x0, v0);
    for _ in 0..n {
        let (k1x, k1v) = f(xr, vr);
        let (k2x, k2v) = f(xr + 0.5 * h * k1x, vr + 0.5 * h * k1v);
        let (k3x, k3v) = f(xr + 0.5 * h * k2x, vr + 0.5 * h * k2v);
        let (k4x, k4v) = f(xr + h * k3x, vr + h * k3v);
        xr += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        vr += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    let scale = x0.abs().max(v0.abs() / wr).max((p.gain_m_per_v * u).abs());
    assert!(
        (x - xr).abs() <= 1e-12 * scale,
        "{x:e} vs RK4 {xr:e} ({:e} of the scale)",
        (x - xr).abs() / scale
    );
    // It moved the mode a visible way (the check is not vacuous).
    assert!((x - x0).abs() > 1e-3 * scale);
    assert_eq!(m.update_for(0.0).err(), Some(ModeError::Step));
    assert_eq!(m.update_for(-dl).err(), Some(ModeError::Step));
    assert_eq!(m.update_for(f64::NAN).err(), Some(ModeError::Step));
}

/// The ADC takes the reference words its DAC fills formed (one rotation per
/// sample for both: issue 35), laid out as it sees them: ADC sample `k`
/// saw DAC word `k − L`. With L = 0, 1 and 3 samples, the pickups fed at
/// the drive phase of word `k − L` (`run_fed`, in f64) are measured within
/// the bound of `the_device_measures_the_response_of_delayed_pickups` —
/// a layout off by one sample would turn every phase by ω/f_s = 29°, and a
/// lag misapplied in either direction likewise — and only the first block,
/// which has no fill before it, forms its own reference.
#[test]
fn the_adc_takes_the_reference_words_its_fills_formed() {
    for lag in [0u32, 1, 3] {
        let cfg = DeviceConfig::driver_board(lag);
        let d = drive_40k();
        let u = volts(&cfg, &d);
        let (ms, _, (formed, blocks)) = run_fed_counted(cfg, d, cfg.pickup_delay_s, 10);
        let tw = (40e3 / cfg.sample_rate_hz * WORDS).round();
        let g = lockin_error_gain(HALF_BUFFER, TAU * tw / WORDS);
        let cal = [cfg.pickup_z.gain, cfg.pickup_x.gain];
        let bound = |ch: usize| {
            0.5 * f64::from(cal[ch]) * g / SIGNAL[ch].0 + 2f64.sqrt() * g * 3.06e-5 + 1e-4
        };
        for m in &ms {
            for ch in 0..2 {
                let (_, arg) = response(m, ch);
                let e = wrap(arg - wrap(SIGNAL[ch].1 - u[ch].1));
                assert!(e.abs() <= bound(ch), "lag {lag} ch {ch}: error {e} rad");
            }
        }
        assert!(blocks > 10, "{blocks}");
        assert_eq!(
            formed, 1,
            "lag {lag}: {formed} of {blocks} blocks formed their own"
        );
    }
    // Half-buffers of 32 samples: no fill's words are kept (the board's
    // are 64), and every block forms its own.
    let cfg = DeviceConfig::driver_board(1);
    let table = SineTable::<1024>::libm();
    let mut dev = Device::new(cfg, &table, CONTACT).unwrap();
    dev.set_drive(drive_40k()).unwrap();
    dev.start().unwrap();
    let mut dac = [0u32; 32];
    let (forces, pickups) = ([(2048u16, 100u16); 32], [(2048u16, 2048u16); 32]);
    for k in 0..20 {
        dev.fill_dac(k % 2, &mut dac);
        dev.adc_block_with_pickups(k % 2, &forces, &pickups);
    }
    assert_eq!((dev.adc_references_formed(), dev.adc_blocks()), (20, 20));
}

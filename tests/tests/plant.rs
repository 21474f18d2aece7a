//! The simulated analog side (`board::plant`), the plant of the
//! host's virtual device and of the firmware under QEMU, checked without the
//! estimator: ADC counts straight from the plant, driven by a real `Device`
//! (DDS ramps, phases, the ADC lag).
//!
//! Drive: 20 kHz (25 samples a period at 500 kS/s), Δu_z = 2 µm,
//! Δu_x = 0.3 µm, u_z0 = 4 µm, φ = 40°; contact μ0 = 0.3, k_z = k_x = 1e7 N/m.

use board::dds::SineTable;
use board::device::{Contact, Device, DeviceConfig, DriveSetting, HALF_BUFFER};
use board::plant::{HalfDrive, Plant, SampleConditions};
use model_core::{FastF32, Float, Libm, Math};

const MU0: f64 = 0.3;

fn drive(phase_rad: f32) -> DriveSetting {
    DriveSetting {
        freq_hz: 20_000.0,
        amp_z_m: 2e-6,
        amp_x_m: 0.3e-6,
        offset_z_m: 4e-6,
        phase_rad,
    }
}

/// Runs the device and the plant (no noise, stage at `v0`, `sub` sub-steps)
/// until the drive has settled and 20 more halves have passed, then returns
/// the ADC samples (x, z) of the next `halves` halves.
fn run<F: Float, M: Math<F>>(
    cfg: DeviceConfig,
    setting: DriveSetting,
    v0: f64,
    sub: u32,
    halves: usize,
) -> Vec<(u16, u16)> {
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev = Device::new(cfg, &table, contact).unwrap();
    dev.set_drive(setting).unwrap();
    dev.start().unwrap();
    let mut plant = Plant::<F>::new(F::from_f64(MU0), F::from_f64(1e7), F::from_f64(1e7));
    let mut dac = [0u32; HALF_BUFFER];
    let mut block = [(0u16, 0u16); HALF_BUFFER];
    let mut out = Vec::new();
    let (mut half, mut after_settled) = (0, 0);
    while out.len() < halves * HALF_BUFFER {
        let d = HalfDrive::fill(&mut dev, half, &mut dac);
        half ^= 1;
        plant.run_half::<M>(
            &cfg,
            &d,
            sub,
            F::ZERO,
            |_| SampleConditions {
                mu0: F::from_f64(MU0),
                v0: F::from_f64(v0),
                counts_z: F::ZERO,
                counts_x: F::ZERO,
            },
            &mut block,
        );
        if dev.status().settled {
            after_settled += 1;
        }
        if after_settled > 20 {
            out.extend_from_slice(&block);
        }
    }
    out
}

/// Σf_x/Σf_z from the counts through the calibrations (N), and the bound of
/// the ADC's rounding on it: each count is off by ≤ ½, so Σf is off by
/// ≤ ½·gain per sample, and the ratio by ≤ |μ|·(½g_x/|f̄_x| + ½g_z/f̄_z).
fn mu_of(cfg: &DeviceConfig, s: &[(u16, u16)]) -> (f64, f64) {
    let (gx, ox) = (f64::from(cfg.adc_x.gain), f64::from(cfg.adc_x.offset));
    let (gz, oz) = (f64::from(cfg.adc_z.gain), f64::from(cfg.adc_z.offset));
    let n = s.len() as f64;
    let fx: f64 = s
        .iter()
        .map(|&(x, _)| (f64::from(x) - ox) * gx)
        .sum::<f64>()
        / n;
    let fz: f64 = s
        .iter()
        .map(|&(_, z)| (f64::from(z) - oz) * gz)
        .sum::<f64>()
        / n;
    let mu = fx / fz;
    (mu, mu.abs() * (0.5 * gx / fx.abs() + 0.5 * gz / fz))
}

/// Beyond the forward critical velocity the contact slides the whole period
/// and f_x = μ0·f_z at every instant (eq. 8): Σf_x/Σf_z = μ0 up to the ADC's
/// rounding, in f64 (libm, 32 sub-steps) and in f32 (fast-f32, 8 sub-steps,
/// the QEMU build's). v_c forward = 0.107 m/s here (`fricctl mu`); 0.2 m/s.
/// 100 halves of 64 samples = 256 whole periods.
#[test]
fn continuous_sliding_gives_mu0_in_f64_and_f32() {
    let cfg = DeviceConfig::driver_board(0);
    for (name, s) in [
        ("f64", run::<f64, Libm>(cfg, drive(0.7), 0.2, 32, 100)),
        ("f32", run::<f32, FastF32>(cfg, drive(0.7), 0.2, 8, 100)),
    ] {
        let (mu, tol) = mu_of(&cfg, &s);
        assert!(
            (mu - MU0).abs() <= tol,
            "{name}: μ = {mu}, μ0 = {MU0}, rounding bound {tol:.2e}"
        );
    }
}

/// Mirror symmetry of eqs. 1–5: reversing the stage (v0 → −v0) and shifting
/// the tangential drive by half a period (φ → φ + π) reverses μ. The two
/// runs differ only in rounding: |μ₊ + μ₋| ≤ the two rounding bounds.
/// v0 = 4 mm/s: stick-slip (μ ≈ 0.108 from `fricctl mu`), where the phase,
/// the stage's direction and the clamp all matter.
#[test]
fn mirror_symmetry_in_stick_slip() {
    let cfg = DeviceConfig::driver_board(0);
    let phi = 40f32.to_radians();
    let (a, ta) = mu_of(&cfg, &run::<f64, Libm>(cfg, drive(phi), 0.004, 32, 100));
    let (b, tb) = mu_of(
        &cfg,
        &run::<f64, Libm>(cfg, drive(phi + core::f32::consts::PI), -0.004, 32, 100),
    );
    assert!(a > 0.05 && a < 0.2, "{a}");
    assert!(
        (a + b).abs() <= ta + tb,
        "μ(v0, φ) = {a}, μ(−v0, φ+π) = {b}"
    );
}

/// The ADC lag: with `adc_lag_samples` = 1 sample k sees the drive of DAC
/// word k − 1, so in the periodic steady state the whole record is the
/// lag-0 record delayed by one sample: x₁[k] = x₀[k − 1] within one count
/// (the two runs round differently). A lag applied the wrong way would
/// shift by −1 and differ by the force's change over two samples (tens of
/// counts here).
#[test]
fn adc_lag_delays_the_record_by_one_sample() {
    let r0 = run::<f64, Libm>(DeviceConfig::driver_board(0), drive(0.7), 0.004, 32, 40);
    let r1 = run::<f64, Libm>(DeviceConfig::driver_board(1), drive(0.7), 0.004, 32, 40);
    let close = |a: u16, b: u16| (i32::from(a) - i32::from(b)).abs() <= 1;
    let mut moved = 0;
    for k in 1..r0.len() {
        assert!(
            close(r1[k].0, r0[k - 1].0) && close(r1[k].1, r0[k - 1].1),
            "sample {k}: lag 1 {:?}, lag 0 one before {:?}",
            r1[k],
            r0[k - 1]
        );
        if !close(r0[k].0, r0[k - 1].0) {
            moved += 1;
        }
    }
    // The record does change from sample to sample (so the check has teeth).
    assert!(moved > r0.len() / 2, "{moved} of {}", r0.len());
}

/// Resonant transducers (`plant::Resonant`) driven by a real `Device` at
/// 20 kHz: the modes' steady amplitudes and the phase between them are those
/// of the transfer function of each mode (`resonator::ModeParams::response`)
/// with the contact's load and the DAC's hold — the phase φ the device
/// believes it sets is off by the difference of the modes' lags (here
/// ≈ 164°: the tangential mode is above its resonance).
#[test]
fn resonant_transducers_follow_their_transfer_functions() {
    use board::plant::{Resonant, ResonantOptions, DAC_VOLTS_PER_CODE};
    use board::resonator::ModeParams;
    use std::f64::consts::{PI, TAU};
    let cfg = DeviceConfig::driver_board(0);
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev = Device::new(cfg, &table, contact).unwrap();
    let phi = 40f64.to_radians();
    dev.set_drive(drive(phi as f32)).unwrap();
    dev.start().unwrap();
    let modes = [
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
    ];
    let load_q = 2000.0;
    let opts = ResonantOptions {
        modes,
        drift_hz_per_s: [0.0; 2],
        thermal_hz_per_um2: 0.0,
        crosstalk: 0.0,
        load_q,
    };
    let sub = 8;
    let fs = cfg.sample_rate_hz;
    let mut plant = Plant::<f64>::new(MU0, 1e7, 1e7);
    plant.resonant = Some(Resonant::new(opts, 1.0 / (fs * f64::from(sub))).unwrap());
    let mut dac = [0u32; HALF_BUFFER];
    let mut block = [(0u16, 0u16); HALF_BUFFER];
    let loaded_q = |q: f64| 1.0 / (1.0 / q + 1.0 / load_q);
    // Settle for 30 of the slower mode's τ = Q_eff/(π f_r) after the ramps.
    let tau = loaded_q(300.0) / (PI * 20_300.0);
    let t_half = HALF_BUFFER as f64 / fs;
    let settle_halves = (30.0 * tau / t_half) as usize;
    let record = 400;
    let mut half = 0;
    let (mut settled_at, mut k) = (None, 0usize);
    let mut rows: Vec<(f64, f64, f64)> = Vec::new(); // (t, x_z, x_x) at half ends
    while rows.len() < record {
        let d = HalfDrive::fill(&mut dev, half, &mut dac);
        half ^= 1;
        plant.run_half::<Libm>(
            &cfg,
            &d,
            sub,
            0.0,
            |_| SampleConditions {
                mu0: MU0,
                v0: 0.004,
                counts_z: 0.0,
                counts_x: 0.0,
            },
            &mut block,
        );
        k += 1;
        if settled_at.is_none() && dev.status().settled {
            settled_at = Some(k);
        }
        if settled_at.is_some_and(|s| k >= s + settle_halves) {
            let r = plant.resonant.as_ref().unwrap();
            rows.push((k as f64 * t_half, r.modes[0].x(), r.modes[1].x()));
        }
    }
    // Least squares x ≈ a cos ωt + b sin ωt at the half ends (2.56 periods
    // apart: the phases are spread, the 2×2 normal equations well posed).
    let w = TAU * dev.applied().achieved.freq_hz;
    let fit = |col: usize| {
        let (mut cc, mut ss, mut cs, mut xc, mut xs) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for r in &rows {
            let x = if col == 0 { r.1 } else { r.2 };
            let (s, c) = (w * r.0).sin_cos();
            cc += c * c;
            ss += s * s;
            cs += c * s;
            xc += x * c;
            xs += x * s;
        }
        let det = cc * ss - cs * cs;
        let a = (xc * ss - xs * cs) / det;
        let b = (xs * cc - xc * cs) / det;
        ((a * a + b * b).sqrt(), b.atan2(a)) // x = A cos(ωt − ψ'), ψ' = atan2(b, a)
    };
    let ((az, pz), (ax, px)) = (fit(0), fit(1));
    // Expected: the DAC's AC amplitude in volts (Δu/metres_per_code codes ×
    // V/code) × |H| × sinc(π f/f_s) (the hold over a sample), for each mode
    // with its loaded Q.
    let f = dev.applied().achieved.freq_hz;
    let sinc = (PI * f / fs).sin() / (PI * f / fs);
    let resp = |m: ModeParams<f64>| {
        ModeParams {
            q: loaded_q(m.q),
            ..m
        }
        .response::<Libm>(f)
    };
    let ((hz, lag_z), (hx, lag_x)) = (resp(modes[0]), resp(modes[1]));
    let d = drive(phi as f32);
    let volts = |amp: f32, mpc: f32| f64::from(amp) / f64::from(mpc) * DAC_VOLTS_PER_CODE;
    let want_z = volts(d.amp_z_m, cfg.dac_z.metres_per_code) * hz * sinc;
    let want_x = volts(d.amp_x_m, cfg.dac_x.metres_per_code) * hx * sinc;
    // Images of the held waveform near f_s ± f pass with gain
    // ≤ g/((f_s − f)²/f_r² − 1) at amplitudes ≤ f/(f_s − f) of the
    // fundamental's drive: relative to the resonant response ≤ that × g/|H|;
    // the sampled record aliases them onto the fit at most once each.
    let image = |m: ModeParams<f64>, h: f64| {
        2.0 * (f / (fs - f)) / ((fs - f).powi(2) / m.resonance_hz.powi(2) - 1.0) * m.gain_m_per_v
            / h
    };
    let (ez, ex) = (image(modes[0], hz), image(modes[1], hx));
    assert!(
        (az / want_z - 1.0).abs() <= ez,
        "z: {az:e} vs {want_z:e} (allowed {ez:e})"
    );
    assert!(
        (ax / want_x - 1.0).abs() <= ex,
        "x: {ax:e} vs {want_x:e} (allowed {ex:e})"
    );
    // The phase between the modes. The ideal drive is u_z = −Δu_z cos θ,
    // u_x = Δu_x cos(θ + φ); each mode lags its own ψ (the hold and the
    // ADC lag delay both alike), so x_x leads −x_z by φ − (ψ_x − ψ_z).
    // With x = A cos(ωt − ψ') from the fit: −x_z ∝ cos(ωt − (ψ'_z − π)),
    // x_x ∝ cos(ωt − ψ'_x); x_x leads by (ψ'_z − π) − ψ'_x.
    let measured = (pz - PI - px).rem_euclid(TAU);
    let want = (phi - (lag_x - lag_z)).rem_euclid(TAU);
    let diff = ((measured - want + PI).rem_euclid(TAU) - PI).abs();
    assert!(
        diff <= ez + ex,
        "phase {measured} vs {want} (lags {lag_z}, {lag_x})"
    );
    // In words: φ set 40°, φ of the displacements ≈ −124° (lags 6.4°, 170°).
    assert!((lag_x - lag_z).to_degrees() > 160.0, "{lag_z} {lag_x}");
}

/// Runs a device and a plant (with resonant transducers if `resonant`) with
/// the motion pickups until the drive has settled, then `windows` more
/// lock-in windows; returns the device's measured motion of each window.
fn measured_motion(
    resonant: Option<board::plant::ResonantOptions<f64>>,
    settle_halves: usize,
    windows: usize,
) -> Vec<board::device::MeasuredDrive> {
    use board::plant::Resonant;
    let cfg = DeviceConfig::driver_board(1);
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev = Device::new(cfg, &table, contact).unwrap();
    dev.set_drive(drive(40f32.to_radians())).unwrap();
    dev.start().unwrap();
    let sub = 8;
    let mut plant = Plant::<f64>::new(MU0, 1e7, 1e7);
    plant.resonant =
        resonant.map(|o| Resonant::new(o, 1.0 / (cfg.sample_rate_hz * f64::from(sub))).unwrap());
    let mut dac = [0u32; HALF_BUFFER];
    let mut forces = [(0u16, 0u16); HALF_BUFFER];
    let mut pickups = [(0u16, 0u16); HALF_BUFFER];
    let (mut half, mut settled_for) = (0, 0usize);
    let mut out = Vec::new();
    let mut seen = 0;
    while out.len() < windows {
        let d = HalfDrive::fill(&mut dev, half, &mut dac);
        plant.run_half_with_pickups::<Libm>(
            &cfg,
            &d,
            sub,
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
        dev.adc_block_with_pickups(half, &forces, &pickups);
        half ^= 1;
        if dev.status().settled {
            settled_for += 1;
        }
        if let Some(m) = dev.measured_drive() {
            if settled_for > settle_halves && m.windows != seen {
                out.push(m);
            }
            seen = m.windows;
        }
    }
    out
}

/// The worst-case effect of the pickups' rounding (±½ count per sample) on
/// one lock-in window of the device (one 64-sample block at 20 kHz and
/// 500 kS/s): ½ count × the window's error gain
/// (`integration_tests::lockin_error_gain`, from the fit's weights), in m.
fn rounding_bound(gain: f32) -> f64 {
    let dtheta = std::f64::consts::TAU * 20e3 / 500e3;
    0.5 * integration_tests::lockin_error_gain(HALF_BUFFER, dtheta) * f64::from(gain)
}

#[test]
fn pickups_measure_the_ideal_drive() {
    let cfg = DeviceConfig::driver_board(1);
    let d = drive(40f32.to_radians());
    let (bz, bx) = (
        rounding_bound(cfg.pickup_z.gain),
        rounding_bound(cfg.pickup_x.gain),
    );
    for m in measured_motion(None, 20, 50) {
        let (az, ax) = (f64::from(d.amp_z_m), f64::from(d.amp_x_m));
        assert!((f64::from(m.amp_z_m) - az).abs() <= bz, "{m:?}");
        assert!((f64::from(m.amp_x_m) - ax).abs() <= bx, "{m:?}");
        let dphi = f64::from(m.phase_rad) - 40f64.to_radians();
        assert!(dphi.abs() <= bz / az + bx / ax, "{m:?}: {dphi}");
        assert!(m.amp_z_peak_m >= m.amp_z_m);
    }
}

#[test]
fn pickups_measure_what_resonant_transducers_really_do() {
    use board::plant::{ResonantOptions, DAC_VOLTS_PER_CODE};
    use board::resonator::ModeParams;
    use std::f64::consts::{PI, TAU};
    let cfg = DeviceConfig::driver_board(1);
    let modes = [
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
    ];
    let opts = ResonantOptions {
        modes,
        drift_hz_per_s: [0.0; 2],
        thermal_hz_per_um2: 0.0,
        crosstalk: 0.0,
        load_q: f64::INFINITY,
    };
    // 30 τ of the slower mode (4.7 ms) in half-buffers of 128 µs.
    let settle = (30.0 * 300.0 / (PI * 20_300.0) / 128e-6) as usize;
    let ms = measured_motion(Some(opts), settle, 50);
    let f = 20e3;
    let sinc = (PI * f / cfg.sample_rate_hz).sin() / (PI * f / cfg.sample_rate_hz);
    let ((hz, lz), (hx, lx)) = (modes[0].response::<Libm>(f), modes[1].response::<Libm>(f));
    let d = drive(40f32.to_radians());
    let volts = |amp: f32, mpc: f32| f64::from(amp) / f64::from(mpc) * DAC_VOLTS_PER_CODE;
    let want_z = volts(d.amp_z_m, cfg.dac_z.metres_per_code) * hz * sinc;
    let want_x = volts(d.amp_x_m, cfg.dac_x.metres_per_code) * hx * sinc;
    let want_phi = (40f64.to_radians() - (lx - lz) + PI).rem_euclid(TAU) - PI;
    let (bz, bx) = (
        rounding_bound(cfg.pickup_z.gain),
        rounding_bound(cfg.pickup_x.gain),
    );
    // Besides the pickups' rounding, 1e-4 of the amplitude: the held
    // waveform's images (≤ 2e-6 here, `resonant_transducers_follow_their_
    // transfer_functions`) and the f32 lock-in's sums of 64 terms
    // (≤ 64·6e-8·2 ≈ 8e-6), with margin.
    for m in ms {
        assert!(
            (f64::from(m.amp_z_m) - want_z).abs() <= bz + 1e-4 * want_z,
            "{m:?} vs {want_z:e}"
        );
        assert!(
            (f64::from(m.amp_x_m) - want_x).abs() <= bx + 1e-4 * want_x,
            "{m:?} vs {want_x:e}"
        );
        let dphi = ((f64::from(m.phase_rad) - want_phi + PI).rem_euclid(TAU) - PI).abs();
        assert!(
            dphi <= bz / want_z + bx / want_x + 1e-4,
            "{m:?} vs {want_phi}"
        );
    }
    // The board believes φ = 40°; the displacements run at ≈ −124°.
    assert!(want_phi.to_degrees() < -100.0, "{}", want_phi.to_degrees());
}

/// The plant's ADC noise (`plant::Noise`) against its spec, written out
/// here: xorshift64 with shifts 13, 7, 17 (Marsaglia 2003), the top 24
/// bits as a fraction `u` in [0, 1), the draw `(2u − 1)·A`. 10 000 draws
/// equal the hand-written generator's exactly, in f64 and in f32 (24-bit
/// fractions are exact in both, so both plants see the same noise; `A = 4`
/// keeps the product exact too), and
/// 10⁵ draws have the uniform law's mean 0 and variance `A²/3` within 5
/// standard errors (`A/√(3N)` for the mean; `√(4/45)·A²/√N` for the
/// variance, from the uniform's fourth moment `A⁴/5`).
#[test]
fn the_noise_is_the_specified_xorshift_uniform() {
    use board::plant::Noise;
    let seed = 0x1234_5678_9ABC_DEF0u64;
    let mut state = seed;
    let mut by_hand = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f64 / 16_777_216.0
    };
    let (mut n64, mut n32) = (Noise::new(seed), Noise::new(seed));
    // A power of two: the product is exact in f32 too.
    let a = 4.0;
    for _ in 0..10_000 {
        let want = (2.0 * by_hand() - 1.0) * a;
        assert_eq!(n64.uniform::<f64>(a), want);
        assert_eq!(f64::from(n32.uniform::<f32>(a as f32)), want);
    }
    let n = 100_000;
    let mut g = Noise::new(7);
    let a = 3.5;
    let xs: Vec<f64> = (0..n).map(|_| g.uniform::<f64>(a)).collect();
    assert!(xs.iter().all(|x| (-a..a).contains(x)));
    let mean = xs.iter().sum::<f64>() / n as f64;
    let var = xs.iter().map(|x| x * x).sum::<f64>() / n as f64 - mean * mean;
    let nn = (n as f64).sqrt();
    assert!(mean.abs() <= 5.0 * a / (3.0f64.sqrt() * nn), "mean {mean}");
    let se_var = (4.0f64 / 45.0).sqrt() * a * a / nn;
    assert!((var - a * a / 3.0).abs() <= 5.0 * se_var, "variance {var}");
}

/// The ideal transducers' first-order amplitude lag (module docs: `keep` =
/// e^(−T_s/τ) per sample, exact for a constant target over one sample). On
/// a settled drive the DAC's levels are the same before and after the fill,
/// so the target of both channels is constant over a half; from amplitudes
/// set to zero, after the half's n samples each is the closed form
/// `Δu·(1 − keepⁿ)`, Δu the set amplitude (2 µm, 0.3 µm). The DAC levels
/// are Δu/metres_per_code in f32 (relative rounding ≤ 6e-8) and the n
/// updates in f64 add ~n ulps: allowed 1e-6 relative.
#[test]
fn ideal_transducers_lag_their_targets_by_the_closed_form() {
    let cfg = DeviceConfig::driver_board(0);
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    let setting = drive(0.7);
    let mut dev = Device::new(cfg, &table, contact).unwrap();
    dev.set_drive(setting).unwrap();
    dev.start().unwrap();
    let mut plant = Plant::<f64>::new(MU0, 1e7, 1e7);
    let mut dac = [0u32; HALF_BUFFER];
    let mut block = [(0u16, 0u16); HALF_BUFFER];
    let conditions = |_| SampleConditions {
        mu0: MU0,
        v0: 0.2,
        counts_z: 0.0,
        counts_x: 0.0,
    };
    let mut half = 0;
    // Settle with no lag, then two more halves so that the fill is steady.
    let mut after = 0;
    while after < 2 {
        let d = HalfDrive::fill(&mut dev, half, &mut dac);
        half ^= 1;
        plant.run_half::<Libm>(&cfg, &d, 4, 0.0, conditions, &mut block);
        if dev.status().settled {
            after += 1;
        }
    }
    // τ = 20 samples: keep = e^(−1/20); 64 samples leave e^(−3.2) = 4 %.
    let keep = (-1.0f64 / 20.0).exp();
    plant.amp = (0.0, 0.0);
    let d = HalfDrive::fill(&mut dev, half, &mut dac);
    plant.run_half::<Libm>(&cfg, &d, 4, keep, conditions, &mut block);
    let left = keep.powi(HALF_BUFFER as i32);
    let (want_z, want_x) = (
        f64::from(setting.amp_z_m) * (1.0 - left),
        f64::from(setting.amp_x_m) * (1.0 - left),
    );
    assert!(
        (plant.amp.0 / want_z - 1.0).abs() <= 1e-6,
        "Δu_z {:e} vs {want_z:e}",
        plant.amp.0
    );
    assert!(
        (plant.amp.1 / want_x - 1.0).abs() <= 1e-6,
        "Δu_x {:e} vs {want_x:e}",
        plant.amp.1
    );
}

/// Self-heating of resonant transducers (module docs: a shift of f_r per
/// squared amplitude, filtered with `THERMAL_TAU_S`): the heat of a mode
/// follows its squared amplitude A² (µm²) through a first-order filter, so
/// from the heat h₁ at t₁, with A² constant at its mean Ā², `h(t) = Ā² +
/// (h₁ − Ā²)·e^{−(t − t₁)/τ}`, and f_r = f_base + k·h (read through
/// `params_now`). Both modes sit at the drive's 20 kHz, so the motion is a
/// steady sinusoid at their own ω and A² = x² + (ẋ/ω)² from the plant's
/// true state, read before every half (when the plant takes it). The
/// filter is a weighted mean of the inputs with weights summing to 1 −
/// e^{−(t − t₁)/τ}, so the inputs' deviation from Ā² (the DAC hold's
/// ripple, measured as max − min over the run) moves the heat by at most
/// that sum times max − min; the DDS frequency (20 kHz within 1.2e-4 Hz)
/// and the heat's own shift of f_r (≤ 0.02 Hz) make the plant's ω_r differ
/// from ω by ≤ 1e-6 relative, 2e-6 on (ẋ/ω)²: allowed 1e-5 of Ā² for it.
#[test]
fn self_heating_follows_the_squared_amplitude_with_its_time_constant() {
    use board::plant::{Resonant, ResonantOptions, THERMAL_TAU_S};
    use board::resonator::ModeParams;
    use std::f64::consts::TAU;
    let cfg = DeviceConfig::driver_board(0);
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev = Device::new(cfg, &table, contact).unwrap();
    dev.set_drive(drive(0.7)).unwrap();
    dev.start().unwrap();
    let f_drive = 20_000.0;
    let modes = [
        ModeParams {
            resonance_hz: f_drive,
            q: 100.0,
            gain_m_per_v: 4e-8,
        },
        ModeParams {
            resonance_hz: f_drive,
            q: 100.0,
            gain_m_per_v: 2e-8,
        },
    ];
    let k = 1e-3; // Hz per µm²
    let opts = ResonantOptions {
        modes,
        drift_hz_per_s: [0.0; 2],
        thermal_hz_per_um2: k,
        crosstalk: 0.0,
        load_q: f64::INFINITY,
    };
    let sub = 4;
    let mut plant = Plant::<f64>::new(MU0, 1e7, 1e7);
    plant.resonant =
        Some(Resonant::new(opts, 1.0 / (cfg.sample_rate_hz * f64::from(sub))).unwrap());
    let mut dac = [0u32; HALF_BUFFER];
    let mut block = [(0u16, 0u16); HALF_BUFFER];
    let t_half = HALF_BUFFER as f64 / cfg.sample_rate_hz;
    let mut half = 0;
    let mut run = |plant: &mut Plant<f64>, dev: &mut Device<'_, 1024>| {
        let d = HalfDrive::fill(dev, half, &mut dac);
        half ^= 1;
        plant.run_half::<Libm>(
            &cfg,
            &d,
            sub,
            0.0,
            |_| SampleConditions {
                mu0: MU0,
                v0: 0.2,
                counts_z: 0.0,
                counts_x: 0.0,
            },
            &mut block,
        );
    };
    let w = TAU * f_drive;
    let amp2 = |plant: &Plant<f64>| -> [f64; 2] {
        let r = plant.resonant.as_ref().unwrap();
        core::array::from_fn(|c| {
            let (x, v) = (r.modes[c].x() * 1e6, r.modes[c].v() / w * 1e6);
            x * x + v * v
        })
    };
    // Settled drive, then 40 τ of the modes (τ = Q/(π f_r) = 1.6 ms).
    while !dev.status().settled {
        run(&mut plant, &mut dev);
    }
    for _ in 0..(40.0 * 100.0 / (std::f64::consts::PI * f_drive) / t_half) as usize {
        run(&mut plant, &mut dev);
    }
    let shift = |plant: &Plant<f64>| -> [f64; 2] {
        let p = plant.resonant.as_ref().unwrap().params_now();
        [p[0].resonance_hz - f_drive, p[1].resonance_hz - f_drive]
    };
    let h1 = shift(&plant).map(|s| s / k);
    let halves = 2000; // 0.256 s, a quarter of the thermal time
    let (mut sum, mut lo, mut hi) = ([0.0; 2], [f64::INFINITY; 2], [0.0f64; 2]);
    for _ in 0..halves {
        let a = amp2(&plant);
        for c in 0..2 {
            sum[c] += a[c];
            lo[c] = lo[c].min(a[c]);
            hi[c] = hi[c].max(a[c]);
        }
        run(&mut plant, &mut dev);
    }
    let decay = (-(halves as f64) * t_half / THERMAL_TAU_S).exp();
    let s2 = shift(&plant);
    for c in 0..2 {
        let a2 = sum[c] / halves as f64;
        let want = a2 + (h1[c] - a2) * decay;
        println!(
            "mode {c}: A² {a2:.6} µm² (spread {:.1e}), heat {:.6} → {:.6} µm², want {want:.6} ({:.1e} off)",
            (hi[c] - lo[c]) / a2,
            h1[c],
            s2[c] / k,
            (s2[c] / k - want) / a2
        );
        let tol = (1.0 - decay) * (hi[c] - lo[c]) + 1e-5 * a2;
        assert!(
            (s2[c] / k - want).abs() <= tol,
            "mode {c}: heat {} µm², want {want} (A² {a2}, h₁ {})",
            s2[c] / k,
            h1[c]
        );
    }
}

#[test]
fn a_rung_down_resonant_mode_comes_to_rest_exactly_at_the_next_half() {
    // A mode ringing in the subnormals (what an undriven mode ends in,
    // tests/resonator.rs) costs ~100 cycles an operation on x86: the plant
    // sets a mode under `SUBNORMAL_FLOOR_M` to rest at each half-buffer. A
    // mode above it decays by the closed form e^{−T/τ} over the half.
    use board::plant::{Resonant, ResonantOptions, SUBNORMAL_FLOOR_M};
    use std::f64::consts::PI;
    let cfg = DeviceConfig::driver_board(0);
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev = Device::new(cfg, &table, contact).unwrap(); // never started: no drive
    let sub = 32;
    let opts = ResonantOptions::<f64>::bench(&cfg);
    let mut plant = Plant::<f64>::new(MU0, 1e7, 1e7);
    plant.resonant =
        Some(Resonant::new(opts, 1.0 / (cfg.sample_rate_hz * f64::from(sub))).unwrap());
    let x_above = 100.0 * SUBNORMAL_FLOOR_M;
    {
        let r = plant.resonant.as_mut().unwrap();
        r.modes[0].set_state(1e-310, 0.0);
        r.modes[1].set_state(x_above, 0.0);
    }
    let mut dac = [0u32; HALF_BUFFER];
    let mut block = [(0u16, 0u16); HALF_BUFFER];
    let d = HalfDrive::fill(&mut dev, 0, &mut dac);
    plant.run_half::<Libm>(
        &cfg,
        &d,
        sub,
        0.0,
        |_| SampleConditions {
            mu0: MU0,
            v0: 0.0,
            counts_z: 0.0,
            counts_x: 0.0,
        },
        &mut block,
    );
    let r = plant.resonant.as_ref().unwrap();
    assert_eq!((r.modes[0].x(), r.modes[0].v()), (0.0, 0.0));
    // The tangential mode rings on: its energy amplitude √(x² + (v/ω)²)
    // after T = 64 µs is x₀·e^{−T/τ} to O(1/Q) (the energy's oscillation
    // at 2ω_d has relative size 1/(2Q) = 0.3 %), τ = Q_loaded/(π f_r).
    let p = r.modes[1].params();
    let w = 2.0 * PI * p.resonance_hz;
    let amp = r.modes[1].x().hypot(r.modes[1].v() / w);
    let t = HALF_BUFFER as f64 / cfg.sample_rate_hz;
    let want = x_above * (-t * PI * p.resonance_hz / p.q).exp();
    assert!(
        (amp / want - 1.0).abs() < 1.0 / p.q,
        "amplitude {amp:e}, closed form {want:e}"
    );
}

#[test]
fn the_bench_transducers_identified_are_the_closed_forms() {
    // What an exact identification finds (eq. 1 of board::identify): the
    // resonances, the loaded Q = 1/(1/Q + 1/2000) (300 → 260.87, 200 →
    // 181.82), the static gains (a thirtieth of the calibration per DAC volt)
    // and the zero-order hold's lag of half a sample at the resonance,
    // θ = π f_r/f_s (0.12755 and 0.12378 rad at 500 kS/s), each rounded
    // once to f32: allowed one f32 ulp (2⁻²³ relative).
    use board::plant::ResonantOptions;
    let cfg = DeviceConfig::driver_board(0);
    let t = ResonantOptions::<f64>::bench(&cfg).identified(cfg.sample_rate_hz);
    let fs = 500_000.0;
    assert_eq!(cfg.sample_rate_hz, fs);
    // RM0090 §14.2: DAC output = V_REF·DOR/4095, V_REF = 3.3 V.
    let volts_per_code = 3.3 / 4095.0;
    for (m, fr, q, cal) in [
        (t.z, 20_300.0, 300.0, cfg.dac_z.metres_per_code),
        (t.x, 19_700.0, 200.0, cfg.dac_x.metres_per_code),
    ] {
        let want = [
            fr,
            1.0 / (1.0 / q + 1.0 / 2000.0),
            f64::from(cal) / volts_per_code / 30.0,
            std::f64::consts::PI * fr / fs,
        ];
        let got = [m.resonance_hz, m.q, m.gain_m_per_v, m.phase_lag_rad].map(f64::from);
        for k in 0..4 {
            assert!(
                (got[k] / want[k] - 1.0).abs() <= f64::from(f32::EPSILON),
                "field {k}: {} against {}",
                got[k],
                want[k]
            );
        }
    }
}

#[test]
fn the_excursion_count_is_the_samples_beyond_the_limit() {
    // Ideal transducers at the settled drive (Δu_z = 2 µm, 20 kHz: 25
    // samples a period at 500 kS/s, the phases 2π/25 apart): |u_z − u_z0| =
    // 2 µm·|sin θ_i| exceeds 1 µm where |sin θ| > ½, on 2/3 of the circle,
    // so 16 or 17 of each 25 consecutive samples; a negative limit counts
    // every sample, an infinite one none. The peak of a half-buffer's 64
    // samples is within 2 µm·[cos(π/25), 1].
    let cfg = DeviceConfig::driver_board(0);
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    for (limit, per_25) in [(-1.0, 25..=25), (f64::INFINITY, 0..=0), (1e-6, 16..=17)] {
        let mut dev = Device::new(cfg, &table, contact).unwrap();
        dev.set_drive(drive(0.7)).unwrap();
        dev.start().unwrap();
        let mut plant = Plant::<f64>::new(MU0, 1e7, 1e7);
        let mut dac = [0u32; HALF_BUFFER];
        let mut block = [(0u16, 0u16); HALF_BUFFER];
        let mut half = 0;
        let mut step = |plant: &mut Plant<f64>, dev: &mut Device<'_, 1024>| {
            let d = HalfDrive::fill(dev, half, &mut dac);
            half ^= 1;
            plant.run_half::<Libm>(
                &cfg,
                &d,
                4,
                0.0,
                |_| SampleConditions {
                    mu0: MU0,
                    v0: 0.0,
                    counts_z: 0.0,
                    counts_x: 0.0,
                },
                &mut block,
            );
        };
        while !dev.status().settled {
            step(&mut plant, &mut dev);
        }
        // 25 halves = 1 600 samples = 64 periods exactly.
        assert_eq!(HALF_BUFFER, 64);
        plant.excursion_limit_m = limit;
        plant.samples_above = 0;
        for _ in 0..25 {
            step(&mut plant, &mut dev);
            let peak = plant.peak_excursion_m;
            let lowest = 2e-6 * (std::f64::consts::PI / 25.0).cos();
            assert!(
                (lowest * (1.0 - 1e-9)..=2e-6 * (1.0 + 1e-6)).contains(&peak),
                "peak {peak:e}"
            );
        }
        let (lo, hi) = (*per_25.start() * 64, *per_25.end() * 64);
        assert!(
            (lo..=hi).contains(&plant.samples_above),
            "limit {limit:e}: {} samples above, {lo}..={hi} expected",
            plant.samples_above
        );
    }
}

#[test]
fn each_channel_adds_its_own_count_offset() {
    // `SampleConditions.counts_z/x` (the virtual device's noise and offset)
    // add to their own channel's reading before the rounding: a whole
    // number of counts shifts every reading of that channel by exactly that
    // many (away from the rails) and leaves the other's unchanged, for ideal
    // and resonant transducers.
    use board::plant::{Resonant, ResonantOptions};
    let cfg = DeviceConfig::driver_board(0);
    let table = SineTable::<1024>::libm();
    let contact = Contact {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev = Device::new(cfg, &table, contact).unwrap();
    dev.set_drive(drive(0.7)).unwrap();
    dev.start().unwrap();
    let mut dac = [0u32; HALF_BUFFER];
    // A settled drive (the offset reached: the normal force mid-range).
    let mut half = 0;
    let d = loop {
        let d = HalfDrive::fill(&mut dev, half, &mut dac);
        half ^= 1;
        if dev.status().settled {
            break d;
        }
    };
    let mut resonant = Plant::<f64>::new(MU0, 1e7, 1e7);
    resonant.resonant = Some(
        Resonant::new(
            ResonantOptions::bench(&cfg),
            1.0 / (cfg.sample_rate_hz * 4.0),
        )
        .unwrap(),
    );
    for plant in [Plant::<f64>::new(MU0, 1e7, 1e7), resonant] {
        let run = |cz: f64, cx: f64| {
            let mut p = plant;
            let mut out = [(0u16, 0u16); HALF_BUFFER];
            p.run_half::<Libm>(
                &cfg,
                &d,
                4,
                0.0,
                |_| SampleConditions {
                    mu0: MU0,
                    v0: 0.004,
                    counts_z: cz,
                    counts_x: cx,
                },
                &mut out,
            );
            out
        };
        let (base, z5, x7) = (run(0.0, 0.0), run(5.0, 0.0), run(0.0, -7.0));
        for i in 0..HALF_BUFFER {
            let (x, z) = base[i];
            assert!(
                (10..4085).contains(&x) && (10..4085).contains(&z),
                "{i}: ({x}, {z}) near a rail"
            );
            assert_eq!(z5[i], (x, z + 5), "sample {i}");
            assert_eq!(x7[i], (x - 7, z), "sample {i}");
        }
    }
}
